//! μ along the lab: μ_m·(1 + p₁P₁(x) + p₂P₂(x)), x over the observed stretch.

use super::form::{p, values_of, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::physics::FrictionVariation;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionPosition {
    pub z_mid_m: f64,
    pub half_span_m: f64,
}


impl Form for FrictionPosition {
    /// μ varying along the observed stretch of groove.
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(FrictionPosition {
            z_mid_m: rg.z_ref(),
            half_span_m: 0.5 * rg.span(),
        })
    }
    fn name(&self) -> &'static str {
        "friction_position"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_dependent_friction")
    }
    fn place(&self) -> Place {
        Place::Friction
    }
    fn form(&self) -> String {
        "mu(z) along the groove: mu (1 + p1 P1(x) + p2 P2(x)), fixed in the lab".into()
    }
    fn size_name(&self) -> &'static str {
        "a variation of friction along the groove"
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![
            p("p1_rel", 0.0, -0.9, 0.9, 1e-5),
            p("p2_rel", 0.0, -0.9, 0.9, 1e-5),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.variation.z_mid_m = self.z_mid_m;
        e.model.variation.half_span_m = self.half_span_m;
        e.model.variation.by_position = [x[0], x[1]];
    }
    fn lab_friction(&self, f: &Finding) -> Option<FrictionVariation> {
        let v = values_of(f, &["p1_rel", "p2_rel", "z_lo_m", "z_hi_m"])?;
        Some(FrictionVariation {
            z_mid_m: 0.5 * (v[2] + v[3]),
            half_span_m: 0.5 * (v[3] - v[2]),
            by_position: [v[0], v[1]],
            ..FrictionVariation::default()
        })
    }
    fn position_dependent(&self) -> bool {
        true
    }
    fn refused_at_bound(&self, _param: usize, _lower: bool) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let (z_mid_m, half_span_m) = (self.z_mid_m, self.half_span_m);
        let est = Estimate::new;
        let mut out = BTreeMap::new();
        let (p1, p2) = (f.x[0], f.x[1]);
        let (mut peak, mut at) = (0.0f64, z_mid_m);
        for j in 0..=200 {
            let x = -1.0 + 2.0 * j as f64 / 200.0;
            let d = p1 * x + p2 * 0.5 * (3.0 * x * x - 1.0);
            if d.abs() > peak.abs() {
                peak = d;
                at = z_mid_m + half_span_m * x;
            }
        }
        out.insert("p1_rel".into(), est(p1, f.se[0]));
        out.insert("p2_rel".into(), est(p2, f.se[1]));
        out.insert("peak_rel".into(), est(peak, f64::NAN));
        out.insert("z_at_peak_m".into(), est(at, 0.0));
        out.insert("z_lo_m".into(), est(z_mid_m - half_span_m, 0.0));
        out.insert("z_hi_m".into(), est(z_mid_m + half_span_m, 0.0));
        out
    }
}
