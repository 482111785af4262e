//! The camera distorts positions: z_meas = z + a₂P₂(x) + a₃P₃(x), x over the observed stretch (the
//! linear part is a length scale, which μ and T absorb exactly).

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::discover::sim;
use std::collections::BTreeMap;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Distortion {
    pub z_mid_m: f64,
    pub half_span_m: f64,
}

impl Distortion {

    fn at(&self, x: &[f64]) -> sim::Distortion {
        sim::Distortion {
            z_mid_m: self.z_mid_m,
            half_span_m: self.half_span_m,
            a2_m: x[0],
            a3_m: x[1],
        }
    }
}

impl Form for Distortion {
    /// The camera's positions distorted over the observed stretch.
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(Distortion {
            z_mid_m: rg.z_ref(),
            half_span_m: 0.5 * rg.span(),
        })
    }
    fn name(&self) -> &'static str {
        "distortion"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_distortion")
    }
    fn place(&self) -> Place {
        Place::Measurement
    }
    fn form(&self) -> String {
        "distortion: z_meas = z + a2 P2(x) + a3 P3(x), x across the image".into()
    }
    fn size_name(&self) -> &'static str {
        "a distortion of the measured positions"
    }
    /// How far the positions are misread, which changes no motion.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, value};
        Some(format!(
            "the measured positions are shifted by up to {} µm across the image, beyond a length scale and an offset, in the measurement and not the motion",
            num(1e6 * value(f, "peak_shift_m")?.abs())
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        vec![
            p("a2_m", 0.0, -1e-3, 1e-3, 1e-9),
            p("a3_m", 0.0, -1e-3, 1e-3, 1e-9),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.distortion = Some(self.at(x));
    }
    fn position_dependent(&self) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let d = self.at(f.x);
        let peak = (0..=200)
            .map(|j| {
                let z = self.z_mid_m + self.half_span_m * (-1.0 + 2.0 * j as f64 / 200.0);
                d.measured(z) - z
            })
            .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
        let mut out = BTreeMap::new();
        out.insert("a2_m".into(), Estimate::new(f.x[0], f.se[0]));
        out.insert("a3_m".into(), Estimate::new(f.x[1], f.se[1]));
        out.insert("peak_shift_m".into(), Estimate::new(peak, f64::NAN));
        out
    }
}
