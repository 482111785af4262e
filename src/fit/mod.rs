//! Fitting: the closed-form baseline to each run (robust Levenberg–Marquardt), per-material
//! aggregates with bootstrap intervals, re-simulation residuals and their pooled statistics.
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
