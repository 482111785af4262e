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
use super::hashing::{is_sha256, json_map_sha256, sha256_hex, HashCache};
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
    #[serde(default, deserialize_with = "sorted_map")]
    items: Option<BTreeMap<String, String>>,
}

/// A JSON object of strings into a `BTreeMap` built in one piece from its pairs (a written
/// entry lists them sorted): inserting 10,000 items one at a time, each a search from the root,
/// was a tenth of a 10,000-run no-op.
fn sorted_map<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<BTreeMap<String, String>>, D::Error> {
    struct Pairs;
    impl<'de> serde::de::Visitor<'de> for Pairs {
        type Value = Vec<(String, String)>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("an object of item names and hashes")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut map: A,
        ) -> Result<Self::Value, A::Error> {
            let mut pairs = Vec::with_capacity(map.size_hint().unwrap_or(0));
            while let Some(pair) = map.next_entry()? {
                pairs.push(pair);
            }
            Ok(pairs)
        }
    }
    // `collect` sorts stably (one pass over sorted pairs) and keeps a repeated key's last value
    Ok(Some(d.deserialize_map(Pairs)?.into_iter().collect()))
}

/// Whether `s` is a plain name for one file in a folder: not empty, not `.` or `..`, no
/// separator (`/`, `\`) and no control character (NUL, newline). Item and output names read
/// from a store or a remote must be, so joining one to a folder never leaves that folder.
pub fn is_plain_name(s: &str) -> bool {
    !s.is_empty()
        && s != "."
        && s != ".."
        && !s.chars().any(|c| c == '/' || c == '\\' || c.is_control())
}

impl TryFrom<StoredFields> for Stored {
    type Error = String;
    fn try_from(f: StoredFields) -> Result<Stored, String> {
        match (f.kind.as_str(), f.sha256, f.items) {
            ("file", Some(sha256), None) if is_sha256(&sha256) => Ok(Stored::File { sha256 }),
            ("collection", None, Some(items))
                if items.iter().all(|(n, h)| is_plain_name(n) && is_sha256(h)) =>
            {
                Ok(Stored::Collection { items })
            }
            ("file", Some(sha256), None) => Err(format!(
                "a stored file's hash `{}` is not 64 lowercase hex digits",
                sha256.escape_debug()
            )),
            ("collection", None, Some(_)) => Err(
                "a stored collection names an item that is not a plain file name or a hash that is not 64 lowercase hex digits".into(),
            ),
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
            Stored::Collection { items } => json_map_sha256(items),
        }
    }
}

/// What one stage key produced.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Entry {
    #[serde(deserialize_with = "plain_outputs")]
    pub outputs: BTreeMap<String, Stored>,
}

/// An entry's outputs as read: every output name a plain name (else the entry is damage).
fn plain_outputs<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<BTreeMap<String, Stored>, D::Error> {
    let outputs = BTreeMap::<String, Stored>::deserialize(d)?;
    match outputs.keys().find(|n| !is_plain_name(n)) {
        Some(bad) => Err(serde::de::Error::custom(format!(
            "output name `{}` is not a plain name",
            bad.escape_debug()
        ))),
        None => Ok(outputs),
    }
}

impl Entry {
    /// Whether the entry holds exactly the outputs `names` (a stage's declaration), each a
    /// file when `files` is `Some(true)`, a collection when `Some(false)`: an entry of another
    /// shape is damage (its stage runs again), never a missing output found later.
    pub fn fits<'n>(&self, names: impl Iterator<Item = &'n String>, files: Option<bool>) -> bool {
        let mut count = 0;
        for n in names {
            count += 1;
            match (self.outputs.get(n), files) {
                (None, _) => return false,
                (Some(Stored::File { .. }), Some(false))
                | (Some(Stored::Collection { .. }), Some(true)) => return false,
                _ => {}
            }
        }
        count == self.outputs.len()
    }
}

