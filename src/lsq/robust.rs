//! The robust loop of the fixed-size back-end, around [`fixed::minimize`](super::fixed::minimize): rounds of LM in which the scale (MAD of the residuals)
//! and the outlier mask (frames beyond `outlier_sigma` scales, left out) come from the previous
//! round, until both settle; then standard errors from the Jacobian scaled by the robust scale.

use super::fixed::{self as lm, Bounds, Problem, Settings, Workspace};
use super::loss::Loss;
use crate::stats::mad_scale;

use super::Termination;

/// How the robust fit treats residuals.
#[derive(Clone, Copy, Debug)]
pub struct RobustOptions<const N: usize> {
    pub loss: Loss,
    /// Frames with |residual| above this many robust scales are outliers (excluded at the end).
    pub outlier_sigma: f64,
    /// The robust scale never goes below this (a noise-free run would otherwise flag every frame).
    pub scale_floor: f64,
    pub settings: Settings<N>,
}

/// The result of a robust fit.
#[derive(Clone, Copy, Debug)]
pub struct RobustFit<const N: usize> {
    pub x: [f64; N],
    /// Standard errors of the free parameters (None when fixed or not identifiable).
    pub se: [Option<f64>; N],
    /// Robust residual scale (1.4826·MAD of the final residuals).
    pub scale: f64,
    /// Root mean square of the residuals of the frames used.
    pub rms: f64,
    pub n_used: usize,
    pub n_outliers: usize,
    pub iterations: u32,
    pub termination: Termination,
}

const MAX_ROUNDS: usize = 6;

/// Fit `prob` robustly from `x0`. `ws` is resized as needed; its buffers hold the final state.
pub fn fit_robust<const N: usize, P: Problem<N>>(
    prob: &P,
    x0: [f64; N],
    bounds: &Bounds<N>,
    opts: &RobustOptions<N>,
    ws: &mut Workspace<N>,
) -> RobustFit<N> {
    let n = prob.n_obs();
    ws.reset(n);
    let n_free = bounds.free.iter().filter(|&&f| f).count();
    let mut fit = RobustFit {
        x: x0,
        se: [None; N],
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
    bounds.clamp(&mut x);
    if !prob.residuals(&x, &mut ws.r, None) {
        fit.termination = Termination::NonFinite;
        return fit;
    }
    // Round 0 is a loose least-squares fit from the start values (their residuals are model
    // error, not noise, so a robust scale means nothing yet); each later round takes the scale
    // (MAD of all residuals) and the outlier mask from the previous one and minimises the robust
    // cost, until neither changes.
    let mut scale = mad_scale(&ws.r, None, &mut ws.scratch).max(opts.scale_floor);
    let loose = Settings {
        ftol: opts.settings.ftol.max(1e-6),
        xtol: opts.settings.xtol.max(1e-5),
        ..opts.settings
    };
    let mut out = None;
    for round in 0..MAX_ROUNDS {
        let (loss, settings) = if round == 0 {
            (Loss::Linear, &loose)
        } else {
            (opts.loss, &opts.settings)
        };
        let o = lm::minimize(prob, x, bounds, loss, scale, settings, ws);
        fit.iterations += o.iterations;
        x = o.x;
        out = Some(o);
        if o.termination == Termination::NonFinite {
            break;
        }
        let new_scale = mad_scale(&ws.r, None, &mut ws.scratch).max(opts.scale_floor);
        let cut = opts.outlier_sigma * new_scale;
        let n_out = ws.r.iter().filter(|r| r.abs() > cut).count();
        let keep_all = n - n_out < n_free + 2;
        let mut changed = false;
        for i in 0..n {
            let bad = !keep_all && ws.r[i].abs() > cut;
            changed |= bad != ws.excluded[i];
            ws.excluded[i] = bad;
        }
        let settled = round > 0 && !changed && (new_scale - scale).abs() <= 0.02 * scale;
        scale = new_scale;
        if settled {
            break;
        }
    }
    let out = out.expect("at least one round ran");
    fit.n_outliers = ws.excluded.iter().filter(|&&e| e).count();
    fit.n_used = n - fit.n_outliers;
    fit.x = out.x;
    fit.termination = out.termination;
    fit.scale = scale;
    if out.termination == Termination::NonFinite {
        return fit;
    }
    // ws.r, ws.jac, ws.w are at out.x; refresh the weights at the final scale
    lm::cost_and_weights(&ws.r, &ws.excluded, opts.loss, scale, &mut ws.w, &mut ws.wh);
    let (sum_sq, m) =
        ws.r.iter()
            .zip(&ws.excluded)
            .filter(|(_, &e)| !e)
            .fold((0.0, 0usize), |(s, m), (r, _)| (s + r * r, m + 1));
    fit.rms = (sum_sq / m.max(1) as f64).sqrt();
    fit.se = standard_errors(&ws.jac, &ws.r, &ws.w, &bounds.free, scale);
    fit
}

/// Standard errors σ·sqrt(diag((Σ w JᵀJ)⁻¹)) of the free parameters, with the IRLS weights w
/// (1 for inliers, less for the few frames in the loss's tails), or None if singular.
fn standard_errors<const N: usize>(
    jac: &[[f64; N]],
    r: &[f64],
    w: &[f64],
    free: &[bool; N],
    scale: f64,
) -> [Option<f64>; N] {
    let (h, _) = lm::normal_equations(jac, r, w, w);
    let mut se = [None; N];
    for i in 0..N {
        if !free[i] {
            continue;
        }
        let mut e = [0.0; N];
        e[i] = 1.0;
        let Some(col) = lm::solve_spd(&h, &e, free) else {
            return [None; N];
        };
        se[i] = (col[i] >= 0.0).then(|| scale * col[i].sqrt());
    }
    se
}
