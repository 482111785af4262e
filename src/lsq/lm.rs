//! The Levenberg–Marquardt driver of the allocating back-ends (dense for a collision run,
//! block-arrow for the whole-run pair fits): rounds of Huber IRLS around a damped Gauss–Newton
//! loop with the same bound strategy as the fixed back-end (parameters pressed against a bound
//! with the gradient pointing out are held; a step that would cross a bound is moved exactly onto
//! it and the others re-solved given that move), and one [`Termination`].
//!
//! A back-end supplies the residuals and its normal equations ([`Model`], [`Normal`]); this
//! module owns everything else, so the two back-ends cannot drift apart.

use super::loss::huber_weight;
use super::Termination;
use crate::stats::abs_scale;

/// One parameter: start value, bounds (held when `lower == upper`) and the finite-difference step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    pub start: f64,
    pub lower: f64,
    pub upper: f64,
    pub step: f64,
}

impl ParamSpec {
    /// Held at its start value.
    pub fn held(&self) -> bool {
        self.lower == self.upper
    }
}

/// The normal equations A = Jᵀ W J, g = Jᵀ W r at a point, in the back-end's own storage.
pub trait Normal {
    /// g = Jᵀ W r.
    fn gradient(&self) -> &[f64];
    /// Solve (A + λ·diag A) δ = rhs for the parameters in `on` (δ = 0 elsewhere); None when
    /// that system is not positive definite.
    fn solve(&self, lambda: f64, on: &[bool], rhs: &[f64]) -> Option<Vec<f64>>;
    /// (A + λ·diag A) x.
    fn apply(&self, lambda: f64, x: &[f64]) -> Vec<f64>;
}

/// A least-squares problem as the driver sees it: flat parameters and residuals.
pub trait Model {
    type Normal: Normal;
    fn n_residuals(&self) -> usize;
    /// Residuals at `x` into `out` (length [`Model::n_residuals`]).
    fn residuals(&self, x: &[f64], out: &mut [f64]);
    /// The normal equations at `x`, where the residuals are `r`, with IRLS weights `w`.
    fn normal(&self, x: &[f64], r: &[f64], w: &[f64]) -> Self::Normal;
}

/// Where the residual scale of the Huber weights comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Scale {
    /// Residuals already whitened: the scale is this number.
    Fixed(f64),
    /// 1.4826 · median |r| of the current residuals, at least `floor`.
    Mad { floor: f64 },
}

/// Settings of the driver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    pub max_iter: usize,
    /// IRLS rounds: each re-weights the residuals with Huber's function, then minimises.
    pub rounds: usize,
    /// Huber threshold in units of the scale.
    pub huber_k: f64,
    pub scale: Scale,
    /// Converged when an accepted step lowers the weighted cost Σ w r² by less than
    /// `cost_tol`·scale² (a χ² change no statistic can see) plus `rel_tol`·cost.
    pub cost_tol: f64,
    pub rel_tol: f64,
    /// The damping λ (a fraction of the normal matrix's diagonal) each round starts from: 1e-3
    /// for a start that may be far from the minimum; a fit started at a neighbouring minimum
    /// takes the Gauss–Newton step sooner from a smaller one (a refused step costs one
    /// evaluation of the residuals, a Jacobian many), but from a far start its first accepted
    /// steps can run parameters to their bounds.
    pub damping: f64,
}

/// The minimum the driver found, with the state the back-end needs for its covariance.
#[derive(Debug, Clone)]
pub struct Solution<N> {
    pub x: Vec<f64>,
    /// Residuals at `x`.
    pub r: Vec<f64>,
    /// Huber weights at `x` for the final scale.
    pub w: Vec<f64>,
    pub scale: f64,
    /// Normal equations at `x` with the weights `w`.
    pub normal: N,
    pub termination: Termination,
    pub iterations: usize,
}

/// Huber IRLS weights of `r` for the threshold `c` (a non-finite residual keeps weight 1, so
/// its cost stays infinite and no step that produces it is accepted).
pub fn huber_weights(r: &[f64], c: f64, w: &mut [f64]) {
    for (wi, ri) in w.iter_mut().zip(r) {
        let a = ri.abs();
        *wi = if a.is_finite() {
            huber_weight(a, c)
        } else {
            1.0
        };
    }
}

