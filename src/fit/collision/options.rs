//! Settings of the collision fit (`fit` stage params reach it through `FitOptions`).

use serde::{Deserialize, Serialize};

/// Settings of the collision fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollisionOptions {
    /// sin(θ/2) of the groove.
    pub s: f64,
    /// m R² / I of the spheres.
    pub k: f64,
    /// At most this many impacts per run (the first and its secondaries).
    pub max_impacts: usize,
    /// A secondary contact is fitted as an impact when the jump of the gap rate exceeds this
    /// many standard errors; otherwise the fit stops where the pair touches again.
    pub contact_z: f64,
    /// Starting values of μ_pg, T and μ_pp (the latter only seeds the spins after an impact).
    pub mu_start: f64,
    pub t_drag_start_s: f64,
    pub mu_pp_start: f64,
    /// Fit one drag time per piece between impacts (absorbs a drag that is not linear in v,
    /// which otherwise biases the velocities at the impacts) instead of one per run.
    pub drag_per_piece: bool,
}

impl Default for CollisionOptions {
    fn default() -> Self {
        CollisionOptions {
            s: (70.6f64.to_radians() / 2.0).sin(),
            k: 2.5,
            max_impacts: 6,
            contact_z: 6.0,
            mu_start: 0.3,
            t_drag_start_s: 0.06,
            mu_pp_start: 1.0,
            drag_per_piece: true,
        }
    }
}
