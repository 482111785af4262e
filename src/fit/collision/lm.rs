//! A small robust Levenberg–Marquardt solver (Huber IRLS, box bounds, Jacobian standard errors)
//! for the joint multi-segment fit of a collision run.
//!
//! The fit helper's `fit::segment` fits one segment at a time; a collision run needs one problem
//! with shared μ, T, fitted impact times and z continuous across impacts, so this module keeps its
//! own robust loop on the shared dense back-end ([`crate::lsq::dense`]) with forward-difference
//! Jacobians ([`crate::lsq::fd`]). Problems are small (≤ ~40 parameters, a few thousand residuals).

use crate::lsq::dense;
use crate::lsq::fd::jacobian_columns;
use crate::lsq::loss::huber_weight;
pub use crate::lsq::Termination;
// 1.4826 · median |r|: the residuals of a good fit have median ≈ 0
use crate::stats::abs_scale as robust_scale;

/// Solver settings.
#[derive(Debug, Clone, Copy)]
pub struct LmOptions {
    pub max_iter: usize,
    /// Outer IRLS rounds (each re-weights the residuals with the Huber function).
    pub irls_rounds: usize,
    /// Huber threshold in units of the robust residual scale.
    pub huber_c: f64,
    /// Lower bound of the robust residual scale (m), so a perfect fit does not divide by zero.
    pub scale_floor: f64,
    pub rel_tol: f64,
    /// Also converged when a step lowers Σ w r² by less than this many squared noise scales
    /// (a change of χ² that no statistic can see).
    pub chi2_tol: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iter: 60,
            irls_rounds: 4,
            huber_c: 2.5,
            scale_floor: 1e-9,
            rel_tol: 1e-10,
            chi2_tol: 1e-3,
        }
    }
}

/// One parameter: start value, bounds and the finite-difference step.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    pub start: f64,
    pub lower: f64,
    pub upper: f64,
    pub step: f64,
}

/// The solution.
#[derive(Debug, Clone)]
pub struct LmResult {
    pub params: Vec<f64>,
    /// Covariance of the parameters: (JᵀWJ)⁻¹ · scale², NaN rows where not identified.
    pub covariance: Vec<Vec<f64>>,
    pub termination: Termination,
    pub iterations: usize,
    /// Robust residual scale (1.4826 · MAD), m.
    pub scale: f64,
    /// Final residuals (unweighted).
    pub residuals: Vec<f64>,
}

impl LmResult {
    /// Standard error of parameter `i` (NaN when not identified).
    pub fn se(&self, i: usize) -> f64 {
        self.covariance[i][i].max(0.0).sqrt()
    }
}

