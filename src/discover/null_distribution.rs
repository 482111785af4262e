//! p-values of a likelihood-ratio statistic from its parametric-bootstrap null replicates.
//!
//! With a few dozen replicates the empirical p-value cannot go below 1/(B+1), too coarse for a
//! multiple-testing correction. The replicates are therefore summarised by a scaled gamma law
//! (moment matched: the χ² family stretched by the dependence of frames within a run), whose tail
//! gives the p-value used for decisions; the empirical one is reported beside it.

use crate::stats::dist::gamma_q;
use serde::Serialize;

/// The null distribution of one statistic.
#[derive(Clone, Debug, Serialize)]
pub struct NullFit {
    pub replicates: usize,
    pub mean: f64,
    pub var: f64,
    /// Gamma shape (effective half degrees of freedom) and scale (dependence inflation × 2).
    pub shape: f64,
    pub scale: f64,
}

impl NullFit {
    /// Moment-matched gamma law of the replicates. Degenerate replicates (all zero) fall back to a
    /// χ² with `df` degrees of freedom so that a real statistic is never judged against nothing.
    pub fn from_replicates(lr: &[f64], df: f64) -> NullFit {
        let n = lr.len() as f64;
        let mean = lr.iter().sum::<f64>() / n.max(1.0);
        let var = if lr.len() > 1 {
            lr.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)
        } else {
            0.0
        };
        let (shape, scale) = if mean > 1e-9 && var > 1e-12 {
            // never narrower than a χ² with df/2·(mean/df) scale: guards against few replicates
            let shape = (mean * mean / var).min(df.max(1.0) / 2.0 * 4.0);
            (shape, mean / shape)
        } else {
            (df / 2.0, 2.0)
        };
        NullFit {
            replicates: lr.len(),
            mean,
            var,
            shape,
            scale,
        }
    }

    /// P(LR* > lr) under the fitted law.
    pub fn p_value(&self, lr: f64) -> f64 {
        gamma_q(self.shape, lr.max(0.0) / self.scale).max(1e-300)
    }
}

/// (1 + #{LR* ≥ lr}) / (B + 1).
pub fn empirical_p(replicates: &[f64], lr: f64) -> f64 {
    let hits = replicates.iter().filter(|x| **x >= lr).count();
    (1 + hits) as f64 / (replicates.len() + 1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chi2_sample_gives_its_own_tail() {
        // χ²_2 quantiles at probabilities (i + 0.5)/200: −2 ln(1 − p)
        let lr: Vec<f64> = (0..200)
            .map(|i| -2.0 * (1.0 - (i as f64 + 0.5) / 200.0).ln())
            .collect();
        let f = NullFit::from_replicates(&lr, 2.0);
        assert!((f.shape - 1.0).abs() < 0.15, "shape {}", f.shape);
        assert!((f.p_value(9.21) - 0.01).abs() < 0.004);
        assert!((empirical_p(&lr, 1e9) - 1.0 / 201.0).abs() < 1e-12);
    }

    /// A statistic far from zero with a narrow spread (a force in time with a phase per run:
    /// (Σ|b_r|)²/Σa_r over 96 runs, one Rayleigh draw each) gets a law as narrow as its
    /// replicates when its degrees of freedom say so (`Extra::null_df`: two per run); bounded
    /// by two, the law's tail at a real signal's statistic was a hundred times too heavy.
    #[test]
    fn a_statistic_of_one_rayleigh_draw_per_run_keeps_its_narrow_law() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let runs = 96;
        let lr: Vec<f64> = (0..60)
            .map(|_| {
                let sum: f64 = (0..runs)
                    .map(|_| {
                        let (x, y): (f64, f64) = (
                            StandardNormal.sample(&mut rng),
                            StandardNormal.sample(&mut rng),
                        );
                        x.hypot(y)
                    })
                    .sum();
                sum * sum / runs as f64
            })
            .collect();
        let wide = NullFit::from_replicates(&lr, 2.0);
        let narrow = NullFit::from_replicates(&lr, 2.0 * runs as f64);
        // the replicates sit near 96·π/2 ≈ 151 with a spread of about 13
        assert!((wide.mean - 151.0).abs() < 10.0, "mean {}", wide.mean);
        let signal = wide.mean + 8.0 * wide.var.sqrt();
        assert!(
            narrow.p_value(signal) < 1e-6,
            "p {}",
            narrow.p_value(signal)
        );
        assert!(wide.p_value(signal) > 1e-4, "p {}", wide.p_value(signal));
        // and a draw of the null itself is not significant under the narrow law
        assert!(narrow.p_value(wide.mean) > 0.3);
    }
}
