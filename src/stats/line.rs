//! Straight-line fits: ordinary least squares over picked indices (bootstrap resamples), with the
//! slope's standard error and t value, weighted by known standard errors, and Theil–Sen (the
//! median of the pairwise slopes).

use super::median::median_in_place;
use serde::Serialize;

/// Intercept and slope of y = a + b·x by ordinary least squares over the pairs picked by `idx`
/// (indices may repeat, as in a bootstrap resample). NaN if the x values do not vary.
pub fn ols_indexed(x: &[f64], y: &[f64], idx: &[usize]) -> (f64, f64) {
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

/// A straight-line fit y = intercept + slope·x with ordinary least-squares standard errors.
#[derive(Clone, Debug, Serialize)]
pub struct Line {
    pub n: usize,
    pub intercept: f64,
    pub slope: f64,
    pub slope_se: f64,
    /// slope / slope_se.
    pub t: f64,
}

/// Ordinary least-squares line; None with fewer than 3 points or no spread in x.
pub fn ols_line(x: &[f64], y: &[f64]) -> Option<Line> {
    let n = x.len();
    if n < 3 {
        return None;
    }
    let nf = n as f64;
    let mx = x.iter().sum::<f64>() / nf;
    let my = y.iter().sum::<f64>() / nf;
    let sxx: f64 = x.iter().map(|v| (v - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let rss: f64 = x
        .iter()
        .zip(y)
        .map(|(a, b)| (b - intercept - slope * a).powi(2))
        .sum();
    let slope_se = (rss / (nf - 2.0) / sxx).sqrt();
    let t = if slope_se > 0.0 {
        slope / slope_se
    } else {
        0.0
    };
    Some(Line {
        n,
        intercept,
        slope,
        slope_se,
        t,
    })
}
/// Weighted least squares y = a + b x through points (x, y, standard error of y): (a, b); None
/// with fewer than two points or no spread in x.
pub fn weighted_line(p: &[(f64, f64, f64)]) -> Option<(f64, f64)> {
    let (mut sw, mut sx, mut sy, mut sxx, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for &(x, y, se) in p {
        let w = 1.0 / (se * se);
        sw += w;
        sx += w * x;
        sy += w * y;
        sxx += w * x * x;
        sxy += w * x * y;
    }
    let det = sw * sxx - sx * sx;
    if p.len() < 2 || det <= 1e-12 * sw * sxx {
        return None;
    }
    let b = (sw * sxy - sx * sy) / det;
    Some(((sy - b * sx) / sw, b))
}

/// Theil–Sen line y = a + b·x over the pairs picked by `idx` (indices may repeat, as in a
/// bootstrap resample): b is the median of the slopes between every two picked points with
/// different x, a the median of y − b·x. One wild point changes at most m − 1 of the m(m − 1)/2
/// slopes, so it can move b only to a neighbouring order statistic of the others (breakdown
/// 29 %), whatever its leverage. `buf` is reused. (NaN, NaN) if the x values do not vary.
///
/// Above `max_pairs` pairs (a campaign of thousands of runs: m² work and memory per call) b is
/// the median over `max_pairs` pairs drawn uniformly, with a generator seeded by `idx` itself
/// (the same picks give the same line); that adds a spread of about 1.25·√(m/max_pairs)
/// standard errors of b, which a bootstrap over such calls carries into its interval.
pub fn theil_sen_indexed(
    x: &[f64],
    y: &[f64],
    idx: &[usize],
    buf: &mut Vec<f64>,
    max_pairs: usize,
) -> (f64, f64) {
    let [line] = theil_sen_many(x, [y], idx, [buf], max_pairs);
    line
}

/// `theil_sen_indexed` of several y over the same x and picks: the pairs are enumerated (or
/// drawn) once for all of them, so each line is the one `theil_sen_indexed` gives.
pub fn theil_sen_many<const K: usize>(
    x: &[f64],
    ys: [&[f64]; K],
    idx: &[usize],
    mut bufs: [&mut Vec<f64>; K],
    max_pairs: usize,
) -> [(f64, f64); K] {
    for b in bufs.iter_mut() {
        b.clear();
    }
    let mut push = |i: usize, j: usize| {
        let dx = x[j] - x[i];
        if dx != 0.0 {
            for (b, y) in bufs.iter_mut().zip(&ys) {
                b.push((y[j] - y[i]) / dx);
            }
        }
    };
    let m = idx.len();
    if m * m.saturating_sub(1) / 2 <= max_pairs {
        for (k, &i) in idx.iter().enumerate() {
            for &j in &idx[k + 1..] {
                push(i, j);
            }
        }
    } else {
        let mut state = idx.iter().fold(m as u64, |h, &i| splitmix(h ^ i as u64));
        for _ in 0..max_pairs {
            state = splitmix(state);
            let i = idx[(state % m as u64) as usize];
            let j = idx[((state >> 32) % m as u64) as usize];
            push(i, j);
        }
    }
    std::array::from_fn(|k| {
        let buf = &mut *bufs[k];
        let b = median_of(buf);
        if b.is_nan() {
            return (f64::NAN, f64::NAN);
        }
        (theil_sen_intercept(x, ys[k], idx, b, buf), b)
    })
}

/// The Theil–Sen intercept for slope `b`: the median of y − b·x over the picks (`buf` reused);
/// NaN if a value is NaN.
pub fn theil_sen_intercept(x: &[f64], y: &[f64], idx: &[usize], b: f64, buf: &mut Vec<f64>) -> f64 {
    buf.clear();
    buf.extend(idx.iter().map(|&i| y[i] - b * x[i]));
    median_of(buf)
}

/// One step of SplitMix64: a well-mixed 64-bit value from the last.
pub(super) fn splitmix(z: u64) -> u64 {
    let mut z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// Median of `v` (reordered in place); NaN if empty or if it holds NaN.
fn median_of(v: &mut [f64]) -> f64 {
    if v.is_empty() || v.iter().any(|a| a.is_nan()) {
        return f64::NAN;
    }
    median_in_place(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_fits_recover_a_known_line() {
        let x = [0.0, 1.0, 2.0, 3.0];
        let y = [1.0, 3.0, 5.0, 7.0];
        let (a, b) = ols_indexed(&x, &y, &[0, 1, 2, 3]);
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
        assert!(ols_indexed(&x, &y, &[2, 2, 2]).0.is_nan());
        let l = ols_line(&x, &[1.0, 3.1, 4.9, 7.0]).unwrap();
        assert!((l.slope - 1.98).abs() < 1e-12 && l.slope_se > 0.0 && l.t > 10.0);
        assert!(ols_line(&[1.0, 1.0, 1.0], &y[..3]).is_none());
        let p: Vec<(f64, f64, f64)> = x.iter().zip(&y).map(|(a, b)| (*a, *b, 0.1)).collect();
        let (a, b) = weighted_line(&p).unwrap();
        assert!((a - 1.0).abs() < 1e-12 && (b - 2.0).abs() < 1e-12);
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
        let (a, b) = theil_sen_indexed(&x, &y, &idx, &mut buf, usize::MAX);
        assert!((b - 1.1).abs() < 0.05 && (a - 0.05).abs() < 5e-3, "{a} {b}");
        // a wild run at the fastest speed (most leverage): T 1 s instead of 0.16 s
        y[19] = 1.0;
        let (_, ols) = ols_indexed(&x, &y, &idx);
        let (_, wild) = theil_sen_indexed(&x, &y, &idx, &mut buf, usize::MAX);
        // least squares follows it (slope ~5), Theil–Sen moves by less than 1/20 of that pull
        assert!(ols > 3.0, "{ols}");
        assert!(
            (wild - b).abs() < (ols - b) / 20.0,
            "{b} → {wild} (ols {ols})"
        );
        // no spread in x: no line
        assert!(theil_sen_indexed(&x, &y, &[3, 3, 3], &mut buf, usize::MAX)
            .1
            .is_nan());
    }

    #[test]
    fn sampled_pairs_follow_the_exact_line_of_a_large_set() {
        // 3,000 points on y = 2 + 0.5·x with a deterministic zig-zag of ±0.1
        let x: Vec<f64> = (0..3000).map(|i| i as f64 / 100.0).collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| 2.0 + 0.5 * v + 0.1 * ((i * 7919 % 13) as f64 / 6.0 - 1.0))
            .collect();
        let idx: Vec<usize> = (0..3000).collect();
        let mut buf = Vec::new();
        let (a, b) = theil_sen_indexed(&x, &y, &idx, &mut buf, usize::MAX);
        let mut small = Vec::new();
        let (sa, sb) = theil_sen_indexed(&x, &y, &idx, &mut small, 50_000);
        // memory follows the draw, not the 4.5 million pairs
        assert!(small.capacity() < 200_000, "{}", small.capacity());
        assert!((b - 0.5).abs() < 1e-3 && (sb - b).abs() < 2e-3, "{b} {sb}");
        assert!((sa - a).abs() < 0.02, "{a} {sa}");
        // the same picks give the same line; other picks another draw
        assert_eq!(theil_sen_indexed(&x, &y, &idx, &mut buf, 50_000), (sa, sb));
    }
}
