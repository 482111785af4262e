//! Drift of per-run fitted parameters with run covariates: least-squares slopes with their t values.

pub use crate::stats::Line;

#[cfg(test)]
mod tests {
    #[test]
    fn recovers_a_known_line() {
        let x: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|v| 0.052 + 1.1 * v + if (*v as i32) % 2 == 0 { 0.01 } else { -0.01 })
            .collect();
        let l = crate::stats::ols_line(&x, &y).unwrap();
        assert!((l.slope - 1.1).abs() < 1e-3 && (l.intercept - 0.052).abs() < 0.02);
        assert!(l.t > 100.0);
    }
}
