//! The `ingest` stage kind: the dataset folder's files in, checked recordings and the list of skipped runs out.

use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
    IN_STORE_INPUT,
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
            Some(Artifact::InStore(_)) => return Err(StageError(IN_STORE_INPUT.into())),
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
        let mut out = StageOutputs::new();
        let (runs, skipped) = match input.put_item {
            // each item into the store as it is made: never all items at once
            Some(put) => {
                let items =
                    ingest::ingest_items_kept(files, &params, ingest::CHUNK_BYTES, &mut |bytes| {
                        put(&bytes)
                    })
                    .map_err(|e| StageError(e.to_string()))?;
                input.report(&format!("{} runs, {}", items.runs.len(), items.how));
                let runs = items
                    .runs
                    .into_iter()
                    .map(|(name, sha)| sha.map(|sha| (name, sha)))
                    .collect::<Result<_, _>>()?;
                (Artifact::InStore(runs), items.skipped)
            }
            None => {
                let items =
                    ingest::ingest_items(files, &params).map_err(|e| StageError(e.to_string()))?;
                input.report(&format!("{} runs, {}", items.runs.len(), items.how));
                (Artifact::Collection(items.runs), items.skipped)
            }
        };
        out.insert("runs".into(), runs);
        out.insert(
            "skipped".into(),
            Artifact::File(ingest::skipped_json(&skipped)),
        );
        Ok(out)
    }
}
