//! The forms of missing physics: one file per form, and the registry that lists them.
//!
//! Files of this folder:
//!
//! - `form.rs`: What a term is (`Form`): place, parameters, entry into the physics, screen, report
//! - `quadratic_drag.rs`: A quadratic drag, a = −v/T − c·v|v|
//! - `saturating_drag.rs`: A saturating drag, a = −v/(T0 + T'|v|)
//! - `rolling_resistance.rs`: A rolling resistance, a = −c·g·sign(v)
//! - `groove_tilt.rs`: A groove tilt, a = −g·sin α
//! - `velocity_friction.rs`: μ of the slip speed, saturating, v_c per material
//! - `friction_slip.rs`: μ of the slip speed, linear about a reference speed
//! - `friction_stribeck.rs`: μ falling with the slip speed from a static value (Stribeck)
//! - `friction_direction.rs`: μ by the direction of motion
//! - `friction_position.rs`: μ along the groove
//! - `friction_periodic.rs`: μ periodic along the groove (wavelength searched)
//! - `wavelength.rs`: What the two forms periodic in z share (their search, amplitude and phase)
//! - `words.rs`: Numbers in a finding's sentence (`Form::in_words`)
//! - `distortion.rs`: The camera's positions distorted across the image (a measurement)
//! - `periodic_z.rs`: A force periodic in z, fixed in the lab (wavelength searched)
//! - `localized.rs`: A localized force fixed in the lab (centre and width searched)
//! - `step_z.rs`: A step in the force along the groove, fixed in the lab (place and width searched)
//! - `time_periodic.rs`: A force periodic in time with a phase per run (frequency searched)
//! - `time_common.rs`: A force periodic in time with one phase for every run, locked to the kick
//! - `position_force.rs`: A force in z as a Fourier series over the observed range
//! - `spline.rs`: The nonparametric fallback, a spline in one variable (`unexplained`)
//! - `speed_drift_t.rs`: Probe: T drifting with the run's speed
//! - `speed_drift_mu.rs`: Probe: μ drifting with the run's speed
//! - `direction_asymmetry.rs`: Probe: μ and T differing by direction
//!
//! A term of a joint model is an `Extra`: one variant per form, each holding its form's type,
//! and it derefs to `dyn Form`, so the rest of discovery asks the form (its parameters, how it
//! enters the integrator, its screen, its sentence) and never matches on which form it is.
//! Adding a form is its file and its line in `registry!` below. `read` turns a finding of
//! `diagnosis.json` back into the form that wrote it, for the checks that carry discovery's
//! accepted model to other experiments.

mod form;
mod wavelength;
pub mod words;

pub use self::form::{as_fitted, p, Entry, Fitted, Form, ParamInfo, Place, Reading, Search};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::{FrictionVariation, Term};

/// The registry: each line names a form's file and type. It declares the file's module and
/// builds `Extra` (a variant per form), the library (`offered`), the probes and the readers.
macro_rules! registry {
    ($(self::$file:ident::$ty:ident),* $(,)?) => {
        $(mod $file;)*
        $(pub use self::$file::$ty;)*

        /// One extra term of a joint model: a form of the registry with its settings.
        #[derive(Clone, Debug, PartialEq)]
        pub enum Extra {
            $($ty($ty)),*
        }

        impl std::ops::Deref for Extra {
            type Target = dyn Form;
            fn deref(&self) -> &(dyn Form + 'static) {
                match self {
                    $(Extra::$ty(f) => f),*
                }
            }
        }

        $(impl From<$ty> for Extra {
            fn from(f: $ty) -> Extra {
                Extra::$ty(f)
            }
        })*

        /// Every form the library offers for data of these ranges, in registry order.
        fn offers(n_materials: usize, rg: &Ranges) -> Vec<Extra> {
            let mut out = Vec::new();
            $(out.extend($ty::offer(n_materials, rg).map(Extra::from));)*
            out
        }

        /// The drift probes about the runs' median speed, in registry order.
        pub fn probes(v_ref_mps: f64) -> Vec<Extra> {
            let mut out = Vec::new();
            $(out.extend($ty::probe(v_ref_mps).map(Extra::from));)*
            out
        }

        /// One term of each form, with default settings (to read findings by).
        fn prototypes() -> Vec<Extra> {
            vec![$(Extra::$ty($ty::default())),*]
        }
    };
}

