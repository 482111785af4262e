//! Fitting: the closed-form baseline to each run (robust Levenberg–Marquardt), per-material
//! aggregates with bootstrap intervals, re-simulation residuals and their pooled statistics.
//!
//! Files of this folder:
//!
//! - `aggregate.rs`: Per-material aggregates of single-run fits
//! - `bootstrap.rs`: Seeded bootstrap over whole runs
//! - `fits_csv.rs`: fits.csv: one row per single run
//! - `model.rs`: The closed-form baseline as a fit model
//! - `options.rs`: Options of every fit
//! - `quality.rs`: Fit quality as data
//! - `refit.rs`: The chapter's numbers under the physics discovery accepted
//! - `refit_impact.rs`: The impact laws discovery accepted, read back from their findings as the whole-run fits carry them
//! - `regression.rs`: Means over runs
//! - `residual_stats.rs`: Pooled statistics of re-simulation residuals
//! - `residuals.rs`: Re-simulation of a run with its fitted parameters
//! - `segment.rs`: Fit one time range of a track with any free subset of parameters
//! - `single.rs`: Fit of a single run
//! - `start.rs`: Starting values of a single-run fit
//! - `track_problem.rs`: The least-squares problem of one track
//! - `collision/`: Collision runs: split both tracks at the impacts
//!
//! How they fit together: `model` (closed form + analytic Jacobian) and `track_problem` (a track
//! as a least-squares problem for the shared core [`crate::lsq`], with the core's types at this
//! model's size), `start` (start values from the data), `segment` (any time range, any free
//! subset), `single` (a single run), `aggregate` + `bootstrap` + `regression` (per material),
//! `fits_csv` (fits.csv; summary.json's types are `artifacts::summary`), `residuals`
//! (re-simulation) and `residual_stats` (pooled statistics for discovery). `collision` holds the
//! collision fits.
//!
//! # Suspect fits and restarts
//!
//! Tracker error has a shape: a spot diameter too small for the
//! particle locks positions to pixel centres. A converged fit is marked `suspect` (fits.csv
//! `status`, with the reasons in the fit JSON and the report) when a parameter sits at a bound or has
//! no standard error, the switch to rolling falls after the recording, the first frames run at a
//! speed the model does not, or the residuals carry structure far above the frame-to-frame noise:
//! the RMS of 15-frame mean residuals more than 30 times what white noise of the frame-to-frame
//! scatter gives. The 30 is calibrated on a null (`tests/trackers.rs`): of the right fits of 1500
//! clean synthesized runs (|v0| 5–100 mm/s, 600 frames), those with white noise of 1 or 3 µm stay
//! below 2, those with pixel-locked positions (1–4 µm) have a median of 1.4 but a tail (16 of 467
//! above 20, 5 above 25, 1 above 30), so at 30 the false-suspect rate is 0.2 % with locked errors
//! and 0 with white noise (the bar is 1 % with each); wrong-basin fits of slow locked runs give
//! 25–40 and also sit at a bound or switch after the recording.
//!
//! A suspect fit is restarted from a grid of starts (v0 from a local quadratic of the first frames
//! and from the data's start, μ over 0.1–0.6, T at the data's start and ten times it) and the
//! cleanest restart is kept (`restarted` in the fit JSON). The aggregate stage's notes, and so the
//! report, say how many: "k of n single runs whose first fit looked wrong … were recovered by a
//! restart … ; m stay suspect and are left out of the aggregates". Measured on 400 synthesized
//! pixel-locked runs: 17 first fits are suspect (slow runs, |v0| ≲ 12 mm/s, whose sliding phase
//! lasts a few frames: pixel locking's signature, v0 halved, μ at its lower bound, T ≈ 0.16 s), the
//! restarts recover 7 of them to a right fit and the other 10 stay suspect (their μ is not
//! determined by the frames: it runs to a bound); no kept restart is wrong, and 2 of the 400 runs
//! (both under 8 mm/s) pass as converged with μ more than 3 standard errors off. Holding v0 at the
//! first frames' speed before releasing it, and a linear or soft-L1 loss instead of Huber, recovered
//! no more. On the real-trackpy pixel-locked fixtures (eight runs of 0.06 s, slow ones at 18 and
//! 10 mm/s): tracked at 11 px (`trackpy_locked/`, 2.7 µm RMS error) every first fit is right; at 9 px
//! (`trackpy_locked_9px/`, 5.8 µm) both slow runs' first fits look wrong, the restart recovers the
//! 18 mm/s one (v0 within 0.6 %, μ 0.316 for 0.337) and the 10 mm/s one stays suspect (μ ran to
//! 4.9 with no standard error); the weighted μ of each material is within 0.01 of the truth in both.
//!
//! Suspect runs stay out of every aggregate and are listed per material (`summary.json`:
//! `left_out`). The weighted μ per material adds the between-run scatter to each run's variance and
//! down-weights runs far from the rest (Huber), and the T-vs-v0 and μ-vs-v0 lines are Theil–Sen lines
//! (the median of the slopes between every two runs — a uniform draw of pairs above 2,000 runs —,
//! with a bootstrap interval over runs), so one
//! wild run can move neither by more than its share.

pub mod aggregate;
pub mod bootstrap;
pub mod collision;
pub mod fits_csv;
pub mod model;
pub mod options;
pub mod quality;
pub mod refit;
pub mod refit_impact;
pub mod regression;
pub mod residual_stats;
pub mod residuals;
pub mod segment;
pub mod single;
pub mod start;
pub mod track_problem;

pub use crate::lsq::Termination;
pub use options::FitOptions;
pub use segment::{fit_segment, FreeParams, SegmentFit, SegmentInit};
pub use single::{fit_single, SingleFit};

pub use crate::artifacts::run_fit::RunFit;
