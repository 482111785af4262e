//! Small estimators over runs: plain and weighted means (the straight line is [`crate::stats::ols_indexed`]).

/// Mean of y over `idx` restricted to the entries where `keep` holds; NaN if none.
pub fn mean_where(y: &[f64], idx: &[usize], keep: impl Fn(usize) -> bool) -> f64 {
    let (mut s, mut m) = (0.0, 0usize);
    for &i in idx {
        if keep(i) {
            s += y[i];
            m += 1;
        }
    }
    if m == 0 {
        f64::NAN
    } else {
        s / m as f64
    }
}

/// Inverse-variance weighted mean of y over `idx` (entries with a non-positive or unknown
/// error are left out); NaN if none.
pub fn weighted_mean(y: &[f64], se: &[f64], idx: &[usize]) -> f64 {
    let (mut s, mut w) = (0.0, 0.0);
    for &i in idx {
        if se[i] > 0.0 && se[i].is_finite() {
            let wi = 1.0 / (se[i] * se[i]);
            s += wi * y[i];
            w += wi;
        }
    }
    if w > 0.0 {
        s / w
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_line_and_means() {
        let x = [0.0, 1.0, 2.0, 3.0];
        let y = [1.0, 3.0, 5.0, 7.0];
        assert_eq!(mean_where(&y, &[0, 1, 2, 3], |i| x[i] > 1.5), 6.0);
        // weights 1 and 1/4: (1·1 + 0.25·7)/1.25
        let w = weighted_mean(&y, &[1.0, f64::NAN, 0.0, 2.0], &[0, 1, 2, 3]);
        assert!((w - (1.0 + 0.25 * 7.0) / 1.25).abs() < 1e-12);
    }
}
