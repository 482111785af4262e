//! `groove clean` and `groove gc`: emptying the store, or dropping entries the lock no longer names.

use super::context::lock_path;
use super::error::{EngineError, IoContext};
use super::lockfile::PipelineLock;
use super::memo;
use super::pipeline::Pipeline;
use super::project_lock;
use super::store::Store;
use std::collections::BTreeSet;

/// Remove everything under `.groove/` (the store, hash cache, run log). Materialized outputs and
/// `pipeline.lock` stay; the next run recomputes what it needs.
pub fn clean(pipeline: &Pipeline) -> Result<usize, EngineError> {
    let store = Store::at(&pipeline.root);
    if !store.dir.exists() {
        return Ok(0);
    }
    let _lock = project_lock::acquire(&store.dir, |holder| {
        eprintln!(
            "groove: another groove run holds this project ({holder}); waiting for it to finish"
        )
    })?;
    // the entries go first, by one rename, so a kill at any moment leaves either every entry
    // with its objects or no entry at all; the rest is moved beside them into `tmp/` (which
    // the next command sweeps if this one is killed) and removed with it
    let trash = store.tmp_dir("cleaned")?;
    let entries = store.dir.join("entries");
    if entries.symlink_metadata().is_ok() {
        std::fs::rename(&entries, trash.join("entries")).at(&entries)?;
    }
    let mut removed = usize::from(trash.join("entries").symlink_metadata().is_ok());
    for entry in std::fs::read_dir(&store.dir).at(&store.dir)?.flatten() {
        let path = entry.path();
        if entry.file_name() == "lock" || entry.file_name() == "tmp" {
            continue;
        }
        std::fs::rename(&path, trash.join(entry.file_name())).at(&path)?;
        removed += 1;
    }
    let tmp = store.tmp_root();
    std::fs::remove_dir_all(&tmp).at(&tmp)?;
    Ok(removed)
}

/// Check the store: drop damaged objects and entries that name a missing object (the stages
/// they belong to run again). Takes the project lock.
pub fn verify(pipeline: &Pipeline) -> Result<super::store_upkeep::Verified, EngineError> {
    let store = Store::at(&pipeline.root);
    if !store.dir.exists() {
        return Ok(super::store_upkeep::Verified::default());
    }
    let _lock = project_lock::acquire(&store.dir, |holder| {
        eprintln!(
            "groove: another groove run holds this project ({holder}); waiting for it to finish"
        )
    })?;
    store.verify()
}

/// Drop store entries that `pipeline.lock` does not reference, then objects that neither they
/// nor the memos of its stages reference (and the memos of other stages). Returns (entries,
/// objects) removed.
pub fn gc(pipeline: &Pipeline) -> Result<(usize, usize), EngineError> {
    let store = Store::at(&pipeline.root);
    if !store.dir.exists() {
        return Ok((0, 0));
    }
    let _lock = project_lock::acquire(&store.dir, |holder| {
        eprintln!(
            "groove: another groove run holds this project ({holder}); waiting for it to finish"
        )
    })?;
    let lock_file = lock_path(pipeline);
    let lock = PipelineLock::load(&lock_file);
    if lock.stages.is_empty() {
        // a missing, unreadable or empty lock names nothing to keep: removing everything would
        // throw away every result, so refuse
        return Err(EngineError::Usage(format!(
            "{} is missing, unreadable or names no stage, so gc cannot tell what to keep; nothing was removed (run `groove run` first)",
            pipeline.show(&lock_file)
        )));
    }
    let mut keep = BTreeSet::new();
    for stage in lock.stages.values() {
        // a per-item stage's key is its index entry (item keys → outputs), kept with its items
        keep.insert(stage.key.clone());
        keep.extend(stage.items.values().cloned());
    }
    // a memo's objects stay while its stage is in the lock (the next edit takes them instead
    // of making them again); the memo of a stage no longer in it goes
    let memos: BTreeSet<String> = lock.stages.keys().map(|s| memo::file_name(s)).collect();
    let mut memo_objects = BTreeSet::new();
    for (file, objects) in memo::files(&store.dir) {
        let name = file.file_name().map(|n| n.to_string_lossy().into_owned());
        if name.is_some_and(|n| memos.contains(&n)) {
            memo_objects.extend(objects);
        } else {
            std::fs::remove_file(&file).at(&file)?;
        }
    }
    store.sweep_tmp()?;
    let (entries, objects, sparse) = store.gc(&keep, &memo_objects)?;
    super::pack_writer::rewrite(&store, &sparse)?;
    Ok((entries, objects))
}
