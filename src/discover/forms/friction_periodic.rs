//! μ periodic along the lab: μ·(1 + A sin(k(z − z_ref)) + … ), its wavenumber k searched — a
//! texture or machining pattern of the groove that friction feels while the particle slides and
//! a rolling particle does not.

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place, Search};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::discover::screen_sums::{best_of, coherent, most_sensitive, Trial, Typical};
use crate::discover::spectral::k_grid;
use crate::physics::Variable;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::f64::consts::TAU;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrictionPeriodic {
    pub z_ref_m: f64,
    pub k_lo: f64,
    pub k_hi: f64,
}

/// The form's label, which `reads` recognises.
const LABEL: &str = "periodic mu(z) along the groove";

impl Form for FrictionPeriodic {
    /// Wavelengths from twice the observed stretch down to the shortest the sampling resolves,
    /// as for a periodic force.
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(FrictionPeriodic {
            z_ref_m: rg.z_ref(),
            k_lo: 0.5 * TAU / rg.span(),
            k_hi: 1.5 * TAU / rg.lambda_min_m,
        })
    }
    fn name(&self) -> &'static str {
        "friction_periodic"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_dependent_friction")
    }
    fn place(&self) -> Place {
        Place::Friction
    }
    fn form(&self) -> String {
        format!("{LABEL}: mu (1 + A sin(2 pi z / lambda + phi)), fixed in the lab")
    }
    fn size_name(&self) -> &'static str {
        "a periodic variation of friction along the groove"
    }
    fn params(&self) -> Vec<ParamInfo> {
        let (k_lo, k_hi) = (self.k_lo, self.k_hi);
        vec![
            p("k_per_m", 0.5 * (k_lo + k_hi), k_lo, k_hi, 1e-7 * k_hi),
            p("sin_rel", 0.0, -0.9, 0.9, 1e-5),
            p("cos_rel", 0.0, -0.9, 0.9, 1e-5),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        let (k, a, b) = (x[0], x[1], x[2]);
        // a sin(u) + b cos(u) = A sin(u + atan2(b, a)), u = k (z − z_ref)
        e.model.variation.periodic = [a.hypot(b), k, b.atan2(a) - k * self.z_ref_m];
    }
    fn position_dependent(&self) -> bool {
        true
    }
    /// Its amplitudes: μ varying by 90 % of itself is no texture.
    fn refused_at_bound(&self, param: usize) -> bool {
        param > 0
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let est = Estimate::new;
        let (k, a, b) = (f.x[0], f.x[1], f.x[2]);
        let (sk, sa, sb) = (f.se[0], f.se[1], f.se[2]);
        let amp = a.hypot(b).max(1e-300);
        let amp_se = ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp;
        let phase = (b.atan2(a) - k * self.z_ref_m).rem_euclid(TAU);
        let phase_se =
            (((b * sa).powi(2) + (a * sb).powi(2)).sqrt() / (amp * amp)).hypot(self.z_ref_m * sk);
        let mut out = BTreeMap::new();
        out.insert("delta_mu_rel".into(), est(amp, amp_se));
        out.insert("wavelength_m".into(), est(TAU / k, TAU * sk / (k * k)));
        out.insert("phase_rad".into(), est(phase, phase_se));
        out
    }
    fn reads(&self, f: &Finding) -> bool {
        Some(f.effect.as_str()) == self.effect() && f.form.starts_with(LABEL)
    }
    fn searched(&self) -> bool {
        true
    }
    /// Each trial wavenumber's two columns are the runs' responses to friction's own
    /// acceleration while sliding times sin and cos of k(z − z_ref): a relative change of μ
    /// there, nothing while rolling.
    fn search(&self, s: &Search) -> (Option<Trial>, Option<Typical>) {
        let (prep, v, rg, reps) = (s.prep, s.v, s.rg, s.reps.clone());
        let z_ref = self.z_ref_m;
        let ks: Vec<f64> = k_grid(rg.span(), rg.lambda_min_m)
            .into_iter()
            .filter(|k| *k >= self.k_lo && *k <= self.k_hi)
            .collect();
        let trials: Vec<Option<Trial>> = ks
            .par_iter()
            .map(|&k| {
                let (lr, b, var) = coherent(prep, v, 2, reps.clone(), &[], |p| {
                    let z = p.track.variable(Variable::Z);
                    let fr = &p.track.friction;
                    if fr.iter().all(|f| *f == 0.0) {
                        return None;
                    }
                    let wave = |g: fn(f64) -> f64| -> Vec<f64> {
                        z.iter()
                            .zip(fr)
                            .map(|(z, f)| f * g(k * (z - z_ref)))
                            .collect()
                    };
                    Some(vec![
                        p.column(p.track.respond_values(&wave(f64::sin))),
                        p.column(p.track.respond_values(&wave(f64::cos))),
                    ])
                })?;
                Some((
                    lr,
                    vec![k, b[0], b[1]],
                    vec![f64::NAN, var[0].sqrt(), var[1].sqrt()],
                ))
            })
            .collect();
        let typical = most_sensitive(&trials, |se| se[1].hypot(se[2]) / 2f64.sqrt()).map(
            |(se, t)| Typical::Se {
                se,
                at: format!("at a wavelength of {:.3} mm", 1e3 * TAU / t.1[0]),
            },
        );
        (best_of(trials, reps.len()), typical)
    }
    fn bound_note(
        &self,
        _k: usize,
        x: f64,
        info: &ParamInfo,
        lower: bool,
        _materials: &[String],
    ) -> Option<String> {
        (info.name == "k_per_m").then(|| format!(
            "the wavelength ({:.3} mm) is the {} the search allows: the data resolve no {} period, so wavelength and amplitude describe the observed stretch rather than a period",
            1e3 * TAU / x,
            if lower { "longest" } else { "shortest" },
            if lower { "longer" } else { "shorter" }
        ))
    }
    fn scale(&self) -> Option<(usize, &'static str)> {
        Some((0, "wavelength"))
    }
    fn scale_at_fine_end(&self, x: f64, lower: bool) -> Option<String> {
        (!lower).then(|| {
            format!(
                "its wavelength ran to the shortest the search allows ({:.3} mm)",
                1e3 * TAU / x
            )
        })
    }
    fn detection_size(
        &self,
        se: &[f64],
        typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some((
            "delta_mu_rel",
            "",
            typical_se.unwrap_or(se[1].hypot(se[2]) / 2f64.sqrt()),
            1.0,
        ))
    }
}
