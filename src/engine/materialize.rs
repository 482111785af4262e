//! Writing stored outputs to their paths in the project (only the engine writes files).
//!
//! Every output of a run is first staged beside its path (a hidden sibling file or folder), and
//! only when all are staged are they swapped in, a file by one rename, a collection by two; a run
//! with a failed stage stages nothing, so the last good outputs stay whole.

use super::atomic::unique_name;
use super::error::{EngineError, IoContext};
use super::hashing::HashCache;
use super::inputs::dir_files;
use super::store::{Store, Stored};
use std::collections::{BTreeMap, BTreeSet};
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

/// One output staged beside its path, ready to be swapped in by [`Staged::commit`].
pub struct Staged {
    path: std::path::PathBuf,
    fresh: std::path::PathBuf,
}

/// Write an artifact next to its path (a hidden `.NAME.groove-new-*` sibling: a file, or a
/// folder for a Collection) without touching the path itself; `None` if the path already holds
/// it. A file output never replaces a folder, and a folder output replaces only what groove
/// wrote there: `was` gives what the lock says this output held before (asked only when the
/// path does not hold the artifact already; see [`check_not_foreign`]).
pub fn stage(
    store: &Store,
    path: &Path,
    stored: &Stored,
    was: &dyn Fn() -> Option<Stored>,
    cache: &HashCache,
) -> Result<Option<Staged>, EngineError> {
    if is_current(path, stored, cache) {
        return Ok(None);
    }
    check_not_foreign(path, stored, was().as_ref(), cache)?;
    let parent = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).at(parent)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let fresh = parent.join(unique_name(&format!(".{name}.groove-new")));
    match stored {
        Stored::File { sha256 } => {
            if path.is_dir() && !path.is_symlink() {
                return Err(EngineError::Usage(format!(
                    "{} is a folder; a file output never replaces a folder: move the folder away or give the output another path",
                    path.display()
                )));
            }
            let bytes = store.read_object(sha256)?;
            std::fs::write(&fresh, bytes).at(&fresh)?;
        }
        Stored::Collection { items } => {
            std::fs::create_dir_all(&fresh).at(&fresh)?;
            for (item, sha256) in items {
                let bytes = store.read_object(sha256)?;
                std::fs::write(fresh.join(item), bytes).at(&fresh.join(item))?;
            }
        }
    }
    Ok(Some(Staged {
        path: path.to_path_buf(),
        fresh,
    }))
}

impl Staged {
    /// Swap the staged copy in: a file by one rename; a folder over a folder item by item, each
    /// by one rename, then the old items the new output lacks removed, so that a run killed
    /// meanwhile leaves each file old or new and none missing (the next run finishes the swap);
    /// a folder over anything else by moving that aside, renaming the new one in, and removing
    /// what was moved.
    pub fn commit(self) -> Result<(), EngineError> {
        let parent = self.path.parent().unwrap_or(Path::new(".")).to_path_buf();
        let name = self
            .path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let folder_over_folder = self.fresh.is_dir()
            && self
                .path
                .symlink_metadata()
                .is_ok_and(|m| m.file_type().is_dir());
        if folder_over_folder {
            let mut new = std::collections::BTreeSet::new();
            for entry in std::fs::read_dir(&self.fresh).at(&self.fresh)? {
                let item = entry.at(&self.fresh)?.file_name();
                let to = self.path.join(&item);
                std::fs::rename(self.fresh.join(&item), &to).at(&to)?;
                new.insert(item);
            }
            // what is left was groove's (`check_not_foreign` said so before staging)
            for entry in std::fs::read_dir(&self.path).at(&self.path)? {
                let entry = entry.at(&self.path)?;
                if !new.contains(&entry.file_name()) {
                    remove_any(&entry.path())?;
                }
            }
            remove_any(&self.fresh)?;
        } else if self.fresh.is_dir() && (self.path.exists() || self.path.is_symlink()) {
            let old = parent.join(unique_name(&format!(".{name}.groove-old")));
            std::fs::rename(&self.path, &old).at(&self.path)?;
            std::fs::rename(&self.fresh, &self.path).at(&self.path)?;
            remove_any(&old)?;
        } else {
            std::fs::rename(&self.fresh, &self.path).at(&self.path)?;
        }
        sweep_leftovers(&parent, &name)
    }

    /// Remove the staged copy (the path keeps what it held).
    pub fn discard(self) {
        let _ = remove_any(&self.fresh);
    }
}

