//! The frequency scan the two forms periodic in time share (a phase per run, `time_periodic`;
//! one phase for every run, `time_common`): at each frequency of the time grid, each run's
//! responses to sin and cos of 2πft projected on its replicates, once for both.
//!
//! Both forms regress the same two columns on the same replicates; they differ only in how the
//! projections (b_s, b_c) of a run are summed: coherently over the runs (`Sums`, one pair shared
//! by every run) or as |b| run by run (the best phase of each run). Reading the runs' replicates
//! and computing the responses was each form's whole cost, so one pass fills both sums, and
//! the second form of a round reads the first one's (`TimeMemo`). Every number is summed in
//! the order each form summed it alone, so the scan gives the same bits as two passes.
//!
//! The scan stops where no force the forms allow could be seen: a run's response to a force at
//! f falls as 1/f² once f is above its slowest motions, and above the frequency where even a
//! force at the forms' amplitude bound would stand less than `RESOLVED_SE` standard errors
//! above the noise (those errors from the data's own responses, on every `COARSE_STEP`-th
//! frequency), trials only add look-elsewhere to the null; the periodogram that proposes the
//! forms' starts stops there too (`proposal.rs`). On the shipped recordings the scan ends near
//! 2.3 kHz, under half of the way to the sampling's Nyquist frequency.

use super::response::Prepared;
use super::screen_sums::{dot, dot2, dot2_twice, scan_block, Sums, Vectors};
use rayon::prelude::*;
use std::f64::consts::TAU;
use std::ops::Range;
use std::sync::{Arc, Mutex};

/// The largest amplitude (m/s²) of the forms periodic in time: 0.5 g, a violent vibration.
pub const AMPLITUDE_BOUND_MPS2: f64 = 5.0;

/// A frequency is scanned while a force at `AMPLITUDE_BOUND_MPS2` stands at least this many
/// standard errors of its amplitude there: at 2, its expected statistic (4) is far below what
/// any test passes after the look-elsewhere of hundreds of frequencies.
const RESOLVED_SE: f64 = 2.0;

/// The coarse pass that finds the top of the scan looks at every this many frequencies.
pub(super) const COARSE_STEP: usize = 16;

/// What one frequency of the scan gathered over the runs.
pub struct AtFrequency {
    /// The coherent sums (two columns, the shared parameters profiled) over every run.
    pub(super) coherent: Sums,
    /// Σ over runs of |b| for each replicate of the batch (runs whose responses vanish at this
    /// frequency left out).
    pub(super) per_run: Vec<f64>,
    /// Σ over runs of the data's |b| when the batch leaves the data out (0 otherwise).
    pub(super) per_run_data: f64,
    /// Each contributing run's information a = (x_s·x_s + x_c·x_c)/2, in run order.
    pub(super) info: Vec<f64>,
}

/// The scan of `asked` (a grid of frequencies) over the replicates `reps` of `v`: its first
/// frequencies up to where a force could still be seen (`grid`), and what each gathered (`at`).
pub struct TimeScan {
    pub(super) asked: Vec<f64>,
    pub(super) grid: Vec<f64>,
    pub(super) reps: Range<usize>,
    pub(super) at: Vec<AtFrequency>,
}

impl TimeScan {
    /// Where the scan stopped short of the grid asked, in words for a detection limit; None
    /// when it went to the end.
    pub fn stopped_short(&self) -> Option<String> {
        let f = self
            .grid
            .last()
            .filter(|_| self.grid.len() < self.asked.len())?;
        Some(format!(
            "searched up to {f:.0} Hz, above which even a force of {AMPLITUDE_BOUND_MPS2} m/s² would stand below {RESOLVED_SE} standard errors"
        ))
    }
}

/// A round's scans, kept for the second form that asks for the same grid and replicates.
#[derive(Default)]
pub struct TimeMemo {
    scans: Mutex<Vec<Arc<TimeScan>>>,
}

impl TimeMemo {
    /// The scan of `grid` over `reps`, computed on the first request (its top frequency
    /// found once for every batch of replicates).
    pub fn get(
        &self,
        prep: &[Prepared],
        v: &Vectors,
        reps: Range<usize>,
        grid: &[f64],
    ) -> Arc<TimeScan> {
        let mut scans = self.scans.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = scans.iter().find(|s| s.reps == reps && s.asked == grid) {
            return Arc::clone(s);
        }
        let kept = match scans.iter().find(|s| s.asked == grid) {
            Some(s) => s.grid.len(),
            None => resolvable(prep, grid),
        };
        let s = Arc::new(TimeScan {
            asked: grid.to_vec(),
            grid: grid[..kept].to_vec(),
            at: scan(prep, v, reps.clone(), &grid[..kept]),
            reps,
        });
        scans.push(Arc::clone(&s));
        s
    }
}

