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
    /// `pipeline.lock` as it was before this evaluation, read when first asked for (`lock()`).
    lock: std::sync::OnceLock<PipelineLock>,
    /// Its stages' digests, when `.groove/lock-digests.json` was taken of the lock as it is:
    /// then a run that changes nothing need not read the lock (`lock_digests`).
    pub lock_digests: Option<std::collections::BTreeMap<String, String>>,
    /// `pipeline.lock` was there and readable (an unreadable or missing one is rewritten).
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
        let lock_digests =
            super::lock_digests::load(&lock_digests_path(pipeline), &lock_path(pipeline));
        // with digests the lock is there (its stamp matched) and is read only when needed
        let (lock, lock_file_read) = match lock_digests {
            Some(_) => (std::sync::OnceLock::new(), true),
            None => {
                let read = PipelineLock::read(&lock_path(pipeline));
                let found = read.is_some();
                (std::sync::OnceLock::from(read.unwrap_or_default()), found)
            }
        };
        Context {
            catalog,
            pipeline,
            store,
            hashes,
            lock_file_read,
            lock,
            lock_digests,
            progress,
            remote: None,
            pusher: None,
            steps: None,
        }
    }
}

impl Context<'_> {
    /// `pipeline.lock` as it was before this evaluation (read now if it was not yet).
    pub fn lock(&self) -> &PipelineLock {
        self.lock
            .get_or_init(|| PipelineLock::load(&lock_path(self.pipeline)))
    }
}

/// `.groove/lock-digests.json`: the digests of `pipeline.lock`'s stages.
pub fn lock_digests_path(pipeline: &Pipeline) -> std::path::PathBuf {
    pipeline.root.join(".groove").join("lock-digests.json")
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
