//! The `simulate` stage kind (per run): re-simulate the run with its fitted parameters, residuals out.

use super::fit_io::{collection_input, file_input, json_bytes, param_error, parse_item, recording};
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::residuals::residuals;
use crate::fit::{FitOptions, RunFit};
use serde::{Deserialize, Serialize};

/// `kind = "simulate"`, `foreach = "runs"`.
pub struct Simulate;

/// The groove of the collision fits (keep equal to the fit stage's params; single-run fits
/// record their own).
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
struct SimulateParams {
    groove_angle_deg: f64,
    k: f64,
}

impl Default for SimulateParams {
    fn default() -> Self {
        let fit = FitOptions::default();
        SimulateParams {
            groove_angle_deg: fit.groove_angle_deg,
            k: fit.k,
        }
    }
}

impl SimulateParams {
    fn options(&self) -> FitOptions {
        FitOptions {
            groove_angle_deg: self.groove_angle_deg,
            k: self.k,
            ..FitOptions::default()
        }
    }
}

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
        let (p, json) = typed_params::<SimulateParams>(params)?;
        p.options().validate().map_err(param_error)?;
        Ok(json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (params, _) =
            typed_params::<SimulateParams>(input.params).map_err(|e| StageError(e.to_string()))?;
        let item = input.item.unwrap_or("?");
        let rec = recording(item, file_input(input, "runs", "simulate")?)?;
        // `foreach = ["runs", "fits"]` passes this run's fit alone (its key then depends on no
        // other run); `foreach = "runs"` passes every fit and this run's is looked up.
        let bytes = match input.inputs.get("fits") {
            Some(Artifact::File(bytes)) => bytes.as_slice(),
            _ => collection_input(input, "fits", "simulate")?
                .get(item)
                .ok_or_else(|| {
                    StageError(format!(
                        "run `{item}` has no fit; bind `fits` to the fit stage that read the same runs (fits = \"fit:fits\")"
                    ))
                })?,
        };
        let fit: RunFit = parse_item(item, bytes, "the fit")?;
        let res = residuals(&rec, &fit, params.options().groove());
        Ok([("residuals".to_string(), Artifact::File(json_bytes(&res)?))].into())
    }
}
