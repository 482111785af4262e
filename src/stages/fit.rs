//! The `fit` stage kind (per run): a Recording in, its `fit::RunFit` JSON out, and the recording again when it is a collision run (so `aggregate` need not load every single run).

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
        &["fits", "pair_runs"]
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
        // `pair_runs`: the recording item's bytes for a collision run, empty for a single
        // run, so a stage needing only the collision recordings binds `fit:pair_runs` and
        // does not load the single runs (the store keeps one copy of identical bytes).
        let (fit, pair_run) = match rec.info.experiment {
            Experiment::Single => (RunFit::Single(single::fit_single(&rec, &opts)), Vec::new()),
            Experiment::Collision => (
                RunFit::Collision(collision::fit_collision(&rec, &opts.collision_options())),
                bytes.to_vec(),
            ),
        };
        Ok([
            ("fits".to_string(), Artifact::File(json_bytes(&fit)?)),
            ("pair_runs".to_string(), Artifact::File(pair_run)),
        ]
        .into())
    }
}
