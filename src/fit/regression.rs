//! Small estimators over runs: plain, weighted and robust weighted means, and the Theil–Sen line.

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

/// Huber's tuning constant for the M-step of [`robust_weighted_mean`].
const HUBER_C: f64 = 1.345;

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
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let m = v.len();
        if m % 2 == 1 {
            v[m / 2]
        } else {
            0.5 * (v[m / 2 - 1] + v[m / 2])
        }
    };
    let mid = median(ok.iter().map(|&i| y[i]).collect());
    let mad = 1.4826 * median(ok.iter().map(|&i| (y[i] - mid).abs()).collect());
    let typical_var = median(ok.iter().map(|&i| se[i] * se[i]).collect());
    let tau2 = (mad * mad - typical_var).max(0.0);
    let var: Vec<f64> = ok.iter().map(|&i| se[i] * se[i] + tau2).collect();
    let mut mean = mid;
    for _ in 0..20 {
        let (mut s, mut w) = (0.0, 0.0);
        for (j, &i) in ok.iter().enumerate() {
            let z = (y[i] - mean).abs() / var[j].sqrt();
            let h = if z > HUBER_C { HUBER_C / z } else { 1.0 };
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

/// Theil–Sen line y = a + b·x over the pairs picked by `idx` (indices may repeat, as in a
/// bootstrap resample): b is the median of the slopes between every two picked points with
/// different x, a the median of y − b·x. One wild point changes at most m − 1 of the m(m − 1)/2
/// slopes, so it can move b only to a neighbouring order statistic of the others (breakdown
/// 29 %), whatever its leverage. `buf` is reused. (NaN, NaN) if the x values do not vary.
pub fn theil_sen_indexed(x: &[f64], y: &[f64], idx: &[usize], buf: &mut Vec<f64>) -> (f64, f64) {
    buf.clear();
    for (k, &i) in idx.iter().enumerate() {
        for &j in &idx[k + 1..] {
            let dx = x[j] - x[i];
            if dx != 0.0 {
                buf.push((y[j] - y[i]) / dx);
            }
        }
    }
    let b = median_of(buf);
    if b.is_nan() {
        return (f64::NAN, f64::NAN);
    }
    buf.clear();
    buf.extend(idx.iter().map(|&i| y[i] - b * x[i]));
    (median_of(buf), b)
}

/// Median of `v` (reordered in place); NaN if empty or if it holds NaN.
fn median_of(v: &mut [f64]) -> f64 {
    let m = v.len();
    if m == 0 || v.iter().any(|a| a.is_nan()) {
        return f64::NAN;
    }
    let (_, &mut hi, _) = v.select_nth_unstable_by(m / 2, f64::total_cmp);
    if m % 2 == 1 {
        hi
    } else {
        let lo = v[..m / 2].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        0.5 * (lo + hi)
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

    #[test]
    fn theil_sen_recovers_a_line_and_one_wild_point_moves_it_by_less_than_its_share() {
        // 20 points on T = 0.05 + 1.1·v with a small zig-zag, v in 0.01..0.1
        let x: Vec<f64> = (0..20).map(|i| 0.01 + 0.09 * i as f64 / 19.0).collect();
        let mut y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| 0.05 + 1.1 * v + if i % 2 == 0 { 2e-3 } else { -2e-3 })
            .collect();
        let idx: Vec<usize> = (0..20).collect();
        let mut buf = Vec::new();
        let (a, b) = theil_sen_indexed(&x, &y, &idx, &mut buf);
        assert!((b - 1.1).abs() < 0.05 && (a - 0.05).abs() < 5e-3, "{a} {b}");
        // a wild run at the fastest speed (most leverage): T 1 s instead of 0.16 s
        y[19] = 1.0;
        let (_, ols) = crate::stats::ols_indexed(&x, &y, &idx);
        let (_, wild) = theil_sen_indexed(&x, &y, &idx, &mut buf);
        // least squares follows it (slope ~5), Theil–Sen moves by less than 1/20 of that pull
        assert!(ols > 3.0, "{ols}");
        assert!(
            (wild - b).abs() < (ols - b) / 20.0,
            "{b} → {wild} (ols {ols})"
        );
        // no spread in x: no line
        assert!(theil_sen_indexed(&x, &y, &[3, 3, 3], &mut buf).1.is_nan());
    }
}
