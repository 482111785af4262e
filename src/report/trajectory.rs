//! One single run's observed positions beside its fitted baseline, with the phase of each sample.
//!
//! The fitted curve comes from the `simulate` stage's residuals when present (the pipeline's own
//! re-simulation); otherwise it is evaluated here from the fitted parameters with the physics
//! module's closed form, taking the fit's convention z(t) = z0 + Δz(t + t0), t0 = time from the kick
//! to the first frame.

use super::singles::SingleRow;
use crate::artifacts::residuals::{Phase, RunResiduals};
use crate::physics::{Baseline, Groove};
use crate::recording::Recording;

/// One sample: time (s), observed z (m), fitted z (m), whether the fit is rolling there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub t_s: f64,
    pub z_obs_m: f64,
    pub z_fit_m: f64,
    pub rolling: bool,
}

/// The samples of particle 0 of a run from its re-simulation residuals (frames with a number).
pub fn from_residuals(r: &RunResiduals) -> Option<Vec<Sample>> {
    let n = r.t_s.len().min(r.z_obs_m.len()).min(r.z_fit_m.len());
    let out: Vec<Sample> = (0..n)
        .filter(|&i| r.particle.get(i).is_none_or(|&p| p == 0))
        .filter(|&i| r.t_s[i].is_finite() && r.z_obs_m[i].is_finite() && r.z_fit_m[i].is_finite())
        .map(|i| Sample {
            t_s: r.t_s[i],
            z_obs_m: r.z_obs_m[i],
            z_fit_m: r.z_fit_m[i],
            rolling: r
                .phase
                .get(i)
                .is_some_and(|p| matches!(p, Phase::Rolling | Phase::Rest)),
        })
        .collect();
    (!out.is_empty()).then_some(out)
}

/// The samples of a run evaluated from its fitted parameters (needs z0 and t0 in the fit JSON).
pub fn from_fit(rec: &Recording, fit: &SingleRow, groove: Groove) -> Option<Vec<Sample>> {
    let track = rec.tracks.first()?;
    let (z0, t0) = (fit.z0_m?, fit.t0_s.unwrap_or(0.0));
    let model = Baseline {
        mu: fit.mu.value,
        t_drag_s: fit.t_drag_s.value,
        groove,
    };
    let out = track
        .t_s
        .iter()
        .zip(&track.z_m)
        .map(|(&t, &z)| {
            let (dz, _v, phase) = model.state(fit.v0_mps.value, t + t0);
            Sample {
                t_s: t,
                z_obs_m: z,
                z_fit_m: z0 + dz,
                rolling: !matches!(phase, crate::physics::Phase::Sliding),
            }
        })
        .collect();
    Some(out)
}