/// A run's (projected, whitened) responses to sin and cos of 2πft, and their information about
/// an amplitude, a = (x_s·x_s + x_c·x_c)/2.
fn responses(p: &Prepared, f: f64) -> (Vec<Vec<f64>>, f64) {
    let (rs, rc) = p.track.respond_time(TAU * f);
    let c = vec![p.column(rs), p.column(rc)];
    let a = 0.5 * (dot(&c[0], &c[0]) + dot(&c[1], &c[1]));
    (c, a)
}

/// How many of `grid`'s first frequencies a force at the amplitude bound could be seen at:
/// up to the coarse frequency after the highest one where it stands `RESOLVED_SE` standard
/// errors (the amplitude's error 1/√Σa over the runs, a as in `AtFrequency::info`); all of
/// them when no coarse frequency does.
pub(super) fn resolvable(prep: &[Prepared], grid: &[f64]) -> usize {
    let coarse: Vec<usize> = (0..grid.len()).step_by(COARSE_STEP).collect();
    let info: Vec<f64> = coarse
        .par_iter()
        .map(|&i| prep.iter().map(|p| responses(p, grid[i]).1).sum())
        .collect();
    let seen = |a: &f64| *a > 0.0 && RESOLVED_SE / a.sqrt() <= AMPLITUDE_BOUND_MPS2;
    match info.iter().rposition(seen) {
        Some(j) => coarse.get(j + 1).map_or(grid.len(), |&i| i + 1),
        None => grid.len(),
    }
}

/// One pass over the runs for every frequency of `grid`, in blocks of frequencies per pass over
/// a run's replicates (`coherent_scan`'s reason), two replicates at a time.
fn scan(prep: &[Prepared], v: &Vectors, reps: Range<usize>, grid: &[f64]) -> Vec<AtFrequency> {
    let nrep = reps.len();
    let data_in = reps.start == 0;
    grid.par_chunks(scan_block(grid.len()))
        .flat_map_iter(|fb| {
            let mut out: Vec<AtFrequency> = fb
                .iter()
                .map(|_| AtFrequency {
                    coherent: Sums::new(2, v.kept.len(), reps.clone()),
                    per_run: vec![0.0; nrep],
                    per_run_data: 0.0,
                    info: Vec::with_capacity(prep.len()),
                })
                .collect();
            for (p, yr) in prep.iter().zip(&v.y) {
                let cols: Vec<(Vec<Vec<f64>>, bool)> = fb
                    .iter()
                    .zip(&mut out)
                    .map(|(&f, o)| {
                        let (c, a) = responses(p, f);
                        if a > 0.0 {
                            o.info.push(a);
                        }
                        o.coherent.add_design(&c, p, v);
                        (c, a > 0.0)
                    })
                    .collect();
                for (pair, two) in yr[reps.clone()].chunks(2).enumerate() {
                    let r = 2 * pair;
                    for ((c, live), o) in cols.iter().zip(&mut out) {
                        match two {
                            [y0, y1] => {
                                let ((s0, c0), (s1, c1)) = dot2_twice(&c[0], &c[1], y0, y1);
                                o.coherent.add_projections(r, &[s0, c0]);
                                o.coherent.add_projections(r + 1, &[s1, c1]);
                                if *live {
                                    o.per_run[r] += s0.hypot(c0);
                                    o.per_run[r + 1] += s1.hypot(c1);
                                }
                            }
                            [y0] => {
                                let (bs, bc) = dot2(&c[0], &c[1], y0);
                                o.coherent.add_projections(r, &[bs, bc]);
                                if *live {
                                    o.per_run[r] += bs.hypot(bc);
                                }
                            }
                            _ => {}
                        }
                    }
                }
                if !data_in {
                    for ((c, live), o) in cols.iter().zip(&mut out) {
                        if *live {
                            let (bs, bc) = dot2(&c[0], &c[1], &yr[0]);
                            o.per_run_data += bs.hypot(bc);
                        }
                    }
                }
            }
            out
        })
        .collect()
}
