//! Quantiles of sorted bootstrap draws, in the two conventions the intervals use.

/// Quantile `p` of ascending `d` (non-empty) by linear interpolation between order statistics.
pub fn quantile_interpolated(d: &[f64], p: f64) -> f64 {
    let pos = p * (d.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos - pos.floor());
    d[i] + f * (d[(i + 1).min(d.len() - 1)] - d[i])
}

/// Quantile `p` of ascending `d` (non-empty) as the nearest order statistic.
pub fn quantile_nearest(d: &[f64], p: f64) -> f64 {
    d[((p * (d.len() - 1) as f64).round() as usize).min(d.len() - 1)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conventions_on_a_known_sample() {
        let d = [0.0, 1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile_interpolated(&d, 0.3), 1.2);
        assert_eq!(quantile_nearest(&d, 0.3), 1.0);
        assert_eq!(quantile_nearest(&d, 1.0), 4.0);
        assert_eq!(quantile_interpolated(&d, 1.0), 4.0);
    }
}
