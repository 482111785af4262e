//! One single run's observed positions beside its fitted baseline, with the phase of each sample.
//!
//! The fitted curve comes from the `simulate` stage's residuals when present (the pipeline's own
//! re-simulation); otherwise it is evaluated here from the fitted parameters with the physics
//! module's closed form, taking the fit's convention z(t) = z0 + Δz(t + t0), t0 = time from the kick
//! to the first frame.

use super::singles::SingleRow;
use super::value::{as_num, field};
use crate::physics::{Baseline, Groove, Phase};
use crate::recording::Recording;
use serde_json::Value;

/// One sample: time (s), observed z (m), fitted z (m), whether the fit is rolling there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    pub t_s: f64,
    pub z_obs_m: f64,
    pub z_fit_m: f64,
    pub rolling: bool,
}

/// The samples of a run from its residuals JSON (columns `{t_s: [..], ..}` or rows `[{t_s, ..}]`).
pub fn from_residuals(v: &Value) -> Option<Vec<Sample>> {
    let v = match field(v, &["samples", "rows", "residuals", "particles", "tracks"]) {
        // a list of particles, each with its own samples: particle 0 (the single particle)
        Some(Value::Array(a)) if a.first().is_some_and(|p| p.get("particle").is_some()) => &a[0],
        Some(inner) => inner,
        None => v,
    };
    const T: [&str; 2] = ["t_s", "t"];
    const ZO: [&str; 3] = ["z_obs_m", "z_obs", "z_m"];
    const ZF: [&str; 5] = ["z_fit_m", "z_sim_m", "z_fit", "z_sim", "z_model_m"];
    let rolling = |p: Option<&Value>| {
        p.and_then(Value::as_str)
            .is_some_and(|s| s.eq_ignore_ascii_case("rolling") || s.eq_ignore_ascii_case("rest"))
    };
    if let Some(rows) = v.as_array() {
        let out: Vec<Sample> = rows
            .iter()
            .filter_map(|r| {
                Some(Sample {
                    t_s: super::value::num(r, &T)?,
                    z_obs_m: super::value::num(r, &ZO)?,
                    z_fit_m: super::value::num(r, &ZF)?,
                    rolling: rolling(r.get("phase")),
                })
            })
            .collect();
        return (!out.is_empty()).then_some(out);
    }
    let col = |names: &[&str]| field(v, names).and_then(Value::as_array);
    let (t, zo, zf) = (col(&T)?, col(&ZO)?, col(&ZF)?);
    let ph = col(&["phase"]);
    let out: Vec<Sample> = (0..t.len().min(zo.len()).min(zf.len()))
        .filter_map(|i| {
            Some(Sample {
                t_s: as_num(&t[i])?,
                z_obs_m: as_num(&zo[i])?,
                z_fit_m: as_num(&zf[i])?,
                rolling: rolling(ph.and_then(|p| p.get(i))),
            })
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
                rolling: !matches!(phase, Phase::Sliding),
            }
        })
        .collect();
    Some(out)
}
