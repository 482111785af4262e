//! diagnosis.json (output of `discover`): what discovery found, every candidate with its evidence,
//! the residual structure and the per-run drift before and after, as the report reads them.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use super::estimate::Estimate;

/// How well a model does: held-out error and in-sample fit.
#[derive(Clone, Debug, Serialize, Deserialize, Default)]
pub struct ModelScore {
    #[serde(with = "super::nan_null")]
    pub cv_rms_m: f64,
    #[serde(with = "super::nan_null")]
    pub rms_m: f64,
    #[serde(with = "super::nan_null")]
    pub chi2: f64,
    pub n_global_params: usize,
    pub terms: Vec<String>,
}

/// The statistics behind a decision.
#[derive(Clone, Debug, Serialize, Deserialize, Default)]
pub struct Evidence {
    pub round: usize,
    /// χ²(smaller) − χ²(larger), residuals in units of each run's noise.
    #[serde(with = "super::nan_null")]
    pub lr: f64,
    pub extra_params: usize,
    /// Bootstrap null: replicates, mean LR*, p from the fitted gamma law, empirical p.
    pub bootstrap_replicates: usize,
    #[serde(with = "super::nan_null")]
    pub null_mean_lr: f64,
    #[serde(with = "super::nan_null")]
    pub p_value: f64,
    #[serde(with = "super::nan_null")]
    pub p_empirical: f64,
    /// Holm-adjusted over the candidates of the round.
    #[serde(with = "super::nan_null")]
    pub p_holm: f64,
    /// Leave-runs-out CV: paired t of the per-run held-out improvement (None: not cross-validated).
    pub cv_paired_t: Option<f64>,
    pub cv_rms_m: Option<f64>,
    pub decision: String,
}

/// One finding of the contract.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Finding {
    pub effect: String,
    pub accepted: bool,
    pub form: String,
    #[serde(with = "super::estimate::stderr::map")]
    pub parameters: BTreeMap<String, Estimate>,
    pub evidence: Evidence,
    #[serde(rename = "where")]
    pub where_: BTreeMap<String, serde_json::Value>,
    pub baseline: ModelScore,
    pub extended: ModelScore,
}

/// One row of the table of every candidate tested.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CandidateRow {
    pub round: usize,
    pub effect: String,
    pub form: String,
    pub accepted: bool,
    #[serde(with = "super::estimate::stderr::map")]
    pub parameters: BTreeMap<String, Estimate>,
    pub evidence: Evidence,
}

/// Fitted T and μ of one run (its own fit) against its covariates.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DriftPoint {
    pub run: String,
    pub material: String,
    #[serde(with = "super::nan_null")]
    pub v0_mps: f64,
    #[serde(with = "super::nan_null")]
    pub t_s: f64,
    #[serde(with = "super::nan_null")]
    pub mu: f64,
    #[serde(with = "super::nan_null")]
    pub z0_m: f64,
}

/// Per-run parameter drift with the baseline and with the final model's extra terms held fixed.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Drift {
    pub before: Vec<DriftPoint>,
    pub after: Vec<DriftPoint>,
    /// Lines such as "t_s vs |v0| (316)" before and after.
    pub lines_before: BTreeMap<String, Line>,
    pub lines_after: BTreeMap<String, Line>,
    pub note: String,
}

/// Settings that produced the diagnosis.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Settings {
    pub bootstrap: usize,
    #[serde(with = "super::nan_null")]
    pub alpha: f64,
    pub folds: usize,
    pub seed: u64,
    pub candidates: Vec<String>,
}

/// The whole diagnosis.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Diagnosis {
    pub mismatch: bool,
    pub findings: Vec<Finding>,
    pub candidates: Vec<CandidateRow>,
    pub model: ModelScore,
    #[serde(with = "super::estimate::stderr::map")]
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

