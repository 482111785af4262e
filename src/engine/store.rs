//! The content-addressed store under `.groove/` beside `pipeline.toml`.
//!
//! Layout: `objects/ab/cdef…` holds each blob once, named by its sha256; `entries/<key>.json`
//! records a stage key's outputs as object hashes; `tmp/` holds work in progress. A commit
//! writes every blob to `tmp/` and renames it into `objects/`, then writes the entry the same
//! way: the entry appears (one rename) only after all its blobs exist, so a kill at any moment
//! leaves either no entry or a complete one. Leftovers in `tmp/` are removed by the next run.
//! Batches of many blobs or entries go into packs instead (`engine::pack`), under the same rule.

use super::atomic::unique_name;
use super::error::{EngineError, IoContext};
use super::hashing::{sha256_hex, HashCache};
use super::pack::{self, PackIndex, PACK_MIN};
use super::stage::Artifact;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::RwLock;

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
    /// What the packs hold, read when first needed (`None` until then).
    packs: RwLock<Option<PackIndex>>,
    entry_packs: RwLock<Option<EntryPacks>>,
}

/// The entry packs as read: their bytes, and where each key's entry lies in them (parsed when
/// looked up: 100,000 parsed entries would take about three times the memory).
#[derive(Default)]
struct EntryPacks {
    files: Vec<Vec<u8>>,
    at: std::collections::HashMap<String, (u32, u32, u32)>,
}

impl EntryPacks {
    fn read(store_dir: &Path) -> EntryPacks {
        let mut packs = EntryPacks::default();
        for file in pack::files_with(&pack::entry_packs(store_dir), "json") {
            let Ok(bytes) = std::fs::read(&file) else {
                continue;
            };
            let Ok(raw) =
                serde_json::from_slice::<BTreeMap<String, &serde_json::value::RawValue>>(&bytes)
            else {
                continue;
            };
            let f = packs.files.len() as u32;
            for (key, value) in raw {
                let start = value.get().as_ptr() as usize - bytes.as_ptr() as usize;
                let len = value.get().len();
                packs.at.insert(key, (f, start as u32, len as u32));
            }
            packs.files.push(bytes);
        }
        packs
    }

