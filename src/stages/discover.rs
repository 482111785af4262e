//! The `discover` stage kind: recordings in, diagnosis.json out.

use crate::discover::{discover_reporting, Options};
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::recording::item;

/// Finds missing physics over all single runs.
pub struct Discover;

fn options(params: &toml::Table) -> Result<(Options, serde_json::Value), ParamError> {
    let (opts, json): (Options, _) = typed_params(params)?;
    opts.validate()
        .map_err(|(key, message)| ParamError { key, message })?;
    Ok((opts, json))
}

impl StageKind for Discover {
    fn kind(&self) -> &'static str {
        "discover"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["runs"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["diagnosis"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        options(params).map(|(_, json)| json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (mut opts, _) = options(input.params).map_err(|e| StageError(e.to_string()))?;
        opts.seed = input.seed;
        let Some(Artifact::Collection(items)) = input.inputs.get("runs") else {
            return Err(StageError(
                "input `runs` must be the collection of recordings from ingest; bind it as `runs = \"ingest:runs\"`".into(),
            ));
        };
        let mut recordings = Vec::with_capacity(items.len());
        for (name, bytes) in items {
            recordings.push(item::decode(bytes).map_err(|e| {
                StageError(format!(
                    "run `{name}`: the item is not a recording: {e}; rerun the ingest stage"
                ))
            })?);
        }
        // discovery refits every run with its own integrator (to measure noise and flag outliers
        // consistently), so it reads no per-run fit and a change to `fit` does not rerun it
        let say = |what: &str| input.report(what);
        let mut diagnosis = discover_reporting(&recordings, &opts, &say);
        let groove = crate::physics::Groove::of_params(opts.groove_angle_deg, opts.k);
        crate::discover::pairs::add_pair_findings(&mut diagnosis, &recordings, groove);
        let bytes =
            crate::artifacts::checked_json::to_json_pretty_checked("diagnosis.json", &diagnosis)
                .map_err(StageError)?;
        let mut out = StageOutputs::new();
        out.insert("diagnosis".into(), Artifact::File(bytes));
        Ok(out)
    }
}
