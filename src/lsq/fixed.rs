//! The fixed-size, allocation-free back-end: Levenberg–Marquardt for a robust loss at a fixed
//! scale on `N ≤ 8` parameters held in arrays, with box bounds and fixed parameters (the per-run hot path).
//!
//! Each iteration takes a damped Newton step on the robust cost: gradient Σ ψ(u)·∂r, curvature
//! Σ ρ''(u)·JᵀJ (the Gauss–Newton matrix of the loss; for Huber only the inliers count, so the step
//! is exact once the inlier set settles), Marquardt's diagonal damping (the step does not depend
//! on the parameters' units), and accepts the step only if the robust cost falls. Parameters at a
//! bound whose gradient points outward are held for that step (an active set). Stopping is data:
//! [`Termination`] says why, never a panic. The caller owns the buffers ([`Workspace`]), so the
//! iterations allocate nothing.

// Small dense linear algebra on fixed N×N arrays reads best with explicit indices.
#![allow(clippy::needless_range_loop)]

use super::loss::Loss;

use super::Termination;

/// A least-squares problem in `N` parameters with an analytic Jacobian.
pub trait Problem<const N: usize> {
    /// Number of observations.
    fn n_obs(&self) -> usize;
    /// Residuals r_i = model_i − obs_i at `x` and, if asked, the rows ∂r_i/∂x.
    /// Returns false if the model cannot be evaluated there (non-finite values).
    fn residuals(&self, x: &[f64; N], r: &mut [f64], jac: Option<&mut [[f64; N]]>) -> bool;
}

/// Box bounds; a parameter with `free[i] == false` stays at its start value.
#[derive(Clone, Copy, Debug)]
pub struct Bounds<const N: usize> {
    pub lo: [f64; N],
    pub hi: [f64; N],
    pub free: [bool; N],
}

impl<const N: usize> Bounds<N> {
    /// Move the free parameters of `x` into the box.
    pub fn clamp(&self, x: &mut [f64; N]) {
        for i in 0..N {
            if self.free[i] {
                x[i] = x[i].clamp(self.lo[i], self.hi[i]);
            }
        }
    }
}

/// Stopping rules.
#[derive(Clone, Copy, Debug)]
pub struct Settings<const N: usize> {
    pub max_iterations: u32,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    pub ftol: f64,
    /// Stop when every component of an accepted step is below `xtol·(|x_i| + typical_i)`.
    pub xtol: f64,
    /// Typical magnitude of each parameter (for the step test near zero).
    pub typical: [f64; N],
}

/// Buffers reused across fits: residuals and Jacobian at the current and the trial point,
/// robust weights, an exclusion mask (outliers) and scratch space for medians.
#[derive(Default)]
pub struct Workspace<const N: usize> {
    pub r: Vec<f64>,
    pub jac: Vec<[f64; N]>,
    r_try: Vec<f64>,
    jac_try: Vec<[f64; N]>,
    pub w: Vec<f64>,
    /// Curvature weights ρ''(u) of the Newton matrix.
    pub wh: Vec<f64>,
    pub excluded: Vec<bool>,
    pub scratch: Vec<f64>,
}

impl<const N: usize> Workspace<N> {
    /// Size every buffer for `n` observations and clear the exclusion mask.
    pub fn reset(&mut self, n: usize) {
        self.r.resize(n, 0.0);
        self.r_try.resize(n, 0.0);
        self.jac.resize(n, [0.0; N]);
        self.jac_try.resize(n, [0.0; N]);
        self.w.resize(n, 1.0);
        self.wh.resize(n, 1.0);
        self.excluded.clear();
        self.excluded.resize(n, false);
        self.scratch.resize(n, 0.0);
    }
}

/// The result of one minimisation at a fixed scale; `ws.r`, `ws.jac` and `ws.w` hold the state at `x`.
#[derive(Clone, Copy, Debug)]
pub struct Outcome<const N: usize> {
    pub x: [f64; N],
    pub cost: f64,
    pub iterations: u32,
    pub termination: Termination,
}

/// Robust cost Σ scale² ρ(r/scale) over the included residuals; also fills the IRLS weights
/// ψ(u)/u (`w`) and the curvature weights ρ''(u) (`wh`).
pub fn cost_and_weights(
    r: &[f64],
    excluded: &[bool],
    loss: Loss,
    scale: f64,
    w: &mut [f64],
    wh: &mut [f64],
) -> f64 {
    let mut cost = 0.0;
    for i in 0..r.len() {
        if excluded[i] {
            w[i] = 0.0;
            wh[i] = 0.0;
            continue;
        }
        let u = r[i] / scale;
        let (rho, wi) = loss.rho_weight(u);
        cost += rho;
        w[i] = wi;
        wh[i] = loss.curvature(u);
    }
    cost * scale * scale
}

fn robust_cost(r: &[f64], excluded: &[bool], loss: Loss, scale: f64) -> f64 {
    let mut cost = 0.0;
    for i in 0..r.len() {
        if !excluded[i] {
            cost += loss.rho_weight(r[i] / scale).0;
        }
    }
    cost * scale * scale
}