/// Minimize Σ ρ(r_i) over `specs`; `residuals(p, out)` fills `out` (length `n`).
pub fn minimize<F>(residuals: F, n: usize, specs: &[ParamSpec], opts: &LmOptions) -> LmResult
where
    F: Fn(&[f64], &mut [f64]),
{
    let m = specs.len();
    let mut p: Vec<f64> = specs
        .iter()
        .map(|s| s.start.clamp(s.lower, s.upper))
        .collect();
    let mut r = vec![0.0; n];
    let mut w = vec![1.0; n];
    let mut jac = vec![vec![0.0; n]; m];
    let step: Vec<f64> = specs.iter().map(|s| s.step).collect();
    let lower: Vec<f64> = specs.iter().map(|s| s.lower).collect();
    let upper: Vec<f64> = specs.iter().map(|s| s.upper).collect();
    let jacobian = |p: &[f64], r: &[f64], jac: &mut [Vec<f64>]| {
        jacobian_columns(&residuals, p, &step, &lower, &upper, r, jac)
    };
    let mut iterations = 0;
    let mut termination = Termination::MaxIterations;
    let mut scale;
    for _ in 0..opts.irls_rounds.max(1) {
        residuals(&p, &mut r);
        scale = robust_scale(&r).max(opts.scale_floor);
        huber_weights(&r, opts.huber_c * scale, &mut w);
        let mut lambda = 1e-3;
        let mut cost = weighted_cost(&r, &w);
        termination = Termination::MaxIterations;
        // costs of the last accepted steps: a plateau (χ² down by < 10·chi2_tol over 10 steps,
        // e.g. creeping along a valley of the switch-time kinks) also counts as converged
        let mut history: Vec<f64> = vec![cost];
        for _ in 0..opts.max_iter {
            iterations += 1;
            jacobian(&p[..], &r[..], &mut jac[..]);
            let (mut a, g) = dense::normal_equations(&jac, &r, &w);
            hold_fixed(specs, &mut a);
            let mut improved = false;
            for _ in 0..12 {
                let mut damped = a.clone();
                for i in 0..m {
                    damped[i * m + i] += lambda * a[i * m + i].max(1e-30);
                }
                let neg_g: Vec<f64> = g.iter().map(|x| -x).collect();
                let Some(step) = dense::solve_spd(&damped, m, &neg_g) else {
                    lambda *= 10.0;
                    continue;
                };
                let trial: Vec<f64> = p
                    .iter()
                    .zip(&step)
                    .zip(specs)
                    .map(|((x, d), s)| {
                        if s.lower == s.upper {
                            *x
                        } else {
                            (x + d).clamp(s.lower, s.upper)
                        }
                    })
                    .collect();
                let mut r_trial = vec![0.0; n];
                residuals(&trial, &mut r_trial);
                let c_trial = weighted_cost(&r_trial, &w);
                if c_trial.is_finite() && c_trial < cost {
                    let cost_before = cost;
                    let rel = (cost - c_trial) / cost.max(1e-300);
                    p = trial;
                    r = r_trial;
                    cost = c_trial;
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = true;
                    history.push(cost);
                    let plateau = history.len() > 10
                        && history[history.len() - 11] - cost
                            < 10.0 * opts.chi2_tol * scale * scale;
                    if rel < opts.rel_tol
                        || rel * cost_before < opts.chi2_tol * scale * scale
                        || plateau
                    {
                        termination = Termination::SmallCostChange;
                    }
                    break;
                }
                lambda *= 4.0;
            }
            if !improved {
                // no downhill step at any damping: a (local) minimum for these weights
                termination = Termination::NoFurtherDecrease;
                break;
            }
            if termination.is_converged() {
                break;
            }
        }
    }
    residuals(&p, &mut r);
    scale = robust_scale(&r).max(opts.scale_floor);
    huber_weights(&r, opts.huber_c * scale, &mut w);
    jacobian(&p[..], &r[..], &mut jac[..]);
    let (mut a, _) = dense::normal_equations(&jac, &r, &w);
    hold_fixed(specs, &mut a);
    // a tiny ridge keeps a parameter the data barely constrain from spoiling the others' errors
    let covariance = match dense::invert_spd_scaled(&a, m, 1e-12) {
        Some(inv) => (0..m)
            .map(|i| {
                (0..m)
                    .map(|j| {
                        if specs[i].lower == specs[i].upper || specs[j].lower == specs[j].upper {
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
    LmResult {
        params: p,
        covariance,
        termination,
        iterations,
        scale,
        residuals: r,
    }
}

/// A parameter with lower == upper is held: its row and column become the identity.
fn hold_fixed(specs: &[ParamSpec], a: &mut [f64]) {
    let m = specs.len();
    for (i, s) in specs.iter().enumerate() {
        if s.lower == s.upper {
            for j in 0..m {
                a[i * m + j] = 0.0;
                a[j * m + i] = 0.0;
            }
            a[i * m + i] = 1.0;
        }
    }
}

fn huber_weights(r: &[f64], c: f64, w: &mut [f64]) {
    for (wi, ri) in w.iter_mut().zip(r) {
        *wi = huber_weight(ri.abs(), c);
    }
}

fn weighted_cost(r: &[f64], w: &[f64]) -> f64 {
    r.iter().zip(w).map(|(x, wi)| wi * x * x).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_a_line_with_an_outlier() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let mut y: Vec<f64> = t.iter().map(|t| 2.0 + 0.5 * t).collect();
        for (i, yi) in y.iter_mut().enumerate() {
            *yi += 1e-3 * ((i * 7919) % 13) as f64 / 13.0 - 0.5e-3;
        }
        y[17] += 5.0;
        let specs = [
            ParamSpec {
                start: 0.0,
                lower: -10.0,
                upper: 10.0,
                step: 1e-6,
            },
            ParamSpec {
                start: 0.0,
                lower: -10.0,
                upper: 10.0,
                step: 1e-6,
            },
        ];
        let res = minimize(
            |p, out| {
                for i in 0..t.len() {
                    out[i] = p[0] + p[1] * t[i] - y[i];
                }
            },
            t.len(),
            &specs,
            &LmOptions::default(),
        );
        assert!((res.params[0] - 2.0).abs() < 2e-3, "{:?}", res.params);
        assert!((res.params[1] - 0.5).abs() < 1e-3, "{:?}", res.params);
        assert!(res.se(1) > 0.0 && res.se(1) < 1e-3);
    }
}
