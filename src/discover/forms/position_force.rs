//! A force in z as a Fourier series over the observed range: a(z) = Σ_k a_k sin(πk(z−z_min)/span) +
//! b_k cos(πk(z−z_min)/span), k = 1..harmonics.

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::physics::Term;
use std::collections::BTreeMap;
use std::f64::consts::PI;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct PositionForce {
    pub harmonics: usize,
    pub z_min_m: f64,
    pub span_m: f64,
}


impl Form for PositionForce {
    fn name(&self) -> &'static str {
        "fourier_z"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_dependent_force")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        format!(
            "a(z) = Fourier series over the observed z range, {} harmonics",
            self.harmonics
        )
    }
    fn size_name(&self) -> &'static str {
        "a periodic force in z"
    }
    /// The force's largest value over the range it is fitted on.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, value};
        let (lo, span) = (value(f, "z_min_m")?, value(f, "span_m")?);
        Some(format!(
            "a force along the groove of up to {} m/s² between z = {} and {} mm, fixed in the lab",
            num(value(f, "peak_accel_mps2")?),
            num(1e3 * lo),
            num(1e3 * (lo + span))
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        (1..=self.harmonics)
            .flat_map(|k| {
                [
                    p(&format!("sin{k}_mps2"), 0.0, -5.0, 5.0, 1e-4),
                    p(&format!("cos{k}_mps2"), 0.0, -5.0, 5.0, 1e-4),
                ]
            })
            .collect()
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        for kk in 0..self.harmonics {
            let (a, b) = (x[2 * kk], x[2 * kk + 1]);
            let kz = PI * (kk + 1) as f64 / self.span_m;
            // a sin(u) + b cos(u) = A sin(u + atan2(b, a)), u = kz (z − z_min)
            let amp = a.hypot(b);
            if amp > 0.0 {
                e.model.position.push((amp, kz, b.atan2(a) - kz * self.z_min_m));
            }
        }
    }
    fn position_dependent(&self) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let (z_min_m, span_m, harmonics) = (self.z_min_m, self.span_m, self.harmonics);
        let mut peak: f64 = 0.0;
        for j in 0..=200 {
            let z = z_min_m + span_m * j as f64 / 200.0;
            let a: f64 = (0..harmonics)
                .map(|k| {
                    let u = PI * (k + 1) as f64 * (z - z_min_m) / span_m;
                    f.x[2 * k] * u.sin() + f.x[2 * k + 1] * u.cos()
                })
                .sum();
            peak = peak.max(a.abs());
        }
        let mut out = BTreeMap::new();
        out.insert("peak_accel_mps2".into(), Estimate::new(peak, f64::NAN));
        out.insert("z_min_m".into(), Estimate::new(z_min_m, 0.0));
        out.insert("span_m".into(), Estimate::new(span_m, 0.0));
        for k in 0..2 * harmonics {
            out.insert(f.params[k].name.clone(), Estimate::new(f.x[k], f.se[k]));
        }
        out
    }
    fn reads(&self, f: &Finding) -> bool {
        Some(f.effect.as_str()) == self.effect() && f.form.starts_with("a(z) = Fourier series")
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        Some(Err(format!(
            "the accepted model has a position force ({}) the pair fit does not carry",
            f.form
        )))
    }
}