    fn get(&self, key: &str) -> Option<Entry> {
        let &(f, start, len) = self.at.get(key)?;
        let bytes = &self.files[f as usize][start as usize..(start + len) as usize];
        serde_json::from_slice(bytes).ok()
    }
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
        Store::in_dir(project_root.join(".groove"))
    }

    /// The store kept in `dir` (the `.groove` folder itself).
    pub fn in_dir(dir: PathBuf) -> Store {
        Store {
            dir,
            trust_objects: false,
            packs: RwLock::new(None),
            entry_packs: RwLock::new(None),
        }
    }

    /// Run `f` on the pack index, reading the packs first if they were never read, or again
    /// (only new files) when `refresh`.
    fn with_packs<T>(&self, refresh: bool, f: impl Fn(&PackIndex) -> T) -> T {
        if !refresh {
            if let Some(index) = &*self.packs.read().expect("pack index lock") {
                return f(index);
            }
        }
        let mut guard = self.packs.write().expect("pack index lock");
        let index = guard.get_or_insert_with(PackIndex::default);
        index.refresh(&self.dir);
        f(index)
    }

    /// A packed blob's bytes (read from the packs written since, if it is not known yet).
    fn packed_object(&self, sha256: &str) -> Option<std::io::Result<Vec<u8>>> {
        let read = |i: &PackIndex| {
            i.objects
                .get(sha256)
                .map(|loc| loc.pack.read(loc.offset, loc.len))
        };
        self.with_packs(false, read)
            .or_else(|| self.with_packs(true, read))
    }

    /// Whether the store holds a blob (loose or packed).
    pub fn has_object(&self, sha256: &str) -> bool {
        self.object_path(sha256).is_file()
            || self.with_packs(false, |i| i.objects.contains_key(sha256))
            || self.with_packs(true, |i| i.objects.contains_key(sha256))
    }

    /// Whether these bytes (of this hash) are already stored soundly: a loose object of the same
    /// bytes, or a packed one (packs are checked on read and by `groove verify`).
    pub(super) fn holds_sound(&self, sha256: &str, bytes: &[u8]) -> bool {
        let path = self.object_path(sha256);
        (std::fs::metadata(&path).is_ok_and(|m| m.len() == bytes.len() as u64)
            && std::fs::read(&path).is_ok_and(|b| b == bytes))
            || self.with_packs(false, |i| i.objects.contains_key(sha256))
    }

    /// Record a pack this process wrote.
    pub(super) fn packs_written(
        &self,
        idx: PathBuf,
        blobs: std::collections::HashMap<String, super::pack::Loc>,
    ) {
        let mut guard = self.packs.write().expect("pack index lock");
        let index = guard.get_or_insert_with(|| {
            let mut i = PackIndex::default();
            i.refresh(&self.dir);
            i
        });
        index.add_objects(idx, blobs);
    }

    /// Forget a damaged or missing blob: its loose file, or the whole pack holding it (the other
    /// blobs of that pack become misses too, and what made them runs again when needed).
    pub fn remove_object(&self, sha256: &str) {
        let _ = std::fs::remove_file(self.object_path(sha256));
        let pack = self.with_packs(false, |i| {
            i.objects.get(sha256).map(|l| l.pack.path.clone())
        });
        if let Some(pack) = pack {
            let _ = std::fs::remove_file(pack.with_extension("idx"));
            let _ = std::fs::remove_file(&pack);
            *self.packs.write().expect("pack index lock") = None;
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
        match std::fs::read(self.entry_path(key)) {
            Ok(bytes) => serde_json::from_slice(&bytes).ok(),
            Err(_) => {
                if let Some(packs) = &*self.entry_packs.read().expect("entry pack lock") {
                    return packs.get(key);
                }
                let mut guard = self.entry_packs.write().expect("entry pack lock");
                guard
                    .get_or_insert_with(|| EntryPacks::read(&self.dir))
                    .get(key)
            }
        }
    }

    /// An object's bytes, checked against its name: a damaged object is an error, never data.
    pub fn read_object(&self, sha256: &str) -> Result<Vec<u8>, EngineError> {
        let path = self.object_path(sha256);
        let bytes = match std::fs::read(&path) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                self.packed_object(sha256).unwrap_or(Err(e))
            }
            read => read,
        }
        .map_err(|e| EngineError::DamagedObject {
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
            let path = self.object_path(h);
            match path.is_file() {
                true => hashes.hash_file(&path).is_ok_and(|got| &got == h),
                false => self.read_object(h).is_ok(),
            }
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

    /// Record many keys' outputs (their blobs must already be stored): one entry pack by one
    /// rename when there are at least `PACK_MIN`, else one loose entry each.
    pub fn commit_many(
        &self,
        batch: Vec<(String, BTreeMap<String, Stored>)>,
    ) -> Result<Vec<Entry>, EngineError> {
        if batch.len() < PACK_MIN {
            return batch
                .into_iter()
                .map(|(key, outputs)| self.commit(&key, outputs))
                .collect();
        }
        let entries: Vec<(String, Entry)> = batch
            .into_iter()
            .map(|(key, outputs)| (key, Entry { outputs }))
            .collect();
        let map: BTreeMap<&str, &Entry> = entries.iter().map(|(k, e)| (k.as_str(), e)).collect();
        self.write_entry_pack(&map)?;
        self.forget_entry_packs();
        Ok(entries.into_iter().map(|(_, e)| e).collect())
    }

    /// Check every object against its name and every entry against its objects; remove damaged
    /// objects (a pack holding one goes whole), unreadable entries and entries naming a missing
    /// object (call while holding the project lock). Returns what was checked and dropped.
    pub fn verify(&self) -> Result<Verified, EngineError> {
        let mut report = Verified::default();
        for (name, obj) in self.loose_objects()? {
            report.objects += 1;
            let sound = std::fs::read(&obj).is_ok_and(|b| sha256_hex(&b) == name);
            if !sound {
                remove_any(&obj)?;
                report.dropped_objects.push(name);
            }
        }
        for idx in pack::files_with(&pack::object_packs(&self.dir), "idx") {
            let blobs = pack::read_idx(&idx).unwrap_or_default();
            report.objects += blobs.len();
            let mut damaged: Vec<String> = blobs
                .iter()
                .filter(|(h, loc)| {
                    !loc.pack
                        .read(loc.offset, loc.len)
                        .is_ok_and(|b| &sha256_hex(&b) == *h)
                })
                .map(|(h, _)| h.clone())
                .collect();
            if blobs.is_empty() || !damaged.is_empty() {
                damaged.sort();
                remove_pack(&idx)?;
                report.dropped_objects.extend(damaged);
            }
        }
        self.forget_packs();
        for (key, e) in self.loose_entries()? {
            report.entries += 1;
            let sound = self
                .entry(&key)
                .is_some_and(|entry| self.names_only_held(&entry));
            if !sound {
                remove_any(&e)?;
                report.dropped_entries.push(key);
            }
        }
        for file in pack::files_with(&pack::entry_packs(&self.dir), "json") {
            let entries = read_entry_pack(&file);
            report.entries += entries.len();
            let (sound, bad): (Vec<_>, Vec<_>) = entries
                .iter()
                .partition(|(_, entry)| self.names_only_held(entry));
            if !bad.is_empty() {
                report
                    .dropped_entries
                    .extend(bad.iter().map(|(k, _)| (*k).clone()));
                self.rewrite_entry_pack(&file, sound.into_iter().map(|(k, e)| (k.as_str(), e)))?;
            }
        }
        self.forget_packs();
        Ok(report)
    }

    /// Keep only the given keys and the objects they reference. A pack none of whose objects is
    /// referenced is removed; one mostly unreferenced (more than half its bytes) is returned with
    /// the objects still referenced, for `pack_writer::rewrite` to copy out before it goes.
    /// Returns (entries, objects) removed, and those packs.
    pub fn gc(
        &self,
        keep: &std::collections::BTreeSet<String>,
    ) -> Result<(usize, usize, Vec<(PathBuf, Vec<String>)>), EngineError> {
        let mut live = std::collections::BTreeSet::new();
        let mut removed_entries = 0;
        let mut hold = |entry: &Entry| {
            for stored in entry.outputs.values() {
                live.extend(stored_objects(stored).cloned());
            }
        };
        for (key, e) in self.loose_entries()? {
            if keep.contains(&key) {
                if let Some(entry) = self.entry(&key) {
                    hold(&entry);
                }
            } else {
                std::fs::remove_file(&e).at(&e)?;
                removed_entries += 1;
            }
        }
        for file in pack::files_with(&pack::entry_packs(&self.dir), "json") {
            let entries = read_entry_pack(&file);
            let kept: Vec<(&str, &Entry)> = entries
                .iter()
                .filter(|(k, _)| keep.contains(*k))
                .map(|(k, e)| (k.as_str(), e))
                .collect();
            kept.iter().for_each(|(_, e)| hold(e));
            if kept.len() < entries.len() {
                removed_entries += entries.len() - kept.len();
                self.rewrite_entry_pack(&file, kept.into_iter())?;
            }
        }
        let mut removed_objects = 0;
        for (name, obj) in self.loose_objects()? {
            if !live.contains(&name) {
                std::fs::remove_file(&obj).at(&obj)?;
                removed_objects += 1;
            }
        }
        let packs = pack::object_packs(&self.dir);
        let mut sparse = Vec::new();
        for idx in pack::files_with(&packs, "idx") {
            let blobs = pack::read_idx(&idx).unwrap_or_default();
            let mut held: Vec<String> = blobs
                .keys()
                .filter(|h| live.contains(*h))
                .cloned()
                .collect();
            if held.is_empty() {
                removed_objects += blobs.len();
                remove_pack(&idx)?;
                continue;
            }
            let bytes =
                |hs: &mut dyn Iterator<Item = &String>| -> u64 { hs.map(|h| blobs[h].len).sum() };
            if 2 * bytes(&mut held.iter()) < bytes(&mut blobs.keys()) {
                removed_objects += blobs.len() - held.len();
                held.sort();
                sparse.push((idx, held));
            }
        }
        // what a kill left: a pack whose idx was never written, a half-written file
        for dir in [packs, pack::entry_packs(&self.dir)] {
            for f in read_dir_sorted(&dir)? {
                let orphan = match f.extension().and_then(|e| e.to_str()) {
                    Some("pack") => !f.with_extension("idx").exists(),
                    Some("idx" | "json") => false,
                    _ => true,
                };
                if orphan {
                    remove_any(&f)?;
                }
            }
        }
        self.forget_packs();
        Ok((removed_entries, removed_objects, sparse))
    }

    /// Whether every object an entry names is held.
    fn names_only_held(&self, entry: &Entry) -> bool {
        entry
            .outputs
            .values()
            .all(|s| stored_objects(s).all(|h| self.has_object(h)))
    }

    /// Replace an entry pack by one of the given entries (none: just remove it).
    fn rewrite_entry_pack<'e>(
        &self,
        file: &Path,
        entries: impl Iterator<Item = (&'e str, &'e Entry)>,
    ) -> Result<(), EngineError> {
        let map: BTreeMap<&str, &Entry> = entries.collect();
        if !map.is_empty() {
            let new = self.write_entry_pack(&map)?;
            if new == file {
                return Ok(());
            }
        }
        std::fs::remove_file(file).at(file)
    }

    /// Read the packs again when next needed.
    pub(super) fn forget_packs(&self) {
        *self.packs.write().expect("pack index lock") = None;
        self.forget_entry_packs();
    }

    /// Let go of the entry packs read (after a stage's lookups; read again when next needed).
    pub fn forget_entry_packs(&self) {
        *self.entry_packs.write().expect("entry pack lock") = None;
    }

    /// Write entries as one entry pack (the blobs they name must be in place). Returns its path.
    fn write_entry_pack(&self, entries: &BTreeMap<&str, &Entry>) -> Result<PathBuf, EngineError> {
        let bytes = serde_json::to_vec(entries).expect("entries serialize");
        let dir = pack::entry_packs(&self.dir);
        std::fs::create_dir_all(&dir).at(&dir)?;
        let path = dir.join(format!("{}.json", sha256_hex(&bytes)));
        super::atomic::write_atomic(&path, &bytes)?;
        Ok(path)
    }

    /// The loose objects: (hash, path), sorted.
    fn loose_objects(&self) -> Result<Vec<(String, PathBuf)>, EngineError> {
        let mut out = Vec::new();
        for sub in read_dir_sorted(&self.dir.join("objects"))? {
            let prefix = file_name(&sub);
            if prefix.len() != 2 {
                continue; // `packs/`
            }
            for obj in read_dir_sorted(&sub)? {
                out.push((format!("{prefix}{}", file_name(&obj)), obj));
            }
        }
        Ok(out)
    }

    /// The loose entries: (key, path), sorted.
    fn loose_entries(&self) -> Result<Vec<(String, PathBuf)>, EngineError> {
        Ok(read_dir_sorted(&self.dir.join("entries"))?
            .into_iter()
            .filter(|e| e.is_file())
            .map(|e| {
                let key = e
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                (key, e)
            })
            .collect())
    }
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

/// An entry pack's entries (none if it cannot be read).
fn read_entry_pack(file: &Path) -> BTreeMap<String, Entry> {
    std::fs::read(file)
        .ok()
        .and_then(|b| serde_json::from_slice(&b).ok())
        .unwrap_or_default()
}

/// Remove a pack: its idx first (so it is never named without its blobs), then its blobs.
pub(super) fn remove_pack(idx: &Path) -> Result<(), EngineError> {
    std::fs::remove_file(idx).at(idx)?;
    let pack = idx.with_extension("pack");
    match std::fs::remove_file(&pack) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(EngineError::io(&pack, e)),
        _ => Ok(()),
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
