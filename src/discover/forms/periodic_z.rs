//! A force periodic in z, fixed in the lab (waviness): a(z) = s·sin(k(z − z_ref)) +
//! c·cos(k(z − z_ref)), its wavenumber k searched in [k_lo, k_hi].

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place, Search};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::{Proposals, Ranges, Wanted};
use crate::discover::screen_sums::{best_of, coherent, most_sensitive, Trial, Typical};
use crate::discover::spectral::k_grid;
use crate::physics::{Term, Variable};
use rayon::prelude::*;
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
        let est = Estimate::new;
        let mut out = BTreeMap::new();
        let (k, a, b) = (f.x[0], f.x[1], f.x[2]);
        let (sk, sa, sb) = (f.se[0], f.se[1], f.se[2]);
        let amp = a.hypot(b).max(1e-300);
        let amp_se = ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp;
        out.insert("amplitude_mps2".into(), est(amp, amp_se));
        out.insert("peak_accel_mps2".into(), est(amp, amp_se));
        out.insert(
            "wavelength_m".into(),
            est(TAU / k, TAU * sk / (k * k)),
        );
        let phase = (b.atan2(a) - k * self.z_ref_m).rem_euclid(TAU);
        let phase_se =
            (((b * sa).powi(2) + (a * sb).powi(2)).sqrt() / (amp * amp)).hypot(self.z_ref_m * sk);
        out.insert("phase_rad".into(), est(phase, phase_se));
        out
    }
    fn searched(&self) -> bool {
        true
    }
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
                    let fs: Vec<f64> = z.iter().map(|z| (k * (z - z_ref)).sin()).collect();
                    let fc: Vec<f64> = z.iter().map(|z| (k * (z - z_ref)).cos()).collect();
                    Some(vec![
                        p.column(p.track.respond_values(&fs)),
                        p.column(p.track.respond_values(&fc)),
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
            "amplitude_mps2",
            "m/s²",
            typical_se.unwrap_or(se[1].hypot(se[2]) / 2f64.sqrt()),
            1.0,
        ))
    }
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        let value = |k: &str| f.parameters.get(k).map(|e| e.value);
        Some(
            match (
                value("amplitude_mps2"),
                value("wavelength_m"),
                value("phase_rad"),
            ) {
                (Some(amp), Some(wavelength), Some(phase)) => Ok(Term::PositionForce {
                    amp_mps2: amp,
                    wavelength_m: wavelength,
                    phase_rad: phase,
                }),
                _ => Err(format!(
                    "the accepted model has a position force ({}) the pair fit does not carry",
                    f.form
                )),
            },
        )
    }
}
