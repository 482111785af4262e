//! Means over runs: plain, inverse-variance weighted, and robust weighted (the Theil–Sen line
//! and the medians are in `stats`).

use crate::lsq::loss::{huber_weight, HUBER_K};
use crate::stats::{median_in_place, MAD_TO_SIGMA};

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

/// A weighted mean of y over `idx` that no single run can capture: each run's variance is its
/// se² plus the between-run scatter τ² (the runs' robust spread, 1.4826·MAD, squared, less their
/// median se²), then Huber weights on the runs' standardised deviations (reweighted from the
/// median until it settles), so a run far from the others with a tiny error counts like an
/// ordinary run at most, and less the further out it lies. Entries with a non-positive or unknown
/// error are left out; NaN if none.
pub fn robust_weighted_mean(y: &[f64], se: &[f64], idx: &[usize]) -> f64 {
    let ok: Vec<usize> = idx
        .iter()
        .copied()
        .filter(|&i| se[i] > 0.0 && se[i].is_finite() && y[i].is_finite())
        .collect();
    if ok.is_empty() {
        return f64::NAN;
    }
    // Between-run scatter from the spread of the runs (1.4826·MAD) less their typical own
    // variance, so that a wild run does not inflate it.
    let median = |mut v: Vec<f64>| median_in_place(&mut v);
    let mid = median(ok.iter().map(|&i| y[i]).collect());
    let mad = MAD_TO_SIGMA * median(ok.iter().map(|&i| (y[i] - mid).abs()).collect());
    let typical_var = median(ok.iter().map(|&i| se[i] * se[i]).collect());
    let tau2 = (mad * mad - typical_var).max(0.0);
    let var: Vec<f64> = ok.iter().map(|&i| se[i] * se[i] + tau2).collect();
    let sd: Vec<f64> = var.iter().map(|v| v.sqrt()).collect();
    let mut mean = mid;
    for _ in 0..20 {
        let (mut s, mut w) = (0.0, 0.0);
        for (j, &i) in ok.iter().enumerate() {
            let z = (y[i] - mean).abs() / sd[j];
            let h = huber_weight(z, HUBER_K);
            s += h * y[i] / var[j];
            w += h / var[j];
        }
        let next = s / w;
        let done = (next - mean).abs() <= 1e-12 * mean.abs().max(1e-12);
        mean = next;
        if done {
            break;
        }
    }
    mean
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

    #[test]
    fn one_wild_run_moves_the_robust_mean_by_less_than_its_share() {
        // nine runs around 0.30 (se 0.01) and one at 0.02 with a tiny error
        let mut y: Vec<f64> = (0..9).map(|i| 0.30 + 0.004 * (i as f64 - 4.0)).collect();
        let mut se = vec![0.01; 9];
        let idx: Vec<usize> = (0..10).collect();
        y.push(0.02);
        se.push(1e-4);
        let fixed = weighted_mean(&y, &se, &idx);
        let robust = robust_weighted_mean(&y, &se, &idx);
        // inverse-variance weights let it capture the mean; its share (1/10) would move it by 0.028
        assert!(fixed < 0.05, "{fixed}");
        // its share (1/10 of its 0.28 offset) would be 0.028; it moves the mean by far less
        assert!((robust - 0.30).abs() < 0.01, "{robust}");
        // without a wild run it is the ordinary weighted mean
        let calm = robust_weighted_mean(&y[..9], &se[..9], &idx[..9]);
        assert!(
            (calm - weighted_mean(&y[..9], &se[..9], &idx[..9])).abs() < 2e-3,
            "{calm}"
        );
    }
}
