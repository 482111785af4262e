//! A rolling resistance: a = −c·g·sign(v), c ≥ 0.

use super::form::{carried_force, p, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::discover::G_MPS2;
use crate::physics::Term;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct RollingResistance;


impl Form for RollingResistance {
    fn offer(_n_materials: usize, _rg: &Ranges) -> Option<Self> {
        Some(RollingResistance)
    }
    fn name(&self) -> &'static str {
        "rolling_resistance"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("rolling_resistance")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "constant resistance: a = -c g sign(v)".into()
    }
    fn size_name(&self) -> &'static str {
        "a rolling resistance"
    }
    /// A constant deceleration against the motion.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::with_error;
        Some(format!(
            "a constant force against the motion of {} m/s² (c = {} of g), while sliding and rolling",
            with_error(f, "deceleration_mps2", 1.0)?,
            with_error(f, "coefficient", 1.0)?
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![p("c", 0.0, 0.0, 0.5, 1e-6)]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.roll_c = x[0];
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let mut out = BTreeMap::new();
        out.insert(
            "deceleration_mps2".into(),
            Estimate::new(f.x[0] * G_MPS2, f.se[0] * G_MPS2),
        );
        out.insert("coefficient".into(), Estimate::new(f.x[0], f.se[0]));
        out
    }
    fn speed_dependent(&self) -> bool {
        true
    }
    fn detection_size(
        &self,
        se: &[f64],
        _typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some(("deceleration_mps2", "m/s²", se[0], G_MPS2))
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        carried_force(f, &["coefficient"], |v| Term::RollingResistance { c: v[0] })
    }
}
