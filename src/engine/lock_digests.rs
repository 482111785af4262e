//! `.groove/lock-digests.json`: one digest per stage of `pipeline.lock`, so that a run which
//! changes nothing can tell without parsing the lock (6.9 MB at 10,000 runs).
//!
//! Written after the lock, with the lock file's stamp (size, mtime, inode); trusted only while
//! the lock still has that stamp. An edited, restored or half-replaced lock has another stamp,
//! and the run then reads the lock itself, as it always could.

use super::atomic::write_atomic;
use super::hashing::{sha256_hex, stamp_of};
use super::lockfile::{LockStage, PipelineLock};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Serialize, Deserialize)]
struct Sidecar {
    /// The lock file's (size, mtime in ns, inode) when the digests were taken.
    lock_stamp: (u64, i128, u64),
    /// Stage name → `stage_digest` of its record in the lock.
    stages: BTreeMap<String, String>,
}

/// The digest of one stage's record: sha256 of its compact JSON (maps sorted, so the same
/// record always gives the same bytes).
pub fn stage_digest(stage: &LockStage) -> String {
    sha256_hex(&serde_json::to_vec(stage).expect("a lock stage serializes"))
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
