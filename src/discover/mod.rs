//! Discovery: locate where the baseline misses, name and fit the missing physics, decide by evidence.
//!
//! The method (issue 5): per-run baseline fits measure each run's noise and flag outliers; a joint
//! model shares the physics (μ and T per material, plus extra terms) over every run with per-run
//! z0, t0, v0. Candidate terms from a physical library are tested against the current model by a
//! likelihood ratio whose null comes from a parametric bootstrap with each run's measured AR(1)
//! noise, Holm-corrected over the candidates, and by leave-runs-out cross-validation; the strongest
//! term passing both is added and the search repeats. Drift probes (T or μ drifting with |v0|, a
//! direction asymmetry), fitted inside the joint model, say whether a mismatch is left unexplained.

pub mod admissible;
pub mod candidate;
pub mod cv;
pub mod data;
pub mod detection;
pub mod diagnosis;
pub mod drift;
pub mod estimates;
mod findings;
pub mod forcemap;
pub mod forward;
pub mod holm;
pub mod joint;
pub mod locate;
pub mod model;
pub mod noise;
pub mod noise_floor;
pub mod null_distribution;
pub mod pairs;
mod particles;
mod pairs_impact;
pub mod perrun;
pub mod proposal;
pub mod residual_structure;
pub mod response;
pub mod run;
mod run_phase;
pub mod screen;
mod screen_sums;
pub mod sim;
pub mod spectral;
pub mod timeforce;

pub use diagnosis::Diagnosis;
pub use run::{discover, discover_reporting};

use serde::{Deserialize, Serialize};

pub use crate::physics::G_MPS2;

/// Every candidate effect id the library knows, in the order they are listed.
pub const EFFECTS: [&str; 9] = [
    "velocity_dependent_drag",
    "rolling_resistance",
    "groove_tilt",
    "velocity_dependent_friction",
    "direction_dependent_friction",
    "position_dependent_friction",
    "position_dependent_force",
    "time_dependent_force",
    "position_distortion",
];

/// Settings of a discovery (the `discover` stage params, plus the seed).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct Options {
    /// Parametric-bootstrap replicates per round.
    pub bootstrap: usize,
    /// Levenberg–Marquardt iterations of each bootstrap refit (warm started).
    pub bootstrap_iterations: usize,
    /// Family-wise error rate of each round (Holm) and level of the cross-validation test.
    pub alpha: f64,
    /// Leave-runs-out folds.
    pub folds: usize,
    /// Candidate effect ids to test (see `EFFECTS`).
    pub candidates: Vec<String>,
    /// Model structure in a force map that no named form explains with a spline in its
    /// variable (tested like a candidate, reported as `unexplained`).
    pub nonparametric: bool,
    /// At most this many terms are added.
    pub max_terms: usize,
    /// Opening angle of the groove and m R²/I of the particle.
    pub groove_angle_deg: f64,
    pub k: f64,
    /// Runs with fewer samples are left out.
    pub min_frames: usize,
    /// Seed of the bootstrap (the stage passes the pipeline seed).
    #[serde(skip)]
    pub seed: u64,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            bootstrap: 24,
            bootstrap_iterations: 4,
            alpha: 0.01,
            folds: 5,
            candidates: EFFECTS.iter().map(|s| s.to_string()).collect(),
            nonparametric: true,
            max_terms: 3,
            groove_angle_deg: 70.6,
            k: 2.5,
            min_frames: 20,
            seed: 0,
        }
    }
}

impl Options {
    /// Check ranges and names; the message says how to fix.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let bad = |k: &str, m: String| Err((k.to_string(), m));
        if self.bootstrap < 5 {
            return bad(
                "bootstrap",
                "needs at least 5 replicates; use 20 or more".into(),
            );
        }
        if !(self.alpha > 0.0 && self.alpha < 0.5) {
            return bad("alpha", "must lie in (0, 0.5); the default is 0.01".into());
        }
        if self.folds < 2 {
            return bad("folds", "needs at least 2 folds; the default is 5".into());
        }
        for c in &self.candidates {
            if !EFFECTS.contains(&c.as_str()) {
                return bad(
                    "candidates",
                    format!("unknown effect `{c}`; use any of {}", EFFECTS.join(", ")),
                );
            }
        }

        if !(self.groove_angle_deg > 0.0 && self.groove_angle_deg < 180.0) {
            return bad("groove_angle_deg", "must lie in (0, 180) degrees".into());
        }
        Ok(())
    }
}
