//! A groove tilt: a = −g·sin α, of a fixed sign in the lab.

use super::form::{carried_force, p, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::discover::G_MPS2;
use crate::physics::Term;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct GrooveTilt;


impl Form for GrooveTilt {
    fn offer(_n_materials: usize, _rg: &Ranges) -> Option<Self> {
        Some(GrooveTilt)
    }
    fn name(&self) -> &'static str {
        "groove_tilt"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("groove_tilt")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    /// A constant force along the groove: the mean of a force map in z.
    fn map_variable(&self) -> Option<crate::physics::Variable> {
        Some(crate::physics::Variable::Z)
    }
    fn form(&self) -> String {
        "tilt: a = -g sin(alpha)".into()
    }
    fn size_name(&self) -> &'static str {
        "a groove tilt"
    }
    /// The tilt and the constant push it gives.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, towards, value, with_error};
        let a = -G_MPS2 * value(f, "alpha_deg")?.to_radians().sin();
        Some(format!(
            "the groove is tilted by {}°, a constant force of {} m/s² {}",
            with_error(f, "alpha_deg", 1.0)?,
            num(a.abs()),
            towards(a)
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![p("alpha_deg", 0.0, -10.0, 10.0, 1e-4)]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.tilt_mps2 = -G_MPS2 * x[0].to_radians().sin();
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let mut out = BTreeMap::new();
        out.insert("alpha_deg".into(), Estimate::new(f.x[0], f.se[0]));
        out
    }
    fn detection_size(
        &self,
        se: &[f64],
        _typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some(("alpha_deg", "°", se[0], 1.0))
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        carried_force(f, &["alpha_deg"], |v| Term::GrooveTilt { alpha_deg: v[0] })
    }
}
