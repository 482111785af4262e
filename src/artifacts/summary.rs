//! The types of summary.json (the output contract of the fits): per-material estimates with
//! bootstrap intervals (each an `Estimate` written as `{value, interval}`), the T-vs-v0 line, and the collision aggregates when there are collision runs.

pub use super::collision_summary::{
    CollisionSummary, LawCandidate, LawChoice, MaterialWholeRun, MuPp, MuPpProfile, ProfilePoint,
    ProfileVerdict, RestitutionCurve, RestitutionPoint, SpinPoint, WholeRun, WholeRunSummary,
    STOP_DEVIANCE,
};
pub use super::estimate::{Estimate, Interval};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// T = intercept + slope·|v0|, a Theil–Sen line over the runs (Fig. 4.2c).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DragLine {
    #[serde(with = "super::estimate::interval")]
    pub intercept_s: Estimate,
    #[serde(with = "super::estimate::interval")]
    pub slope_s_per_mps: Estimate,
}

/// μ = intercept + slope·|v0|, a Theil–Sen line over the runs (Fig. 4.2d).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrictionLine {
    #[serde(with = "super::estimate::interval")]
    pub intercept: Estimate,
    #[serde(with = "super::estimate::interval")]
    pub slope_per_mps: Estimate,
}

/// The aggregates of the single runs of one material (or of all materials pooled).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MaterialSummary {
    /// Single runs of this material, and how many of their fits converged (only those are used).
    pub n_runs: usize,
    pub n_converged: usize,
    /// Inverse-variance weighted mean of μ over the converged runs.
    #[serde(with = "super::estimate::interval")]
    pub mu_weighted: Estimate,
    /// Plain mean of μ over the runs with |v0| above `fast_min_speed_mps` (the chapter's value).
    #[serde(with = "super::estimate::interval")]
    pub mu_fast: Estimate,
    pub n_fast: usize,
    pub t_vs_v0: DragLine,
    pub mu_vs_v0: FrictionLine,
    /// Smallest and largest |v0| of the converged runs.
    pub speed_range_mps: Option<[f64; 2]>,
    /// Runs left out of every aggregate (fit suspect, failed or unfinished), with the reason.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub left_out: Vec<LeftOut>,
}

/// A run the aggregates leave out, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeftOut {
    pub run: String,
    pub status: String,
    pub why: String,
}

/// Everything about the single runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SingleSummary {
    pub n_runs: usize,
    pub n_converged: usize,
    /// |v0| above which a run counts in `mu_fast`.
    pub fast_min_speed_mps: f64,
    /// Per material, sorted by name.
    pub materials: BTreeMap<String, MaterialSummary>,
    /// All materials pooled (the chapter fits one T-vs-v0 line to both).
    pub pooled: MaterialSummary,
}

/// How the intervals were made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BootstrapInfo {
    pub resamples: usize,
    pub level: f64,
    pub seed: u64,
    /// What is resampled.
    pub unit: String,
}

/// summary.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Null when the dataset has no single runs (see `notes`).
    pub single: Option<SingleSummary>,
    /// Null when the dataset has no collision runs (see `notes`).
    pub collisions: Option<CollisionSummary>,
    /// Plain-language notes: parts skipped and why.
    pub notes: Vec<String>,
    pub bootstrap: BootstrapInfo,
}
