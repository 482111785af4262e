//! Fit of a single run: the closed-form baseline (μ, T) with nuisance offset z0, kick time t0
//! (within the first frame) and initial velocity v0 (its sign is the direction), robustly.

use super::model::{Prepared, MU, NP, T0, TD, V0, Z0};
use super::options::FitOptions;
use super::quality::{early_speed, suspect_reasons};
use super::segment::{model_bounds, settings};
use super::start::single_start;
use super::track_problem::TrackProblem;
use super::track_problem::{Bounds, RobustFit, Workspace};
use crate::lsq::robust::fit_robust;
use crate::lsq::Termination;
use crate::physics::Groove;
use crate::recording::Recording;

use crate::artifacts::run_fit::FitStatus;
pub use crate::artifacts::run_fit::SingleFit;

/// Fit particle 0 of a single run.
pub fn fit_single(rec: &Recording, opts: &FitOptions) -> SingleFit {
    fit_single_with(rec, opts, &mut Workspace::default())
}

/// [`fit_single`] with caller-owned buffers.
pub fn fit_single_with(rec: &Recording, opts: &FitOptions, ws: &mut Workspace) -> SingleFit {
    let empty = (Vec::new(), Vec::new());
    let (t, z) = rec
        .track(0)
        .map_or((&empty.0, &empty.1), |tr| (&tr.t_s, &tr.z_m));
    let mut fit = fit_track(t, z, rec.info.fps, opts, ws);
    fit.run = rec.info.run.clone();
    fit.material = rec.info.material.clone();
    fit
}

/// Which restarts a suspect first fit gets ([`Restarts::Grid`] in [`fit_track`]; `None` exists
/// to measure what the restarts add, tests/trackers.rs).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Restarts {
    /// Keep the first fit.
    None,
    /// Free fits from a grid of starts: v0 from the first frames' speed (a local quadratic) and
    /// from the data's start, μ at 0.1, 0.3 and 0.6, T at the data's start and ten times it.
    /// (Holding v0 at the first frames' speed while the rest settles, then releasing it, recovered
    /// no more runs on the pixel-locked null, nor did a linear or soft-L1 loss; see the docs of `fit`.)
    Grid,
}

/// Fit the frames of one single-particle track recorded at `fps`; `run` and `material` are left empty.
pub fn fit_track(
    t_s: &[f64],
    z_m: &[f64],
    fps: f64,
    opts: &FitOptions,
    ws: &mut Workspace,
) -> SingleFit {
    fit_track_using(t_s, z_m, fps, opts, ws, Restarts::Grid)
}

/// [`fit_track`] with a chosen set of restarts.
pub fn fit_track_using(
    t_s: &[f64],
    z_m: &[f64],
    fps: f64,
    opts: &FitOptions,
    ws: &mut Workspace,
    restarts: Restarts,
) -> SingleFit {
    let n = t_s.len().min(z_m.len());
    let groove = opts.groove();
    if n < opts.min_frames.max(8) || fps.is_nan() || fps <= 0.0 {
        return failed(n, groove, Termination::TooFewPoints);
    }
    let (t_s, z_m) = (&t_s[..n], &z_m[..n]);
    let x0 = single_start(t_s, z_m, fps, groove, &mut ws.scratch);
    let mut bounds = model_bounds();
    bounds.free = [true, true, true, false, true, true];
    bounds.hi[T0] = 1.0 / fps;
    if x0[V0] > 0.0 {
        bounds.lo[V0] = 1e-7;
    } else {
        bounds.hi[V0] = -1e-7;
    }
    let prob = TrackProblem {
        t_s,
        z_m,
        t_ref_s: 0.0,
        groove,
    };
    let set = settings(opts);
    let first = fit_robust(&prob, x0, &bounds, &set, ws);
    let reasons =
        |f: &RobustFit| suspect_reasons(t_s, z_m, &f.x, &f.se, &bounds.lo, &bounds.hi, groove);
    let mut why = reasons(&first);
    let mut r = first;
    let mut restarted = false;
    if r.termination.is_converged() && !why.is_empty() && restarts != Restarts::None {
        // The clean restart with the smallest RMS wins; none clean: the first fit stands.
        let v_early = early_speed(t_s, z_m).filter(|v| v.signum() == x0[V0].signum());
        let mut best: Option<RobustFit> = None;
        let mut consider = |f: RobustFit| {
            if f.termination.is_converged()
                && reasons(&f).is_empty()
                && best.as_ref().is_none_or(|b| f.rms < b.rms)
            {
                best = Some(f);
            }
        };
        for x in grid(x0, v_early, &bounds) {
            consider(fit_robust(&prob, x, &bounds, &set, ws));
        }
        if let Some(f) = best {
            why = Vec::new();
            r = f;
            restarted = true;
        }
    }
    let x = r.x;
    let t1_s = Prepared::new(&x, groove).map_or(f64::NAN, |m| m.t1_s);
    let status = FitStatus::of(r.termination, !why.is_empty());
    SingleFit {
        run: String::new(),
        material: String::new(),
        groove,
        v0_mps: x[V0],
        v0_se: r.se[V0],
        mu: x[MU],
        mu_se: r.se[MU],
        t_drag_s: x[TD],
        t_drag_se: r.se[TD],
        z0_m: x[Z0],
        z0_se: r.se[Z0],
        t0_s: x[T0],
        t0_se: r.se[T0],
        t1_s,
        rms_m: r.rms,
        scale_m: r.scale,
        outlier_cut_m: opts.outlier_sigma * r.scale,
        n_frames: n,
        n_used: r.n_used,
        n_outliers: r.n_outliers,
        iterations: r.iterations,
        termination: r.termination,
        status,
        suspect: if r.termination.is_converged() {
            why
        } else {
            Vec::new()
        },
        restarted,
    }
}

/// The grid of [`Restarts::Grid`]: v0 from the first frames' speed (when it has the
/// direction of the data's start) and the data's start, each with μ at 0.1, 0.3 and 0.6 and T at
/// the data's start and ten times it.
fn grid(x0: [f64; NP], v_early: Option<f64>, bounds: &Bounds) -> Vec<[f64; NP]> {
    let mut v0s = vec![x0[V0]];
    if let Some(v) = v_early.filter(|v| v.abs() > 1e-6) {
        v0s.insert(0, v);
    }
    let mut out = Vec::new();
    for &v0 in &v0s {
        for mu in [0.1, 0.3, 0.6] {
            for td in [x0[TD], 10.0 * x0[TD]] {
                let mut x = x0;
                x[V0] = v0.clamp(bounds.lo[V0], bounds.hi[V0]);
                x[MU] = mu;
                x[TD] = td.clamp(bounds.lo[TD], bounds.hi[TD]);
                out.push(x);
            }
        }
    }
    out
}

fn failed(n: usize, groove: Groove, why: Termination) -> SingleFit {
    let nan = f64::NAN;
    SingleFit {
        run: String::new(),
        material: String::new(),
        groove,
        v0_mps: 0.0,
        v0_se: None,
        mu: 0.0,
        mu_se: None,
        t_drag_s: 0.0,
        t_drag_se: None,
        z0_m: 0.0,
        z0_se: None,
        t0_s: 0.0,
        t0_se: None,
        t1_s: nan,
        rms_m: nan,
        scale_m: nan,
        outlier_cut_m: nan,
        n_frames: n,
        n_used: 0,
        n_outliers: 0,
        iterations: 0,
        termination: why,
        status: FitStatus::of(why, false),
        suspect: Vec::new(),
        restarted: false,
    }
}
