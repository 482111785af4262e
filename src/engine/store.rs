//! The content-addressed store under `.groove/` beside `pipeline.toml`.
//!
//! Layout: `objects/ab/cdef…` holds each blob once, named by its sha256; `entries/<key>.json`
//! records a stage key's outputs as object hashes; `tmp/` holds work in progress. A commit
//! writes every blob to `tmp/` and renames it into `objects/`, then writes the entry the same
//! way: the entry appears (one rename) only after all its blobs exist, so a kill at any moment
//! leaves either no entry or a complete one. Leftovers in `tmp/` are removed by the next run.

use super::atomic::unique_name;
use super::error::{EngineError, IoContext};
use super::hashing::sha256_hex;
use super::stage::Artifact;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// An artifact as the store records it: object hashes instead of bytes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Stored {
    File { sha256: String },
    Collection { items: BTreeMap<String, String> },
}

impl Stored {
    /// The content digest that enters downstream keys.
    pub fn digest(&self) -> String {
        match self {
            Stored::File { sha256 } => sha256.clone(),
            Stored::Collection { items } => {
                sha256_hex(&serde_json::to_vec(items).expect("collection serializes"))
            }
        }
    }
}

/// What one stage key produced.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Entry {
    pub outputs: BTreeMap<String, Stored>,
}

pub struct Store {
    pub dir: PathBuf,
}

impl Store {
    /// The store of a project (folders are created when first written).
    pub fn at(project_root: &Path) -> Store {
        Store {
            dir: project_root.join(".groove"),
        }
    }

    pub fn object_path(&self, sha256: &str) -> PathBuf {
        self.dir
            .join("objects")
            .join(&sha256[..2])
            .join(&sha256[2..])
    }

    fn entry_path(&self, key: &str) -> PathBuf {
        self.dir.join("entries").join(format!("{key}.json"))
    }

    pub fn tmp_root(&self) -> PathBuf {
        self.dir.join("tmp")
    }

    /// A fresh private folder under `tmp/`.
    pub fn tmp_dir(&self, prefix: &str) -> Result<PathBuf, EngineError> {
        let dir = self.tmp_root().join(unique_name(prefix));
        std::fs::create_dir_all(&dir).at(&dir)?;
        Ok(dir)
    }

    /// Remove what killed runs left in `tmp/` (call while holding the project lock). Best effort:
    /// a command orphaned by a killed run may still be writing there, and names never collide.
    pub fn sweep_tmp(&self) -> Result<(), EngineError> {
        let _ = std::fs::remove_dir_all(self.tmp_root());
        Ok(())
    }

    /// The entry of a key, if a complete one was committed.
    pub fn entry(&self, key: &str) -> Option<Entry> {
        let bytes = std::fs::read(self.entry_path(key)).ok()?;
        serde_json::from_slice(&bytes).ok()
    }

    pub fn read_object(&self, sha256: &str) -> Result<Vec<u8>, EngineError> {
        let path = self.object_path(sha256);
        std::fs::read(&path).map_err(|e| {
            EngineError::Usage(format!(
                "the store is missing object {sha256} ({e}); run `groove clean` and `groove run` again"
            ))
        })
    }

    /// Load a stored artifact's bytes.
    pub fn load(&self, stored: &Stored) -> Result<Artifact, EngineError> {
        Ok(match stored {
            Stored::File { sha256 } => Artifact::File(self.read_object(sha256)?),
            Stored::Collection { items } => Artifact::Collection(
                items
                    .iter()
                    .map(|(name, h)| Ok((name.clone(), self.read_object(h)?)))
                    .collect::<Result<_, EngineError>>()?,
            ),
        })
    }

    /// Put one blob into `objects/` (no-op when present). Returns its hash.
    pub fn put_object(&self, bytes: &[u8]) -> Result<String, EngineError> {
        let sha256 = sha256_hex(bytes);
        let path = self.object_path(&sha256);
        if !path.exists() {
            let tmp = self.tmp_root();
            std::fs::create_dir_all(&tmp).at(&tmp)?;
            let staged = tmp.join(unique_name("object"));
            std::fs::write(&staged, bytes).at(&staged)?;
            let parent = path.parent().expect("object paths have a parent");
            std::fs::create_dir_all(parent).at(parent)?;
            std::fs::rename(&staged, &path).at(&path)?;
        }
        Ok(sha256)
    }

    /// Store an artifact's blobs and return its record.
    pub fn put(&self, artifact: &Artifact) -> Result<Stored, EngineError> {
        Ok(match artifact {
            Artifact::File(bytes) => Stored::File {
                sha256: self.put_object(bytes)?,
            },
            Artifact::Collection(items) => Stored::Collection {
                items: items
                    .iter()
                    .map(|(name, bytes)| Ok((name.clone(), self.put_object(bytes)?)))
                    .collect::<Result<_, EngineError>>()?,
            },
        })
    }

    /// Record a key's outputs (their blobs must already be stored): one atomic rename.
    pub fn commit(
        &self,
        key: &str,
        outputs: BTreeMap<String, Stored>,
    ) -> Result<Entry, EngineError> {
        let entry = Entry { outputs };
        let bytes = serde_json::to_vec_pretty(&entry).expect("an entry serializes");
        let path = self.entry_path(key);
        let tmp = self.tmp_root();
        std::fs::create_dir_all(&tmp).at(&tmp)?;
        let staged = tmp.join(unique_name("entry"));
        std::fs::write(&staged, &bytes).at(&staged)?;
        let parent = path.parent().expect("entry paths have a parent");
        std::fs::create_dir_all(parent).at(parent)?;
        std::fs::rename(&staged, &path).at(&path)?;
        Ok(entry)
    }

    /// Keep only the given keys and the objects they reference. Returns (entries, objects) removed.
    pub fn gc(
        &self,
        keep: &std::collections::BTreeSet<String>,
    ) -> Result<(usize, usize), EngineError> {
        let mut live = std::collections::BTreeSet::new();
        let mut removed_entries = 0;
        let entries_dir = self.dir.join("entries");
        for e in read_dir_sorted(&entries_dir)? {
            let key = e
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            if keep.contains(&key) {
                if let Some(entry) = self.entry(&key) {
                    for stored in entry.outputs.values() {
                        match stored {
                            Stored::File { sha256 } => {
                                live.insert(sha256.clone());
                            }
                            Stored::Collection { items } => live.extend(items.values().cloned()),
                        }
                    }
                }
            } else {
                std::fs::remove_file(&e).at(&e)?;
                removed_entries += 1;
            }
        }
        let mut removed_objects = 0;
        for sub in read_dir_sorted(&self.dir.join("objects"))? {
            let prefix = sub
                .file_name()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            for obj in read_dir_sorted(&sub)? {
                let rest = obj
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                if !live.contains(&format!("{prefix}{rest}")) {
                    std::fs::remove_file(&obj).at(&obj)?;
                    removed_objects += 1;
                }
            }
        }
        Ok((removed_entries, removed_objects))
    }
}

fn read_dir_sorted(dir: &Path) -> Result<Vec<PathBuf>, EngineError> {
    if !dir.exists() {
        return Ok(Vec::new());
    }
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .at(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    out.sort();
    Ok(out)
}
