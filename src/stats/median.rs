//! Medians and median-based scales. Two conventions are kept on purpose, each named: the
//! textbook median (mean of the two middle values for an even count) and the upper median (the
//! value of rank n/2), which the detectors and the discoverer were calibrated with.

/// 1.4826·MAD estimates σ for Gaussian data.
pub const MAD_TO_SIGMA: f64 = 1.4826;

/// Median of a non-empty slice (mean of the two middle values for an even count), reordering it.
pub fn median_in_place(v: &mut [f64]) -> f64 {
    let n = v.len();
    let (_, &mut hi, _) = v.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        hi
    } else {
        let lo = v[..n / 2].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lo + hi)
    }
}

/// The value of rank n/2 in `f64::total_cmp` order (the upper of the two middle values for an
/// even count), reordering the slice; NaN if it is empty.
pub fn upper_median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mid = v.len() / 2;
    v.select_nth_unstable_by(mid, f64::total_cmp);
    v[mid]
}

/// Centred scale: 1.4826 · median |v − median v| of the values not excluded (all if `excluded`
/// is None), using `scratch` (at least as long as `r`) so that nothing is allocated; 0 if none.
pub fn mad_scale(r: &[f64], excluded: Option<&[bool]>, scratch: &mut [f64]) -> f64 {
    let mut m = 0;
    for (i, &v) in r.iter().enumerate() {
        if !excluded.is_some_and(|e| e[i]) {
            scratch[m] = v;
            m += 1;
        }
    }
    if m == 0 {
        return 0.0;
    }
    let med = median_in_place(&mut scratch[..m]);
    for v in &mut scratch[..m] {
        *v = (*v - med).abs();
    }
    MAD_TO_SIGMA * median_in_place(&mut scratch[..m])
}

/// Uncentred scale about zero: 1.4826 · upper median |r| over the finite values, for residuals
/// whose centre is zero by construction (a fit's residuals, second differences); NaN if none.
pub fn abs_scale(r: &[f64]) -> f64 {
    let mut a: Vec<f64> = r
        .iter()
        .map(|x| x.abs())
        .filter(|x| x.is_finite())
        .collect();
    MAD_TO_SIGMA * upper_median(&mut a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_conventions_on_known_samples() {
        assert_eq!(median_in_place(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median_in_place(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(upper_median(&mut [4.0, 1.0, 3.0, 2.0]), 3.0);
        assert!(upper_median(&mut []).is_nan());
        // |r| = 1, 1, 2, 2, 100 → rank 2 is 2; the NaN is left out
        assert_eq!(
            abs_scale(&[1.0, -1.0, 2.0, -2.0, 100.0, f64::NAN]),
            1.4826 * 2.0
        );
    }

    #[test]
    fn mad_of_a_known_sample() {
        let r = [1.0, -1.0, 2.0, -2.0, 100.0];
        let mut s = [0.0; 5];
        // median 1, deviations 0, 2, 1, 3, 99 → median 2
        assert!((mad_scale(&r, None, &mut s) - 1.4826 * 2.0).abs() < 1e-12);
        // excluding the outlier: values -2,-1,1,2 → median 0, deviations 2,1,1,2 → 1.5
        let ex = [false, false, false, false, true];
        assert!((mad_scale(&r, Some(&ex), &mut s) - 1.4826 * 1.5).abs() < 1e-12);
    }
}