pub struct Store {
    pub dir: PathBuf,
    /// Take an entry's objects as sound at lookup when they are there (a `stat` each, or a
    /// look in the pack index read), without reading them. Every read still checks an object's bytes against its name, so a damaged object is
    /// found when a stage needs it; `groove run` then checks every object and reruns what made
    /// the damaged one (`engine::run`). Off by default.
    pub trust_objects: bool,
    /// The stat at which each loose object last matched its name, read when first needed:
    /// with `trust_objects`, an object is taken as sound at lookup only at that stat.
    stamps: std::sync::OnceLock<super::object_stamps::ObjectStamps>,
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
            stamps: std::sync::OnceLock::new(),
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
        let read = |i: &PackIndex| packed_in(i, sha256);
        self.with_packs(false, read)
            .or_else(|| self.with_packs(true, read))
    }

    /// Whether the store holds a blob (loose or packed).
    pub fn has_object(&self, sha256: &str) -> bool {
        self.holds(sha256) || self.with_packs(true, |i| i.objects.contains_key(sha256))
    }

    /// Whether the store holds a blob by what this process knows: the pack index as read (no
    /// reading of packs written since), or a loose file. For lookups a miss of which costs only
    /// work made again (`engine::memo`), many of which must not each read the pack index anew.
    pub fn holds(&self, sha256: &str) -> bool {
        self.with_packs(false, |i| i.objects.contains_key(sha256))
            || self.object_path(sha256).is_file()
    }

    /// Whether these bytes (of this hash) are already stored soundly: a loose object of the same
    /// bytes, or a packed one (packs are checked on read and by `groove verify`).
    pub(super) fn holds_sound(&self, sha256: &str, bytes: &[u8]) -> bool {
        self.loose_sound(sha256, bytes)
            || self.with_packs(false, |i| i.objects.contains_key(sha256))
    }

    /// Whether a loose object of these bytes is there. The bytes were just hashed, so equal
    /// bytes are sound without hashing the file again; a damaged one is not (it is replaced).
    fn loose_sound(&self, sha256: &str, bytes: &[u8]) -> bool {
        let path = self.object_path(sha256);
        std::fs::metadata(&path).is_ok_and(|m| m.len() == bytes.len() as u64)
            && std::fs::read(&path).is_ok_and(|b| b == bytes)
    }

    /// Record a pack this process wrote (packs not read yet are read, this one with them, when
    /// first needed).
    pub(super) fn packs_written(
        &self,
        idx: PathBuf,
        blobs: std::collections::HashMap<String, super::pack::Loc>,
    ) {
        if let Some(index) = &mut *self.packs.write().expect("pack index lock") {
            index.add_objects(idx, blobs);
        }
    }

    /// Forget a damaged or missing blob: its loose file, or the whole pack holding it (the other
    /// blobs of that pack become misses too, and what made them runs again when needed).
    pub fn remove_object(&self, sha256: &str) {
        let _ = std::fs::remove_file(self.object_path(sha256));
        let pack = self.with_packs(false, |i| {
            i.objects.get(sha256).map(|l| l.pack.path.clone())
        });
        if let Some(pack) = pack {
            let _ = pack::remove_pack(&pack.with_extension("idx"));
            self.forget_packs();
        }
    }

    /// Where a loose object lies. Every hash read from a store, a remote or a lock is checked
    /// to be one when parsed; anything else gets a name in `objects/` no object has, never a
    /// path outside it.
    pub fn object_path(&self, sha256: &str) -> PathBuf {
        let objects = self.dir.join("objects");
        match is_sha256(sha256) {
            true => objects.join(&sha256[..2]).join(&sha256[2..]),
            false => objects.join("not-a-hash"),
        }
    }

    /// Where a key's loose entry lies (`None` for a key that is not a hash: no entry).
    fn entry_path(&self, key: &str) -> Option<PathBuf> {
        is_sha256(key).then(|| self.dir.join("entries").join(format!("{key}.json")))
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
        let path = self.entry_path(key)?;
        match std::fs::read(path) {
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
        // a blob the pack index already knows is read from its pack first, with no failed open of
        // a loose path per item; a damaged copy there falls through to the loose one
        if let Some(Ok(bytes)) = self.with_packs(false, |i| packed_in(i, sha256)) {
            if sha256_hex(&bytes) == sha256 {
                return Ok(bytes);
            }
        }
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

    /// The entry of a key if it is complete and every object it names exists with the right
    /// hash. A file object is checked through `hashes`; the objects of a collection are read
    /// and hashed on every core. With `trust_objects` each object only has to be there (a pack's
    /// blob or a loose file; a damaged one is found when read). A damaged or missing object
    /// makes the entry a miss: the stage runs again and stores the object anew.
    pub fn entry_checked(&self, key: &str, hashes: &HashCache) -> Option<Entry> {
        let entry = self.entry(key)?;
        if self.trust_objects {
            // trusted, a packed object only has to be in a pack read (packs are checked on read
            // and by `groove verify`), a loose one unchanged since its bytes last matched its
            // name (a `stat`; read and hashed once when not); a damaged one found when read
            // makes `run` check everything
            let stamps = self
                .stamps
                .get_or_init(|| super::object_stamps::ObjectStamps::load(&self.dir));
            let there = |h: &String| {
                self.with_packs(false, |i| i.objects.contains_key(h))
                    || stamps.sound(h, &self.object_path(h))
            };
            let all_there = entry.outputs.values().all(|s| stored_objects(s).all(there));
            return all_there.then_some(entry);
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

    /// Keep the loose objects' stamps taken this run (best-effort).
    pub fn save_stamps(&self) {
        if let Some(stamps) = self.stamps.get() {
            stamps.save();
        }
    }

    /// Load a stored artifact's bytes.
    pub fn load(&self, stored: &Stored) -> Result<Artifact, EngineError> {
        Ok(match stored {
            Stored::File { sha256 } => Artifact::File(self.read_object(sha256)?),
            Stored::Collection { items } => {
                // read and checked on every core; the first bad item in name order is the error
                let read: Vec<Result<Vec<u8>, EngineError>> =
                    items.par_iter().map(|(_, h)| self.read_object(h)).collect();
                Artifact::Collection(
                    items
                        .keys()
                        .zip(read)
                        .map(|(name, bytes)| Ok((name.clone(), bytes?)))
                        .collect::<Result<_, EngineError>>()?,
                )
            }
        })
    }

    /// Put one blob into `objects/` (no-op when present). Returns its hash.
    pub fn put_object(&self, bytes: &[u8]) -> Result<String, EngineError> {
        let sha256 = sha256_hex(bytes);
        let path = self.object_path(&sha256);
        if !self.loose_sound(&sha256, bytes) {
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
        let path = self.entry_path(key).ok_or_else(|| {
            EngineError::Usage(format!("`{}` is not a store key", key.escape_debug()))
        })?;
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
    pub(super) fn write_entry_pack(
        &self,
        entries: &BTreeMap<&str, &Entry>,
    ) -> Result<PathBuf, EngineError> {
        let bytes = serde_json::to_vec(entries).expect("entries serialize");
        let dir = pack::entry_packs(&self.dir);
        std::fs::create_dir_all(&dir).at(&dir)?;
        let path = dir.join(format!("{}.json", sha256_hex(&bytes)));
        super::atomic::write_atomic(&path, &bytes)?;
        Ok(path)
    }
}

/// The object hashes an artifact record names.
pub fn stored_objects(stored: &Stored) -> Box<dyn Iterator<Item = &String> + '_> {
    match stored {
        Stored::File { sha256 } => Box::new(std::iter::once(sha256)),
        Stored::Collection { items } => Box::new(items.values()),
    }
}

/// A blob's bytes from the pack that `index` says holds it (`None`: no pack it knows does).
fn packed_in(index: &PackIndex, sha256: &str) -> Option<std::io::Result<Vec<u8>>> {
    index
        .objects
        .get(sha256)
        .map(|loc| loc.pack.read(loc.offset, loc.len))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_entry_reads_its_items_as_a_map_whatever_their_order() {
        let h = |c: char| c.to_string().repeat(64);
        let text = format!(
            r#"{{"outputs": {{"runs": {{"type": "collection", "items": {{"b": "{}", "a": "{}", "c": "{}", "a": "{}"}}}}, "summary": {{"type": "file", "sha256": "{}"}}}}}}"#,
            h('2'),
            h('1'),
            h('3'),
            h('4'),
            h('f')
        );
        let entry: Entry = serde_json::from_str(&text).unwrap();
        let items = BTreeMap::from([
            ("a".to_string(), h('4')),
            ("b".to_string(), h('2')),
            ("c".to_string(), h('3')),
        ]);
        assert_eq!(entry.outputs["runs"], Stored::Collection { items });
        assert_eq!(entry.outputs["summary"], Stored::File { sha256: h('f') });
        let both = text.replace(r#""type": "file","#, r#""type": "file", "items": {},"#);
        assert!(serde_json::from_str::<Entry>(&both).is_err());
    }

    #[test]
    fn hashes_and_names_that_are_paths_are_damage() {
        let good = format!(
            r#"{{"outputs": {{"x": {{"type": "file", "sha256": "{}"}}}}}}"#,
            "a".repeat(64)
        );
        assert!(serde_json::from_str::<Entry>(&good).is_ok());
        for bad in [
            "ab",
            "../../etc/passwd",
            &"A".repeat(64),
            &format!("..{}", "/".repeat(62)),
        ] {
            let text = good.replace(&"a".repeat(64), bad);
            assert!(serde_json::from_str::<Entry>(&text).is_err(), "{bad}");
        }
        for name in ["..", ".", "a/b", "/abs", "", r"a\nb", r"a\u0000b"] {
            let output = good.replace(r#""x""#, &format!("\"{name}\""));
            assert!(
                serde_json::from_str::<Entry>(&output).is_err(),
                "output {name}"
            );
            let item = format!(
                r#"{{"outputs": {{"x": {{"type": "collection", "items": {{"{name}": "{}"}}}}}}}}"#,
                "a".repeat(64)
            );
            assert!(serde_json::from_str::<Entry>(&item).is_err(), "item {name}");
        }
        let store = Store::in_dir(PathBuf::from("/nowhere/.groove"));
        assert!(store
            .object_path("../../x")
            .starts_with("/nowhere/.groove/objects"));
        assert!(store.entry("../../x").is_none());
    }

    #[test]
    fn a_packed_blob_is_read_from_its_pack_and_a_damaged_one_from_its_loose_copy() {
        let dir = tempfile::tempdir().unwrap();
        let store = Store::at(dir.path());
        let blobs: Vec<Vec<u8>> = (0..PACK_MIN + 1)
            .map(|k| format!("blob {k}").into_bytes())
            .collect();
        let writer = crate::engine::pack_writer::PackWriter::new(&store);
        let hashes: Vec<String> = blobs.iter().map(|b| writer.add(b).unwrap()).collect();
        writer.finish().unwrap();
        for (b, h) in blobs.iter().zip(&hashes) {
            assert!(!store.object_path(h).exists(), "packed, not loose");
            assert_eq!(store.read_object(h).unwrap(), *b);
        }
        // damage the first blob inside its pack: an error while no loose copy exists, its
        // bytes once one does
        let pack = pack::files_with(&pack::object_packs(&store.dir), "pack").remove(0);
        let mut bytes = std::fs::read(&pack).unwrap();
        let at = bytes
            .windows(blobs[0].len())
            .position(|w| w == blobs[0].as_slice())
            .unwrap();
        bytes[at] ^= 0x20;
        std::fs::write(&pack, bytes).unwrap();
        let fresh = Store::at(dir.path());
        assert!(fresh.read_object(&hashes[0]).is_err());
        fresh.put_object(&blobs[0]).unwrap();
        assert!(fresh.object_path(&hashes[0]).exists());
        assert_eq!(fresh.read_object(&hashes[0]).unwrap(), blobs[0]);
        assert_eq!(fresh.read_object(&hashes[1]).unwrap(), blobs[1]);
    }
}
