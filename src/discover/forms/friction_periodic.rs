//! μ periodic along the lab: μ·(1 + A sin(k(z − z_ref)) + … ), its wavenumber k searched — a
//! texture or machining pattern of the groove that friction feels while the particle slides and
//! a rolling particle does not.

use super::form::{p, values_of, Entry, Fitted, Form, ParamInfo, Place, Search};
use super::wavelength;
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::Ranges;
use crate::discover::screen_sums::{Trial, Typical};
use crate::physics::FrictionVariation;
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
    /// The amplitude and wavelength of μ's variation along the groove.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::with_error;
        Some(format!(
            "μ varies by ± {} % along the groove, periodic with a wavelength of {} mm fixed in the lab, while sliding",
            with_error(f, "delta_mu_rel", 1e2)?,
            with_error(f, "wavelength_m", 1e3)?
        ))
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
    fn lab_friction(&self, f: &Finding) -> Option<FrictionVariation> {
        let v = values_of(f, &["delta_mu_rel", "wavelength_m", "phase_rad"])?;
        Some(FrictionVariation {
            periodic: [v[0], TAU / v[1], v[2]],
            ..FrictionVariation::default()
        })
    }
    fn position_dependent(&self) -> bool {
        true
    }
    /// Its amplitudes: μ varying by 90 % of itself is no texture.
    fn refused_at_bound(&self, param: usize, _lower: bool) -> bool {
        param > 0
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let [amp, wavelength, phase] =
            wavelength::amplitude_wavelength_phase(f.x, f.se, self.z_ref_m);
        let mut out = BTreeMap::new();
        out.insert("delta_mu_rel".into(), amp);
        out.insert("wavelength_m".into(), wavelength);
        out.insert("phase_rad".into(), phase);
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
        let z_ref = self.z_ref_m;
        wavelength::search(s, (self.k_lo, self.k_hi), z_ref, |p| {
            let fr = &p.track.friction;
            (!fr.iter().all(|f| *f == 0.0)).then(|| fr.clone())
        })
    }
    fn bound_note(
        &self,
        _k: usize,
        x: f64,
        info: &ParamInfo,
        lower: bool,
        _materials: &[String],
    ) -> Option<String> {
        wavelength::bound_note(x, info, lower)
    }
    fn scale(&self) -> Option<(usize, &'static str)> {
        Some((0, "wavelength"))
    }
    fn scale_at_end(&self, x: f64, lower: bool) -> Option<String> {
        wavelength::at_fine_end(x, lower)
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