/// Weighted normal equations H = Σ wh JᵀJ and g = Σ w J r (`lsq::wide`: compiled for AVX2 too).
pub use super::wide::normal_equations;

/// Solve A δ = b for the parameters in `on` (others get δ = 0) by Cholesky on the matrix scaled
/// to unit diagonal. Returns `None` if A restricted to `on` is not positive definite.
pub fn solve_spd<const N: usize>(
    a: &[[f64; N]; N],
    b: &[f64; N],
    on: &[bool; N],
) -> Option<[f64; N]> {
    let idx: [usize; N] = {
        let mut idx = [0; N];
        let mut m = 0;
        for i in 0..N {
            if on[i] {
                idx[m] = i;
                m += 1;
            }
        }
        idx
    };
    let m = on.iter().filter(|&&o| o).count();
    let mut d = [0.0; N];
    for p in 0..m {
        let aii = a[idx[p]][idx[p]];
        if aii.is_nan() || aii <= 0.0 || aii.is_infinite() {
            return None;
        }
        d[p] = aii.sqrt();
    }
    let mut l = [[0.0; N]; N];
    for p in 0..m {
        for q in 0..=p {
            let mut sum = a[idx[p]][idx[q]] / (d[p] * d[q]);
            for k in 0..q {
                sum -= l[p][k] * l[q][k];
            }
            if p == q {
                if sum.is_nan() || sum <= 1e-14 {
                    return None;
                }
                l[p][p] = sum.sqrt();
            } else {
                l[p][q] = sum / l[q][q];
            }
        }
    }
    let mut y = [0.0; N];
    for p in 0..m {
        let mut sum = b[idx[p]] / d[p];
        for k in 0..p {
            sum -= l[p][k] * y[k];
        }
        y[p] = sum / l[p][p];
    }
    let mut x = [0.0; N];
    for p in (0..m).rev() {
        let mut sum = y[p];
        for k in p + 1..m {
            sum -= l[k][p] * x[k];
        }
        x[p] = sum / l[p][p];
    }
    let mut out = [0.0; N];
    for p in 0..m {
        out[idx[p]] = x[p] / d[p];
    }
    Some(out)
}

/// The damped step A δ = −g that stays inside the bounds: a parameter the full step would push
/// through a bound is moved exactly onto it and the others re-solved given that move (so the
/// step stays optimal in the remaining subspace, unlike a clipped step). `on` marks the
/// parameters that may move.
fn bounded_step<const N: usize>(
    a: &[[f64; N]; N],
    g: &[f64; N],
    x: &[f64; N],
    bounds: &Bounds<N>,
    mut on: [bool; N],
) -> Option<[f64; N]> {
    let mut pinned = [None::<f64>; N];
    for _ in 0..N {
        let mut rhs = [0.0; N];
        for i in 0..N {
            rhs[i] = -g[i];
            for j in 0..N {
                if let Some(d) = pinned[j] {
                    rhs[i] -= a[i][j] * d;
                }
            }
        }
        let mut step = solve_spd(a, &rhs, &on)?;
        for j in 0..N {
            if let Some(d) = pinned[j] {
                step[j] = d;
            }
        }
        let hit = super::pin_crossings(
            x,
            &step,
            |i| (bounds.lo[i], bounds.hi[i]),
            &mut on,
            &mut pinned,
        );
        if !hit {
            return Some(step);
        }
        if !on.iter().any(|&o| o) {
            return Some(pinned.map(|d| d.unwrap_or(0.0)));
        }
    }
    None
}

