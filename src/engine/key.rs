//! The cache key of a stage (or of one item of a per-item stage): exactly what can change its output.

use super::hashing::{json_map_sha256, put_json_map, put_json_str, sha256_hex, BufHasher};
use serde::Serialize;
use sha2::{Digest, Sha256};
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

/// The keys of many items of one stage, which differ only in `inputs` and `item`: the JSON of
/// every other field is written once, and the hash of the part before `inputs` is taken once,
/// so that 100,000 item keys cost their own bytes only. Gives `StageKey::digest` exactly (the
/// JSON is written as serde_json writes the struct: fields in order, no spaces).
pub struct ItemKeys {
    /// sha256 state after `{"kind":…,"params":…,"cmd":…,"inputs":`.
    before_inputs: Sha256,
    /// `,"outputs":…,"item":`
    middle: Vec<u8>,
    /// `,"seed":…,"groove_version":…,"code":…}`
    after_item: Vec<u8>,
}

impl ItemKeys {
    /// From a key whose `inputs` and `item` are replaced per item.
    pub fn new(key: &StageKey) -> ItemKeys {
        let mut head = b"{\"kind\":".to_vec();
        head.extend(json(&key.kind));
        head.extend(b",\"params\":");
        head.extend(json(key.params));
        head.extend(b",\"cmd\":");
        head.extend(json(&key.cmd));
        head.extend(b",\"inputs\":");
        let mut middle = b",\"outputs\":".to_vec();
        middle.extend(json(&key.outputs));
        middle.extend(b",\"item\":");
        let mut after_item = b",\"seed\":".to_vec();
        after_item.extend(json(&key.seed));
        after_item.extend(b",\"groove_version\":");
        after_item.extend(json(&key.groove_version));
        after_item.extend(b",\"code\":");
        after_item.extend(json(&key.code));
        after_item.push(b'}');
        ItemKeys {
            before_inputs: Sha256::new().chain_update(&head),
            middle,
            after_item,
        }
    }

    /// The key of the item with these inputs.
    pub fn digest(&self, inputs: &BTreeMap<String, String>, item: Option<&str>) -> String {
        let mut h = BufHasher::from(self.before_inputs.clone());
        put_json_map(&mut h, inputs);
        h.put(&self.middle);
        match item {
            Some(item) => put_json_str(&mut h, item),
            None => h.put(b"null"),
        }
        h.put(&self.after_item);
        h.hex()
    }
}

/// A key field as compact JSON.
fn json<T: Serialize + ?Sized>(value: &T) -> Vec<u8> {
    serde_json::to_vec(value).expect("a key field serializes")
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
    json_map_sha256(items)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn item_keys_are_the_stage_keys_of_each_item() {
        let params = serde_json::json!({"a": 1.5e-7, "b": "x\"y", "c": [1, 2], "d": {"z": null}});
        for cmd in [None, Some("echo \"$x\"")] {
            let first = BTreeMap::from([
                ("runs".to_string(), "ab".repeat(32)),
                ("truth".to_string(), "cd".repeat(32)),
            ]);
            let key = StageKey {
                kind: "fit",
                params: &params,
                cmd,
                inputs: &first,
                outputs: vec!["fits", "pair_runs"],
                item: Some("r0"),
                seed: u64::MAX,
                groove_version: "0.1.0",
                code: "ef01",
            };
            let keys = ItemKeys::new(&key);
            for item in [Some("single-316-001"), Some("a\\b"), None] {
                let mut inputs = first.clone();
                inputs.insert("runs".into(), format!("{item:?}"));
                let want = StageKey {
                    inputs: &inputs,
                    item,
                    ..key.clone()
                }
                .digest();
                assert_eq!(keys.digest(&inputs, item), want, "{cmd:?} {item:?}");
            }
        }
    }
}
