//! A force periodic in time: a(t) = A·sin(2π f t + φ_run), t since the kick, with each run's own
//! phase (profiled), its frequency searched.

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place, Search};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::noise_floor::local_floor;
use crate::discover::ranges::{Proposals, Ranges, Wanted};
use crate::discover::screen_sums::{best_of, Trial, Typical};
use crate::discover::spectral::f_grid;
use crate::discover::time_scan::AMPLITUDE_BOUND_MPS2;
use crate::physics::Term;
use std::collections::BTreeMap;
use std::f64::consts::TAU;

/// A frequency within this factor of the search's floor is at the floor.
const FLOOR_MARGIN: f64 = 1.05;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct TimePeriodic {
    pub f_lo: f64,
    pub f_hi: f64,
}


impl Form for TimePeriodic {
    fn offer(_n_materials: usize, rg: &Ranges) -> Option<Self> {
        Some(TimePeriodic {
            // one period in the longest run at least, as for the common phase: slower, a force
            // in time is one smooth push per run, which drag, tilt or a force in z explain (a
            // fit that ends at this floor is refused: `scale_at_end`)
            f_lo: 1.0 / rg.duration_s,
            f_hi: 1.05 * rg.f_max_hz,
        })
    }
    fn name(&self) -> &'static str {
        "time_periodic"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("time_dependent_force")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        "periodic in time: a = A sin(2 pi f t + phi_run), t since the kick, a phase per run".into()
    }
    fn size_name(&self) -> &'static str {
        "a periodic force in time"
    }
    /// The vibration's amplitude and frequency.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::with_error;
        Some(format!(
            "a vibration, a force of amplitude {} m/s² at {} Hz, its phase each run's own",
            with_error(f, "amplitude_mps2", 1.0)?,
            with_error(f, "frequency_hz", 1.0)?
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        let (f_lo, f_hi) = (self.f_lo, self.f_hi);
        vec![
            p("frequency_hz", 0.5 * (f_lo + f_hi), f_lo, f_hi, 1e-3),
            p("amplitude_mps2", 0.0, 0.0, AMPLITUDE_BOUND_MPS2, 1e-4),
        ]
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.phased_term = Some(e.model.terms.len());
        e.model.terms.push(Term::TimePeriodicForce {
            amp_mps2: x[1],
            freq_hz: x[0],
            phase_rad: 0.0,
        });
    }
    /// Its statistic (Σ|b_r|)²/Σa_r sums a Rayleigh draw per run and so sits far from zero with
    /// a narrow spread, like a χ² of two per run. Bounded by its two parameters, the law came out
    /// so wide that a 0.15 m/s² vibration at 120 Hz (LR 510 against replicates near 200) read
    /// p = 0.012 before Holm, below the detection limit the report states.
    fn null_df(&self, runs: usize) -> f64 {
        (2 * runs.max(1)) as f64
    }
    fn run_phase(&self) -> bool {
        true
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let est = Estimate::new;
        let mut out = BTreeMap::new();
        out.insert("frequency_hz".into(), est(f.x[0], f.se[0]));
        out.insert("amplitude_mps2".into(), est(f.x[1], f.se[1]));
        out.insert("peak_accel_mps2".into(), est(f.x[1], f.se[1]));
        out
    }
    fn searched(&self) -> bool {
        true
    }
    /// One amplitude and each run's own phase. Per run the (sin, cos) responses carry
    /// information a_r (half the trace of their normal matrix, the two being nearly orthogonal
    /// over many periods) and the data project to |b_r| at the best phase; a shared amplitude α
    /// drops χ² by Σ(2α|b_r| − α²a_r), at best (Σ|b_r|)²/Σa_r. A free amplitude per run would
    /// absorb any structure at all one run at a time; the shared one does not.
    fn search(&self, s: &Search) -> (Option<Trial>, Option<Typical>) {
        let (rg, reps) = (s.rg, s.reps.clone());
        let asked: Vec<f64> = f_grid(rg.duration_s, rg.f_max_hz)
            .into_iter()
            .filter(|f| *f >= self.f_lo && *f <= self.f_hi)
            .collect();
        // the frequencies where a force could be seen (`time_scan`)
        let scan = s.time_scan(&asked);
        let fs = &scan.grid;
        let nrep = reps.len();
        // the data (replicate 0) is in every batch's scan, for the noise floor below
        let data_in = reps.start == 0;
        let mut out: Vec<(Option<Trial>, Vec<f64>, f64)> = scan
            .at
            .iter()
            .zip(fs)
            .map(|(at, &f)| {
                let (sb, info) = (&at.per_run, at.info.clone());
                let sa: f64 = info.iter().sum();
                if sa <= 0.0 {
                    return (None, info, f64::NAN);
                }
                let data = if data_in { sb[0] } else { at.per_run_data };
                let lr: Vec<f64> = sb.iter().map(|b| b * b / sa).collect();
                (
                    Some((lr, vec![f, sb[0] / sa], vec![f64::NAN, 1.0 / sa.sqrt()])),
                    info,
                    data * data / sa,
                )
            })
            .collect();
        // the replicates raised to the noise floor the data show around each frequency: with
        // tracking noise of lag-1 correlation 0.6 the data's statistic ran about 10 % above the
        // AR(1) replicates' at every frequency, and the largest of them passed for a vibration
        let ratio: Vec<Option<f64>> = out
            .iter()
            .map(|(t, _, data)| {
                let reps_lr = &t.as_ref()?.0[usize::from(data_in)..];
                let mean = reps_lr.iter().sum::<f64>() / reps_lr.len().max(1) as f64;
                (mean > 0.0 && !reps_lr.is_empty()).then(|| data / mean)
            })
            .collect();
        let floor = local_floor(&ratio);
        for ((t, _, _), k) in out.iter_mut().zip(&floor) {
            if let Some((lr, _, _)) = t {
                for x in &mut lr[usize::from(data_in)..] {
                    *x *= k;
                }
            }
        }
        // the most sensitive frequency: the most information over the runs, above the floor (a
        // fit there is refused, `scale_at_end`, so no limit is said of it)
        let mut top: Option<(f64, usize)> = None;
        for (i, (t, info, _)) in out.iter().enumerate() {
            let sa: f64 = info.iter().sum();
            let inside = fs[i] > FLOOR_MARGIN * self.f_lo;
            if t.is_some() && inside && top.is_none_or(|b| sa > b.0) {
                top = Some((sa, i));
            }
        }
        let typical = top.map(|(_, i)| Typical::PerRun {
            a: out[i].1.clone(),
            floor: floor[i],
            at: format!(
                "at {:.0} Hz (higher at higher frequencies, as f² far above{})",
                fs[i],
                scan.stopped_short()
                    .map(|t| format!("; {t}"))
                    .unwrap_or_default()
            ),
        });
        (
            best_of(out.into_iter().map(|(t, _, _)| t).collect(), nrep),
            typical,
        )
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
            .map(|pk| vec![pk.omega / TAU, pk.coef[0].max(1e-3)])
            .collect()
    }
    fn scale(&self) -> Option<(usize, &'static str)> {
        Some((0, "frequency"))
    }
    /// Either end: at the slow one, one period in the longest run, a term with its own phase in
    /// each run is a free smooth push per run, which takes whatever a run misfits (a wave in z
    /// crossed at the run's own speed took the place of its wave on the test bed).
    /// (The caller's "at the end" is 1 % of the whole range, hundreds of Hz: the slow end is taken
    /// here as within 5 % of the floor.)
    fn scale_at_end(&self, x: f64, lower: bool) -> Option<String> {
        if lower && x > FLOOR_MARGIN * self.f_lo {
            return None;
        }
        Some(if lower {
            format!("its frequency is the lowest the search allows ({x:.1} Hz, one period in the longest run), where a phase of its own in each run makes it one free push per run")
        } else {
            format!("its frequency ran to the highest the search allows ({x:.1} Hz)")
        })
    }
    fn detection_size(
        &self,
        se: &[f64],
        _typical_se: Option<f64>,
    ) -> Option<(&'static str, &'static str, f64, f64)> {
        Some(("amplitude_mps2", "m/s²", se[1], 1.0))
    }
    /// A collision run's own phase is not known from the single runs, and the pair fit frees none.
    fn lab_force(&self, _f: &Finding) -> Option<Result<Term, String>> {
        Some(Err(
            "the accepted model has a force in time with its own phase in each run, which the pair fit does not carry".into(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fit at either end of the frequency search is no finding; the slow end is the floor
    /// itself (one period in the longest run), not the caller's 1 % of the whole range.
    #[test]
    fn a_frequency_at_either_end_of_its_search_is_refused() {
        let form = TimePeriodic {
            f_lo: 16.7,
            f_hi: 5250.0,
        };
        let slow = form.scale_at_end(16.7, true).expect("refused at the floor");
        assert!(slow.contains("lowest") && slow.contains("16.7 Hz"), "{slow}");
        assert_eq!(form.scale_at_end(37.0, true), None, "37 Hz is inside the search");
        let fast = form.scale_at_end(5249.0, false).expect("refused at the top");
        assert!(fast.contains("highest"), "{fast}");
    }
}
