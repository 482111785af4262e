//! A force periodic in z, fixed in the lab (waviness): a(z) = s·sin(k(z − z_ref)) +
//! c·cos(k(z − z_ref)), its wavenumber k searched in [k_lo, k_hi].

use super::form::{carried_force, p, Entry, Fitted, Form, ParamInfo, Place, Search};
use super::wavelength;
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::{Proposals, Ranges, Wanted};
use crate::discover::screen_sums::{Trial, Typical};
use crate::physics::{Term, Variable};
use std::collections::BTreeMap;
use std::f64::consts::TAU;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct PeriodicZ {
    pub z_ref_m: f64,
    pub k_lo: f64,
    pub k_hi: f64,
}


impl Form for PeriodicZ {
    /// Wavelengths from twice the observed stretch down to the shortest the sampling resolves.
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(PeriodicZ {
            z_ref_m: rg.z_ref(),
            k_lo: 0.5 * TAU / rg.span(),
            k_hi: 1.5 * TAU / rg.lambda_min_m,
        })
    }
    fn name(&self) -> &'static str {
        "periodic_z"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("position_dependent_force")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "periodic in z: a = A sin(2 pi z / lambda + phi), fixed in the lab".into()
    }
    fn size_name(&self) -> &'static str {
        "a periodic force in z"
    }
    /// The force's amplitude and wavelength along the groove.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::with_error;
        Some(format!(
            "a force of amplitude {} m/s² periodic along the groove with a wavelength of {} mm, fixed in the lab",
            with_error(f, "amplitude_mps2", 1.0)?,
            with_error(f, "wavelength_m", 1e3)?
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        let (k_lo, k_hi) = (self.k_lo, self.k_hi);
        vec![
            p("k_per_m", 0.5 * (k_lo + k_hi), k_lo, k_hi, 1e-7 * k_hi),
            p("sin_mps2", 0.0, -5.0, 5.0, 1e-4),
            p("cos_mps2", 0.0, -5.0, 5.0, 1e-4),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        let (k, a, b) = (x[0], x[1], x[2]);
        let amp = a.hypot(b);
        if amp > 0.0 {
            e.model
                .position
                .push((amp, k, b.atan2(a) - k * self.z_ref_m));
        }
    }
    fn position_dependent(&self) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let [amp, wavelength, phase] =
            wavelength::amplitude_wavelength_phase(f.x, f.se, self.z_ref_m);
        let mut out = BTreeMap::new();
        out.insert("amplitude_mps2".into(), amp);
        out.insert("peak_accel_mps2".into(), amp);
        out.insert("wavelength_m".into(), wavelength);
        out.insert("phase_rad".into(), phase);
        out
    }
    fn searched(&self) -> bool {
        true
    }
    fn search(&self, s: &Search) -> (Option<Trial>, Option<Typical>) {
        wavelength::search(s, (self.k_lo, self.k_hi), self.z_ref_m, |p| {
            Some(vec![1.0; p.track.variable(Variable::Z).len()])
        })
    }
    fn wanted(&self) -> Wanted {
        Wanted {
            z: true,
            ..Wanted::default()
        }
    }
    fn proposed(&self, p: &Proposals) -> Vec<Vec<f64>> {
        p.z.iter()
            .flat_map(|s| s.peaks.iter())
            .map(|pk| vec![pk.omega, pk.coef[0], pk.coef[1]])
            .collect()
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
            "amplitude_mps2",
            "m/s²",
            typical_se.unwrap_or(se[1].hypot(se[2]) / 2f64.sqrt()),
            1.0,
        ))
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        carried_force(f, &["amplitude_mps2", "wavelength_m", "phase_rad"], |v| Term::PositionForce {
            amp_mps2: v[0],
            wavelength_m: v[1],
            phase_rad: v[2],
        })
    }
}
