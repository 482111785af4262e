//! A force periodic in time with one phase for every run, locked to the kick (a vibration the
//! laser pulse sets off in the mount): a(t) = s·sin(2πft) + c·cos(2πft), t since the kick, its
//! frequency searched.
//!
//! Unlike the form with a phase per run (`time_periodic`), nothing here is fitted run by run,
//! so it is screened coherently over the runs like a force in z and cross-validated like any
//! term, and it may go down to one period in the longest run: a push common to every run in
//! the lab, whichever way each run moves, is neither a drag (which turns with the motion) nor a
//! tilt (which does not change in time).

use super::form::{carried_force, p, Entry, Fitted, Form, ParamInfo, Place, Search};
use super::wavelength;
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::ranges::{Proposals, Ranges, Wanted};
use crate::discover::screen_sums::{Trial, Typical};
use crate::discover::spectral::f_grid;
use crate::discover::time_scan::AMPLITUDE_BOUND_MPS2;
use crate::physics::Term;
use std::collections::BTreeMap;
use std::f64::consts::TAU;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimeCommon {
    pub f_lo: f64,
    pub f_hi: f64,
}

impl Form for TimeCommon {
    /// Frequencies from one period in the longest run up to the sampling's.
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(TimeCommon {
            f_lo: 1.0 / rg.duration_s,
            f_hi: 1.05 * rg.f_max_hz,
        })
    }
    fn name(&self) -> &'static str {
        "time_common"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("time_dependent_force")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "periodic in time, one phase for every run: a = A sin(2 pi f t + phi), t since the kick"
            .into()
    }
    fn size_name(&self) -> &'static str {
        "a periodic force in time locked to the kick"
    }
    /// The vibration's amplitude and frequency, locked to the kick.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::with_error;
        Some(format!(
            "a vibration locked to the kick, a force of amplitude {} m/s² at {} Hz, one phase for every run",
            with_error(f, "amplitude_mps2", 1.0)?,
            with_error(f, "frequency_hz", 1.0)?
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        let (f_lo, f_hi) = (self.f_lo, self.f_hi);
        vec![
            p("frequency_hz", 0.5 * (f_lo + f_hi), f_lo, f_hi, 1e-7 * f_hi),
            p("sin_mps2", 0.0, -AMPLITUDE_BOUND_MPS2, AMPLITUDE_BOUND_MPS2, 1e-4),
            p("cos_mps2", 0.0, -AMPLITUDE_BOUND_MPS2, AMPLITUDE_BOUND_MPS2, 1e-4),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        let (f, a, b) = (x[0], x[1], x[2]);
        let amp = a.hypot(b);
        if amp > 0.0 {
            e.model.terms.push(Term::TimePeriodicForce {
                amp_mps2: amp,
                freq_hz: f,
                phase_rad: b.atan2(a),
            });
        }
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        // the pair's amplitude and phase as a wave's in z, with ω in place of k; the phase is
        // at t = 0, so the frequency's error does not enter it (nor the period, not used)
        let x = [TAU * f.x[0], f.x[1], f.x[2]];
        let se = [0.0, f.se[1], f.se[2]];
        let [amp, _, phase] = wavelength::amplitude_wavelength_phase(&x, &se, 0.0);
        let mut out = BTreeMap::new();
        out.insert("frequency_hz".into(), Estimate::new(f.x[0], f.se[0]));
        out.insert("amplitude_mps2".into(), amp);
        out.insert("peak_accel_mps2".into(), amp);
        out.insert("phase_rad".into(), phase);
        out
    }
    fn searched(&self) -> bool {
        true
    }
    /// At each frequency of the grid, the runs' responses to sin and cos of 2πft regressed on
    /// the prepared runs coherently (one pair shared by every run), from the round's shared
    /// scan (`time_scan`).
    fn search(&self, s: &Search) -> (Option<Trial>, Option<Typical>) {
        let asked: Vec<f64> = f_grid(s.rg.duration_s, s.rg.f_max_hz)
            .into_iter()
            .filter(|f| *f >= self.f_lo && *f <= self.f_hi)
            .collect();
        // the frequencies where a force could be seen (`time_scan`)
        let scan = s.time_scan(&asked);
        let solved = scan.at.iter().map(|at| at.coherent.solve(s.v, &[])).collect();
        wavelength::pair_trials(solved, &scan.grid, s.reps.len(), |f| {
            match scan.stopped_short() {
                Some(t) => format!("at {f:.0} Hz ({t})"),
                None => format!("at {f:.0} Hz"),
            }
        })
    }
    fn wanted(&self) -> Wanted {
        Wanted {
            t: true,
            ..Wanted::default()
        }
    }
    fn proposed(&self, p: &Proposals) -> Vec<Vec<f64>> {
        p.t.iter()
            .flat_map(|s| s.peaks.iter())
            .map(|pk| vec![pk.omega / TAU, pk.coef[0], pk.coef[1]])
            .collect()
    }
    fn scale(&self) -> Option<(usize, &'static str)> {
        Some((0, "frequency"))
    }
    fn scale_at_end(&self, x: f64, lower: bool) -> Option<String> {
        (!lower).then(|| format!("its frequency ran to the highest the search allows ({x:.1} Hz)"))
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
    /// The vibration acts on the collision runs too: the same mount, set off by the same kind of
    /// kick, and their times are counted from the striker's kick.
    fn lab_force(&self, f: &Finding) -> Option<Result<Term, String>> {
        carried_force(f, &["amplitude_mps2", "frequency_hz", "phase_rad"], |v| {
            Term::TimePeriodicForce {
                amp_mps2: v[0],
                freq_hz: v[1],
                phase_rad: v[2],
            }
        })
    }
}