/// Never lose a user's file: a folder output replaces what is at its path only when groove
/// wrote it. Each file there must be an item the output held before (`was`, from the lock; with
/// no lock at all, an item of the new output by name: a fresh clone's committed reports) or
/// hold exactly the bytes the new output gives it; a subfolder, a link or any other file is
/// the user's, and the run stops naming it (exit 2) with nothing changed. A file in the way of a
/// folder output counts as groove's only when it is the file the output held before.
pub fn check_not_foreign(
    path: &Path,
    stored: &Stored,
    was: Option<&Stored>,
    cache: &HashCache,
) -> Result<(), EngineError> {
    let Stored::Collection { items } = stored else {
        return Ok(());
    };
    let Ok(meta) = path.symlink_metadata() else {
        return Ok(()); // nothing there
    };
    let foreign = |what: &Path| {
        EngineError::Usage(format!(
            "{} is in the way of a folder output and groove did not write it; groove replaces only what it wrote there, so nothing was changed: move it away (or delete it) and run again, or give the output another path",
            what.display()
        ))
    };
    let was_items = match was {
        Some(Stored::Collection { items }) => Some(items),
        _ => None,
    };
    if meta.is_symlink() {
        return Ok(()); // the link itself is replaced, never what it points to
    }
    if !meta.is_dir() {
        let ours = matches!(was, Some(Stored::File { sha256 })
            if cache.hash_file(path).ok().as_ref() == Some(sha256));
        return if ours { Ok(()) } else { Err(foreign(path)) };
    }
    for entry in std::fs::read_dir(path).at(path)? {
        let entry = entry.at(path)?;
        let name = entry.file_name().to_string_lossy().into_owned();
        let file = entry.path();
        let plain = entry.file_type().is_ok_and(|t| t.is_file());
        // with no lock to ask (a fresh clone of a project whose reports are committed), a file
        // named as one of the output's own items is taken as an earlier run's
        let written_before = match was_items {
            Some(w) => w.contains_key(&name),
            None => was.is_none() && items.contains_key(&name),
        };
        let same_bytes = || {
            items
                .get(&name)
                .is_some_and(|h| cache.hash_file(&file).ok().as_ref() == Some(h))
        };
        if !plain || !(written_before || same_bytes()) {
            return Err(foreign(&file));
        }
    }
    Ok(())
}

/// Write an artifact to its path unless it is already there. Returns whether it wrote.
pub fn materialize(
    store: &Store,
    path: &Path,
    stored: &Stored,
    cache: &HashCache,
) -> Result<bool, EngineError> {
    match stage(store, path, stored, &|| None, cache)? {
        Some(staged) => staged.commit().map(|()| true),
        None => Ok(false),
    }
}

/// Refuses a path whose folders below `base` include a symbolic link: writing through it could
/// land outside the project. `base` itself may be a link (a reports folder kept elsewhere).
pub fn check_no_symlink_below(base: &Path, path: &Path) -> Result<(), EngineError> {
    let Ok(rel) = path.strip_prefix(base) else {
        return Ok(());
    };
    let mut at = base.to_path_buf();
    let parts: Vec<_> = rel.components().collect();
    for part in parts.iter().take(parts.len().saturating_sub(1)) {
        at.push(part);
        if at
            .symlink_metadata()
            .is_ok_and(|m| m.file_type().is_symlink())
        {
            return Err(EngineError::Usage(format!(
                "{} is a symbolic link; groove does not write through links inside the project (the output {} could land outside it): replace the link with a folder",
                at.display(),
                path.display()
            )));
        }
    }
    Ok(())
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

/// Remove what killed runs left beside any of `paths` (`.NAME.groove-new-*` and the like, see
/// [`sweep_leftovers`]): one listing per folder, so a run removes them even when it writes
/// nothing there. Best effort: a folder that cannot be read is left as it is.
pub fn sweep_leftovers_of<'p>(paths: impl Iterator<Item = &'p Path>) {
    let mut by_parent: BTreeMap<&Path, BTreeSet<String>> = BTreeMap::new();
    for path in paths {
        if let (Some(parent), Some(name)) = (path.parent(), path.file_name()) {
            let names = by_parent.entry(parent).or_default();
            names.insert(name.to_string_lossy().into_owned());
        }
    }
    for (parent, names) in by_parent {
        let Ok(list) = std::fs::read_dir(parent) else {
            continue;
        };
        for entry in list.flatten() {
            let n = entry.file_name().to_string_lossy().into_owned();
            let Some(rest) = n.strip_prefix('.') else {
                continue;
            };
            let left = ["groove-new-", "groove-old-", "groove-tmp-"]
                .iter()
                .filter_map(|tag| rest.rfind(&format!(".{tag}")))
                .any(|at| names.contains(&rest[..at]));
            if left {
                let _ = remove_any(&entry.path());
            }
        }
    }
}
