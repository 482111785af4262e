//! One single run's fitted curve under the physics discovery accepted: the material's μ and drag
//! from the refit (`under_accepted_physics.json`), every other accepted term at discovery's value,
//! and the run's own start (z0, t0, v0) fitted to its samples with that model held.

use super::inputs::ReportData;
use super::trajectory::Sample;
use crate::discover::candidate::OwnValues;
use crate::lsq::dense_fit::minimize;
use crate::lsq::lm::{ParamSpec, Scale, Settings};
use crate::physics::{simulate, Model, State};

/// The model of `material` under the accepted physics, when the refit accepted terms and has
/// this material's single-run numbers; None otherwise (or when the terms cannot be carried).
/// The material's μ and drag line are the refit's, every other accepted term discovery's.
pub fn model_of(d: &ReportData, material: &str) -> Option<Model> {
    let u = d.under_accepted.as_ref().filter(|u| u.accepted)?;
    let sm = u.single.as_ref()?.materials.get(material)?;
    let diag = d.diagnosis.as_ref()?;
    let mut lab = crate::discover::forms::in_the_lab(crate::fit::refit::accepted_terms(diag));
    let mut own = OwnValues::of(&diag.model_parameters, material).ok()?;
    own.mu = sm.mu;
    if let Some(line) = &sm.t_line {
        own.t_s = line.intercept_s;
        if lab.drag_slope.is_some() {
            lab.drag_slope = Some(line.slope_s_per_mps);
        }
    }
    crate::discover::pairs::single_run_physics(&own, &lab, d.groove).ok()
}

/// Positions under `model` at the samples' times, from z0 and v0 at the kick, t0 before the
/// first frame (the fits' convention z(t) = z(t + t0 after the kick)).
fn positions(model: &Model, s: &[Sample], z0: f64, t0: f64, v0: f64) -> Vec<f64> {
    let tt: Vec<f64> = s.iter().map(|p| p.t_s + t0).collect();
    let init = State {
        z_m: z0,
        v_mps: v0,
        va_mps: 0.0,
    };
    simulate(model, init, &tt).z_m
}

/// The fitted positions under `model` at each sample, started from the baseline's (z0, t0, v0):
/// a robust least-squares fit of the run's start with the physics held. None when the fit
/// gives no finite curve.
pub fn fit_curve(model: &Model, s: &[Sample], start: (f64, f64, f64)) -> Option<Vec<f64>> {
    let (z0, t0, v0) = start;
    if s.len() < 4 || !(z0.is_finite() && t0.is_finite() && v0.is_finite()) || v0 == 0.0 {
        return None;
    }
    let dt = s
        .windows(2)
        .map(|w| w[1].t_s - w[0].t_s)
        .fold(f64::INFINITY, f64::min)
        .max(1e-7);
    let specs = [
        ParamSpec {
            start: z0,
            lower: z0 - 5e-4,
            upper: z0 + 5e-4,
            step: 1e-8,
        },
        ParamSpec {
            start: t0.max(0.0),
            lower: 0.0,
            upper: t0.max(0.0) + 20.0 * dt,
            step: 1e-3 * dt,
        },
        ParamSpec {
            start: v0,
            lower: v0.min(0.25 * v0).min(4.0 * v0),
            upper: v0.max(0.25 * v0).max(4.0 * v0),
            step: 1e-6 * v0.abs().max(1e-4),
        },
    ];
    let settings = Settings {
        max_iter: 60,
        rounds: 2,
        huber_k: 2.5,
        scale: Scale::Mad { floor: 1e-8 },
        cost_tol: 1e-6,
        rel_tol: 1e-12,
        damping: 1e-3,
    };
    let fit = minimize(
        |p, out| {
            let z = positions(model, s, p[0], p[1], p[2]);
            for ((o, zf), smp) in out.iter_mut().zip(&z).zip(s) {
                *o = zf - smp.z_obs_m;
            }
        },
        s.len(),
        &specs,
        &settings,
    );
    let p = &fit.params;
    let z = positions(model, s, p[0], p[1], p[2]);
    z.iter().all(|v| v.is_finite()).then_some(z)
}

/// The run's curve under the accepted physics at the samples `s`, when there is one.
pub fn curve(d: &ReportData, fit: &super::singles::SingleRow, s: &[Sample]) -> Option<Vec<f64>> {
    let model = model_of(d, &fit.material)?;
    let first = s.first()?;
    let t0 = fit.t0_s.unwrap_or(0.0);
    // the baseline's start; without its z0, the baseline's curve at the first frame
    let z0 = fit.z0_m.unwrap_or(first.z_fit_m);
    fit_curve(&model, s, (z0, t0, fit.v0_mps.value))
}

/// The chapter's groove under a constant μ and a saturating drag, for the tests below.
#[cfg(test)]
fn saturating(mu: f64, t0_s: f64, tp: f64) -> Model {
    Model {
        groove: crate::physics::Groove::CHAPTER,
        friction: crate::physics::Friction::Constant { mu },
        variation: Default::default(),
        terms: vec![crate::physics::Term::SaturatingDrag {
            t0_s,
            tp_s_per_mps: tp,
        }],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_start_is_fitted_with_the_physics_held() {
        let truth = saturating(0.33, 0.054, 2.66);
        let t: Vec<f64> = (0..300).map(|i| i as f64 * 1e-4).collect();
        let (z0, t0, v0) = (1.2e-3, 4e-5, 0.03);
        let base: Vec<Sample> = t
            .iter()
            .map(|&t_s| Sample {
                t_s,
                z_obs_m: 0.0,
                z_fit_m: 0.0,
                rolling: false,
            })
            .collect();
        let z = positions(&truth, &base, z0, t0, v0);
        let s: Vec<Sample> = base
            .iter()
            .zip(&z)
            .map(|(p, &z)| Sample { z_obs_m: z, ..*p })
            .collect();
        // started off by 20 µm, 60 µs and 10 % in v0, the fit finds the run again
        let got = fit_curve(&truth, &s, (z0 + 2e-5, t0 + 6e-5, v0 * 1.1)).unwrap();
        let worst = got
            .iter()
            .zip(&z)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 2e-8, "worst misfit {worst} m");
        assert_eq!(fit_curve(&truth, &s[..3], (z0, t0, v0)), None);
    }
}
