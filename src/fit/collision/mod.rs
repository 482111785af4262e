//! PLACEHOLDER for the collision fits (owned by the collision helper, branch `collision`): only the
//! contract's names, so that `fit::RunFit` and the aggregate stage compile before that branch is
//! merged. Every function here says plainly that collision fitting is not built.

use super::FitOptions;
use crate::recording::{Recording, RunInfo};
use serde::{Deserialize, Serialize};

/// The fit of one collision run (placeholder: carries only a status).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CollisionFit {
    pub run: String,
    pub status: String,
}

/// Collision aggregates (placeholder).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CollisionSummary {
    pub status: String,
}

const NOT_BUILT: &str = "not_built: collision fitting is not merged into this build";

/// Fit a collision run (placeholder: returns the status `not_built`).
pub fn fit_collision(rec: &Recording, _opts: &FitOptions) -> CollisionFit {
    CollisionFit {
        run: rec.info.run.clone(),
        status: NOT_BUILT.to_string(),
    }
}

/// Aggregate collision fits (placeholder: returns the status `not_built`).
pub fn summarize(_fits: &[(RunInfo, CollisionFit)]) -> CollisionSummary {
    CollisionSummary {
        status: NOT_BUILT.to_string(),
    }
}
