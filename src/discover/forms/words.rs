//! Numbers in a finding's sentence: a size with its unit, its error beside it.

use crate::artifacts::diagnosis::Finding;

/// `x` to three significant figures, plain decimals where they are short.
pub fn num(x: f64) -> String {
    if !x.is_finite() {
        return "—".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    // the exponent after rounding to three figures (0.99996 is 1.00, not 0.9999…)
    let rounded = format!("{x:.2e}");
    let exp: i32 = rounded
        .rsplit('e')
        .next()
        .and_then(|e| e.parse().ok())
        .unwrap_or(0);
    let digits = 2 - exp;
    if (-1..=5).contains(&digits) {
        format!("{:.*}", digits.max(0) as usize, x)
    } else {
        format!("{x:.2e}")
    }
}

/// The value of parameter `name` of finding `f` in units of `scale` (1e3: mm, 1e2: %) with its
/// error: "21 ± 2", or the value alone when the error is none or not finite.
pub fn with_error(f: &Finding, name: &str, scale: f64) -> Option<String> {
    let e = f.parameters.get(name)?;
    let v = num(scale * e.value.abs());
    Some(match e.se.filter(|s| s.is_finite() && *s > 0.0) {
        Some(se) => format!("{v} ± {}", num(scale * se)),
        None => v,
    })
}

/// The value of parameter `name` of finding `f`.
pub fn value(f: &Finding, name: &str) -> Option<f64> {
    f.parameters
        .get(name)
        .map(|e| e.value)
        .filter(|v| v.is_finite())
}

/// Every material's value of a parameter named `<prefix>_<material>`, in units of `scale`:
/// "3.2 (316), 4.1 (440c)".
pub fn per_material(f: &Finding, prefix: &str, scale: f64) -> Option<String> {
    let parts: Vec<String> = f
        .parameters
        .iter()
        .filter_map(|(k, e)| {
            let m = k.strip_prefix(prefix)?.strip_prefix('_')?;
            e.value
                .is_finite()
                .then(|| format!("{} ({m})", num(scale * e.value)))
        })
        .collect();
    (!parts.is_empty()).then(|| parts.join(", "))
}

/// "towards +z" or "towards −z" for a signed push along the groove.
pub fn towards(x: f64) -> &'static str {
    if x >= 0.0 {
        "towards +z"
    } else {
        "towards −z"
    }
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn numbers_keep_three_significant_figures() {
        assert_eq!(num(0.2063), "0.206");
        assert_eq!(num(21.06), "21.1");
        assert_eq!(num(-1234.0), "-1234");
        assert_eq!(num(0.000123), "1.23e-4");
        assert_eq!(num(0.0), "0");
        assert_eq!(num(0.9999999), "1.00");
        assert_eq!(num(1.0000000000000002), "1.00");
    }
}
