//! A localized force fixed in the lab (a bump, a defect): a(z) = A·exp(−(z − z_c)²/(2w²)), its
//! centre and width searched.

use super::form::{carried_force, p, Entry, Fitted, Form, ParamInfo, Place, Search};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::{bump_column, bump_trials, Proposals, Ranges, Wanted};
use crate::discover::response::Prepared;
use crate::discover::screen_sums::{best_of, coherent_scan, most_sensitive, Trial, Typical};
use crate::physics::Term;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Localized {
    pub z_lo: f64,
    pub z_hi: f64,
    pub w_lo: f64,
    pub w_hi: f64,
}


impl Form for Localized {
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(Localized {
            z_lo: rg.z_lo,
            z_hi: rg.z_hi,
            w_lo: rg.w_lo(),
            w_hi: 0.5 * rg.span(),
        })
    }
    fn name(&self) -> &'static str {
        "localized"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_dependent_force")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "localized in z: a = A exp(-(z - z_c)^2 / (2 w^2)), fixed in the lab".into()
    }
    fn size_name(&self) -> &'static str {
        "a localized force"
    }
    /// The bump's size, direction, place and width.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{towards, value, with_error};
        Some(format!(
            "a force of {} m/s² {} localized at z = {} mm over a width of {} mm, fixed in the lab",
            with_error(f, "amplitude_mps2", 1.0)?,
            towards(value(f, "amplitude_mps2")?),
            with_error(f, "centre_m", 1e3)?,
            with_error(f, "width_m", 1e3)?
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        let s = self;
        vec![
            p("amplitude_mps2", 0.0, -5.0, 5.0, 1e-4),
            p("centre_m", 0.5 * (s.z_lo + s.z_hi), s.z_lo, s.z_hi, 1e-8),
            p("width_m", (s.w_lo * s.w_hi).sqrt(), s.w_lo, s.w_hi, 1e-8),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.terms.push(Term::LocalizedForce {
            amp_mps2: x[0],
            centre_m: x[1],
            width_m: x[2],
        });
    }
    fn position_dependent(&self) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let est = Estimate::new;
        let mut out = BTreeMap::new();
        out.insert("amplitude_mps2".into(), est(f.x[0], f.se[0]));
        out.insert("peak_accel_mps2".into(), est(f.x[0].abs(), f.se[0]));
        out.insert("centre_m".into(), est(f.x[1], f.se[1]));
        out.insert("width_m".into(), est(f.x[2], f.se[2]));
        out
    }
    fn searched(&self) -> bool {
        true
    }
    fn search(&self, s: &Search) -> (Option<Trial>, Option<Typical>) {
        let (prep, v, reps) = (s.prep, s.v, s.reps.clone());
        let trials = bump_trials(s.rg, self.w_lo, self.w_hi);
        let column = |p: &Prepared, &(c, w): &(f64, f64)| bump_column(p, c, w).map(|x| vec![x]);
        let out: Vec<Option<Trial>> = coherent_scan(prep, v, 1, reps.clone(), &trials, column)
        .into_iter()
        .zip(&trials)
        .map(|(t, &(c, w))| {
            let (lr, b, var) = t?;
            Some((
                lr,
                vec![b[0], c, w],
                vec![var[0].sqrt(), f64::NAN, f64::NAN],
            ))
        })
        .collect();
        let typical = most_sensitive(&out, |se| se[0]).map(|(se, t)| Typical::Se {
            se,
            at: format!(
                "of width {:.3} mm at z = {:.2} mm",
                1e3 * t.1[2],
                1e3 * t.1[1]
            ),
        });
        (best_of(out, reps.len()), typical)
    }
    fn wanted(&self) -> Wanted {
        Wanted {
            bump: true,
            ..Wanted::default()
        }
    }
    fn proposed(&self, p: &Proposals) -> Vec<Vec<f64>> {
        p.bumps.iter().map(|b| b.to_vec()).collect()
    }
    fn scale(&self) -> Option<(usize, &'static str)> {
        Some((2, "width"))
    }
    fn scale_at_end(&self, x: f64, lower: bool) -> Option<String> {
        lower.then(|| {
            format!(
                "its width ran to the narrowest the search allows ({:.3} mm)",
                1e3 * x
            )
        })
    }
    fn detection_size(
        &self,
        se: &[f64],
        typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some(("amplitude_mps2", "m/s²", typical_se.unwrap_or(se[0]), 1.0))
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        carried_force(f, &["amplitude_mps2", "centre_m", "width_m"], |v| Term::LocalizedForce {
            amp_mps2: v[0],
            centre_m: v[1],
            width_m: v[2],
        })
    }
}
