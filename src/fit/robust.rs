//! A robust fit around [`lm::minimize`]: the scale from the MAD of the residuals (re-estimated
//! until it settles), then frames beyond `outlier_sigma` scales excluded and the fit polished,
//! then standard errors from the Jacobian scaled by the robust residual scale.

use super::lm::{self, Bounds, Problem, Settings, Workspace};
use super::loss::{mad_scale, Loss};
use super::model::NP;
use super::status::Termination;

/// How the robust fit treats residuals.
#[derive(Clone, Copy, Debug)]
pub struct RobustOptions {
    pub loss: Loss,
    /// Frames with |residual| above this many robust scales are outliers (excluded at the end).
    pub outlier_sigma: f64,
    /// The robust scale never goes below this (a noise-free run would otherwise flag every frame).
    pub scale_floor: f64,
    pub settings: Settings,
}

/// The result of a robust fit.
#[derive(Clone, Copy, Debug)]
pub struct RobustFit {
    pub x: [f64; NP],
    /// Standard errors of the free parameters (None when fixed or not identifiable).
    pub se: [Option<f64>; NP],
    /// Robust residual scale (1.4826·MAD of the final residuals).
    pub scale: f64,
    /// Root mean square of the residuals of the frames used.
    pub rms: f64,
    pub n_used: usize,
    pub n_outliers: usize,
    pub iterations: u32,
    pub termination: Termination,
}

const MAX_SCALE_ROUNDS: usize = 5;

/// Fit `prob` robustly from `x0`. `ws` is resized as needed; its buffers hold the final state.
pub fn fit_robust<P: Problem>(
    prob: &P,
    x0: [f64; NP],
    bounds: &Bounds,
    opts: &RobustOptions,
    ws: &mut Workspace,
) -> RobustFit {
    let n = prob.n_obs();
    ws.reset(n);
    let n_free = bounds.free.iter().filter(|&&f| f).count();
    let mut fit = RobustFit {
        x: x0,
        se: [None; NP],
        scale: f64::NAN,
        rms: f64::NAN,
        n_used: n,
        n_outliers: 0,
        iterations: 0,
        termination: Termination::TooFewPoints,
    };
    if n < n_free + 2 {
        return fit;
    }
    let mut x = x0;
    for i in 0..NP {
        if bounds.free[i] {
            x[i] = x[i].clamp(bounds.lo[i], bounds.hi[i]);
        }
    }
    if !prob.residuals(&x, &mut ws.r, None) {
        fit.termination = Termination::NonFinite;
        return fit;
    }
    let mut scale = mad_scale(&ws.r, &ws.excluded, &mut ws.scratch).max(opts.scale_floor);
    let mut out = None;
    for _ in 0..MAX_SCALE_ROUNDS {
        let o = lm::minimize(prob, x, bounds, opts.loss, scale, &opts.settings, ws);
        fit.iterations += o.iterations;
        x = o.x;
        out = Some(o);
        if o.termination == Termination::NonFinite {
            break;
        }
        let new_scale = mad_scale(&ws.r, &ws.excluded, &mut ws.scratch).max(opts.scale_floor);
        let settled = (new_scale - scale).abs() <= 0.02 * scale;
        scale = new_scale;
        if settled {
            break;
        }
    }
    let mut out = out.expect("at least one round ran");
    if out.termination != Termination::NonFinite {
        let mut n_out = 0;
        for i in 0..n {
            let bad = ws.r[i].abs() > opts.outlier_sigma * scale;
            ws.excluded[i] = bad;
            n_out += bad as usize;
        }
        if n_out > 0 && n - n_out >= n_free + 2 {
            let o = lm::minimize(prob, x, bounds, opts.loss, scale, &opts.settings, ws);
            fit.iterations += o.iterations;
            out = o;
        } else if n_out > 0 {
            ws.excluded.iter_mut().for_each(|e| *e = false);
            n_out = 0;
        }
        fit.n_outliers = n_out;
        fit.n_used = n - n_out;
    }
    fit.x = out.x;
    fit.termination = out.termination;
    fit.scale = scale;
    if out.termination == Termination::NonFinite {
        return fit;
    }
    // ws.r, ws.jac, ws.w are at out.x; refresh the weights at the final scale
    lm::cost_and_weights(&ws.r, &ws.excluded, opts.loss, scale, &mut ws.w);
    let (sum_sq, m) =
        ws.r.iter()
            .zip(&ws.excluded)
            .filter(|(_, &e)| !e)
            .fold((0.0, 0usize), |(s, m), (r, _)| (s + r * r, m + 1));
    fit.rms = (sum_sq / m.max(1) as f64).sqrt();
    fit.se = standard_errors(&ws.jac, &ws.r, &ws.w, &bounds.free, scale);
    fit
}

/// Standard errors σ·sqrt(diag((Σ w JᵀJ)⁻¹)) of the free parameters, or None if singular.
fn standard_errors(
    jac: &[[f64; NP]],
    r: &[f64],
    w: &[f64],
    free: &[bool; NP],
    scale: f64,
) -> [Option<f64>; NP] {
    let (h, _) = lm::normal_equations(jac, r, w);
    let mut se = [None; NP];
    for i in 0..NP {
        if !free[i] {
            continue;
        }
        let mut e = [0.0; NP];
        e[i] = 1.0;
        let Some(col) = lm::solve_spd(&h, &e, free) else {
            return [None; NP];
        };
        se[i] = (col[i] >= 0.0).then(|| scale * col[i].sqrt());
    }
    se
}
