//! Probe: μ_m + δμ·dir and T_m·(1 + δT·dir), dir = ±1 the run's direction (locates a mismatch;
//! never a finding).

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::Estimate;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct DirectionAsymmetry;


impl Form for DirectionAsymmetry {
    fn probe(_v_ref_mps: f64) -> Option<Self> {
        Some(DirectionAsymmetry)
    }
    fn name(&self) -> &'static str {
        "direction_asymmetry"
    }
    fn effect(&self) -> Option<&'static str> {
        None
    }
    fn place(&self) -> Place {
        Place::Probe
    }
    fn form(&self) -> String {
        "probe: mu and T differ by direction".into()
    }
    fn size_name(&self) -> &'static str {
        "a drift"
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![
            p("dmu_dir", 0.0, -0.5, 0.5, 1e-5),
            p("dT_rel_dir", 0.0, -0.9, 0.9, 1e-5),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        let dir = e.v0_mps.signum();
        e.mu += x[0] * dir;
        e.t_s *= 1.0 + x[1] * dir;
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        super::form::as_fitted(self, f)
    }
}
