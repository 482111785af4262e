//! `groove push` and `groove pull`: every store key `pipeline.lock` names, to or from the remote.

use super::cache::RemoteCache;
use super::push::Pusher;
use crate::engine::lockfile::PipelineLock;
use crate::engine::store::Store;
use std::collections::BTreeSet;
use std::sync::Arc;

/// The store keys of a lock: a stage's key, or its item keys for a per-item stage.
pub fn lock_keys(lock: &PipelineLock) -> BTreeSet<String> {
    let mut keys = BTreeSet::new();
    for stage in lock.stages.values() {
        if stage.items.is_empty() {
            keys.insert(stage.key.clone());
        } else {
            keys.extend(stage.items.values().cloned());
        }
    }
    keys
}

/// What `push` or `pull` did, by key.
#[derive(Debug, Default, Clone, PartialEq, Eq)]
pub struct Synced {
    /// Keys considered.
    pub keys: usize,
    /// Keys not in the local store (push) or already in it (pull): nothing to do.
    pub skipped: usize,
}

/// Upload every key of `keys` the local store holds (blobs first, entry last).
pub fn push_all(
    cache: &Arc<RemoteCache>,
    store: &Store,
    keys: &BTreeSet<String>,
    concurrency: usize,
) -> Synced {
    let pusher = Pusher::start(Arc::clone(cache), store, concurrency);
    let mut skipped = 0;
    for key in keys {
        match store.entry(key) {
            Some(entry) => pusher.submit(key, &entry),
            None => skipped += 1,
        }
    }
    pusher.finish();
    Synced {
        keys: keys.len(),
        skipped,
    }
}

/// `groove pull`: walk the DAG as `status` does, but look every key up on the remote too, so
/// each result the pipeline can reuse lands (verified) in the local store. Runs nothing and
/// writes no output; takes the project lock like `run`. Returns the stages now complete.
pub fn pull(
    catalog: &crate::engine::catalog::Catalog,
    pipeline: &crate::engine::pipeline::Pipeline,
    cache: &Arc<RemoteCache>,
) -> Result<usize, crate::engine::error::EngineError> {
    use crate::engine::context::Context;
    use crate::engine::evaluate::{evaluate, Action};
    use crate::engine::progress::Progress;
    let store_dir = pipeline.root.join(".groove");
    let progress = Progress::new(pipeline.stages.len() as u64, true);
    let _lock = crate::engine::project_lock::acquire(&store_dir, |holder| {
        eprintln!(
            "groove: another groove run holds this project ({holder}); waiting for it to finish"
        )
    })?;
    let mut ctx = Context::new(catalog, pipeline, progress);
    ctx.remote = Some(Arc::clone(cache));
    let all: BTreeSet<String> = pipeline.stages.keys().cloned().collect();
    let (done, _errors) = evaluate(&ctx, &all, |_| Action::Check, |_, _| {});
    ctx.hashes.save()?;
    Ok(done.values().filter(|e| e.complete).count())
}
