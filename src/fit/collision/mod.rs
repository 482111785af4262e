//! Collision runs: split both tracks at the impacts, fit each phase with the closed-form motion
//! (nonzero initial spin), recover velocities and spins before and after every impact, and
//! summarize μ_pp and the coefficient of restitution over a dataset.
//!
//! Files of this folder:
//!
//! - `curves.rs`: Falling curves of the coefficient of restitution against impact speed
//! - `detect.rs`: Finding impacts in noisy tracks
//! - `fit.rs`: `fit_collision`
//! - `impulse.rs`: The impulse model of one impact between equal spheres
//! - `model.rs`: The joint piecewise model of a collision run
//! - `motion.rs`: The closed-form motion of one sphere in the groove
//! - `mu_pp.rs`: Estimates of the particle–particle friction μ_pp from the impacts of a dataset
//! - `options.rs`: Settings of the collision fit (`fit` stage params reach it through `FitOptions`)
//! - `plan.rs`: A fit plan: starting values and bounds of every parameter of the joint model
//! - `profile.rs`: Profile likelihood of μ_pp
//! - `report.rs`: from a solved joint model to the `CollisionFit` record
//! - `restitution_law.rs`: The restitution law C(v) of one material and setup from the whole-run fits
//! - `secondary.rs`: Secondary collisions
//! - `start.rs`: Starting plans of the joint fit
//! - `summary.rs`: `summarize`: the collision results of a dataset
//! - `trajectory.rs`: The fitted model trajectory of a collision run
//! - `warm_start.rs`: The start of a whole-run fit from an earlier analysis of the same runs
//! - `whole_summary.rs`: The whole-run collision analysis of a dataset
//! - `wholerun.rs`: Whole-run pair fits
//!
//! Code map: `fit` (entry) → `detect` (noise, departure from rest, contacts in the gap) →
//! `start` + `secondary` (starting plans, secondary impacts, where to stop) → `plan` + `model`
//! (the joint piecewise model) → `crate::lsq::dense_fit` (robust solver) → `report` (the per-run record, `artifacts::collision_fit`).
//! `summary` aggregates a dataset with `mu_pp` and `curves`. `motion` wraps the physics closed
//! form, `impulse` is the impact model, `trajectory` evaluates a fitted run (figures, residuals).

pub mod curves;
pub mod detect;
pub mod fit;
pub mod impulse;
pub mod model;
pub mod motion;
pub mod mu_pp;
pub mod options;
pub mod plan;
pub mod profile;
mod report;
pub mod restitution_law;
mod secondary;
mod start;
pub mod summary;
mod trajectory;
pub mod warm_start;
pub mod whole_summary;
pub mod wholerun;

pub use crate::artifacts::collision_fit::CollisionFit;
pub use crate::artifacts::collision_summary::CollisionSummary;
pub use fit::fit_collision;
pub use options::CollisionOptions;
pub use summary::{summarize, summarize_seeded};
pub use trajectory::FittedState;
