//! The `validate` stage kind: recovered values beside the truth of a synthesized dataset.

use crate::artifacts::diagnosis::{Diagnosis, Effect};
use crate::artifacts::summary::Summary;
use crate::artifacts::validation::{
    EffectCheck, MuPpCheck, ParameterCheck, TruthEffect, Validation,
};
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
    IN_STORE_INPUT,
};
use crate::physics::{Friction, Restitution, Term};
use crate::synth::Truth;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};

/// `kind = "validate"`: inputs `truth` (optional: the truth TOML), `summary` (summary.json) and
/// `diagnosis` (diagnosis.json); output `validation`. Without a truth file it writes
/// `{"truth": false}`: a dataset of real recordings has nothing to validate against.
pub struct Validate;

#[derive(Debug, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct ValidateParams {}

impl StageKind for Validate {
    fn kind(&self) -> &'static str {
        "validate"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["summary", "diagnosis"]
    }
    fn optional_inputs(&self) -> &'static [&'static str] {
        &["truth"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["validation"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        typed_params::<ValidateParams>(params).map(|(_, json)| json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let validation = match read_truth(input)? {
            None => Validation::no_truth(),
            Some(truth) => {
                let summary: Summary = json_input(input, "summary")?;
                let diagnosis: Diagnosis = json_input(input, "diagnosis")?;
                validate(&truth, &summary, &diagnosis)
            }
        };
        let bytes =
            crate::artifacts::checked_json::to_json_pretty_checked("validation.json", &validation)
                .map_err(StageError)?;
        Ok(BTreeMap::from([(
            "validation".to_string(),
            Artifact::File(bytes),
        )]))
    }
}

/// The truth file, when the dataset has one.
fn read_truth(input: &StageInput) -> Result<Option<Truth>, StageError> {
    let Some(truth) = input.inputs.get("truth") else {
        return Ok(None);
    };
    let text = std::str::from_utf8(file(truth, "truth")?)
        .map_err(|_| StageError("truth file is not UTF-8 text; save it as UTF-8".into()))?;
    Truth::parse(text)
        .map(Some)
        .map_err(|e| StageError(format!("truth file: {e}")))
}

fn file<'a>(artifact: &'a Artifact, name: &str) -> Result<&'a [u8], StageError> {
    match artifact {
        Artifact::File(bytes) => Ok(bytes),
        Artifact::Collection(_) => Err(StageError(format!(
            "input `{name}` must be a single file, not a collection; bind it to a file"
        ))),
        Artifact::InStore(_) | Artifact::OnDisk(_) => Err(StageError(IN_STORE_INPUT.into())),
    }
}

fn json_input<T: serde::de::DeserializeOwned>(
    input: &StageInput,
    name: &str,
) -> Result<T, StageError> {
    let artifact = input.inputs.get(name).ok_or_else(|| {
        StageError(format!(
            "input `{name}` is missing; bind it in pipeline.toml"
        ))
    })?;
    crate::artifacts::from_json(&format!("input `{name}`"), file(artifact, name)?)
        .map_err(StageError)
}

/// The effect of `diagnosis.json` that a truth term belongs to (`None`: the baseline's own drag).
pub fn effect_id(term: &Term) -> Option<Effect> {
    match term {
        Term::LinearDrag { .. } => None,
        Term::QuadraticDrag { .. } | Term::SaturatingDrag { .. } => {
            Some(Effect::VelocityDependentDrag)
        }
        Term::RollingResistance { .. } => Some(Effect::RollingResistance),
        Term::GrooveTilt { .. } => Some(Effect::GrooveTilt),
        Term::PositionForce { .. } | Term::LocalizedForce { .. } | Term::StepForce { .. } => {
            Some(Effect::PositionDependentForce)
        }
        Term::TimePeriodicForce { .. } => Some(Effect::TimeDependentForce),
        Term::Spline(_) => Some(Effect::Unexplained),
    }
}

