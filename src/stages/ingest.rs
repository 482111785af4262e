//! The `ingest` stage kind: the dataset folder's files in, checked recordings and the list of skipped runs out.

use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::ingest::{self, IngestParams};

/// `kind = "ingest"`: input `dataset` (a folder's top-level files), outputs `runs` (run → `Recording` in
/// the binary format of `recording::item`) and `skipped` (JSON list of `{run, reason}`). (A Parquet table of all samples
/// was an output too; no stage read it, and writing it cost as much as reading the CSV typed.)
pub struct Ingest;

impl StageKind for Ingest {
    fn kind(&self) -> &'static str {
        "ingest"
    }

    fn inputs(&self) -> &'static [&'static str] {
        &["dataset"]
    }

    fn outputs(&self) -> &'static [&'static str] {
        &["runs", "skipped"]
    }

    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        let (typed, json) = typed_params::<IngestParams>(params)?;
        typed.check().map_err(|p| ParamError {
            key: p.key,
            message: format!("{}; {}", p.message, p.fix),
        })?;
        Ok(json)
    }

    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (params, _) =
            typed_params::<IngestParams>(input.params).map_err(|e| StageError(e.to_string()))?;
        let files = match input.inputs.get("dataset") {
            Some(Artifact::Collection(files)) => files,
            Some(Artifact::File(_)) => {
                return Err(StageError(
                    "input dataset is a single file; bind it to the dataset folder (inputs = { dataset = \"${data}\" })".into(),
                ))
            }
            None => {
                return Err(StageError(
                    "input dataset is missing; bind it to the dataset folder (inputs = { dataset = \"${data}\" })".into(),
                ))
            }
        };
        let items = ingest::ingest_items(files, &params).map_err(|e| StageError(e.to_string()))?;
        input.report(&format!("{} runs, {}", items.runs.len(), items.how));
        let mut out = StageOutputs::new();
        out.insert("runs".into(), Artifact::Collection(items.runs));
        out.insert(
            "skipped".into(),
            Artifact::File(ingest::skipped_json(&items.skipped)),
        );
        Ok(out)
    }
}
