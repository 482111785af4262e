//! The `compare` stage's `comparison`: pooled re-simulation residual statistics by phase, speed,
//! position, direction, material, experiment and run; collision runs by phase and time since impact.

use super::residuals::Phase;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Statistics of one group of residuals.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct GroupStats {
    pub n: usize,
    pub mean_m: f64,
    pub rms_m: f64,
    /// Σ r_i r_{i+1} / Σ r_i² over consecutive pairs; null if no pairs.
    pub lag1_autocorr: Option<f64>,
    /// Runs-test z of the residual signs; null if too few frames of both signs.
    pub runs_test_z: Option<f64>,
}

/// A group with its bin edges (speed in m/s, position in m, time in s).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bin {
    pub lo: f64,
    /// Null for the open last speed bin.
    pub hi: Option<f64>,
    pub stats: GroupStats,
}

/// The `comparison` artifact of the `compare` stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    pub n_runs: usize,
    /// Runs without residuals (failed fits, collision runs), by run id, with the reason.
    pub skipped: BTreeMap<String, String>,
    pub n_frames: usize,
    pub n_outliers: usize,
    pub overall: GroupStats,
    pub by_phase: BTreeMap<Phase, GroupStats>,
    pub by_speed: Vec<Bin>,
    pub by_position: Vec<Bin>,
    /// "+z" and "-z".
    pub by_direction: BTreeMap<String, GroupStats>,
    pub by_material: BTreeMap<String, GroupStats>,
    /// "single" and "collision" (collision runs: both particles, piece by piece).
    pub by_experiment: BTreeMap<String, GroupStats>,
    pub by_run: BTreeMap<String, GroupStats>,
    /// The collision runs' residuals (both particles, piece by piece) by phase and by time
    /// since the last impact; null without collision runs.
    pub pairs: Option<PairResiduals>,
}

/// Residuals of the collision runs' piecewise fits, where impacts could leave structure.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PairResiduals {
    pub n_runs: usize,
    pub by_phase: BTreeMap<Phase, GroupStats>,
    /// Frames before the run's first fitted impact (the striker's approach, the target at rest).
    pub before_first_impact: GroupStats,
    /// By time since the last impact (s); the last bin is open.
    pub by_time_since_impact: Vec<Bin>,
}
