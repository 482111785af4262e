//! Re-simulation of a run with its fitted parameters: per-frame residuals, phase and outlier flag
//! (the `simulate` stage's item, read by `compare` and the discovery). Single runs use the fitted
//! baseline; collision runs each fitted piece between impacts (both particles).

use super::collision::CollisionFit;
use super::single::SingleFit;
use super::RunFit;
use crate::artifacts::run_fit::FitStatus;
use crate::physics::{self, Baseline, Groove};
use crate::recording::Recording;

pub use crate::artifacts::residuals::{Phase, RunResiduals};

impl From<physics::Phase> for Phase {
    fn from(p: physics::Phase) -> Phase {
        match p {
            physics::Phase::Sliding => Phase::Sliding,
            physics::Phase::Rolling => Phase::Rolling,
            physics::Phase::Rest => Phase::Rest,
        }
    }
}

impl RunResiduals {
    fn empty(rec: &Recording, status: String) -> RunResiduals {
        RunResiduals {
            run: rec.info.run.clone(),
            material: rec.info.material.clone(),
            experiment: rec.info.experiment,
            direction: 0,
            status,
            particle: vec![],
            t_s: vec![],
            z_obs_m: vec![],
            z_fit_m: vec![],
            residual_m: vec![],
            v_fit_mps: vec![],
            phase: vec![],
            outlier: vec![],
            impacts_s: vec![],
        }
    }
}

/// Re-simulate `rec` with its fit. `groove` is used for collision runs (a single-run fit records
/// its own).
pub fn residuals(rec: &Recording, fit: &RunFit, groove: Groove) -> RunResiduals {
    match fit {
        RunFit::Single(f) => single_residuals(rec, f),
        RunFit::Collision(c) => collision_residuals(rec, c, groove),
    }
}

/// One re-simulated frame.
struct Sample {
    particle: u32,
    t_s: f64,
    z_obs_m: f64,
    z_fit_m: f64,
    v_fit_mps: f64,
    phase: Phase,
}

impl RunResiduals {
    /// Append a frame; it is an outlier if its residual exceeds `cut_m`.
    fn push(&mut self, f: Sample, cut_m: f64) {
        let res = f.z_obs_m - f.z_fit_m;
        self.particle.push(f.particle);
        self.t_s.push(f.t_s);
        self.z_obs_m.push(f.z_obs_m);
        self.z_fit_m.push(f.z_fit_m);
        self.residual_m.push(res);
        self.v_fit_mps.push(f.v_fit_mps);
        self.phase.push(f.phase);
        self.outlier.push(cut_m.is_finite() && res.abs() > cut_m);
    }
}

/// Collision runs: each particle's frames re-simulated piece by piece from the fitted state at
/// the start of each piece (between impacts), with the run's μ and the piece's drag time. Frames
/// outside every fitted piece are left out.
fn collision_residuals(rec: &Recording, c: &CollisionFit, groove: Groove) -> RunResiduals {
    if c.segments.is_empty() || !c.mu_pg.value.is_finite() {
        return RunResiduals::empty(
            rec,
            format!("skipped: the collision fit has no pieces ({:?})", c.status),
        );
    }
    let mut out = RunResiduals::empty(rec, "ok".into());
    out.direction = if c.direction >= 0 { 1 } else { -1 };
    out.impacts_s = c.impacts.iter().map(|im| im.t_s.value).collect();
    let cut = 5.0 * c.noise_m;
    for track in &rec.tracks {
        for i in 0..track.t_s.len() {
            let t = track.t_s[i];
            let Some(st) = c.state_at(track.particle, t, groove) else {
                continue;
            };
            let sample = Sample {
                particle: track.particle,
                t_s: t,
                z_obs_m: track.z_m[i],
                z_fit_m: st.z_m,
                v_fit_mps: st.v_mps,
                phase: st.phase.into(),
            };
            out.push(sample, cut);
        }
    }
    if out.t_s.is_empty() {
        out.status = "skipped: no frame lies in a fitted piece".into();
    }
    out
}

fn single_residuals(rec: &Recording, f: &SingleFit) -> RunResiduals {
    let Some(track) = rec.track(0) else {
        return RunResiduals::empty(rec, "skipped: the run has no track of particle 0".into());
    };
    if f.status == FitStatus::Failed {
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
    let mut out = RunResiduals::empty(rec, "ok".into());
    out.direction = if f.v0_mps >= 0.0 { 1 } else { -1 };
    let cut = f.outlier_cut_m;
    for (&t, &z) in track.t_s.iter().zip(&track.z_m) {
        let (dz, v, phase) = model.state(f.v0_mps, (t + f.t0_s).max(0.0));
        let sample = Sample {
            particle: 0,
            t_s: t,
            z_obs_m: z,
            z_fit_m: f.z0_m + dz,
            v_fit_mps: v,
            phase: phase.into(),
        };
        out.push(sample, cut);
    }
    out
}