/// Minimise the robust cost at a fixed `scale` from `x0` (clamped into the bounds).
pub fn minimize<const N: usize, P: Problem<N>>(
    prob: &P,
    x0: [f64; N],
    bounds: &Bounds<N>,
    loss: Loss,
    scale: f64,
    settings: &Settings<N>,
    ws: &mut Workspace<N>,
) -> Outcome<N> {
    let mut x = x0;
    bounds.clamp(&mut x);
    let mut out = Outcome {
        x,
        cost: f64::INFINITY,
        iterations: 0,
        termination: Termination::NonFinite,
    };
    if !prob.residuals(&x, &mut ws.r, Some(&mut ws.jac)) {
        return out;
    }
    let mut cost = cost_and_weights(&ws.r, &ws.excluded, loss, scale, &mut ws.w, &mut ws.wh);
    out.cost = cost;
    let mut lambda = 1e-3;
    for iter in 1..=settings.max_iterations {
        out.iterations = iter;
        let (h, g) = normal_equations(&ws.jac, &ws.r, &ws.w, &ws.wh);
        // active set: hold parameters pressed against a bound
        let mut on = bounds.free;
        for i in 0..N {
            if on[i]
                && ((x[i] <= bounds.lo[i] && g[i] > 0.0) || (x[i] >= bounds.hi[i] && g[i] < 0.0))
            {
                on[i] = false;
            }
        }
        if !on.iter().any(|&o| o) {
            out.termination = Termination::AtBounds;
            break;
        }
        let mut accepted = false;
        while lambda < 1e12 {
            let mut a = h;
            for i in 0..N {
                a[i][i] += lambda * h[i][i].max(1e-300);
            }
            let Some(step) = bounded_step(&a, &g, &x, bounds, on) else {
                lambda *= 10.0;
                continue;
            };
            let mut x_try = x;
            for i in 0..N {
                x_try[i] += step[i];
            }
            bounds.clamp(&mut x_try);
            if !prob.residuals(&x_try, &mut ws.r_try, Some(&mut ws.jac_try)) {
                lambda *= 10.0;
                continue;
            }
            let cost_try = robust_cost(&ws.r_try, &ws.excluded, loss, scale);
            if cost_try <= cost {
                let small_step = (0..N).all(|i| {
                    (x_try[i] - x[i]).abs() <= settings.xtol * (x[i].abs() + settings.typical[i])
                });
                let small_drop = cost - cost_try <= settings.ftol * cost;
                std::mem::swap(&mut ws.r, &mut ws.r_try);
                std::mem::swap(&mut ws.jac, &mut ws.jac_try);
                x = x_try;
                cost = cost_and_weights(&ws.r, &ws.excluded, loss, scale, &mut ws.w, &mut ws.wh);
                lambda = (lambda / 3.0).max(1e-12);
                accepted = true;
                if small_step {
                    out.termination = Termination::SmallStep;
                } else if small_drop {
                    out.termination = Termination::SmallCostChange;
                }
                break;
            }
            lambda *= 4.0;
        }
        out.x = x;
        out.cost = cost;
        if !accepted {
            // no step lowers the cost at any damping: x is a minimum to working precision
            out.termination = Termination::NoFurtherDecrease;
            return out;
        }
        if out.termination.is_converged() {
            return out;
        }
        out.termination = Termination::MaxIterations;
    }
    out.x = x;
    out.cost = cost;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = a·exp(−b t) + c with a known truth: the solver must recover it from far away.
    struct Exp<'a> {
        t: &'a [f64],
        y: &'a [f64],
    }

    const N: usize = 6;

    impl Problem<N> for Exp<'_> {
        fn n_obs(&self) -> usize {
            self.t.len()
        }
        fn residuals(&self, x: &[f64; N], r: &mut [f64], jac: Option<&mut [[f64; N]]>) -> bool {
            let mut jac = jac;
            for i in 0..self.t.len() {
                let e = (-x[1] * self.t[i]).exp();
                r[i] = x[0] * e + x[2] - self.y[i];
                if let Some(j) = jac.as_deref_mut() {
                    j[i] = [e, -x[0] * self.t[i] * e, 1.0, 0.0, 0.0, 0.0];
                }
            }
            true
        }
    }

    #[test]
    fn recovers_an_exponential_and_respects_bounds() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let y: Vec<f64> = t.iter().map(|t| 2.0 * (-0.7 * t).exp() + 0.5).collect();
        let prob = Exp { t: &t, y: &y };
        let mut ws = Workspace::default();
        ws.reset(t.len());
        let settings = Settings {
            max_iterations: 200,
            ftol: 1e-15,
            xtol: 1e-12,
            typical: [1.0; N],
        };
        let mut bounds = Bounds {
            lo: [-10.0, 0.0, -10.0, 0.0, 0.0, 0.0],
            hi: [10.0, 10.0, 10.0, 0.0, 0.0, 0.0],
            free: [true, true, true, false, false, false],
        };
        let out = minimize(
            &prob,
            [0.5, 3.0, 0.0, 0.0, 0.0, 0.0],
            &bounds,
            Loss::Linear,
            1.0,
            &settings,
            &mut ws,
        );
        assert!(out.termination.is_converged(), "{:?}", out.termination);
        assert!(
            (out.x[0] - 2.0).abs() < 1e-8
                && (out.x[1] - 0.7).abs() < 1e-8
                && (out.x[2] - 0.5).abs() < 1e-8,
            "{:?}",
            out.x
        );
        // an upper bound below the truth holds the rate at the bound
        bounds.hi[1] = 0.5;
        let out = minimize(
            &prob,
            [0.5, 0.3, 0.0, 0.0, 0.0, 0.0],
            &bounds,
            Loss::Linear,
            1.0,
            &settings,
            &mut ws,
        );
        assert_eq!(out.x[1], 0.5);
        assert!(out.termination.is_converged(), "{:?}", out.termination);
    }

    #[test]
    fn solve_spd_skips_held_parameters() {
        let mut a = [[0.0; N]; N];
        for i in 0..N {
            a[i][i] = (i + 1) as f64;
        }
        a[0][1] = 0.5;
        a[1][0] = 0.5;
        let b = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0];
        let on = [true, true, false, true, false, false];
        let x = solve_spd(&a, &b, &on).unwrap();
        // 2x2 block [[1, .5], [.5, 2]] x = [1, 2]
        let det = 1.0 * 2.0 - 0.25;
        assert!((x[0] - (2.0 - 1.0) / det).abs() < 1e-14);
        assert!((x[1] - (2.0 - 0.5) / det).abs() < 1e-14);
        assert!((x[3] - 1.0).abs() < 1e-14 && x[2] == 0.0 && x[4] == 0.0);
    }
}
