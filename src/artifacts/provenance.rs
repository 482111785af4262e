//! `engine:provenance` as its readers see it: the code, the seed, every data input's hash, every
//! upstream stage's key and every stage's params as run. The engine writes it (`engine::provenance`, which knows no analysis); this
//! type is the contract the report reads, pinned against the engine's bytes by `tests/contracts.rs`.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The provenance record.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Provenance {
    pub groove_version: String,
    pub code_commit: String,
    /// Code fingerprint of every kind, by kind.
    pub fingerprints: BTreeMap<String, String>,
    pub seed: u64,
    pub inputs: Vec<InputHash>,
    pub stages: Vec<StageKeyRecord>,
    /// The checked params (defaults filled in) of the reading stage and every stage upstream,
    /// by stage name.
    pub params: BTreeMap<String, serde_json::Value>,
}

/// A data input read upstream, with the sha256 of its bytes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InputHash {
    pub path: String,
    pub sha256: String,
}

/// An upstream stage and its cache key.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StageKeyRecord {
    pub stage: String,
    pub kind: String,
    pub key: String,
}
