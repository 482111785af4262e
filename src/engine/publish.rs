//! `groove publish --to DIR`: the report bundle, only when every stage is fresh.
//!
//! The bundle holds every output the pipeline materializes inside the reports folder (the
//! report pages and figures, and the tables beside them), `pipeline.lock`, and `SHA256SUMS`
//! listing each file's sha256. Files come from the store, not from the working copy, so what
//! is published is exactly what the lock describes.

use super::atomic::unique_name;
use super::catalog::Catalog;
use super::context::lock_path;
use super::error::{EngineError, IoContext};
use super::hashing::sha256_hex;
use super::lockfile::PipelineLock;
use super::pipeline::Pipeline;
use super::status::{status, StageStatus, State};
use super::store::{Store, Stored};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub const MANIFEST: &str = "SHA256SUMS";

pub enum Published {
    /// Some stages are stale: nothing was written.
    Refused(Vec<StageStatus>),
    /// The bundle's files (relative paths, sorted), manifest included.
    Written { dir: PathBuf, files: Vec<String> },
}

pub fn publish(
    catalog: &Catalog,
    pipeline: &Pipeline,
    to: &Path,
) -> Result<Published, EngineError> {
    // one snapshot: no run changes the lock or the store between the check and the copy
    let _lock = super::project_lock::acquire_shared(&pipeline.root.join(".groove"), |holder| {
        eprintln!(
            "groove: another groove run holds this project ({holder}); waiting for it to finish"
        )
    })?;
    let statuses = status(catalog, pipeline, None)?;
    let stale: Vec<StageStatus> = statuses
        .into_iter()
        .filter(|s| s.state == State::Stale)
        .collect();
    if !stale.is_empty() {
        return Ok(Published::Refused(stale));
    }
    let to = super::config::validate::normalize(&std::path::absolute(to).at(to)?);
    if pipeline.root.starts_with(&to)
        || to.starts_with(pipeline.root.join(".groove"))
        || to.starts_with(&pipeline.reports_dir)
        || to.starts_with(&pipeline.data_dir)
    {
        return Err(EngineError::Usage(format!(
            "cannot publish into {}; choose a folder outside the project's store, reports and data",
            to.display()
        )));
    }
    if to.is_symlink() || (to.exists() && !to.is_dir()) {
        return Err(EngineError::Usage(format!(
            "{} is {}, not a folder; publish only writes a new or empty folder or an earlier bundle, so choose another path",
            to.display(),
            if to.is_symlink() { "a symbolic link" } else { "a file" }
        )));
    }
    // folders a killed publish left beside the target
    if let (Some(parent), Some(name)) = (to.parent(), to.file_name()) {
        if parent.is_dir() {
            super::materialize::sweep_leftovers(parent, &name.to_string_lossy())?;
        }
    }
    if to.is_dir()
        && std::fs::read_dir(&to).at(&to)?.next().is_some()
        && !to.join(MANIFEST).is_file()
    {
        return Err(EngineError::Usage(format!(
            "{} is not empty and holds no earlier bundle ({MANIFEST}); choose a new or empty folder",
            to.display()
        )));
    }
    let lock_file = lock_path(pipeline);
    let lock_bytes = std::fs::read(&lock_file).at(&lock_file)?;
    let lock: PipelineLock = serde_json::from_slice(&lock_bytes).map_err(|e| {
        EngineError::Usage(format!(
            "{} cannot be read ({e}); run `groove run` to write it again",
            pipeline.show(&lock_file)
        ))
    })?;
    let store = Store::at(&pipeline.root);

    let mut files: BTreeMap<String, Vec<u8>> = BTreeMap::new();
    for stage in pipeline.stages.values() {
        let Some(record) = lock.stages.get(&stage.name) else {
            continue;
        };
        for (output, path) in &stage.outputs {
            let Some(path) = path else { continue };
            let Ok(rel) = path.strip_prefix(&pipeline.reports_dir) else {
                continue;
            };
            let rel = rel.to_string_lossy().replace('\\', "/");
            let Some(stored) = record.outputs.get(output) else {
                return Err(EngineError::Usage(format!(
                    "{} has no record of output `{output}` of stage `{}`; run `groove run` to write it again",
                    pipeline.show(&lock_file),
                    stage.name
                )));
            };
            match stored {
                Stored::File { sha256 } => {
                    files.insert(rel, store.read_object(sha256)?);
                }
                Stored::Collection { items } => {
                    for (item, sha256) in items {
                        files.insert(format!("{rel}/{item}"), store.read_object(sha256)?);
                    }
                }
            }
        }
    }
    if files.is_empty() {
        return Err(EngineError::Usage(format!(
            "no stage writes into the reports folder {}; nothing to publish",
            pipeline.show(&pipeline.reports_dir)
        )));
    }
    files.insert("pipeline.lock".into(), lock_bytes);
    let manifest: String = files
        .iter()
        .map(|(rel, bytes)| format!("{}  {rel}\n", sha256_hex(bytes)))
        .collect();
    files.insert(MANIFEST.into(), manifest.into_bytes());

    // build beside the target, then swap it in
    let parent = to.parent().unwrap_or(Path::new(".")).to_path_buf();
    std::fs::create_dir_all(&parent).at(&parent)?;
    let name = to
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "bundle".into());
    let fresh = parent.join(unique_name(&format!(".{name}.groove-new")));
    let written = files.iter().try_for_each(|(rel, bytes)| {
        let p = fresh.join(rel);
        let dir = p.parent().expect("bundle files have a parent");
        std::fs::create_dir_all(dir).at(dir)?;
        std::fs::write(&p, bytes).at(&p)
    });
    if let Err(e) = written {
        // a bundle that could not be written whole (a full disk) leaves nothing beside the target
        let _ = std::fs::remove_dir_all(&fresh);
        return Err(e);
    }
    if to.exists() {
        let old = parent.join(unique_name(&format!(".{name}.groove-old")));
        std::fs::rename(&to, &old).at(&to)?;
        std::fs::rename(&fresh, &to).at(&to)?;
        std::fs::remove_dir_all(&old).at(&old)?;
    } else {
        std::fs::rename(&fresh, &to).at(&to)?;
    }
    Ok(Published::Written {
        dir: to,
        files: files.into_keys().collect(),
    })
}
