//! Writing stored outputs to their paths in the project (only the engine writes files).
//!
//! A file is replaced by rename. A collection becomes a folder built beside the target and
//! swapped in with two renames, so the last good copy stays until the new one is complete; a
//! stage that fails never reaches this step, so its old outputs stay as they were.

use super::error::{EngineError, IoContext};
use super::hashing::HashCache;
use super::inputs::dir_files;
use super::atomic::{unique_name, write_atomic};
use super::store::{Store, Stored};
use std::path::Path;

/// Does the path already hold exactly this artifact?
pub fn is_current(path: &Path, stored: &Stored, cache: &HashCache) -> bool {
    match stored {
        Stored::File { sha256 } => {
            path.is_file() && cache.hash_file(path).ok().as_ref() == Some(sha256)
        }
        Stored::Collection { items } => {
            if !path.is_dir() {
                return false;
            }
            let Ok(files) = dir_files(path) else {
                return false;
            };
            files.len() == items.len()
                && files.iter().all(|(name, p)| {
                    items
                        .get(name)
                        .is_some_and(|h| cache.hash_file(p).ok().as_ref() == Some(h))
                })
        }
    }
}

/// Write an artifact to its path unless it is already there. Returns whether it wrote.
pub fn materialize(
    store: &Store,
    path: &Path,
    stored: &Stored,
    cache: &HashCache,
) -> Result<bool, EngineError> {
    if is_current(path, stored, cache) {
        return Ok(false);
    }
    let parent = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).at(parent)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match stored {
        Stored::File { sha256 } => {
            let bytes = store.read_object(sha256)?;
            if path.is_dir() {
                std::fs::remove_dir_all(path).at(path)?;
            }
            write_atomic(path, &bytes)?;
        }
        Stored::Collection { items } => {
            let fresh = parent.join(unique_name(&format!(".{name}.groove-new")));
            std::fs::create_dir_all(&fresh).at(&fresh)?;
            for (item, sha256) in items {
                let bytes = store.read_object(sha256)?;
                std::fs::write(fresh.join(item), bytes).at(&fresh.join(item))?;
            }
            if path.exists() || path.is_symlink() {
                let old = parent.join(unique_name(&format!(".{name}.groove-old")));
                std::fs::rename(path, &old).at(path)?;
                std::fs::rename(&fresh, path).at(path)?;
                remove_any(&old)?;
            } else {
                std::fs::rename(&fresh, path).at(path)?;
            }
        }
    }
    sweep_leftovers(parent, &name)?;
    Ok(true)
}

fn remove_any(path: &Path) -> Result<(), EngineError> {
    if path.is_dir() {
        std::fs::remove_dir_all(path).at(path)
    } else {
        std::fs::remove_file(path).at(path)
    }
}

/// Remove temp siblings a killed run left behind (`.NAME.groove-new-*`, `.NAME.groove-old-*`).
pub fn sweep_leftovers(parent: &Path, name: &str) -> Result<(), EngineError> {
    let prefixes = [
        format!(".{name}.groove-new-"),
        format!(".{name}.groove-old-"),
        format!(".{name}.groove-tmp-"),
    ];
    for entry in std::fs::read_dir(parent).at(parent)?.flatten() {
        let n = entry.file_name().to_string_lossy().into_owned();
        if prefixes.iter().any(|p| n.starts_with(p.as_str())) {
            let _ = remove_any(&entry.path());
        }
    }
    Ok(())
}