/// Σ w r², infinite when any term is not finite.
pub fn weighted_cost(r: &[f64], w: &[f64]) -> f64 {
    r.iter()
        .zip(w)
        .map(|(x, w)| {
            let v = w * x * x;
            if v.is_finite() {
                v
            } else {
                f64::INFINITY
            }
        })
        .sum()
}

fn scale_of(r: &[f64], rule: Scale) -> f64 {
    match rule {
        Scale::Fixed(s) => s,
        Scale::Mad { floor } => abs_scale(r).max(floor),
    }
}

/// The active set: free parameters not pressed against a bound by the gradient.
fn active(x: &[f64], g: &[f64], specs: &[ParamSpec]) -> Vec<bool> {
    specs
        .iter()
        .enumerate()
        .map(|(i, s)| {
            !(s.held() || (x[i] <= s.lower && g[i] > 0.0) || (x[i] >= s.upper && g[i] < 0.0))
        })
        .collect()
}

/// The damped step (A + λ·diag A) δ = −g that stays inside the bounds: a parameter the step
/// would push through a bound is moved exactly onto it and the others re-solved given that move.
fn bounded_step<N: Normal>(
    normal: &N,
    lambda: f64,
    x: &[f64],
    specs: &[ParamSpec],
    mut on: Vec<bool>,
) -> Option<Vec<f64>> {
    let m = x.len();
    let g = normal.gradient();
    let mut pinned: Vec<Option<f64>> = vec![None; m];
    for _ in 0..m.max(1) {
        let d: Vec<f64> = pinned.iter().map(|p| p.unwrap_or(0.0)).collect();
        let ad = if pinned.iter().any(Option::is_some) {
            normal.apply(lambda, &d)
        } else {
            vec![0.0; m]
        };
        let rhs: Vec<f64> = (0..m).map(|i| -g[i] - ad[i]).collect();
        let mut step = normal.solve(lambda, &on, &rhs)?;
        for i in 0..m {
            if let Some(di) = pinned[i] {
                step[i] = di;
            } else if !on[i] {
                step[i] = 0.0;
            }
        }
        let hit = super::pin_crossings(
            x,
            &step,
            |i| (specs[i].lower, specs[i].upper),
            &mut on,
            &mut pinned,
        );
        if !hit {
            return Some(step);
        }
        if !on.iter().any(|&o| o) {
            return Some(pinned.iter().map(|p| p.unwrap_or(0.0)).collect());
        }
    }
    None
}

/// Minimise Σ ρ(r) over `specs` by rounds of IRLS (weights and scale from the round's start),
/// each a bounded Levenberg–Marquardt on Σ w r²; the termination is the last round's. The
/// solution carries the normal equations at the minimum, for the covariance.
pub fn minimize<M: Model>(model: &M, specs: &[ParamSpec], s: &Settings) -> Solution<M::Normal> {
    let d = descend(model, specs, s);
    let normal = model.normal(&d.x, &d.r, &d.w);
    Solution {
        x: d.x,
        r: d.r,
        w: d.w,
        scale: d.scale,
        normal,
        termination: d.termination,
        iterations: d.iterations,
    }
}

