//! What one evaluation works with (`Context`) and what it finds out about each stage (`Evaluated`).
//!
//! Shared by the walk (`evaluate`), the runner of one key (`execute`), the provenance record and
//! the status reasons, so none of them needs another's internals.

use super::catalog::Catalog;
use super::hashing::HashCache;
use super::lockfile::{LockStage, PipelineLock};
use super::pipeline::Pipeline;
use super::progress::Progress;
use super::store::Store;

/// Everything one evaluation needs.
pub struct Context<'a> {
    pub catalog: &'a Catalog,
    pub pipeline: &'a Pipeline,
    pub store: Store,
    pub hashes: HashCache,
    /// `pipeline.lock` as it was before this evaluation.
    pub lock: PipelineLock,
    /// `pipeline.lock` was there and read (an unreadable or missing one is rewritten).
    pub lock_file_read: bool,
    pub progress: Progress,
    /// The shared remote cache, looked up after the local store (`None`: local only).
    pub remote: Option<std::sync::Arc<super::remote::RemoteCache>>,
    /// Uploads each local commit to the remote (`None`: no remote, or read-only).
    pub pusher: Option<super::remote::push::Pusher>,
    /// Runs the keys that must run elsewhere, as Slurm job steps (`None`: on this machine).
    pub steps: Option<Box<dyn super::slurm::job::StepRunner>>,
}

impl<'a> Context<'a> {
    pub fn new(catalog: &'a Catalog, pipeline: &'a Pipeline, progress: Progress) -> Context<'a> {
        let store = Store::at(&pipeline.root);
        let hashes = HashCache::load(&store.dir.join("hashes.json"));
        let lock = PipelineLock::read(&lock_path(pipeline));
        Context {
            catalog,
            pipeline,
            store,
            hashes,
            lock_file_read: lock.is_some(),
            lock: lock.unwrap_or_default(),
            progress,
            remote: None,
            pusher: None,
            steps: None,
        }
    }
}

/// `pipeline.lock`, beside `pipeline.toml`.
pub fn lock_path(pipeline: &Pipeline) -> std::path::PathBuf {
    pipeline.root.join("pipeline.lock")
}

/// What became of one stage.
#[derive(Debug, Default)]
pub struct Evaluated {
    /// The key and its parts; `None` while an upstream stage's outputs are unknown.
    pub current: Option<LockStage>,
    /// Upstream stages whose outputs are unknown.
    pub waiting_on: Vec<String>,
    /// While waiting: the key parts known without the inputs (kind, params, cmd, code, seed).
    pub pending: Option<LockStage>,
    /// Every key has a complete entry in the store, so `current.outputs` is known.
    pub complete: bool,
    /// Keys that had no entry when the evaluation began (item names; `None` = the whole stage).
    pub missing: Vec<Option<String>>,
    /// Keys run in this evaluation.
    pub executed: usize,
    /// Outputs whose materialized path does not hold the stored content.
    pub stale_outputs: Vec<String>,
    pub failed: bool,
}
