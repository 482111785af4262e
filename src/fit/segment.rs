//! Fit one time range of a track with z(t) = z0 + Δz(t − t_ref; v0, va0, μ, T), any subset of the
//! parameters free. The single-run fit and the collision phases both build on it.

use super::model::{Prepared, MU, NP, T0, TD, V0, VA0, Z0};
use super::options::FitOptions;
use super::track_problem::TrackProblem;
use super::track_problem::{Bounds, RobustFit, RobustOptions, Settings, Workspace};
use crate::lsq::robust::fit_robust;
use crate::lsq::Termination;
use serde::{Deserialize, Serialize};

/// Which parameters a segment fit may change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct FreeParams {
    pub z0: bool,
    pub v0: bool,
    pub va0: bool,
    pub mu: bool,
    pub t_drag: bool,
}

/// Start values (and the fixed values of the parameters not free) of a segment fit.
/// `v0_mps` and `va0_mps` are the velocity and spin surface speed at `t_ref_s`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentInit {
    pub t_ref_s: f64,
    pub z0_m: f64,
    pub v0_mps: f64,
    pub va0_mps: f64,
    pub mu: f64,
    pub t_drag_s: f64,
    pub free: FreeParams,
}

/// Standard errors of a segment fit (None for a fixed or unidentifiable parameter).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SegmentSe {
    pub z0_m: Option<f64>,
    pub v0_mps: Option<f64>,
    pub va0_mps: Option<f64>,
    pub mu: Option<f64>,
    pub t_drag_s: Option<f64>,
}

/// The fitted segment: parameters at `t_ref_s`, their errors, and how the fit went.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SegmentFit {
    pub t_ref_s: f64,
    pub z0_m: f64,
    pub v0_mps: f64,
    pub va0_mps: f64,
    pub mu: f64,
    pub t_drag_s: f64,
    pub se: SegmentSe,
    /// Time from `t_ref_s` to the end of sliding (0 if the segment starts rolling).
    #[serde(with = "crate::artifacts::nan_null")]
    pub t1_s: f64,
    /// RMS of the residuals of the frames used, and the robust scale (null if no fit was made).
    #[serde(with = "crate::artifacts::nan_null")]
    pub rms_m: f64,
    #[serde(with = "crate::artifacts::nan_null")]
    pub scale_m: f64,
    pub n_frames: usize,
    pub n_used: usize,
    pub n_outliers: usize,
    pub iterations: u32,
    pub termination: Termination,
}

/// Bounds shared by every fit of the model: no physical run leaves them.
pub(crate) fn model_bounds() -> Bounds {
    let inf = f64::INFINITY;
    Bounds {
        lo: [-inf, 0.0, -20.0, -50.0, 1e-4, 1e-4],
        hi: [inf, 0.0, 20.0, 50.0, 5.0, 1e3],
        free: [false; NP],
    }
}

/// Step tolerances and typical magnitudes for the model's parameters.
pub(crate) fn settings(opts: &FitOptions) -> RobustOptions {
    RobustOptions {
        loss: opts.loss,
        outlier_sigma: opts.outlier_sigma,
        scale_floor: 1e-10,
        settings: Settings {
            max_iterations: opts.max_iterations,
            ftol: 1e-8,
            xtol: 1e-8,
            typical: [1e-6, 1e-6, 1e-4, 1e-4, 1e-3, 1e-3],
        },
    }
}

/// Fit the frames `t_s`, `z_m` (same length) of one segment.
pub fn fit_segment(t_s: &[f64], z_m: &[f64], init: SegmentInit, opts: &FitOptions) -> SegmentFit {
    let mut ws = Workspace::default();
    fit_segment_with(t_s, z_m, init, opts, &mut ws)
}

/// [`fit_segment`] with caller-owned buffers (for many fits in a row).
pub fn fit_segment_with(
    t_s: &[f64],
    z_m: &[f64],
    init: SegmentInit,
    opts: &FitOptions,
    ws: &mut Workspace,
) -> SegmentFit {
    let groove = opts.groove();
    let n = t_s.len().min(z_m.len());
    let prob = TrackProblem {
        t_s: &t_s[..n],
        z_m: &z_m[..n],
        t_ref_s: init.t_ref_s,
        groove,
    };
    let mut bounds = model_bounds();
    bounds.free[Z0] = init.free.z0;
    bounds.free[V0] = init.free.v0;
    bounds.free[VA0] = init.free.va0;
    bounds.free[MU] = init.free.mu;
    bounds.free[TD] = init.free.t_drag;
    let mut x0 = [0.0; NP];
    x0[Z0] = init.z0_m;
    x0[T0] = 0.0;
    x0[V0] = init.v0_mps;
    x0[VA0] = init.va0_mps;
    x0[MU] = init.mu;
    x0[TD] = init.t_drag_s;
    let fit = fit_robust(&prob, x0, &bounds, &settings(opts), ws);
    to_segment_fit(&fit, init.t_ref_s, n, groove)
}

fn to_segment_fit(
    fit: &RobustFit,
    t_ref_s: f64,
    n: usize,
    groove: crate::physics::Groove,
) -> SegmentFit {
    let x = fit.x;
    let t1_s = Prepared::new(&x, groove).map_or(f64::NAN, |m| m.t1_s);
    SegmentFit {
        t_ref_s,
        z0_m: x[Z0],
        v0_mps: x[V0],
        va0_mps: x[VA0],
        mu: x[MU],
        t_drag_s: x[TD],
        se: SegmentSe {
            z0_m: fit.se[Z0],
            v0_mps: fit.se[V0],
            va0_mps: fit.se[VA0],
            mu: fit.se[MU],
            t_drag_s: fit.se[TD],
        },
        t1_s,
        rms_m: fit.rms,
        scale_m: fit.scale,
        n_frames: n,
        n_used: fit.n_used,
        n_outliers: fit.n_outliers,
        iterations: fit.iterations,
        termination: fit.termination,
    }
}
