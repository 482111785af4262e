//! The cache key of a stage (or of one item of a per-item stage): exactly what can change its output.

use super::hashing::sha256_hex;
use serde::Serialize;
use std::collections::BTreeMap;

/// Serialized to JSON (maps sorted) and hashed with sha256. Adding a field here changes every key.
#[derive(Debug, Clone, Serialize)]
pub struct StageKey<'a> {
    pub kind: &'a str,
    /// Canonical params (defaults filled in, keys sorted).
    pub params: &'a serde_json::Value,
    /// The shell command of a `command` stage.
    pub cmd: Option<&'a str>,
    /// Input name → content digest.
    pub inputs: &'a BTreeMap<String, String>,
    /// Output names and the kind of artifact each must be.
    pub outputs: Vec<&'a str>,
    /// The current item of a per-item stage.
    pub item: Option<&'a str>,
    pub seed: u64,
    pub groove_version: &'a str,
    /// The code fingerprint of the kind.
    pub code: &'a str,
}

impl StageKey<'_> {
    pub fn digest(&self) -> String {
        sha256_hex(&serde_json::to_vec(self).expect("a stage key serializes"))
    }
}

/// Rebuild a JSON value with every object's keys in sorted order, whatever map type serde_json uses.
pub fn canonical_json(value: serde_json::Value) -> serde_json::Value {
    match value {
        serde_json::Value::Object(map) => {
            let sorted: BTreeMap<String, serde_json::Value> = map
                .into_iter()
                .map(|(k, v)| (k, canonical_json(v)))
                .collect();
            serde_json::Value::Object(sorted.into_iter().collect())
        }
        serde_json::Value::Array(items) => {
            serde_json::Value::Array(items.into_iter().map(canonical_json).collect())
        }
        other => other,
    }
}

/// Hash of a per-item stage: its item keys in item order.
pub fn items_digest(items: &BTreeMap<String, String>) -> String {
    sha256_hex(&serde_json::to_vec(items).expect("item keys serialize"))
}
