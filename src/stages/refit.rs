//! The `refit` stage kind: the diagnosis, the collision recordings and summary.json in,
//! under_accepted_physics.json out (the chapter's numbers under the physics discovery accepted).

use super::fit_io::{collection_input, json_pretty, param_error, recording};
use crate::artifacts::{self, Diagnosis, Summary};
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::collision::whole_summary::WholeRunOptions;
use crate::fit::refit::under_accepted;
use serde::{Deserialize, Serialize};

/// Params of the `refit` stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RefitParams {
    /// The groove's opening angle (degrees) and k = m R² / I of the particles; both inherited
    /// from `[project] params` like every stage that needs the geometry.
    pub groove_angle_deg: f64,
    pub k: f64,
}

impl Default for RefitParams {
    fn default() -> Self {
        let chapter = crate::fit::FitOptions::default();
        RefitParams {
            groove_angle_deg: chapter.groove_angle_deg,
            k: chapter.k,
        }
    }
}

fn params(table: &toml::Table) -> Result<(RefitParams, serde_json::Value), ParamError> {
    let (p, json): (RefitParams, _) = typed_params(table)?;
    crate::fit::options::check_groove(p.groove_angle_deg, p.k).map_err(param_error)?;
    Ok((p, json))
}

/// `kind = "refit"`: refits with every accepted term carried.
pub struct Refit;

fn file<'a>(input: &'a StageInput, name: &str) -> Result<Option<&'a [u8]>, StageError> {
    match input.inputs.get(name) {
        None => Ok(None),
        Some(Artifact::File(b)) => Ok(Some(b)),
        Some(_) => Err(StageError(format!(
            "the refit stage's input `{name}` must be one file: bind it to \"discover:diagnosis\" or \"aggregate:summary\""
        ))),
    }
}

impl StageKind for Refit {
    fn kind(&self) -> &'static str {
        "refit"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["diagnosis", "runs"]
    }
    fn optional_inputs(&self) -> &'static [&'static str] {
        &["summary"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["physics"]
    }
    fn canonical_params(&self, table: &toml::Table) -> Result<serde_json::Value, ParamError> {
        params(table).map(|(_, json)| json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (p, _) = params(input.params).map_err(|e| StageError(e.to_string()))?;
        let diagnosis: Diagnosis = match file(input, "diagnosis")? {
            Some(b) => artifacts::from_json("diagnosis", b).map_err(StageError)?,
            None => {
                return Err(StageError(
                    "the refit stage needs `diagnosis`: bind it to \"discover:diagnosis\"".into(),
                ))
            }
        };
        let summary: Option<Summary> = file(input, "summary")?
            .map(|b| artifacts::from_json("summary", b))
            .transpose()
            .map_err(StageError)?;
        // the collision recordings only (`fit:pair_runs` leaves single runs' items empty)
        let mut recordings = Vec::new();
        for (item, bytes) in collection_input(input, "runs", "refit")? {
            if !bytes.is_empty() {
                recordings.push(recording(item, bytes)?);
            }
        }
        let groove = crate::physics::Groove::of_params(p.groove_angle_deg, p.k);
        let baseline = summary
            .as_ref()
            .and_then(|s| s.collisions.as_ref())
            .and_then(|c| c.whole_run.as_ref());
        let out = under_accepted(
            &diagnosis,
            &recordings,
            baseline,
            groove,
            &WholeRunOptions::default(),
        );
        let mut outputs = StageOutputs::new();
        outputs.insert("physics".into(), Artifact::File(json_pretty(&out)?));
        Ok(outputs)
    }
}
