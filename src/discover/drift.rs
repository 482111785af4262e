//! Drift of per-run fitted parameters with run covariates: least-squares slopes with their t values.

pub use crate::artifacts::diagnosis::Line;

/// Ordinary least-squares line; None with fewer than 3 points or no spread in x.
pub fn line(x: &[f64], y: &[f64]) -> Option<Line> {
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

#[cfg(test)]
mod tests {
    #[test]
    fn recovers_a_known_line() {
        let x: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|v| 0.052 + 1.1 * v + if (*v as i32) % 2 == 0 { 0.01 } else { -0.01 })
            .collect();
        let l = super::line(&x, &y).unwrap();
        assert!((l.slope - 1.1).abs() < 1e-3 && (l.intercept - 0.052).abs() < 0.02);
        assert!(l.t > 100.0);
    }
}