/// [`minimize`] without the normal equations at the minimum: the same point and residuals for
/// a caller that needs no covariance (one Jacobian fewer, the costliest part of a short fit).
pub fn descend<M: Model>(model: &M, specs: &[ParamSpec], s: &Settings) -> Solution<()> {
    let n = model.n_residuals();
    let mut x: Vec<f64> = specs
        .iter()
        .map(|s| s.start.clamp(s.lower, s.upper))
        .collect();
    let mut r = vec![0.0; n];
    let mut r_try = vec![0.0; n];
    let mut w = vec![1.0; n];
    let mut iterations = 0;
    let mut termination = Termination::MaxIterations;
    model.residuals(&x, &mut r);
    'rounds: for _ in 0..s.rounds.max(1) {
        let scale = scale_of(&r, s.scale);
        huber_weights(&r, s.huber_k * scale, &mut w);
        let mut cost = weighted_cost(&r, &w);
        let mut lambda = s.damping;
        // a step is tried at up to twelve dampings from 1e-3 up (×4 each); a smaller start gets
        // the tries that bring it to 1e-3 on top, so a bad start reaches the damping it did
        let tries = 12 + (1e-3 / s.damping).log(4.0).ceil().clamp(0.0, 30.0) as usize;
        termination = Termination::MaxIterations;
        for _ in 0..s.max_iter {
            iterations += 1;
            let normal = model.normal(&x, &r, &w);
            if normal.gradient().iter().any(|g| !g.is_finite()) {
                // a difference step left the model's domain: no direction to take from here,
                // and no evidence of a minimum either (not "converged")
                termination = Termination::NonFinite;
                break 'rounds;
            }
            let on = active(&x, normal.gradient(), specs);
            if !on.iter().any(|&o| o) {
                termination = Termination::AtBounds;
                break;
            }
            let mut improved = false;
            for _ in 0..tries {
                let Some(step) = bounded_step(&normal, lambda, &x, specs, on.clone()) else {
                    lambda *= 10.0;
                    continue;
                };
                let trial: Vec<f64> = x
                    .iter()
                    .zip(&step)
                    .zip(specs)
                    .map(|((x, d), s)| (x + d).clamp(s.lower, s.upper))
                    .collect();
                if trial.iter().any(|v| !v.is_finite()) {
                    // a step that overflowed (a non-finite entry of the normal matrix behind a
                    // finite gradient): not a point to evaluate; more damping shortens it
                    lambda *= 4.0;
                    continue;
                }
                model.residuals(&trial, &mut r_try);
                let c_trial = weighted_cost(&r_try, &w);
                if c_trial.is_finite() && c_trial < cost {
                    let drop = cost - c_trial;
                    x = trial;
                    std::mem::swap(&mut r, &mut r_try);
                    cost = c_trial;
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = true;
                    if drop < s.cost_tol * scale * scale + s.rel_tol * cost {
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
    let scale = scale_of(&r, s.scale);
    huber_weights(&r, s.huber_k * scale, &mut w);
    Solution {
        x,
        r,
        w,
        scale,
        normal: (),
        termination,
        iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// r = x − 2 whose normal equations carry a NaN: in the gradient (`nan_gradient`, as a
    /// difference step that left the model's domain gives) or only in the solved step. Its
    /// residuals refuse a non-finite point, as the simulator does.
    struct NanNormal {
        nan_gradient: bool,
    }
    struct Nan(Vec<f64>);
    impl Normal for Nan {
        fn gradient(&self) -> &[f64] {
            &self.0
        }
        fn solve(&self, _: f64, _: &[bool], rhs: &[f64]) -> Option<Vec<f64>> {
            Some(rhs.iter().map(|_| f64::NAN).collect())
        }
        fn apply(&self, _: f64, x: &[f64]) -> Vec<f64> {
            x.to_vec()
        }
    }
    impl Model for NanNormal {
        type Normal = Nan;
        fn n_residuals(&self) -> usize {
            1
        }
        fn residuals(&self, x: &[f64], out: &mut [f64]) {
            assert!(x[0].is_finite(), "the driver evaluated a non-finite point");
            out[0] = x[0] - 2.0;
        }
        fn normal(&self, x: &[f64], _: &[f64], _: &[f64]) -> Nan {
            Nan(vec![if self.nan_gradient {
                f64::NAN
            } else {
                x[0] - 2.0
            }])
        }
    }

    fn minimize_nan(nan_gradient: bool) -> Solution<Nan> {
        let spec = ParamSpec {
            start: 1.0,
            lower: 0.0,
            upper: 10.0,
            step: 1e-6,
        };
        let s = Settings {
            max_iter: 5,
            rounds: 3,
            huber_k: 2.5,
            scale: Scale::Fixed(1.0),
            cost_tol: 1e-9,
            rel_tol: 0.0,
            damping: 1e-3,
        };
        minimize(&NanNormal { nan_gradient }, &[spec], &s)
    }

    #[test]
    fn a_non_finite_gradient_ends_the_fit_as_non_finite_not_converged() {
        let sol = minimize_nan(true);
        assert_eq!(sol.x, vec![1.0]);
        assert_eq!(sol.termination, Termination::NonFinite);
        assert!(!sol.termination.is_converged());
        assert_eq!(sol.iterations, 1, "the rounds after it are not run");
    }

    #[test]
    fn a_step_with_a_non_finite_value_is_refused_not_evaluated() {
        let sol = minimize_nan(false);
        assert_eq!(sol.x, vec![1.0]);
        assert_eq!(sol.termination, Termination::NoFurtherDecrease);
    }
}
