//! The `compare` stage kind: every run's residuals in, pooled residual statistics out (for discovery).

use super::fit_io::{collection_input, json_pretty, parse_item};
use crate::artifacts::RunResiduals;
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::residual_stats::compare;
use serde::{Deserialize, Serialize};

/// `kind = "compare"`.
pub struct Compare;

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct NoParams {}

impl StageKind for Compare {
    fn kind(&self) -> &'static str {
        "compare"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["residuals"]
    }
    /// `runs` is accepted (pipeline.toml binds it) but not needed: each residuals item carries
    /// its run's material and direction.
    fn optional_inputs(&self) -> &'static [&'static str] {
        &["runs"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["comparison"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        Ok(typed_params::<NoParams>(params)?.1)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let items = collection_input(input, "residuals", "compare")?;
        let mut all = Vec::with_capacity(items.len());
        for (item, bytes) in items {
            all.push(parse_item::<RunResiduals>(item, bytes, "the residuals")?);
        }
        let comparison = compare(&all);
        Ok([(
            "comparison".to_string(),
            Artifact::File(json_pretty(&comparison)?),
        )]
        .into())
    }
}
