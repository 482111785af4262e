//! The `validate` stage kind: recovered values beside the truth of a synthesized dataset.

use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::physics::{Friction, Restitution, Term};
use crate::synth::Truth;
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use std::collections::BTreeMap;

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
        let validation = match input.inputs.get("truth") {
            None => json!({ "truth": false }),
            Some(truth) => {
                let text = std::str::from_utf8(file(truth, "truth")?).map_err(|_| {
                    StageError("truth file is not UTF-8 text; save it as UTF-8".into())
                })?;
                let truth =
                    Truth::parse(text).map_err(|e| StageError(format!("truth file: {e}")))?;
                let summary = json_input(input, "summary")?;
                let diagnosis = json_input(input, "diagnosis")?;
                validate(&truth, &summary, &diagnosis)
            }
        };
        let mut bytes = serde_json::to_vec_pretty(&validation)
            .map_err(|e| StageError(format!("cannot encode validation: {e}")))?;
        bytes.push(b'\n');
        Ok(BTreeMap::from([(
            "validation".to_string(),
            Artifact::File(bytes),
        )]))
    }
}

fn file<'a>(artifact: &'a Artifact, name: &str) -> Result<&'a [u8], StageError> {
    match artifact {
        Artifact::File(bytes) => Ok(bytes),
        Artifact::Collection(_) => Err(StageError(format!(
            "input `{name}` must be a single file, not a collection; bind it to a file"
        ))),
    }
}

fn json_input(input: &StageInput, name: &str) -> Result<Value, StageError> {
    let artifact = input.inputs.get(name).ok_or_else(|| {
        StageError(format!(
            "input `{name}` is missing; bind it in pipeline.toml"
        ))
    })?;
    serde_json::from_slice(file(artifact, name)?).map_err(|e| {
        StageError(format!(
            "input `{name}` is not valid JSON ({e}); rerun its stage"
        ))
    })
}

/// The effect ID of `diagnosis.json` that a truth term belongs to (`None`: the baseline's own drag).
pub fn effect_id(term: &Term) -> Option<&'static str> {
    match term {
        Term::LinearDrag { .. } => None,
        Term::QuadraticDrag { .. } | Term::SaturatingDrag { .. } => Some("velocity_dependent_drag"),
        Term::RollingResistance { .. } => Some("rolling_resistance"),
        Term::GrooveTilt { .. } => Some("groove_tilt"),
        Term::PositionForce { .. } => Some("position_dependent_force"),
    }
}

/// Compare what the analysis recovered with the truth: friction per material, μ_pp, and the
/// concealed physics (which effects are in the truth, which discovery accepted).
pub fn validate(truth: &Truth, summary: &Value, diagnosis: &Value) -> Value {
    let mut materials = Vec::new();
    for material in &truth.materials {
        let recovered = &summary["single"]["materials"][&material.name];
        let mu_truth = match material.friction {
            Friction::Constant { mu } => Some(mu),
            Friction::VelocityDependent { mu_inf, .. } => Some(mu_inf),
        };
        for (quantity, key) in [("mu_weighted", "mu_weighted"), ("mu_fast", "mu_fast")] {
            let estimate = &recovered[key];
            let (Some(value), Some(truth_value)) = (estimate["value"].as_f64(), mu_truth) else {
                continue;
            };
            let low = estimate["interval"]["lo"].as_f64();
            let high = estimate["interval"]["hi"].as_f64();
            let within = match (low, high) {
                (Some(l), Some(h)) => Some(l <= truth_value && truth_value <= h),
                _ => None,
            };
            materials.push(json!({
                "material": material.name,
                "quantity": quantity,
                "truth": truth_value,
                "recovered": value,
                "low": low,
                "high": high,
                "error": value - truth_value,
                "within_interval": within,
            }));
        }
        for (setup, law) in [
            ("rolling", &material.restitution_rolling),
            ("contact", &material.restitution_contact),
        ] {
            materials.push(json!({
                "material": material.name,
                "quantity": format!("restitution_{setup}"),
                "truth_law": restitution_text(law),
            }));
        }
    }
    let mu_pp_recovered = summary["collisions"]["mu_pp"]["value"]["value"].as_f64();
    let mut truth_effects: Vec<Value> = truth
        .physics
        .terms
        .iter()
        .filter_map(|term| {
            effect_id(term).map(|id| json!({ "effect": id, "term": serde_json::to_value(term).unwrap_or(Value::Null) }))
        })
        .collect();
    for material in &truth.materials {
        if let Friction::VelocityDependent { .. } = material.friction {
            truth_effects.push(json!({
                "effect": "velocity_dependent_friction",
                "material": material.name,
                "term": serde_json::to_value(material.friction).unwrap_or(Value::Null),
            }));
        }
    }
    let truth_ids: std::collections::BTreeSet<String> = truth_effects
        .iter()
        .filter_map(|e| e["effect"].as_str().map(str::to_string))
        .collect();
    let accepted: std::collections::BTreeSet<String> = diagnosis["findings"]
        .as_array()
        .map(|findings| {
            findings
                .iter()
                .filter(|f| f["accepted"].as_bool() == Some(true))
                // findings about collision runs (discover::pairs) name no single-run term
                .filter(|f| f["where"]["experiment"] != "collision")
                .filter_map(|f| f["effect"].as_str().map(str::to_string))
                .collect()
        })
        .unwrap_or_default();
    json!({
        "truth": true,
        "parameters": materials,
        "mu_pp": { "truth": truth.pair.mu_pp, "recovered": mu_pp_recovered },
        "effects": {
            "truth": truth_effects,
            "accepted": accepted,
            "missed": truth_ids.difference(&accepted).collect::<Vec<_>>(),
            "spurious": accepted.difference(&truth_ids).collect::<Vec<_>>(),
            "all_named": truth_ids == accepted,
        },
    })
}

fn restitution_text(law: &Restitution) -> String {
    serde_json::to_string(law).unwrap_or_default()
}
