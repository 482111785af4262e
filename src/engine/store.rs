//! The content-addressed store under `.groove/` beside `pipeline.toml`.
//!
//! Layout: `objects/ab/cdef…` holds each blob once, named by its sha256; `entries/<key>.json`
//! records a stage key's outputs as object hashes; `tmp/` holds work in progress. A commit
//! writes every blob to `tmp/` and renames it into `objects/`, then writes the entry the same
//! way: the entry appears (one rename) only after all its blobs exist, so a kill at any moment
//! leaves either no entry or a complete one. Leftovers in `tmp/` are removed by the next run.

use super::atomic::unique_name;
use super::error::{EngineError, IoContext};
use super::hashing::{sha256_hex, HashCache};
use super::stage::Artifact;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// An artifact as the store records it: object hashes instead of bytes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(
    tag = "type",
    rename_all = "lowercase",
    try_from = "StoredFields",
    deny_unknown_fields
)]
pub enum Stored {
    File { sha256: String },
    Collection { items: BTreeMap<String, String> },
}

/// `Stored` as read: one plain struct, so serde does not buffer every value of an internally
/// tagged enum before choosing the variant (that buffering was a third of a 10,000-run no-op).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StoredFields {
    #[serde(rename = "type")]
    kind: String,
    sha256: Option<String>,
    items: Option<BTreeMap<String, String>>,
}

impl TryFrom<StoredFields> for Stored {
    type Error = String;
    fn try_from(f: StoredFields) -> Result<Stored, String> {
        match (f.kind.as_str(), f.sha256, f.items) {
            ("file", Some(sha256), None) => Ok(Stored::File { sha256 }),
            ("collection", None, Some(items)) => Ok(Stored::Collection { items }),
            (kind, _, _) => Err(format!(
                "a stored artifact of type `{kind}` needs `sha256` (file) or `items` (collection), not both"
            )),
        }
    }
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
    /// Take an entry's objects as sound at lookup without checking them (one `stat` each:
    /// 20,000 on a 10,000-run no-op, most of its time). Every read still checks an object's bytes
    /// against its name, so a damaged object is found when a stage needs it; `groove run` then
    /// checks every object and reruns what made the damaged one (`engine::run`). Off by default.
    pub trust_objects: bool,
}

/// What `Store::verify` checked and dropped.
#[derive(Debug, Default)]
pub struct Verified {
    pub objects: usize,
    pub entries: usize,
    /// Objects whose bytes did not match their name (removed).
    pub dropped_objects: Vec<String>,
    /// Entries that could not be read or named a missing object (removed).
    pub dropped_entries: Vec<String>,
}

fn remove_any(path: &Path) -> Result<(), EngineError> {
    if path.is_dir() {
        std::fs::remove_dir_all(path).at(path)
    } else {
        std::fs::remove_file(path).at(path)
    }
}

impl Store {
    /// The store of a project (folders are created when first written).
    pub fn at(project_root: &Path) -> Store {
        Store {
            dir: project_root.join(".groove"),
            trust_objects: false,
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

    /// An object's bytes, checked against its name: a damaged object is an error, never data.
    pub fn read_object(&self, sha256: &str) -> Result<Vec<u8>, EngineError> {
        let path = self.object_path(sha256);
        let bytes = std::fs::read(&path).map_err(|e| EngineError::DamagedObject {
            sha256: sha256.to_string(),
            missing: true,
            why: e.to_string(),
        })?;
        if sha256_hex(&bytes) != sha256 {
            return Err(EngineError::DamagedObject {
                sha256: sha256.to_string(),
                missing: false,
                why: "its bytes have another hash".into(),
            });
        }
        Ok(bytes)
    }

    /// The entry of a key if it is complete and (unless `trust_objects`) every object it names
    /// exists with the right hash. A file object is checked through `hashes` (one `stat` while
    /// unchanged); the objects of a collection, read and hashed on every core (only a run
    /// repairing a damaged object checks them, so their stamps are not kept). A damaged or
    /// missing object makes the entry a miss: the stage runs again and stores the object anew.
    pub fn entry_checked(&self, key: &str, hashes: &HashCache) -> Option<Entry> {
        let entry = self.entry(key)?;
        if self.trust_objects {
            return Some(entry);
        }
        let sound_object = |h: &String| {
            hashes
                .hash_file(&self.object_path(h))
                .is_ok_and(|got| &got == h)
        };
        let sound_item = |h: &String| self.read_object(h).is_ok();
        let sound = entry.outputs.values().all(|stored| match stored {
            Stored::File { sha256 } => sound_object(sha256),
            Stored::Collection { items } => items.par_iter().all(|(_, h)| sound_item(h)),
        });
        sound.then_some(entry)
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
        // an object already there is reused only if it is sound (a damaged one is replaced);
        // these bytes were just hashed, so equal bytes are sound without hashing them again
        let sound = std::fs::metadata(&path).is_ok_and(|m| m.len() == bytes.len() as u64)
            && std::fs::read(&path).is_ok_and(|b| b == bytes);
        if !sound {
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
            // put by the stage as it ran (`StageInput::put_item`)
            Artifact::InStore(items) => Stored::Collection {
                items: items.clone(),
            },
            Artifact::OnDisk(_) => {
                return Err(EngineError::Usage(super::stage::IN_STORE_INPUT.into()))
            }
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

    /// Check every object against its name and every entry against its objects; remove damaged
    /// objects, unreadable entries and entries naming a missing object (call while holding the
    /// project lock). Returns what was checked and what was dropped.
    pub fn verify(&self) -> Result<Verified, EngineError> {
        let mut report = Verified::default();
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
                report.objects += 1;
                let name = format!("{prefix}{rest}");
                let sound = std::fs::read(&obj).is_ok_and(|b| sha256_hex(&b) == name);
                if !sound {
                    remove_any(&obj)?;
                    report.dropped_objects.push(name);
                }
            }
        }
        for e in read_dir_sorted(&self.dir.join("entries"))? {
            let key = e
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            report.entries += 1;
            let sound = self.entry(&key).is_some_and(|entry| {
                entry
                    .outputs
                    .values()
                    .all(|s| stored_objects(s).all(|h| self.object_path(h).is_file()))
            });
            if !sound {
                remove_any(&e)?;
                report.dropped_entries.push(key);
            }
        }
        Ok(report)
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

/// The object hashes an artifact record names.
pub fn stored_objects(stored: &Stored) -> Box<dyn Iterator<Item = &String> + '_> {
    match stored {
        Stored::File { sha256 } => Box::new(std::iter::once(sha256)),
        Stored::Collection { items } => Box::new(items.values()),
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
