//! `.groove/lock-digests.json`: one digest per stage of `pipeline.lock`, so that a run which
//! changes nothing can tell without parsing the lock (6.9 MB at 10,000 runs).
//!
//! Written after the lock, with the lock file's stamp (size, mtime, inode, ctime); trusted only
//! while the lock still has that stamp. An edited, restored or half-replaced lock has another
//! stamp, and the run then reads the lock itself, as it always could.

use super::atomic::write_atomic;
use super::hashing::stamp_of;
use super::lockfile::{LockStage, PipelineLock};
use super::store::Stored;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Serialize, Deserialize)]
struct Sidecar {
    /// The lock file's (size, mtime in ns, inode, ctime in ns) when the digests were taken (a
    /// sidecar of three fields, from before the change time was kept, does not read: unused).
    lock_stamp: (u64, i128, u64, i128),
    /// Stage name → `stage_digest` of its record in the lock.
    stages: BTreeMap<String, String>,
}

/// The digest of one stage's record: sha256 over every field, each string fed with its length
/// so that no two records feed the same bytes (maps in their sorted order). Every field is
/// named below, so a field added to `LockStage` does not compile until it is digested too.
pub fn stage_digest(stage: &LockStage) -> String {
    let LockStage {
        kind,
        key,
        code,
        groove_version,
        seed,
        params,
        cmd,
        inputs,
        outputs,
        items,
    } = stage;
    // through a buffer: 60,000 small hasher updates cost more than the hashing
    let mut h = super::hashing::BufHasher::default();
    let mut put = |s: &str| {
        h.put(&(s.len() as u64).to_le_bytes());
        h.put(s.as_bytes());
    };
    put(kind);
    put(key);
    put(code);
    put(groove_version);
    put(&seed.to_string());
    put(&serde_json::to_string(params).expect("params serialize"));
    put(cmd.as_deref().unwrap_or("\0none"));
    for (label, map) in [("inputs", inputs), ("outputs", outputs)] {
        put(label);
        put(&map.len().to_string());
        for (name, stored) in map {
            put(name);
            match stored {
                Stored::File { sha256 } => {
                    put("file");
                    put(sha256);
                }
                Stored::Collection { items } => {
                    put("collection");
                    put(&items.len().to_string());
                    for (item, sha256) in items {
                        put(item);
                        put(sha256);
                    }
                }
            }
        }
    }
    put("items");
    put(&items.len().to_string());
    for (item, item_key) in items {
        put(item);
        put(item_key);
    }
    h.hex()
}

/// The digests of the lock at `lock_file`, when the sidecar at `path` was taken of it as it is
/// now; `None` otherwise (missing, unreadable, or the lock changed since).
pub fn load(path: &Path, lock_file: &Path) -> Option<BTreeMap<String, String>> {
    let meta = std::fs::metadata(lock_file).ok()?;
    let sidecar: Sidecar = serde_json::from_slice(&std::fs::read(path).ok()?).ok()?;
    (sidecar.lock_stamp == stamp_of(&meta)).then_some(sidecar.stages)
}

/// Take the digests of `lock` as now written at `lock_file`.
pub fn save(path: &Path, lock_file: &Path, lock: &PipelineLock) -> Result<(), super::EngineError> {
    let meta = std::fs::metadata(lock_file).map_err(|e| super::EngineError::io(lock_file, e))?;
    let sidecar = Sidecar {
        lock_stamp: stamp_of(&meta),
        stages: lock
            .stages
            .iter()
            .map(|(name, stage)| (name.clone(), stage_digest(stage)))
            .collect(),
    };
    write_atomic(
        path,
        &serde_json::to_vec(&sidecar).expect("lock digests serialize"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_and_its_copy_share_a_digest_and_any_change_moves_it() {
        let items: BTreeMap<String, String> = [
            ("a".to_string(), "1".repeat(64)),
            ("b".to_string(), "2".repeat(64)),
        ]
        .into();
        let stage = LockStage {
            kind: "fit".into(),
            key: "k".repeat(64),
            code: "c".into(),
            groove_version: "0.1.0".into(),
            seed: 7,
            params: serde_json::json!({"x": 1}),
            cmd: None,
            inputs: [(
                "runs".to_string(),
                Stored::Collection {
                    items: items.clone(),
                },
            )]
            .into(),
            outputs: [(
                "fits".to_string(),
                Stored::Collection {
                    items: items.clone(),
                },
            )]
            .into(),
            items: items.clone(),
        };
        let d = stage_digest(&stage);
        assert_eq!(d, stage_digest(&stage.clone()));
        let mut changed = vec![stage.clone(), stage.clone(), stage.clone(), stage.clone()];
        if let Stored::Collection { items } = changed[0].outputs.get_mut("fits").unwrap() {
            items.insert("b".into(), "3".repeat(64));
        }
        changed[1].items.remove("a");
        changed[2].params = serde_json::json!({"x": 2});
        // the same bytes split differently between two fields
        changed[3].kind = "fitk".into();
        changed[3].key = "k".repeat(63);
        for c in &changed {
            assert_ne!(stage_digest(c), d);
        }
    }
}
