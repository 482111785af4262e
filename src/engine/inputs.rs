//! Path inputs: a file, or a directory meaning its top-level regular files (not subfolders, not
//! dotfiles); read whole, or left on disk for a kind that reads them in pieces, checked either way.

use super::error::{EngineError, IoContext};
use super::hashing::{sha256_hex, HashCache};
use super::stage::{Artifact, InputFile};
use super::store::Stored;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Collection item names are file-name safe: `[A-Za-z0-9._-]`, not starting with a dot.
pub fn item_name_ok(name: &str) -> bool {
    !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'))
}

/// A dataset file's name may also hold inner spaces (TrackMate's `Spots in tracks statistics.csv`).
fn input_name_ok(name: &str) -> bool {
    name.trim() == name && item_name_ok(&name.replace(' ', "_"))
}

/// The top-level regular files of a directory, sorted by name. Dotfiles are skipped; a symlink
/// counts as the regular file it points to (a dangling one is skipped). A file whose name is not
/// an item name (`notes (copy).txt`) is no part of the input: it is skipped, and named once per
/// process on stderr so a user who meant it as data learns why it is not read.
pub fn dir_files(dir: &Path) -> Result<Vec<(String, PathBuf)>, EngineError> {
    let mut out = Vec::new();
    for entry in std::fs::read_dir(dir).at(dir)? {
        let entry = entry.at(dir)?;
        let name = entry.file_name().to_string_lossy().into_owned();
        // `metadata` follows a symlink; one that cannot be followed is not a file.
        if name.starts_with('.') || !std::fs::metadata(entry.path()).is_ok_and(|m| m.is_file()) {
            continue;
        }
        if !input_name_ok(&name) {
            note_skipped(dir, &name);
            continue;
        }
        out.push((name, entry.path()));
    }
    out.sort();
    Ok(out)
}

/// Says once per process that `dir/name` is left out of a folder input, and why.
fn note_skipped(dir: &Path, name: &str) {
    static SAID: std::sync::Mutex<std::collections::BTreeSet<PathBuf>> =
        std::sync::Mutex::new(std::collections::BTreeSet::new());
    let path = dir.join(name);
    let fresh = SAID
        .lock()
        .map(|mut s| s.insert(path.clone()))
        .unwrap_or(false);
    if fresh {
        eprintln!(
            "groove: note: {} is not read (file names in an input folder may use only letters, digits, `.`, `_` and `-`; rename it to use it)",
            path.display()
        );
    }
}

/// The files of a path input that are links to a file outside `root` (the project), with where
/// they lead. A stage's error may quote what it read; from such a file it must not (a dataset
/// can link `runs.csv` to any file the user can read), so the engine says this instead.
pub fn linked_from_outside(root: &Path, path: &Path, stored: &Stored) -> Vec<(PathBuf, PathBuf)> {
    let files: Vec<PathBuf> = match stored {
        Stored::File { .. } => vec![path.to_path_buf()],
        Stored::Collection { items } => items.keys().map(|n| path.join(n)).collect(),
    };
    let root = std::fs::canonicalize(root).unwrap_or_else(|_| root.to_path_buf());
    files
        .into_iter()
        .filter(|f| std::fs::symlink_metadata(f).is_ok_and(|m| m.file_type().is_symlink()))
        .filter_map(|f| {
            let target = std::fs::canonicalize(&f).ok()?;
            (!target.starts_with(&root)).then_some((f, target))
        })
        .collect()
}

/// Hash a path input through the cache.
pub fn hash_path(path: &Path, cache: &HashCache) -> Result<Stored, EngineError> {
    if path.is_dir() {
        let items = dir_files(path)?
            .into_iter()
            .map(|(name, p)| Ok((name, cache.hash_file(&p)?)))
            .collect::<Result<BTreeMap<_, _>, EngineError>>()?;
        Ok(Stored::Collection { items })
    } else {
        Ok(Stored::File {
            sha256: cache.hash_file(path)?,
        })
    }
}

/// Read a path input and check it still has the content its key was computed from.
pub fn load_path(path: &Path, expected: &Stored) -> Result<Artifact, EngineError> {
    let changed = || {
        EngineError::Usage(format!(
            "{} changed while groove was running; run again",
            path.display()
        ))
    };
    match expected {
        Stored::File { sha256 } => {
            let bytes = std::fs::read(path).at(path)?;
            if &sha256_hex(&bytes) != sha256 {
                return Err(changed());
            }
            Ok(Artifact::File(bytes))
        }
        Stored::Collection { items } => {
            let mut out = BTreeMap::new();
            for (name, sha256) in items {
                let p = path.join(name);
                let bytes = std::fs::read(&p).at(&p)?;
                if &sha256_hex(&bytes) != sha256 {
                    return Err(changed());
                }
                out.insert(name.clone(), bytes);
            }
            Ok(Artifact::Collection(out))
        }
    }
}

/// The name a single-file input goes by in `Artifact::OnDisk`: its file name.
pub fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// A path input as files left on disk (`Artifact::OnDisk`), each with the sha256 its key was made
/// from, or the stat under which the file-hash cache holds that sha256 (the read then checks the
/// stat instead of hashing again); a single-file input is one entry named by its file name.
pub fn on_disk(path: &Path, expected: &Stored, cache: &HashCache) -> Artifact {
    let file = |path: PathBuf, sha256: &String| match cache.vouched(&path, sha256) {
        Some(stamp) => InputFile::vouched(path, stamp),
        None => InputFile::checked(path, sha256.clone()),
    };
    Artifact::OnDisk(match expected {
        Stored::File { sha256 } => {
            BTreeMap::from([(file_name(path), file(path.to_path_buf(), sha256))])
        }
        Stored::Collection { items } => items
            .iter()
            .map(|(name, sha256)| (name.clone(), file(path.join(name), sha256)))
            .collect(),
    })
}
