//! Collision runs: split both tracks at the impacts, fit each phase with the closed-form motion
//! (nonzero initial spin), recover velocities and spins before and after every impact, and
//! summarize μ_pp and the coefficient of restitution over a dataset.
//!
//! Code map: `fit` (entry) → `detect` (noise, departure from rest, contacts in the gap) →
//! `start` + `secondary` (starting plans, secondary impacts, where to stop) → `plan` + `model`
//! (the joint piecewise model) → `crate::lsq::dense_fit` (robust solver) → `report` (the per-run record, `types`).
//! `summary` aggregates a dataset with `mu_pp` and `curves`. `motion` wraps the physics closed
//! form, `impulse` is the impact model, `trajectory` evaluates a fitted run (figures, residuals).

pub mod curves;
pub mod detect;
mod fit;
pub mod impulse;
pub mod model;
pub mod motion;
pub mod mu_pp;
mod options;
pub mod plan;
pub mod profile;
mod report;
pub mod restitution_law;
mod secondary;
mod start;
pub mod summary;
mod trajectory;
pub mod types;
pub mod whole_summary;
pub mod wholerun;

pub use fit::fit_collision;
pub use options::CollisionOptions;
pub use summary::{summarize, summarize_seeded, CollisionSummary};
pub use trajectory::FittedState;
pub use types::CollisionFit;
