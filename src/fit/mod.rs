//! Fitting: the closed-form baseline to each run (robust Levenberg–Marquardt), per-material
//! aggregates with bootstrap intervals, re-simulation residuals and their pooled statistics.
//!
//! Files of this folder:
//!
//! - `aggregate.rs`: Per-material aggregates of single-run fits
//! - `bootstrap.rs`: Seeded bootstrap over whole runs
//! - `fits_csv.rs`: fits.csv: one row per single run
//! - `lm.rs`: The per-run fits' view of the fixed-size back-end `lsq::fixed`
//! - `loss.rs`: The robust losses of the per-run fits (the shared `lsq::loss`)
//! - `model.rs`: The closed-form baseline as a fit model
//! - `nan_null.rs`: Serde helper for an `f64` that may be NaN
//! - `options.rs`: Options of every fit
//! - `quality.rs`: Fit quality as data
//! - `regression.rs`: Means over runs
//! - `residual_stats.rs`: Pooled statistics of re-simulation residuals
//! - `residuals.rs`: Re-simulation of a run with its fitted parameters
//! - `robust.rs`: The robust fit of the per-run fits
//! - `segment.rs`: Fit one time range of a track with any free subset of parameters
//! - `single.rs`: Fit of a single run
//! - `start.rs`: Starting values of a single-run fit
//! - `status.rs`: Why a fit stopped
//! - `summary.rs`: The types of summary.json
//! - `track_problem.rs`: The least-squares problem of one track
//! - `collision/`: Collision runs: split both tracks at the impacts
//!
//! Code map: `model` (closed form + analytic Jacobian), `lm`, `loss`, `robust` and `status` (the
//! shared least-squares core [`crate::lsq`] at this model's size), `track_problem` (a track as a
//! least-squares problem), `start` (start values from the data), `segment`
//! (any time range, any free subset), `single` (a single run), `aggregate` + `bootstrap` +
//! `regression` (per material), `summary` and `fits_csv` (the output contract), `residuals`
//! (re-simulation) and `residual_stats` (pooled statistics for discovery). `collision` belongs to
//! the collision fits.

pub mod aggregate;
pub mod bootstrap;
pub mod collision;
pub mod fits_csv;
pub mod lm;
pub mod loss;
pub mod model;
mod nan_null;
pub mod options;
pub mod quality;
pub mod regression;
pub mod residual_stats;
pub mod residuals;
pub mod robust;
pub mod segment;
pub mod single;
pub mod start;
pub mod status;
pub mod summary;
pub mod track_problem;

pub use options::FitOptions;
pub use segment::{fit_segment, FreeParams, SegmentFit, SegmentInit};
pub use single::{fit_single, SingleFit};
pub use status::Termination;

pub use crate::artifacts::run_fit::RunFit;
