//! Falling curves of the coefficient of restitution against impact speed, fitted by weighted
//! least squares to points (speed m/s, C, standard error of C).

/// Weighted least squares of 1 − C = a v through the origin.
pub fn one_minus_av(p: &[(f64, f64, f64)]) -> Option<f64> {
    let (mut num, mut den) = (0.0, 0.0);
    for &(x, y, se) in p {
        let w = 1.0 / (se * se);
        num += w * x * (1.0 - y);
        den += w * x * x;
    }
    (den > 0.0).then(|| num / den)
}

/// Weighted least squares of C = c_inf + (1 − c_inf) e^{−v/v_ref}: for each v_ref on a log
/// grid, 1 − C = (1 − c_inf)(1 − e^{−v/v_ref}) is linear in (1 − c_inf); keep the best pair.
pub fn exp_fit(p: &[(f64, f64, f64)]) -> Option<(f64, f64)> {
    let solve = |v_ref: f64| -> (f64, f64) {
        let (mut num, mut den) = (0.0, 0.0);
        for &(x, y, se) in p {
            let w = 1.0 / (se * se);
            let f = 1.0 - (-x / v_ref).exp();
            num += w * f * (1.0 - y);
            den += w * f * f;
        }
        let b = if den > 0.0 { num / den } else { 0.0 };
        let sse = p
            .iter()
            .map(|&(x, y, se)| ((1.0 - y) - b * (1.0 - (-x / v_ref).exp())).powi(2) / (se * se))
            .sum();
        (1.0 - b, sse)
    };
    if p.len() < 3 {
        return None;
    }
    let grid: Vec<f64> = (0..=200)
        .map(|i| 1e-3 * 10f64.powf(i as f64 / 66.0))
        .collect();
    let best = (0..grid.len()).min_by(|&a, &b| solve(grid[a]).1.total_cmp(&solve(grid[b]).1))?;
    let (mut lo, mut hi) = (
        grid[best.saturating_sub(1)].ln(),
        grid[(best + 1).min(grid.len() - 1)].ln(),
    );
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..50 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if solve(a.exp()).1 < solve(b.exp()).1 {
            hi = b;
        } else {
            lo = a;
        }
    }
    let v_ref = (0.5 * (lo + hi)).exp();
    Some((solve(v_ref).0, v_ref))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::weighted_line as line_fit;

    /// Points on C = 0.6 + 0.4 e^{−v/0.1} with small alternating errors.
    fn points() -> Vec<(f64, f64, f64)> {
        (1..=12)
            .map(|i| {
                let v = 0.025 * i as f64;
                let c = 0.6 + 0.4 * (-v / 0.1f64).exp() + if i % 2 == 0 { 0.002 } else { -0.002 };
                (v, c, 0.01)
            })
            .collect()
    }

    #[test]
    fn exponential_law_is_recovered() {
        let (c_inf, v_ref) = exp_fit(&points()).unwrap();
        assert!((c_inf - 0.6).abs() < 0.01, "{c_inf}");
        assert!((v_ref - 0.1).abs() < 0.01, "{v_ref}");
    }

    #[test]
    fn straight_lines_fall_with_speed() {
        let (c0, slope) = line_fit(&points()).unwrap();
        assert!(slope < 0.0 && c0 > 0.8 && c0 < 1.0, "{c0} {slope}");
        let a = one_minus_av(&[(0.1, 0.9, 0.01), (0.2, 0.8, 0.01)]).unwrap();
        assert!((a - 1.0).abs() < 1e-12);
        assert!(line_fit(&[(0.1, 0.9, 0.01)]).is_none());
    }
}
