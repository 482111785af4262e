//! μ by the direction of motion: μ_m·(1 + δ·dir) (friction, not a force: it acts while sliding
//! and on the rolling hold only).

use super::form::{p, values_of, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::FrictionVariation;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionDirection;


impl Form for FrictionDirection {
    fn offer(_n_materials: usize, _rg: &Ranges) -> Option<Self> {
        Some(FrictionDirection)
    }
    fn name(&self) -> &'static str {
        "friction_direction"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("direction_dependent_friction")
    }
    fn place(&self) -> Place {
        Place::Friction
    }
    fn form(&self) -> String {
        "mu by direction: mu (1 + delta dir), while sliding and holding".into()
    }
    fn size_name(&self) -> &'static str {
        "a difference of friction by direction"
    }
    /// How much higher μ is one way than the other.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{value, with_error};
        let d = value(f, "delta_mu_rel")?;
        Some(format!(
            "μ is {} % higher moving {} and as much lower moving the other way, while sliding and holding",
            with_error(f, "delta_mu_rel", 1e2)?,
            if d >= 0.0 { "towards +z" } else { "towards −z" }
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![p("delta_mu_rel", 0.0, -0.9, 0.9, 1e-5)]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.variation.by_direction = x[0];
    }
    fn lab_friction(&self, f: &Finding) -> Option<FrictionVariation> {
        let v = values_of(f, &["delta_mu_rel"])?;
        Some(FrictionVariation {
            by_direction: v[0],
            ..FrictionVariation::default()
        })
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let mut out = BTreeMap::new();
        let d = f.x[0];
        out.insert("delta_mu_rel".into(), Estimate::new(d, f.se[0]));
        for (k, name) in f.materials.iter().enumerate() {
            let mu = f.global[k];
            out.insert(
                format!("mu_forward_{name}"),
                Estimate::new(mu * (1.0 + d), f64::NAN),
            );
            out.insert(
                format!("mu_backward_{name}"),
                Estimate::new(mu * (1.0 - d), f64::NAN),
            );
        }
        out
    }
}
