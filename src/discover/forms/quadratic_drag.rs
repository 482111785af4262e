//! A quadratic drag: a = −v/T − c·v|v|, c of either sign (the total must still oppose the motion).

use super::form::{carried_force, p, with_drag_times, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::Term;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct QuadraticDrag;


impl Form for QuadraticDrag {
    fn offer(_n_materials: usize, _rg: &Ranges) -> Option<Self> {
        Some(QuadraticDrag)
    }
    fn name(&self) -> &'static str {
        "quadratic_drag"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("velocity_dependent_drag")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "quadratic: a = -v/T - c v|v|".into()
    }
    fn size_name(&self) -> &'static str {
        "a quadratic drag coefficient"
    }
    /// The drag's part quadratic in speed, and what it adds at 5 cm/s.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, value, with_error};
        let c = value(f, "c_per_m")?;
        Some(format!(
            "the drag grows {} than linearly with speed, beside −v/T a part c·v|v| with c = {} /m ({} m/s² at 5 cm/s)",
            if c >= 0.0 { "faster" } else { "slower" },
            with_error(f, "c_per_m", 1.0)?,
            num(c * 0.05 * 0.05)
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![p("c_per_m", 0.0, -1e3, 1e3, 1e-2)]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.quad = x[0];
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        with_drag_times(self, f)
    }
    fn speed_dependent(&self) -> bool {
        true
    }
    fn physical_only_within_data(&self, x: &[f64]) -> bool {
        x[0] < 0.0
    }
    fn detection_size(
        &self,
        se: &[f64],
        _typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some(("c_per_m", "1/m", se[0], 1.0))
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        carried_force(f, &["c_per_m"], |v| Term::QuadraticDrag { c_per_m: v[0] })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quadratic drag with c < 0 pushes the particle above 1/(T|c|): physical only over the
    /// speeds the runs reach, and held back in a tie; with c ≥ 0 it opposes the motion at every
    /// speed.
    #[test]
    fn a_quadratic_drag_that_weakens_with_speed_is_physical_only_within_the_data() {
        assert!(QuadraticDrag.physical_only_within_data(&[-28.0]));
        assert!(!QuadraticDrag.physical_only_within_data(&[0.0]));
        assert!(!QuadraticDrag.physical_only_within_data(&[5.0]));
    }
}
