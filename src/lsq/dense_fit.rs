//! The dense back-end of the [`lm`] driver: residuals from a closure, forward-difference
//! Jacobian columns ([`super::fd`]), normal equations and covariance by [`super::dense`]. For
//! small problems (a collision run: ≤ ~40 parameters, a few thousand residuals).

use super::dense;
use super::fd::jacobian_columns;
use super::lm::{self, Model, Normal, ParamSpec, Settings};
use super::Termination;

/// Normal equations stored densely (row-major, both triangles).
#[derive(Debug, Clone)]
pub struct DenseNormal {
    pub a: Vec<f64>,
    pub g: Vec<f64>,
}

impl DenseNormal {
    fn damped(&self, i: usize, lambda: f64) -> f64 {
        let m = self.g.len();
        let d = self.a[i * m + i];
        d + lambda * d.max(1e-30)
    }
}

impl Normal for DenseNormal {
    fn gradient(&self) -> &[f64] {
        &self.g
    }
    fn solve(&self, lambda: f64, on: &[bool], rhs: &[f64]) -> Option<Vec<f64>> {
        let m = self.g.len();
        let idx: Vec<usize> = (0..m).filter(|&i| on[i]).collect();
        let k = idx.len();
        let mut sub = vec![0.0; k * k];
        for (p, &i) in idx.iter().enumerate() {
            for (q, &j) in idx.iter().enumerate() {
                sub[p * k + q] = if i == j {
                    self.damped(i, lambda)
                } else {
                    self.a[i * m + j]
                };
            }
        }
        let b: Vec<f64> = idx.iter().map(|&i| rhs[i]).collect();
        let sol = dense::solve_spd(&sub, k, &b)?;
        let mut out = vec![0.0; m];
        for (p, &i) in idx.iter().enumerate() {
            out[i] = sol[p];
        }
        Some(out)
    }
    fn apply(&self, lambda: f64, x: &[f64]) -> Vec<f64> {
        let m = self.g.len();
        (0..m)
            .map(|i| {
                (0..m)
                    .map(|j| {
                        let a = if i == j {
                            self.damped(i, lambda)
                        } else {
                            self.a[i * m + j]
                        };
                        a * x[j]
                    })
                    .sum()
            })
            .collect()
    }
}

struct Closure<'a, F> {
    f: F,
    n: usize,
    step: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    specs: &'a [ParamSpec],
}

impl<F: Fn(&[f64], &mut [f64])> Model for Closure<'_, F> {
    type Normal = DenseNormal;
    fn n_residuals(&self) -> usize {
        self.n
    }
    fn residuals(&self, x: &[f64], out: &mut [f64]) {
        (self.f)(x, out)
    }
    fn normal(&self, x: &[f64], r: &[f64], w: &[f64]) -> DenseNormal {
        let mut jac = vec![vec![0.0; self.n]; self.specs.len()];
        jacobian_columns(
            &self.f,
            x,
            &self.step,
            &self.lower,
            &self.upper,
            r,
            &mut jac,
        );
        let (a, g) = dense::normal_equations(&jac, r, w);
        DenseNormal { a, g }
    }
}

/// A dense robust fit.
#[derive(Debug, Clone)]
pub struct DenseFit {
    pub params: Vec<f64>,
    /// Covariance (JᵀWJ)⁻¹·scale², 0 rows and columns for held parameters, NaN when singular.
    pub covariance: Vec<Vec<f64>>,
    pub termination: Termination,
    pub iterations: usize,
    /// The final residual scale.
    pub scale: f64,
    /// Final residuals (unweighted).
    pub residuals: Vec<f64>,
}

impl DenseFit {
    /// Standard error of parameter `i` (NaN when not identified).
    pub fn se(&self, i: usize) -> f64 {
        self.covariance[i][i].max(0.0).sqrt()
    }
}

