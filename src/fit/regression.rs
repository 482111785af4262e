//! Small estimators over runs: a straight line by ordinary least squares, plain and weighted means.

/// Intercept and slope of y = a + b·x by ordinary least squares over the pairs picked by `idx`
/// (indices may repeat, as in a bootstrap resample). NaN if the x values do not vary.
pub fn line_fit(x: &[f64], y: &[f64], idx: &[usize]) -> (f64, f64) {
    let m = idx.len() as f64;
    if idx.len() < 2 {
        return (f64::NAN, f64::NAN);
    }
    let xm = idx.iter().map(|&i| x[i]).sum::<f64>() / m;
    let ym = idx.iter().map(|&i| y[i]).sum::<f64>() / m;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for &i in idx {
        sxy += (x[i] - xm) * (y[i] - ym);
        sxx += (x[i] - xm) * (x[i] - xm);
    }
    if sxx.is_nan() || sxx <= 1e-300 {
        return (f64::NAN, f64::NAN);
    }
    let b = sxy / sxx;
    (ym - b * xm, b)
}

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
        let (a, b) = line_fit(&x, &y, &[0, 1, 2, 3]);
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
        assert!(line_fit(&x, &y, &[2, 2, 2]).0.is_nan());
        assert_eq!(mean_where(&y, &[0, 1, 2, 3], |i| x[i] > 1.5), 6.0);
        // weights 1 and 1/4: (1·1 + 0.25·7)/1.25
        let w = weighted_mean(&y, &[1.0, f64::NAN, 0.0, 2.0], &[0, 1, 2, 3]);
        assert!((w - (1.0 + 0.25 * 7.0) / 1.25).abs() < 1e-12);
    }
}
