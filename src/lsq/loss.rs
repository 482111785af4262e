//! Robust losses: ρ(u) and the IRLS weight ψ(u)/u of a residual u measured in units of the scale.

use serde::{Deserialize, Serialize};

/// Huber's tuning constant: 95 % efficiency for Gaussian noise.
pub const HUBER_K: f64 = 1.345;

/// How residuals count in the cost.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Loss {
    /// Ordinary least squares, ρ = u²/2.
    Linear,
    /// Quadratic inside ±1.345, linear outside.
    Huber,
    /// ρ = √(1 + u²) − 1: smooth, linear in the tails.
    SoftL1,
}

impl Loss {
    /// ρ(u) and the weight ψ(u)/u, with ρ normalised so that ρ ≈ u²/2 near 0.
    #[inline]
    pub fn rho_weight(self, u: f64) -> (f64, f64) {
        match self {
            Loss::Linear => (0.5 * u * u, 1.0),
            Loss::Huber => {
                let a = u.abs();
                if a <= HUBER_K {
                    (0.5 * u * u, 1.0)
                } else {
                    (
                        HUBER_K * a - 0.5 * HUBER_K * HUBER_K,
                        huber_weight(a, HUBER_K),
                    )
                }
            }
            Loss::SoftL1 => {
                let q = (1.0 + u * u).sqrt();
                (q - 1.0, 1.0 / q)
            }
        }
    }
}

/// Huber's IRLS weight ψ(u)/u at |u| = `a` for the threshold `k` (in the same units): 1 inside,
/// k/a outside. The per-run fits use k = [`HUBER_K`] scales, the collision fits 2.5 scales.
#[inline]
pub fn huber_weight(a: f64, k: f64) -> f64 {
    if a <= k {
        1.0
    } else {
        k / a
    }
}

impl Loss {
    /// ρ''(u): the weight of a residual in the Newton (curvature) matrix. Unlike the IRLS weight it
    /// is 0 on Huber's linear part, which makes the step exact once the set of inliers is settled.
    #[inline]
    pub fn curvature(self, u: f64) -> f64 {
        match self {
            Loss::Linear => 1.0,
            Loss::Huber => {
                if u.abs() <= HUBER_K {
                    1.0
                } else {
                    0.0
                }
            }
            Loss::SoftL1 => {
                let q = 1.0 + u * u;
                1.0 / (q * q.sqrt())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn losses_agree_near_zero_and_bound_the_influence() {
        for loss in [Loss::Linear, Loss::Huber, Loss::SoftL1] {
            let (rho, w) = loss.rho_weight(1e-3);
            assert!((rho - 0.5e-6).abs() < 1e-12 && (w - 1.0).abs() < 1e-6);
        }
        // influence ψ = u·w stays bounded for the robust losses
        assert!((Loss::Huber.rho_weight(100.0).1 * 100.0 - HUBER_K).abs() < 1e-12);
        assert!(Loss::SoftL1.rho_weight(1e4).1 * 1e4 < 1.0 + 1e-9);
        // curvature is the derivative of ψ(u) = u·w(u), by central differences
        for loss in [Loss::Linear, Loss::Huber, Loss::SoftL1] {
            for u in [0.3, -0.9, 2.0, -5.0] {
                let psi = |u: f64| u * loss.rho_weight(u).1;
                let d = (psi(u + 1e-6) - psi(u - 1e-6)) / 2e-6;
                assert!((d - loss.curvature(u)).abs() < 1e-6, "{loss:?} at {u}");
            }
        }
    }
}