registry! {
    self::quadratic_drag::QuadraticDrag,
    self::saturating_drag::SaturatingDrag,
    self::rolling_resistance::RollingResistance,
    self::groove_tilt::GrooveTilt,
    self::velocity_friction::VelocityFriction,
    self::friction_slip::FrictionSlip,
    self::friction_stribeck::FrictionStribeck,
    self::friction_direction::FrictionDirection,
    self::friction_position::FrictionPosition,
    self::friction_periodic::FrictionPeriodic,
    self::distortion::Distortion,
    self::periodic_z::PeriodicZ,
    self::localized::Localized,
    self::step_z::StepZ,
    self::time_periodic::TimePeriodic,
    self::time_common::TimeCommon,
    self::position_force::PositionForce,
    self::spline::Spline,
    self::speed_drift_t::SpeedDriftT,
    self::speed_drift_mu::SpeedDriftMu,
    self::direction_asymmetry::DirectionAsymmetry,
}

/// The library's forms of the effects `candidates` (ids of `EFFECTS`), in the order of the
/// candidates and, within an effect, of the registry.
pub fn library(candidates: &[String], n_materials: usize, rg: &Ranges) -> Vec<Extra> {
    let all = offers(n_materials, rg);
    candidates
        .iter()
        .flat_map(|c| {
            all.iter()
                .filter(move |e| e.effect() == Some(c.as_str()))
                .cloned()
        })
        .collect()
}

/// The names a material's drag time takes in the joint model (`t_s`, or a form's own, as `t0_s`
/// beside a saturating drag).
pub fn drag_time_names() -> Vec<&'static str> {
    let mut out = vec!["t_s"];
    out.extend(prototypes().iter().filter_map(|e| e.drag_time_name()));
    out
}

/// The form that wrote finding `f`, read back with what it holds; None for a finding no form
/// writes (differences between particles, the pair checks).
pub fn read(f: &Finding) -> Option<Reading> {
    prototypes()
        .into_iter()
        .find(|e| e.reads(f))
        .map(|e| {
            let drag_slope = e.lab_drag_slope(f);
            // a form that makes each material's T its T0 holds the slope beside it: without it,
            // the finding would be carried as a linear drag
            let lab_force = match (e.drag_time_name(), drag_slope) {
                (Some(_), None) => Some(Err(format!(
                    "the accepted model has a drag ({}) whose finding gives no slope, which the pair fit does not carry",
                    f.form
                ))),
                _ => e.lab_force(f),
            };
            Reading {
                form: e.name(),
                place: e.place(),
                lab_force,
                lab_friction: e.lab_friction(f),
                drag_slope,
            }
        })
}

/// Finding `f` in physical words, by the form that wrote it; None for a finding no form writes
/// or a form without words.
pub fn in_words(f: &Finding) -> Option<String> {
    prototypes().into_iter().find(|e| e.reads(f))?.in_words(f)
}

/// What another experiment in the same groove (the collision runs) carries of discovery's
/// accepted model, read back from its findings by their forms.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InTheLab {
    /// The forces on any particle in the groove (a drag, a resistance, the tilt, a force fixed
    /// in z or locked to the kick), in the findings' order; Err says why a finding cannot be
    /// carried.
    pub forces: Vec<Result<Term, String>>,
    /// The friction's variation, each form setting its own part.
    pub friction: FrictionVariation,
    /// The slope T' of a drag time growing with speed (each material's T0 its own drag time).
    pub drag_slope: Option<Estimate>,
}

