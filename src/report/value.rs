//! Tolerant readers for upstream JSON: numbers by any of several field names, plain or `{value, stderr}`.
//!
//! The report reads other stages' artifacts as `serde_json::Value` so that it stays decoupled from
//! their Rust types; these helpers keep that reading short and forgiving of small naming choices.

use serde_json::Value;

/// A number with an optional standard error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Est {
    pub value: f64,
    pub stderr: Option<f64>,
}

/// The first of `names` present in `obj` (an object), as a raw value.
pub fn field<'a>(obj: &'a Value, names: &[&str]) -> Option<&'a Value> {
    let map = obj.as_object()?;
    names
        .iter()
        .find_map(|n| map.get(*n))
        .filter(|v| !v.is_null())
}

/// A finite number under the first of `names`; an object with `value` (or `estimate`) counts too.
pub fn num(obj: &Value, names: &[&str]) -> Option<f64> {
    field(obj, names).and_then(as_num)
}

/// A value read as a finite number (plain, numeric string, or `{value: ..}`).
pub fn as_num(v: &Value) -> Option<f64> {
    let x = match v {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => s.trim().parse().ok(),
        Value::Object(_) => num(v, &["value", "estimate", "mean", "fitted"]),
        _ => None,
    }?;
    x.is_finite().then_some(x)
}

/// A number with its standard error: `{name: {value, stderr}}`, or `name` plus `name_se` /
/// `name_stderr` siblings, or `stderr: {name: ..}`.
pub fn est(obj: &Value, names: &[&str]) -> Option<Est> {
    let v = field(obj, names)?;
    let value = as_num(v)?;
    let mut stderr = num(v, &["stderr", "se", "std_err", "sigma"]);
    if stderr.is_none() {
        for n in names {
            let base = n
                .trim_end_matches("_mps")
                .trim_end_matches("_s")
                .trim_end_matches("_m");
            let cands = [
                format!("{n}_se"),
                format!("{n}_stderr"),
                format!("{base}_se"),
                format!("{base}_stderr"),
            ];
            let refs: Vec<&str> = cands.iter().map(String::as_str).collect();
            stderr = num(obj, &refs)
                .or_else(|| field(obj, &["stderr", "se"]).and_then(|s| num(s, &[n, base])));
            if stderr.is_some() {
                break;
            }
        }
    }
    Some(Est { value, stderr })
}

/// A string under the first of `names`.
pub fn text<'a>(obj: &'a Value, names: &[&str]) -> Option<&'a str> {
    field(obj, names).and_then(Value::as_str)
}

/// An interval `[lo, hi]` under the first of `names`: a two-element array or `{lo, hi}` / `{low, high}`.
pub fn interval(obj: &Value, names: &[&str]) -> Option<(f64, f64)> {
    let v = field(obj, names)?;
    if let Some(a) = v.as_array() {
        if a.len() == 2 {
            return Some((as_num(&a[0])?, as_num(&a[1])?));
        }
    }
    let lo = num(v, &["lo", "low", "lower", "min"])?;
    let hi = num(v, &["hi", "high", "upper", "max"])?;
    Some((lo, hi))
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

/// `value ± stderr` with sensible digits (two significant digits on the error).
pub fn pm(e: Est) -> String {
    match e.stderr {
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
    fn reads_plain_nested_and_sibling_errors() {
        let v = json!({"mu": 0.3, "mu_se": 0.01, "T_s": {"value": 0.05, "stderr": 0.002},
                       "v0_mps": "0.02", "stderr": {"v0": 1e-4}});
        assert_eq!(est(&v, &["mu"]).unwrap().stderr, Some(0.01));
        assert_eq!(est(&v, &["T_s"]).unwrap().stderr, Some(0.002));
        let v0 = est(&v, &["v0_mps"]).unwrap();
        assert_eq!((v0.value, v0.stderr), (0.02, Some(1e-4)));
        assert_eq!(num(&v, &["nope", "mu"]), Some(0.3));
    }

    #[test]
    fn formats_with_error_digits() {
        let e = Est {
            value: 0.33712,
            stderr: Some(0.0042),
        };
        assert_eq!(pm(e), "0.3371 ± 0.0042");
        assert_eq!(sig(2.1834, 3), "2.18");
        assert_eq!(sig(0.0483, 2), "0.048");
    }
}
