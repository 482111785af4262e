//! The `validate` stage's `validation`: recovered values beside the truth of a synthesized dataset
//! (`{"truth": false}` when the dataset has no truth file). Fields are in the order they are
//! written (alphabetical, as the file has always been).

use super::diagnosis::Effect;
use serde::{Deserialize, Serialize};

/// validation.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Validation {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub effects: Option<EffectCheck>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_pp: Option<MuPpCheck>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub parameters: Option<Vec<ParameterCheck>>,
    /// False: the dataset has no truth file, and nothing else is present.
    pub truth: bool,
}

impl Validation {
    /// The validation of a dataset without a truth file.
    pub fn no_truth() -> Validation {
        Validation {
            effects: None,
            mu_pp: None,
            parameters: None,
            truth: false,
        }
    }
}

/// One checked quantity of one material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum ParameterCheck {
    /// A number recovered with its bootstrap interval (μ).
    Value {
        error: f64,
        high: Option<f64>,
        low: Option<f64>,
        material: String,
        quantity: String,
        recovered: f64,
        truth: f64,
        within_interval: Option<bool>,
    },
    /// A law the truth states (restitution), shown beside the fitted curves.
    Law {
        material: String,
        quantity: String,
        truth_law: String,
    },
}

/// μ_pp: the truth and the recovered value (null when the data have no slip impacts).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MuPpCheck {
    pub recovered: Option<f64>,
    pub truth: f64,
}

/// The concealed physics: which effects the truth has, which discovery accepted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EffectCheck {
    pub accepted: Vec<Effect>,
    pub all_named: bool,
    pub missed: Vec<Effect>,
    pub spurious: Vec<Effect>,
    pub truth: Vec<TruthEffect>,
}

/// One effect of the truth: its diagnosis.json effect id and the truth term.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruthEffect {
    pub effect: Effect,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    /// The truth term as the truth file states it.
    pub term: serde_json::Value,
}