/// Minimise Σ ρ(r) over `specs`, where `residuals(p, out)` fills the `n` residuals.
pub fn minimize<F>(residuals: F, n: usize, specs: &[ParamSpec], settings: &Settings) -> DenseFit
where
    F: Fn(&[f64], &mut [f64]),
{
    let model = Closure {
        f: residuals,
        n,
        step: specs.iter().map(|s| s.step).collect(),
        lower: specs.iter().map(|s| s.lower).collect(),
        upper: specs.iter().map(|s| s.upper).collect(),
        specs,
    };
    let sol = lm::minimize(&model, specs, settings);
    let m = specs.len();
    let mut a = sol.normal.a;
    // a held parameter's row and column become the identity (its covariance is set to 0 below)
    for (i, s) in specs.iter().enumerate() {
        if s.held() {
            for j in 0..m {
                a[i * m + j] = 0.0;
                a[j * m + i] = 0.0;
            }
            a[i * m + i] = 1.0;
        }
    }
    let mut termination = sol.termination;
    let scale = sol.scale;
    // a tiny ridge keeps a parameter the data barely constrain from spoiling the others' errors
    let covariance = match dense::invert_spd_scaled(&a, m, 1e-12) {
        Some(inv) => (0..m)
            .map(|i| {
                (0..m)
                    .map(|j| {
                        if specs[i].held() || specs[j].held() {
                            0.0
                        } else {
                            inv[i * m + j] * scale * scale
                        }
                    })
                    .collect()
            })
            .collect(),
        None => {
            termination = Termination::Singular;
            vec![vec![f64::NAN; m]; m]
        }
    };
    DenseFit {
        params: sol.x,
        covariance,
        termination,
        iterations: sol.iterations,
        scale,
        residuals: sol.r,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsq::lm::Scale;

    fn settings() -> Settings {
        Settings {
            max_iter: 60,
            rounds: 4,
            huber_k: 2.5,
            scale: Scale::Mad { floor: 1e-9 },
            cost_tol: 1e-3,
            rel_tol: 1e-10,
            damping: 1e-3,
        }
    }

    fn spec(start: f64, lower: f64, upper: f64) -> ParamSpec {
        ParamSpec {
            start,
            lower,
            upper,
            step: 1e-6,
        }
    }

    fn line(t: &[f64], y: &[f64], specs: &[ParamSpec]) -> DenseFit {
        minimize(
            |p, out| {
                for i in 0..t.len() {
                    out[i] = p[0] + p[1] * t[i] - y[i];
                }
            },
            t.len(),
            specs,
            &settings(),
        )
    }

    /// Two nearly parallel columns (a line and the same line bent by 0.1 %), exact data: the
    /// minimum is one Gauss–Newton step away, and the damping the descent starts from decides
    /// how many steps it takes to get there.
    #[test]
    fn a_small_starting_damping_takes_the_gauss_newton_step_at_once() {
        let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.05).collect();
        let col2 = |t: f64| t + 1e-3 * t * t;
        let y: Vec<f64> = t.iter().map(|&t| 0.3 * t - 0.2 * col2(t)).collect();
        let fit = |damping: f64| {
            let s = Settings {
                max_iter: 60,
                rounds: 1,
                huber_k: f64::INFINITY,
                scale: Scale::Fixed(1.0),
                cost_tol: 1e-20,
                rel_tol: 0.0,
                damping,
            };
            minimize(
                |p, out| {
                    for (i, &ti) in t.iter().enumerate() {
                        out[i] = p[0] * ti + p[1] * col2(ti) - y[i];
                    }
                },
                t.len(),
                &[spec(0.0, -10.0, 10.0), spec(0.0, -10.0, 10.0)],
                &s,
            )
        };
        let (usual, small) = (fit(1e-3), fit(1e-9));
        for res in [&usual, &small] {
            assert!((res.params[0] - 0.3).abs() < 1e-3, "{:?}", res.params);
            assert!((res.params[1] + 0.2).abs() < 1e-3, "{:?}", res.params);
        }
        // along the near-dependent direction a damping of 1e-3 of the diagonal shortens every
        // step: 16 iterations here where the nearly undamped step needs 4 (the minimum, then
        // steps of rounding)
        assert!(small.iterations <= 4, "{} iterations", small.iterations);
        assert!(
            usual.iterations >= 2 * small.iterations,
            "{} against {}",
            usual.iterations,
            small.iterations
        );
    }

    /// Rosenbrock's valley from its classic far start: the first Gauss–Newton steps overshoot
    /// and must be damped well beyond 1e-3 of the diagonal; a descent that starts from a tiny
    /// damping still gets there (it is given the tries that bring it up to 1e-3 on top).
    #[test]
    fn a_tiny_starting_damping_still_damps_a_far_start() {
        let s = Settings {
            max_iter: 200,
            rounds: 1,
            huber_k: f64::INFINITY,
            scale: Scale::Fixed(1.0),
            cost_tol: 1e-24,
            rel_tol: 0.0,
            damping: 1e-12,
        };
        let res = minimize(
            |p, out| {
                out[0] = 10.0 * (p[1] - p[0] * p[0]);
                out[1] = 1.0 - p[0];
            },
            2,
            &[spec(-1.2, -10.0, 10.0), spec(1.0, -10.0, 10.0)],
            &s,
        );
        assert!((res.params[0] - 1.0).abs() < 1e-6, "{:?}", res.params);
        assert!((res.params[1] - 1.0).abs() < 1e-6, "{:?}", res.params);
    }

    #[test]
    fn fits_a_line_with_an_outlier() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let mut y: Vec<f64> = t.iter().map(|t| 2.0 + 0.5 * t).collect();
        for (i, yi) in y.iter_mut().enumerate() {
            *yi += 1e-3 * ((i * 7919) % 13) as f64 / 13.0 - 0.5e-3;
        }
        y[17] += 5.0;
        let res = line(&t, &y, &[spec(0.0, -10.0, 10.0), spec(0.0, -10.0, 10.0)]);
        assert!((res.params[0] - 2.0).abs() < 2e-3, "{:?}", res.params);
        assert!((res.params[1] - 0.5).abs() < 1e-3, "{:?}", res.params);
        assert!(res.se(1) > 0.0 && res.se(1) < 1e-3);
        assert!(res.termination.is_converged(), "{:?}", res.termination);
    }

    #[test]
    fn a_bound_below_the_truth_holds_the_slope_and_refits_the_rest_exactly() {
        // y = 2 + 0.5 t, slope capped at 0.3: the intercept must be the least-squares one for a
        // slope of 0.3 (mean of y − 0.3 t), which a clipped step reaches only by creeping
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 + 0.5 * t).collect();
        let res = line(&t, &y, &[spec(0.0, -10.0, 10.0), spec(0.0, -1.0, 0.3)]);
        let want = y.iter().zip(&t).map(|(y, t)| y - 0.3 * t).sum::<f64>() / t.len() as f64;
        assert_eq!(res.params[1], 0.3);
        assert!((res.params[0] - want).abs() < 1e-6, "{:?}", res.params);
        assert!(res.termination.is_converged(), "{:?}", res.termination);
        assert!(res.iterations < 20, "{} iterations", res.iterations);
    }

    #[test]
    fn a_held_parameter_stays_and_has_no_error() {
        let t: Vec<f64> = (0..20).map(|i| i as f64).collect();
        let y: Vec<f64> = t.iter().map(|t| 1.0 + 2.0 * t).collect();
        let res = line(&t, &y, &[spec(1.5, 1.5, 1.5), spec(0.0, -10.0, 10.0)]);
        assert_eq!(res.params[0], 1.5);
        assert_eq!(res.se(0), 0.0);
        // slope given the held intercept: Σ t (y − 1.5) / Σ t² = 2 − 0.5 Σt / Σt²
        let want = 2.0 - 0.5 * 190.0 / 2470.0;
        assert!((res.params[1] - want).abs() < 1e-6, "{:?}", res.params);
    }
}
