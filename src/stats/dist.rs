//! Tail probabilities and quantiles for the tests, from `statrs`: the χ² and gamma tails of the
//! likelihood-ratio nulls, the normal tail of the runs test, and the Student t quantile of the
//! paired cross-validation test and of the impact test over runs, and the F tail of the per-impact
//! law tests.

use statrs::distribution::{ContinuousCDF, FisherSnedecor, Normal, StudentsT};
use statrs::function::gamma::checked_gamma_ur;

/// Upper regularized incomplete gamma Q(a, x) = Γ(a, x)/Γ(a); 1 for x ≤ 0, NaN for a ≤ 0.
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    checked_gamma_ur(a, x).unwrap_or(f64::NAN)
}

/// P(χ²_df > x).
pub fn chi2_sf(x: f64, df: f64) -> f64 {
    gamma_q(df / 2.0, x / 2.0)
}

fn standard_normal() -> Normal {
    Normal::new(0.0, 1.0).expect("N(0, 1) is a valid distribution")
}

/// P(N(0,1) > z).
pub fn normal_sf(z: f64) -> f64 {
    standard_normal().sf(z)
}

/// t with P(T_df > t) = p for Student's t with `df` degrees of freedom (df ≥ 1); NaN otherwise.
pub fn t_upper_quantile(p: f64, df: f64) -> f64 {
    match StudentsT::new(0.0, 1.0, df) {
        Ok(t) if df >= 1.0 => t.inverse_cdf(1.0 - p),
        _ => f64::NAN,
    }
}

/// P(T_df > t) for Student's t with `df` degrees of freedom (df > 0); NaN otherwise.
pub fn t_sf(t: f64, df: f64) -> f64 {
    match StudentsT::new(0.0, 1.0, df) {
        Ok(d) => d.sf(t),
        _ => f64::NAN,
    }
}

/// P(F > f) for Fisher's F with `d1` and `d2` degrees of freedom (both > 0); 1 for f ≤ 0, NaN
/// otherwise.
pub fn f_sf(f: f64, d1: f64, d2: f64) -> f64 {
    if f <= 0.0 {
        return 1.0;
    }
    match FisherSnedecor::new(d1, d2) {
        Ok(d) => d.sf(f),
        _ => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // χ²_1 tail at 3.841 is 0.05, χ²_4 at 9.488 is 0.05, χ²_2 at x: exp(−x/2)
        assert!((chi2_sf(3.841_458_8, 1.0) - 0.05).abs() < 1e-6);
        assert!((chi2_sf(9.487_729, 4.0) - 0.05).abs() < 1e-6);
        assert!((chi2_sf(7.0, 2.0) - (-3.5f64).exp()).abs() < 1e-12);
        assert!((normal_sf(1.959_964) - 0.025).abs() < 1e-6);
        assert!((normal_sf(-1.0) - 0.841_344_7).abs() < 1e-6);
        // one-sided 5 % points of t: 6.314 (1 df), 2.015 (5 df), 1.697 (30 df)
        assert!((t_upper_quantile(0.05, 1.0) - 6.313_752).abs() < 1e-4);
        // F(2, 10) upper 5 % point 4.103, F(1, 20) 1 % point 8.096
        assert!((f_sf(4.102_821, 2.0, 10.0) - 0.05).abs() < 1e-6);
        assert!((f_sf(8.095_958, 1.0, 20.0) - 0.01).abs() < 1e-6);
        assert!((t_upper_quantile(0.05, 5.0) - 2.015_048).abs() < 1e-5);
        assert!((t_upper_quantile(0.05, 30.0) - 1.697_261).abs() < 1e-5);
        assert!(t_upper_quantile(0.05, 0.0).is_nan());
        assert!((t_sf(2.015_048, 5.0) - 0.05).abs() < 1e-6);
        assert!((t_sf(0.0, 11.0) - 0.5).abs() < 1e-12);
        assert!(t_sf(1.0, 0.0).is_nan());
    }
}
