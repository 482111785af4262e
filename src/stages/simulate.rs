//! The `simulate` stage kind (per run): re-simulate the run with its fitted parameters, residuals out.
// groove:uses src/fit src/physics src/recording.rs src/engine/stage.rs src/stages/simulate.rs src/stages/fit_io.rs

use super::fit_io::{collection_input, file_input, json_bytes, parse_item};
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::residuals::residuals;
use crate::fit::RunFit;
use crate::recording::Recording;
use serde::{Deserialize, Serialize};

/// `kind = "simulate"`, `foreach = "runs"`.
pub struct Simulate;

/// No params yet (the groove and outlier cut come from each fit).
#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct NoParams {}

impl StageKind for Simulate {
    fn kind(&self) -> &'static str {
        "simulate"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["runs", "fits"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["residuals"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        Ok(typed_params::<NoParams>(params)?.1)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let item = input.item.unwrap_or("?");
        let rec: Recording = parse_item(
            item,
            file_input(input, "runs", "simulate")?,
            "the recording",
        )?;
        let fits = collection_input(input, "fits", "simulate")?;
        let bytes = fits.get(item).ok_or_else(|| {
            StageError(format!(
                "run `{item}` has no fit; bind `fits` to the fit stage that read the same runs (fits = \"fit:fits\")"
            ))
        })?;
        let fit: RunFit = parse_item(item, bytes, "the fit")?;
        let res = residuals(&rec, &fit);
        Ok([("residuals".to_string(), Artifact::File(json_bytes(&res)?))].into())
    }
}
