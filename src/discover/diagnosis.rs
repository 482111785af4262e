//! diagnosis.json: the output contract of issue 5, plus the tables and before/after data the report shows.

use super::drift::Line;
use super::residual_structure::Structure;
use serde::Serialize;
use std::collections::BTreeMap;

/// A value with its standard error.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Estimate {
    pub value: f64,
    pub stderr: f64,
}

/// How well a model does: held-out error and in-sample fit.
#[derive(Clone, Debug, Serialize, Default)]
pub struct ModelScore {
    pub cv_rms_m: f64,
    pub rms_m: f64,
    pub chi2: f64,
    pub n_global_params: usize,
    pub terms: Vec<String>,
}

/// The statistics behind a decision.
#[derive(Clone, Debug, Serialize, Default)]
pub struct Evidence {
    pub round: usize,
    /// χ²(smaller) − χ²(larger), residuals in units of each run's noise.
    pub lr: f64,
    pub extra_params: usize,
    /// Bootstrap null: replicates, mean LR*, p from the fitted gamma law, empirical p.
    pub bootstrap_replicates: usize,
    pub null_mean_lr: f64,
    pub p_value: f64,
    pub p_empirical: f64,
    /// Holm-adjusted over the candidates of the round.
    pub p_holm: f64,
    /// Leave-runs-out CV: paired t of the per-run held-out improvement (None: not cross-validated).
    pub cv_paired_t: Option<f64>,
    pub cv_rms_m: Option<f64>,
    pub decision: String,
}

/// One finding of the contract.
#[derive(Clone, Debug, Serialize)]
pub struct Finding {
    pub effect: String,
    pub accepted: bool,
    pub form: String,
    pub parameters: BTreeMap<String, Estimate>,
    pub evidence: Evidence,
    #[serde(rename = "where")]
    pub where_: BTreeMap<String, serde_json::Value>,
    pub baseline: ModelScore,
    pub extended: ModelScore,
}

/// One row of the table of every candidate tested.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateRow {
    pub round: usize,
    pub effect: String,
    pub form: String,
    pub accepted: bool,
    pub parameters: BTreeMap<String, Estimate>,
    pub evidence: Evidence,
}

/// Fitted T and μ of one run (its own fit) against its covariates.
#[derive(Clone, Debug, Serialize)]
pub struct DriftPoint {
    pub run: String,
    pub material: String,
    pub v0_mps: f64,
    pub t_s: f64,
    pub mu: f64,
    pub z0_m: f64,
}

/// Per-run parameter drift with the baseline and with the final model's extra terms held fixed.
#[derive(Clone, Debug, Serialize)]
pub struct Drift {
    pub before: Vec<DriftPoint>,
    pub after: Vec<DriftPoint>,
    /// Lines such as "t_s vs |v0| (316)" before and after.
    pub lines_before: BTreeMap<String, Line>,
    pub lines_after: BTreeMap<String, Line>,
    pub note: String,
}

/// Settings that produced the diagnosis.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    pub bootstrap: usize,
    pub alpha: f64,
    pub folds: usize,
    pub seed: u64,
    pub candidates: Vec<String>,
}

/// The whole diagnosis.
#[derive(Clone, Debug, Serialize)]
pub struct Diagnosis {
    pub mismatch: bool,
    pub findings: Vec<Finding>,
    pub candidates: Vec<CandidateRow>,
    pub model: ModelScore,
    pub model_parameters: BTreeMap<String, Estimate>,
    pub baseline_model: ModelScore,
    pub residuals_before: Option<Structure>,
    pub residuals_after: Option<Structure>,
    pub drift: Option<Drift>,
    pub runs_used: usize,
    pub materials: Vec<String>,
    pub settings: Settings,
    pub note: String,
}
