//! The `fit` stage kind (per run): a Recording in, its `fit::RunFit` JSON out.

use super::fit_io::{file_input, json_bytes, param_error, recording};
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::{collision, single, FitOptions, RunFit};
use crate::recording::Experiment;

/// `kind = "fit"`, `foreach = "runs"`: fit one run.
pub struct Fit;

impl StageKind for Fit {
    fn kind(&self) -> &'static str {
        "fit"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["runs"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["fits"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        let (opts, json) = typed_params::<FitOptions>(params)?;
        opts.validate().map_err(param_error)?;
        Ok(json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (opts, _) =
            typed_params::<FitOptions>(input.params).map_err(|e| StageError(e.to_string()))?;
        let bytes = file_input(input, "runs", "fit")?;
        let rec = recording(input.item.unwrap_or("?"), bytes)?;
        let fit = match rec.info.experiment {
            Experiment::Single => RunFit::Single(single::fit_single(&rec, &opts)),
            Experiment::Collision => {
                RunFit::Collision(collision::fit_collision(&rec, &opts.collision_options()))
            }
        };
        Ok([("fits".to_string(), Artifact::File(json_bytes(&fit)?))].into())
    }
}
