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

use super::response::Prepared;
use super::screen_sums::{dot, dot2, dot2_twice, scan_block, Sums, Vectors};
use rayon::prelude::*;
use std::f64::consts::TAU;
use std::ops::Range;
use std::sync::{Arc, Mutex};

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

/// The scan of `grid` over the replicates `reps` of `v`.
pub struct TimeScan {
    pub(super) grid: Vec<f64>,
    pub(super) reps: Range<usize>,
    pub(super) at: Vec<AtFrequency>,
}

/// A round's scans, kept for the second form that asks for the same grid and replicates.
#[derive(Default)]
pub struct TimeMemo {
    scans: Mutex<Vec<Arc<TimeScan>>>,
}

impl TimeMemo {
    /// The scan of `grid` over `reps`, computed on the first request.
    pub fn get(
        &self,
        prep: &[Prepared],
        v: &Vectors,
        reps: Range<usize>,
        grid: &[f64],
    ) -> Arc<TimeScan> {
        let mut scans = self.scans.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(s) = scans.iter().find(|s| s.reps == reps && s.grid == grid) {
            return Arc::clone(s);
        }
        let s = Arc::new(TimeScan {
            grid: grid.to_vec(),
            at: scan(prep, v, reps.clone(), grid),
            reps,
        });
        scans.push(Arc::clone(&s));
        s
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
                        let (rs, rc) = p.track.respond_time(TAU * f);
                        let c = vec![p.column(rs), p.column(rc)];
                        let a = 0.5 * (dot(&c[0], &c[0]) + dot(&c[1], &c[1]));
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
