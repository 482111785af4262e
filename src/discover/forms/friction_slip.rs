//! μ of the slip speed, linear: μ_m·(1 + β(|u|/u_ref − 1)), rising or falling, about the runs'
//! median early speed.

use super::form::{p, values_of, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::FrictionVariation;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionSlip {
    pub u_ref_mps: f64,
}


impl Form for FrictionSlip {
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(FrictionSlip {
            u_ref_mps: rg.v_ref_mps,
        })
    }
    fn name(&self) -> &'static str {
        "friction_slip"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("velocity_dependent_friction")
    }
    fn place(&self) -> Place {
        Place::Friction
    }
    fn form(&self) -> String {
        "mu(u) = mu (1 + beta (|u|/u_ref - 1)), u slip speed".into()
    }
    fn size_name(&self) -> &'static str {
        "a slip-speed dependence of friction"
    }
    /// μ's change with slip speed, per 10 mm/s.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, value};
        let d = value(f, "dmu_rel_per_mps")?;
        Some(format!(
            "μ {} linearly with slip speed, by {} % of itself per 10 mm/s, while sliding",
            if d >= 0.0 { "rises" } else { "falls" },
            num(d.abs())
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![p("beta_rel", 0.0, -0.95, 5.0, 1e-5)]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.variation.u_ref_mps = self.u_ref_mps;
        e.model.variation.by_slip = x[0];
    }
    fn lab_friction(&self, f: &Finding) -> Option<FrictionVariation> {
        let v = values_of(f, &["beta_rel", "u_ref_mps"])?;
        Some(FrictionVariation {
            u_ref_mps: v[1],
            by_slip: v[0],
            ..FrictionVariation::default()
        })
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let u_ref = self.u_ref_mps;
        let mut out = BTreeMap::new();
        out.insert("beta_rel".into(), Estimate::new(f.x[0], f.se[0]));
        out.insert("u_ref_mps".into(), Estimate::new(u_ref, 0.0));
        out.insert(
            "dmu_rel_per_mps".into(),
            Estimate::new(f.x[0] / u_ref, f.se[0] / u_ref),
        );
        out
    }
}
