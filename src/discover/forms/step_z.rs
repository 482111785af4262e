//! A step in the force along the groove, fixed in the lab (the joint of two pieces of groove
//! at different slopes): a(z) = A·(1 + tanh((z − z_s)/(2w)))/2, its place and width searched.
//!
//! The step is searched only where runs go on both sides of it (a quarter of the observed
//! stretch in from either end): a step near an end is a constant force over nearly all the runs,
//! which is the tilt.

use super::form::{carried_force, p, Entry, Fitted, Form, ParamInfo, Place, Search};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::{Ranges, Wanted};
use crate::discover::response::Prepared;
use crate::discover::screen_sums::{best_of, coherent_scan, most_sensitive, Trial, Typical};
use crate::physics::{step_shape, Term, Variable};
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct StepZ {
    pub z_lo: f64,
    pub z_hi: f64,
    pub w_lo: f64,
    pub w_hi: f64,
}

impl StepZ {
    /// Trial (place, width): widths doubling from the narrowest up to `w_hi`, places every
    /// half width between `z_lo` and `z_hi`.
    fn trials(&self) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        let mut w = self.w_lo;
        while w <= self.w_hi {
            let mut z = self.z_lo;
            while z <= self.z_hi {
                out.push((z, w));
                z += 0.5 * w.max(0.02 * (self.z_hi - self.z_lo));
            }
            w *= 2.0;
        }
        out
    }
}

impl Form for StepZ {
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        let q = 0.25 * rg.span();
        Some(StepZ {
            z_lo: rg.z_lo + q,
            z_hi: rg.z_hi - q,
            w_lo: rg.w_lo(),
            w_hi: rg.span() / 16.0,
        })
    }
    fn name(&self) -> &'static str {
        "step_z"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_dependent_force")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "step in z: a = A (1 + tanh((z - z_s) / 2w)) / 2, fixed in the lab".into()
    }
    fn size_name(&self) -> &'static str {
        "a step in the force along the groove"
    }
    /// The force that acts beyond the step, and where the step is.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{towards, value, with_error};
        Some(format!(
            "beyond z = {} mm a force of {} m/s² {} acts, its edge {} mm wide, fixed in the lab",
            with_error(f, "z_step_m", 1e3)?,
            with_error(f, "step_mps2", 1.0)?,
            towards(value(f, "step_mps2")?),
            with_error(f, "width_m", 1e3)?
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        let s = self;
        vec![
            p("step_mps2", 0.0, -5.0, 5.0, 1e-4),
            p("z_step_m", 0.5 * (s.z_lo + s.z_hi), s.z_lo, s.z_hi, 1e-8),
            p("width_m", (s.w_lo * s.w_hi).sqrt(), s.w_lo, s.w_hi, 1e-8),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.terms.push(Term::StepForce {
            amp_mps2: x[0],
            z_step_m: x[1],
            width_m: x[2],
        });
    }
    fn position_dependent(&self) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let est = Estimate::new;
        let mut out = BTreeMap::new();
        out.insert("step_mps2".into(), est(f.x[0], f.se[0]));
        out.insert("peak_accel_mps2".into(), est(f.x[0].abs(), f.se[0]));
        out.insert("z_step_m".into(), est(f.x[1], f.se[1]));
        out.insert("width_m".into(), est(f.x[2], f.se[2]));
        out
    }
    fn searched(&self) -> bool {
        true
    }
    /// At each trial (place, width) the runs' responses to a unit step, regressed on the
    /// prepared runs coherently (one height shared by every run).
    fn search(&self, s: &Search) -> (Option<Trial>, Option<Typical>) {
        let (prep, v, reps) = (s.prep, s.v, s.reps.clone());
        let trials = self.trials();
        let column = |p: &Prepared, &(zs, w): &(f64, f64)| {
            let z = p.track.variable(Variable::Z);
            let f: Vec<f64> = z.iter().map(|zz| step_shape((zz - zs) / w)).collect();
            // a run that never comes near the step's upper side feels nothing
            f.iter()
                .any(|x| *x > 1e-3)
                .then(|| vec![p.column(p.track.respond_values(&f))])
        };
        let out: Vec<Option<Trial>> = coherent_scan(prep, v, 1, reps.clone(), &trials, column)
        .into_iter()
        .zip(&trials)
        .map(|(t, &(zs, w))| {
            let (lr, b, var) = t?;
            Some((lr, vec![b[0], zs, w], vec![var[0].sqrt(), f64::NAN, f64::NAN]))
        })
        .collect();
        let typical = most_sensitive(&out, |se| se[0]).map(|(se, t)| Typical::Se {
            se,
            at: format!("at z = {:.2} mm", 1e3 * t.1[1]),
        });
        (best_of(out, reps.len()), typical)
    }
    fn wanted(&self) -> Wanted {
        Wanted::default()
    }
    fn scale(&self) -> Option<(usize, &'static str)> {
        Some((2, "width"))
    }
    fn detection_size(
        &self,
        se: &[f64],
        typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some(("step_mps2", "m/s²", typical_se.unwrap_or(se[0]), 1.0))
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        carried_force(f, &["step_mps2", "z_step_m", "width_m"], |v| Term::StepForce {
            amp_mps2: v[0],
            z_step_m: v[1],
            width_m: v[2],
        })
    }
}