/// What `findings` (the accepted ones) put in the lab for another experiment to carry.
pub fn in_the_lab<'a>(findings: impl IntoIterator<Item = &'a Finding>) -> InTheLab {
    let readings: Vec<Reading> = findings.into_iter().filter_map(read).collect();
    InTheLab {
        forces: readings
            .iter()
            .filter_map(|r| r.lab_force.clone())
            .collect(),
        friction: readings
            .iter()
            .filter_map(|r| r.lab_friction)
            .fold(FrictionVariation::default(), FrictionVariation::with),
        drag_slope: readings.iter().find_map(|r| r.drag_slope),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::diagnosis::{Effect, Evidence, ModelScore};
    use crate::discover::candidate::Spec;
    use crate::physics::Variable;
    use std::collections::BTreeMap;

    fn ranges() -> Ranges {
        Ranges {
            z_lo: 0.001,
            z_hi: 0.021,
            dz_med: 1e-5,
            lambda_min_m: 2e-4,
            duration_s: 0.1,
            f_max_hz: 2500.0,
            v_ref_mps: 0.1,
        }
    }

    /// One term of every form of the registry, with settings as the library gives them.
    fn every_form() -> Vec<Extra> {
        let rg = ranges();
        let mut all = offers(2, &rg);
        all.push(
            PositionForce {
                harmonics: 2,
                z_min_m: rg.z_lo,
                span_m: rg.span(),
            }
            .into(),
        );
        all.push(
            Spline {
                variable: Variable::Z,
                lo: rg.z_lo,
                dx: rg.span() / 16.0,
                segments: 16,
                penalty: 1.0,
            }
            .into(),
        );
        all.extend(probes(0.1));
        all
    }

    /// Values inside every parameter's range, off where the term vanishes.
    fn values(e: &Extra) -> Vec<f64> {
        e.params()
            .iter()
            .map(|p| p.lo + 0.61 * (p.hi - p.lo))
            .collect()
    }

    /// The finding a fitted term is written as (effect, form, parameters).
    fn written(e: &Extra, spec: &Spec, g: &[f64], materials: &[String]) -> Finding {
        let i = spec.extras.len() - 1;
        let off = spec.extra_offset(i);
        let se = vec![0.01; g.len()];
        let params = spec.global_params(materials);
        Finding {
            effect: e.effect().unwrap_or("probe").into(),
            accepted: true,
            form: e.form(),
            parameters: e.parameters(&Fitted {
                x: &g[off..],
                se: &se[off..],
                global: g,
                global_se: &se,
                n_materials: spec.n_materials,
                materials,
                params: &params[off..],
            }),
            evidence: Evidence::default(),
            where_: BTreeMap::new(),
            baseline: ModelScore::default(),
            extended: ModelScore::default(),
        }
    }

    /// Every form's finding is said in physical words with its numbers, by the form that wrote
    /// it (read back from the finding); a probe, which is never a finding, has none.
    #[test]
    fn every_form_says_its_finding_in_words() {
        let materials = vec!["316".to_string(), "440c".to_string()];
        let base = Spec {
            n_materials: 2,
            s: 0.58,
            k: 2.5,
            extras: vec![],
        };
        for e in &every_form() {
            let spec = base.with(e.clone());
            let mut g = vec![0.3, 0.35, 0.08, 0.09];
            g.extend(values(e));
            let f = written(e, &spec, &g, &materials);
            let words = in_words(&f);
            if e.effect().is_none() {
                assert_eq!(words, None, "{}: a probe is no finding", e.name());
                continue;
            }
            let w = words.unwrap_or_else(|| panic!("{}: no words for its finding", e.name()));
            assert!(
                w.chars().any(|c| c.is_ascii_digit()) && !w.contains('—') && !w.contains("NaN"),
                "{}: {w}",
                e.name()
            );
        }
        // the numbers are the finding's: a μ along the groove of p1 = 0.1, p2 = 0.02 runs from
        // 8 % below μ at one end to 12 % above at the other, ± 10 % about its middle
        let e: Extra = FrictionPosition {
            z_mid_m: 0.006,
            half_span_m: 0.005,
        }
        .into();
        let spec = base.with(e.clone());
        let f = written(&e, &spec, &[0.3, 0.35, 0.08, 0.09, 0.1, 0.02], &materials);
        let w = in_words(&f).unwrap();
        assert!(
            w.starts_with(
                "μ varies by ± 10.0 ± 1.00 % along the groove between z = 1.00 and 11.0 mm"
            ),
            "{w}"
        );
        assert!(w.contains("12.0 % higher at z = 11.0 mm"), "{w}");
    }

    /// Every form's finding reads back as that form, in its place; a force fixed in the lab reads
    /// back as the very force the fitted term put in the physics (the same acceleration at every
    /// z), and a probe, which is never a finding, reads as none.
    #[test]
    fn every_form_reads_back_from_its_finding() {
        let materials = vec!["316".to_string(), "440c".to_string()];
        let all = every_form();
        let mut names: Vec<&str> = all.iter().map(|e| e.name()).collect();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), all.len(), "every form has a name of its own");
        assert_eq!(
            all.len(),
            prototypes().len(),
            "every registered form is tried"
        );
        let base = Spec {
            n_materials: 2,
            s: 0.58,
            k: 2.5,
            extras: vec![],
        };
        let mut g0 = vec![0.3, 0.35, 0.08, 0.09];
        for e in &all {
            let spec = base.with(e.clone());
            g0.truncate(4);
            let mut g = g0.clone();
            g.extend(values(e));
            let f = written(e, &spec, &g, &materials);
            let reading = read(&f);
            let Some(effect) = e.effect() else {
                assert_eq!(reading, None, "{}: a probe is no finding", e.name());
                continue;
            };
            let r = reading.unwrap_or_else(|| panic!("{}: its finding is not read", e.name()));
            assert_eq!(r.form, e.name());
            assert_eq!(r.place, e.place());
            assert_eq!(Effect::from_id(effect).unwrap().place(), e.place().id());
            // the force held as read back (a drag's slope making each material's T its T0)
            let mut held = base.sim_model(&g0, 0, 0.1).to_physics();
            if let Some(tp) = r.drag_slope {
                for t in &mut held.terms {
                    if let Term::LinearDrag { t_s } = *t {
                        *t = Term::SaturatingDrag {
                            t0_s: t_s,
                            tp_s_per_mps: tp.value,
                        };
                    }
                }
            }
            match &r.lab_force {
                Some(Ok(term)) => held.terms.push(term.clone()),
                Some(Err(why)) => assert!(why.contains("does not carry"), "{why}"),
                // every force reads back or says why not: checked below
                None => {}
            }
            if matches!(r.lab_force, Some(Ok(_))) || r.drag_slope.is_some() {
                let with = spec.sim_model(&g, 0, 0.1).to_physics();
                for j in 0..=40 {
                    let z = 0.001 + 0.02 * j as f64 / 40.0;
                    for v in [-0.2, 0.1] {
                        let (a, b) = (with.accel(z, v, 0.01), held.accel(z, v, 0.01));
                        assert!((a - b).abs() < 1e-9, "{} at z = {z}: {a} vs {b}", e.name());
                    }
                }
            } else if e.place() == Place::Force && e.effect().is_some() {
                assert!(
                    matches!(r.lab_force, Some(Err(_))),
                    "{}: a force reads back with its force or says why not",
                    e.name()
                );
            }
            let fitted = spec.sim_model(&g, 0, 0.1).to_physics().variation;
            match r.lab_friction {
                Some(part) => {
                    let held = FrictionVariation::default().with(part);
                    assert!(
                        !held.is_none(),
                        "{}: its part of μ is no variation",
                        e.name()
                    );
                    for j in 0..=40 {
                        let z = 0.001 + 0.02 * j as f64 / 40.0;
                        for (dir, slip) in [(1.0, 0.0), (-1.0, 0.004), (1.0, 0.05)] {
                            let (a, b) = (fitted.factor(z, dir, slip), held.factor(z, dir, slip));
                            assert!((a - b).abs() < 1e-9, "{} at z = {z}: {a} vs {b}", e.name());
                        }
                    }
                }
                None => assert!(
                    fitted.is_none(),
                    "{}: a variation of μ reads back with its variation",
                    e.name()
                ),
            }
        }
    }

    /// The library offers each effect's forms, in the candidates' order.
    #[test]
    fn the_library_offers_the_forms_of_the_effects_asked() {
        let rg = ranges();
        let ask = |c: &[&str]| -> Vec<&'static str> {
            let c: Vec<String> = c.iter().map(|s| s.to_string()).collect();
            library(&c, 1, &rg).iter().map(|e| e.name()).collect()
        };
        assert_eq!(
            ask(&["position_dependent_force", "velocity_dependent_drag"]),
            [
                "periodic_z",
                "localized",
                "step_z",
                "quadratic_drag",
                "saturating_drag"
            ]
        );
        assert_eq!(
            ask(&["velocity_dependent_friction"]),
            ["velocity_friction", "friction_slip", "friction_stribeck"]
        );
        // every effect the stage can be asked for has a form
        for id in crate::discover::EFFECTS {
            assert!(!ask(&[id]).is_empty(), "{id}");
        }
    }
}
