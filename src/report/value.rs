//! Numbers as the report prints them: a value with its standard error, significant digits, and a
//! number read from free-form JSON (the truth file's terms, discovery's `where`).

use serde_json::Value;

use crate::artifacts::Estimate;

/// A JSON value read as a finite number (a number, or a numeric string).
pub fn as_num(v: &Value) -> Option<f64> {
    let x = match v {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => s.trim().parse().ok(),
        _ => None,
    }?;
    x.is_finite().then_some(x)
}

/// The name a unit enum variant is written with in the artifacts (`max_iterations`, `rolling`),
/// or `?` for anything that is not written as a string.
pub fn serde_name<T: serde::Serialize>(x: &T) -> String {
    match serde_json::to_value(x) {
        Ok(Value::String(s)) => s,
        _ => "?".into(),
    }
}

/// `n` and the noun, plural unless n is 1: "1 recorded run", "3 recorded runs".
pub fn count(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// Format a number with `digits` significant digits, plain notation where readable.
pub fn sig(x: f64, digits: usize) -> String {
    if !x.is_finite() {
        return "—".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let mag = x.abs().log10().floor() as i32;
    if !(-4..=5).contains(&mag) {
        return format!("{:.*e}", digits.saturating_sub(1), x);
    }
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    format!("{x:.decimals$}")
}

/// `value ± se` with sensible digits (two significant digits on the error).
pub fn pm(e: Estimate) -> String {
    match e.se {
        Some(se) if se > 0.0 && se.is_finite() => {
            let mag = se.log10().floor() as i32;
            let decimals = (1 - mag).max(0) as usize;
            if decimals > 8 {
                format!("{} ± {}", sig(e.value, 4), sig(se, 2))
            } else {
                format!("{:.*} ± {:.*}", decimals, e.value, decimals, se)
            }
        }
        _ => sig(e.value, 4),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn reads_numbers_only() {
        assert_eq!(as_num(&json!(0.3)), Some(0.3));
        assert_eq!(as_num(&json!("0.02")), Some(0.02));
        assert_eq!(as_num(&json!({"value": 1.0})), None);
        assert_eq!(as_num(&json!(null)), None);
    }

    #[test]
    fn formats_with_error_digits() {
        let e = Estimate {
            value: 0.33712,
            se: Some(0.0042),
            interval: None,
        };
        assert_eq!(pm(e), "0.3371 ± 0.0042");
        assert_eq!(sig(2.1834, 3), "2.18");
        assert_eq!(sig(0.0483, 2), "0.048");
    }
}
