//! Helpers shared by the fit-side stage kinds (fit, aggregate, simulate, compare): reading inputs out of artifacts, writing JSON bytes.

use crate::engine::stage::{Artifact, ParamError, StageError, StageInput, IN_STORE_INPUT};
use crate::fit::options::OptionError;
use crate::recording::{self, Recording, RunInfo};
use std::collections::BTreeMap;

/// A fit-side param out of range as the engine's [`ParamError`].
pub fn param_error(e: OptionError) -> ParamError {
    ParamError {
        key: e.key.to_string(),
        message: e.message.to_string(),
    }
}

/// The bytes of the per-item input `name` of a `foreach` stage.
pub fn file_input<'a>(
    input: &'a StageInput,
    name: &str,
    kind: &str,
) -> Result<&'a [u8], StageError> {
    match input.inputs.get(name) {
        Some(Artifact::File(b)) => Ok(b),
        Some(Artifact::Collection(_)) => Err(StageError(format!(
            "the {kind} stage runs once per run: add `foreach = \"{name}\"` to its section in pipeline.toml"
        ))),
        Some(Artifact::InStore(_) | Artifact::OnDisk(_)) => Err(StageError(IN_STORE_INPUT.into())),
        None => Err(StageError(format!(
            "the {kind} stage needs the input `{name}`: bind it in pipeline.toml, e.g. {name} = \"ingest:runs\""
        ))),
    }
}

/// The items of the collection input `name`.
pub fn collection_input<'a>(
    input: &'a StageInput,
    name: &str,
    kind: &str,
) -> Result<&'a BTreeMap<String, Vec<u8>>, StageError> {
    match input.inputs.get(name) {
        Some(Artifact::Collection(items)) => Ok(items),
        Some(Artifact::InStore(_) | Artifact::OnDisk(_)) => Err(StageError(IN_STORE_INPUT.into())),
        Some(Artifact::File(_)) => Err(StageError(format!(
            "the {kind} stage needs `{name}` whole: bind it to a per-run output (e.g. \"fit:fits\") and do not list it in `foreach`"
        ))),
        None => Err(StageError(format!(
            "the {kind} stage needs the input `{name}`: bind it in pipeline.toml"
        ))),
    }
}

/// Parse one JSON item of a collection, naming the item and the stage that made it on failure.
pub fn parse_item<T: serde::de::DeserializeOwned>(
    item: &str,
    bytes: &[u8],
    what: &str,
) -> Result<T, StageError> {
    serde_json::from_slice(bytes).map_err(|e| {
        StageError(format!(
            "{what} of `{item}` is not valid JSON ({e}); rerun the stage that makes it"
        ))
    })
}

/// The recording of one `ingest:runs` item (`recording::item`), naming the item on failure.
pub fn recording(item: &str, bytes: &[u8]) -> Result<Recording, StageError> {
    recording::item::decode(bytes).map_err(|e| not_a_recording(item, &e))
}

/// The run metadata of a recording item, without decoding its tracks.
pub fn run_info(item: &str, bytes: &[u8]) -> Result<RunInfo, StageError> {
    recording::item::decode_info(bytes).map_err(|e| not_a_recording(item, &e))
}

fn not_a_recording(item: &str, why: &recording::item::DecodeError) -> StageError {
    StageError(format!(
        "run `{item}`: the item is not a recording: {why}; rerun the ingest stage"
    ))
}

/// Compact, deterministic JSON bytes (per-run artifacts).
pub fn json_bytes<T: serde::Serialize>(value: &T) -> Result<Vec<u8>, StageError> {
    serde_json::to_vec(value).map_err(|e| {
        StageError(format!(
            "cannot write JSON ({e}); this is a bug, please report it"
        ))
    })
}

/// Indented, deterministic JSON bytes with a final newline (files people read).
pub fn json_pretty<T: serde::Serialize>(value: &T) -> Result<Vec<u8>, StageError> {
    let mut v = serde_json::to_vec_pretty(value).map_err(|e| {
        StageError(format!(
            "cannot write JSON ({e}); this is a bug, please report it"
        ))
    })?;
    v.push(b'\n');
    Ok(v)
}