/// Pooled residual statistics of one bin.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Bin {
    pub n: usize,
    #[serde(with = "super::nan_null")]
    pub rms_m: f64,
    #[serde(with = "super::nan_null")]
    pub mean_m: f64,
    /// Mean residual over its standard error (runs as independent units).
    #[serde(with = "super::nan_null")]
    pub mean_z: f64,
    /// RMS of residual/σ_run: 1 where the model fits within noise.
    #[serde(with = "super::nan_null")]
    pub rms_over_noise: f64,
}

/// Residual structure of a fitted model.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Structure {
    pub by_phase: BTreeMap<String, Bin>,
    pub by_speed: BTreeMap<String, Bin>,
    pub by_position: BTreeMap<String, Bin>,
    pub by_direction: BTreeMap<String, Bin>,
    pub by_material: BTreeMap<String, Bin>,
    /// Stouffer combination of per-run Wald–Wolfowitz runs tests (negative: too few sign changes).
    #[serde(with = "super::nan_null")]
    pub runs_test_z: f64,
    #[serde(with = "super::nan_null")]
    pub runs_test_p: f64,
    /// Mean lag-1 autocorrelation of residuals, and its combined z (√n-weighted).
    #[serde(with = "super::nan_null")]
    pub lag1_autocorrelation: f64,
    #[serde(with = "super::nan_null")]
    pub lag1_z: f64,
}

/// A straight-line fit y = intercept + slope·x with ordinary least-squares standard errors.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Line {
    pub n: usize,
    #[serde(with = "super::nan_null")]
    pub intercept: f64,
    #[serde(with = "super::nan_null")]
    pub slope: f64,
    #[serde(with = "super::nan_null")]
    pub slope_se: f64,
    /// slope / slope_se.
    #[serde(with = "super::nan_null")]
    pub t: f64,
}

/// An effect id of diagnosis.json: the physics a finding names. Variants are in the order of their
/// ids, so sorting effects sorts their names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    GrooveTilt,
    /// Collision runs only: the impacts do something the impulse rule misses.
    ImpactSpecificMismatch,
    /// Collision runs only: the pairs' friction or drag differ from the single runs'.
    PairPhysicsMismatch,
    PositionDependentForce,
    RollingResistance,
    Unexplained,
    VelocityDependentDrag,
    VelocityDependentFriction,
}

impl Effect {
    /// Every effect, in id order.
    pub const ALL: [Effect; 8] = [
        Effect::GrooveTilt,
        Effect::ImpactSpecificMismatch,
        Effect::PairPhysicsMismatch,
        Effect::PositionDependentForce,
        Effect::RollingResistance,
        Effect::Unexplained,
        Effect::VelocityDependentDrag,
        Effect::VelocityDependentFriction,
    ];

    /// The id as written in diagnosis.json.
    pub fn id(self) -> &'static str {
        match self {
            Effect::GrooveTilt => "groove_tilt",
            Effect::ImpactSpecificMismatch => "impact_specific_mismatch",
            Effect::PairPhysicsMismatch => "pair_physics_mismatch",
            Effect::PositionDependentForce => "position_dependent_force",
            Effect::RollingResistance => "rolling_resistance",
            Effect::Unexplained => "unexplained",
            Effect::VelocityDependentDrag => "velocity_dependent_drag",
            Effect::VelocityDependentFriction => "velocity_dependent_friction",
        }
    }

    /// The effect of an id, if it is one.
    pub fn from_id(id: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.id() == id)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effect_ids_are_the_serialized_names_in_sorted_order() {
        for e in Effect::ALL {
            assert_eq!(
                serde_json::to_string(&e).unwrap(),
                format!("\"{}\"", e.id())
            );
            assert_eq!(Effect::from_id(e.id()), Some(e));
        }
        assert!(Effect::ALL.windows(2).all(|w| w[0].id() < w[1].id()));
        for id in crate::discover::EFFECTS {
            assert!(Effect::from_id(id).is_some(), "{id} has no Effect");
        }
        assert_eq!(Effect::from_id("probe"), None);
    }
}
