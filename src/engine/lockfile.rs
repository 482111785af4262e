//! `pipeline.lock`: each stage's key, params, code and input/output hashes after its last run.
//!
//! Deterministic (sorted maps, no times, no paths outside the project) so that it only changes
//! when a result changes, and written by rename so an interrupted run never leaves half a file.

use super::atomic::write_atomic;
use super::error::EngineError;
use super::store::Stored;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

pub const LOCK_VERSION: u32 = 1;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PipelineLock {
    pub version: u32,
    pub stages: BTreeMap<String, LockStage>,
}

impl Default for PipelineLock {
    fn default() -> Self {
        PipelineLock {
            version: LOCK_VERSION,
            stages: BTreeMap::new(),
        }
    }
}

/// One stage as last run: everything its key was computed from, and what it produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LockStage {
    pub kind: String,
    /// The stage key (per-item stage: the hash of its item keys).
    pub key: String,
    pub code: String,
    pub groove_version: String,
    pub seed: u64,
    pub params: serde_json::Value,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cmd: Option<String>,
    pub inputs: BTreeMap<String, Stored>,
    #[serde(default)]
    pub outputs: BTreeMap<String, Stored>,
    /// Per-item stage: item → key.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub items: BTreeMap<String, String>,
}

impl PipelineLock {
    /// Read `pipeline.lock`; a missing or unreadable lock is empty (everything is stale).
    pub fn load(path: &Path) -> PipelineLock {
        Self::read(path).unwrap_or_default()
    }

    /// Read `pipeline.lock`: None when it is missing, unreadable or of another version.
    pub fn read(path: &Path) -> Option<PipelineLock> {
        std::fs::read(path)
            .ok()
            .and_then(|b| serde_json::from_slice::<PipelineLock>(&b).ok())
            .filter(|l| l.version == LOCK_VERSION)
    }

    pub fn to_bytes(&self) -> Vec<u8> {
        let mut bytes = serde_json::to_vec_pretty(self).expect("the lock serializes");
        bytes.push(b'\n');
        bytes
    }

    /// Write the lock (`publish` calls this only when a record changed, so the file on disk
    /// is not read to compare).
    pub fn save(&self, path: &Path) -> Result<(), EngineError> {
        write_atomic(path, &self.to_bytes())
    }
}
