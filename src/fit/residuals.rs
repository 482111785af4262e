//! Re-simulation of a run with its fitted parameters: per-frame residuals, phase and outlier flag
//! (the `simulate` stage's item, read by `compare` and the discovery).

use super::single::SingleFit;
use super::RunFit;
use crate::physics::{self, Baseline};
use crate::recording::{Experiment, Recording};
use serde::{Deserialize, Serialize};

/// The motion regime of the fitted model at a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    Sliding,
    Rolling,
    Rest,
}

impl From<physics::Phase> for Phase {
    fn from(p: physics::Phase) -> Phase {
        match p {
            physics::Phase::Sliding => Phase::Sliding,
            physics::Phase::Rolling => Phase::Rolling,
            physics::Phase::Rest => Phase::Rest,
        }
    }
}

/// Residuals of one run, column-wise (one entry per frame of the fitted track).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResiduals {
    pub run: String,
    pub material: String,
    pub experiment: Experiment,
    /// +1 for motion towards +z, −1 towards −z, 0 if not fitted.
    pub direction: i8,
    /// `ok`, or why there are no residuals (`skipped: …`).
    pub status: String,
    pub t_s: Vec<f64>,
    pub z_obs_m: Vec<f64>,
    pub z_fit_m: Vec<f64>,
    /// z_obs − z_fit.
    pub residual_m: Vec<f64>,
    /// Model velocity at the frame.
    pub v_fit_mps: Vec<f64>,
    pub phase: Vec<Phase>,
    /// |residual| above the fit's outlier cut (the fit left these frames out).
    pub outlier: Vec<bool>,
}

impl RunResiduals {
    fn empty(rec: &Recording, status: String) -> RunResiduals {
        RunResiduals {
            run: rec.info.run.clone(),
            material: rec.info.material.clone(),
            experiment: rec.info.experiment,
            direction: 0,
            status,
            t_s: vec![],
            z_obs_m: vec![],
            z_fit_m: vec![],
            residual_m: vec![],
            v_fit_mps: vec![],
            phase: vec![],
            outlier: vec![],
        }
    }
}

/// Re-simulate `rec` with its fit.
pub fn residuals(rec: &Recording, fit: &RunFit) -> RunResiduals {
    match fit {
        RunFit::Single(f) => single_residuals(rec, f),
        RunFit::Collision(_) => RunResiduals::empty(
            rec,
            "skipped: residuals of collision runs are not computed by the baseline re-simulation"
                .into(),
        ),
    }
}

fn single_residuals(rec: &Recording, f: &SingleFit) -> RunResiduals {
    let Some(track) = rec.track(0) else {
        return RunResiduals::empty(rec, "skipped: the run has no track of particle 0".into());
    };
    if f.status == "failed" {
        return RunResiduals::empty(
            rec,
            format!("skipped: the fit failed ({:?})", f.termination),
        );
    }
    let model = Baseline {
        mu: f.mu,
        t_drag_s: f.t_drag_s,
        groove: f.groove,
    };
    let n = track.t_s.len();
    let mut out = RunResiduals::empty(rec, "ok".into());
    out.direction = if f.v0_mps >= 0.0 { 1 } else { -1 };
    let cut = f.outlier_cut_m;
    for i in 0..n {
        let tau = (track.t_s[i] + f.t0_s).max(0.0);
        let (dz, v, phase) = model.state(f.v0_mps, tau);
        let z_fit = f.z0_m + dz;
        let res = track.z_m[i] - z_fit;
        out.t_s.push(track.t_s[i]);
        out.z_obs_m.push(track.z_m[i]);
        out.z_fit_m.push(z_fit);
        out.residual_m.push(res);
        out.v_fit_mps.push(v);
        out.phase.push(phase.into());
        out.outlier.push(cut.is_finite() && res.abs() > cut);
    }
    out
}
