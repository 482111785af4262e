//! A saturating drag: a = −v/(T0 + T'|v|), T' ≥ 0; the per-material T become T0.

use super::form::{p, with_drag_times, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct SaturatingDrag;


impl Form for SaturatingDrag {
    fn offer(_n_materials: usize, _rg: &Ranges) -> Option<Self> {
        Some(SaturatingDrag)
    }
    fn name(&self) -> &'static str {
        "saturating_drag"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("velocity_dependent_drag")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "saturating: a = -v/(T0 + T'|v|)".into()
    }
    fn size_name(&self) -> &'static str {
        "a saturating drag slope T'"
    }
    /// The drag time's growth with speed, and the drag times at rest.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, per_material, value, with_error};
        let tp = value(f, "tp_s_per_mps")?;
        Some(format!(
            "the drag saturates with speed, its time T growing from T0 = {} ms at rest by T' = {} s per m/s ({} ms more at 5 cm/s)",
            per_material(f, "t0_s", 1e3)?,
            with_error(f, "tp_s_per_mps", 1.0)?,
            num(tp * 0.05 * 1e3)
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![p("tp_s_per_mps", 0.0, 0.0, 1e3, 1e-3)]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.tp = Some(x[0]);
    }
    fn drag_time_name(&self) -> Option<&'static str> {
        Some("t0_s")
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        with_drag_times(self, f)
    }
    fn speed_dependent(&self) -> bool {
        true
    }
    fn detection_size(
        &self,
        se: &[f64],
        _typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some(("tp_s_per_mps", "s²/m", se[0], 1.0))
    }
    fn lab_drag_slope(&self, f: &Finding) -> Option<Estimate> {
        f.parameters.get("tp_s_per_mps").copied()
    }
}
