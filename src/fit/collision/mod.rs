//! Collision runs: split both tracks at the impacts, fit each phase with the closed-form motion
//! (nonzero initial spin), recover velocities and spins before and after every impact, and
//! summarize μ_pp and the coefficient of restitution over a dataset.
//!
//! Code map: `detect` (noise, departure from rest, kink scan) → `plan` + `model` (the joint
//! piecewise model) → `lm` (robust solver) → `report` (the per-run record, `types`) →
//! `summary` (dataset aggregates). `motion` is the closed form, `impulse` the impact model.

pub mod detect;
mod fit;
pub mod impulse;
pub mod lm;
pub mod model;
pub mod motion;
pub mod plan;
mod report;
pub mod summary;
pub mod types;

pub use fit::{fit_collision, CollisionOptions};
pub use summary::{summarize, summarize_seeded, CollisionSummary};
pub use types::CollisionFit;