/// Compare what the analysis recovered with the truth: friction per material, μ_pp, and the
/// concealed physics (which effects are in the truth, which discovery accepted).
pub fn validate(truth: &Truth, summary: &Summary, diagnosis: &Diagnosis) -> Validation {
    let mu_pp_recovered = summary
        .collisions
        .as_ref()
        .and_then(|c| c.mu_pp.value)
        .map(|v| v.value)
        .filter(|v| v.is_finite());
    Validation {
        effects: Some(effect_check(truth, diagnosis)),
        mu_pp: Some(MuPpCheck {
            recovered: mu_pp_recovered,
            truth: truth.pair.mu_pp,
        }),
        parameters: Some(parameter_checks(truth, summary)),
        truth: true,
    }
}

/// μ per material (weighted and fast means) against the truth's μ (μ∞ for a speed-dependent law),
/// and the truth's restitution laws as text.
fn parameter_checks(truth: &Truth, summary: &Summary) -> Vec<ParameterCheck> {
    let mut checks = Vec::new();
    for material in &truth.materials {
        let recovered = summary
            .single
            .as_ref()
            .and_then(|s| s.materials.get(&material.name));
        let mu_truth = match material.friction {
            Friction::Constant { mu } => mu,
            Friction::VelocityDependent { mu_inf, .. } => mu_inf,
        };
        for quantity in ["mu_weighted", "mu_fast"] {
            let Some(m) = recovered else { continue };
            let estimate = if quantity == "mu_weighted" {
                m.mu_weighted
            } else {
                m.mu_fast
            };
            if !estimate.value.is_finite() {
                continue;
            }
            let (low, high) = match estimate.interval {
                Some(iv) => (Some(iv.lo), Some(iv.hi)),
                None => (None, None),
            };
            checks.push(ParameterCheck::Value {
                error: estimate.value - mu_truth,
                high,
                low,
                material: material.name.clone(),
                quantity: quantity.to_string(),
                recovered: estimate.value,
                truth: mu_truth,
                within_interval: estimate.interval.map(|iv| iv.contains(mu_truth)),
            });
        }
        for (setup, law) in [
            ("rolling", &material.restitution_rolling),
            ("contact", &material.restitution_contact),
        ] {
            checks.push(ParameterCheck::Law {
                material: material.name.clone(),
                quantity: format!("restitution_{setup}"),
                truth_law: restitution_text(law),
            });
        }
    }
    checks
}

/// The truth's effects (physics terms beyond the baseline, and speed-dependent friction per
/// material) against the effects discovery accepted.
fn effect_check(truth: &Truth, diagnosis: &Diagnosis) -> EffectCheck {
    let mut truth_effects: Vec<TruthEffect> = truth
        .physics
        .terms
        .iter()
        .filter_map(|term| {
            effect_id(term).map(|effect| TruthEffect {
                effect,
                material: None,
                term: serde_json::to_value(term).unwrap_or(serde_json::Value::Null),
            })
        })
        .collect();
    for material in &truth.materials {
        if let Friction::VelocityDependent { .. } = material.friction {
            truth_effects.push(TruthEffect {
                effect: Effect::VelocityDependentFriction,
                material: Some(material.name.clone()),
                term: serde_json::to_value(material.friction).unwrap_or(serde_json::Value::Null),
            });
        }
    }
    let truth_ids: BTreeSet<Effect> = truth_effects.iter().map(|e| e.effect).collect();
    // an accepted finding names one of the effects (`unexplained` is never accepted)
    let accepted: BTreeSet<Effect> = diagnosis
        .findings
        .iter()
        .filter(|f| f.accepted)
        // findings about collision runs (discover::pairs) name no single-run term
        .filter(|f| f.where_.get("experiment").and_then(|v| v.as_str()) != Some("collision"))
        .filter_map(|f| Effect::from_id(&f.effect))
        .collect();
    EffectCheck {
        missed: truth_ids.difference(&accepted).copied().collect(),
        spurious: accepted.difference(&truth_ids).copied().collect(),
        all_named: truth_ids == accepted,
        accepted: accepted.into_iter().collect(),
        truth: truth_effects,
    }
}

fn restitution_text(law: &Restitution) -> String {
    serde_json::to_string(law).unwrap_or_default()
}
