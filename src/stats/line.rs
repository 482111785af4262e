//! Straight-line fits: ordinary least squares over picked indices (bootstrap resamples), with the
//! slope's standard error and t value, and weighted by known standard errors.

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
}
