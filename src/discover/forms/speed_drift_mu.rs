//! Probe: μ of a run = μ_m + γ·(|v0| − v_ref) (locates a mismatch; never a finding).

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::Estimate;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct SpeedDriftMu {
    pub v_ref_mps: f64,
}


impl Form for SpeedDriftMu {
    fn probe(v_ref_mps: f64) -> Option<Self> {
        Some(SpeedDriftMu { v_ref_mps })
    }
    fn name(&self) -> &'static str {
        "speed_drift_mu"
    }
    fn effect(&self) -> Option<&'static str> {
        None
    }
    fn place(&self) -> Place {
        Place::Probe
    }
    fn form(&self) -> String {
        "probe: mu drifts with |v0|".into()
    }
    fn size_name(&self) -> &'static str {
        "a drift"
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![p("dmu_dv_s_per_m", 0.0, -1e3, 1e3, 1e-4)]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.mu += x[0] * (e.v0_mps.abs() - self.v_ref_mps);
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        super::form::as_fitted(self, f)
    }
}
