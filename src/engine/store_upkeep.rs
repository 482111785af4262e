//! Keeping the store sound and small: `Store::verify` (check every object and entry, drop what
//! is damaged) and `Store::gc` (keep what the lock names), for loose files and packs alike.

use super::error::{EngineError, IoContext};
use super::hashing::is_sha256;
use super::hashing::sha256_hex;
use super::pack;
use super::store::{stored_objects, Entry, Store};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

/// Remove a file, a link (never what it points to) or a folder.
fn remove_any(path: &Path) -> Result<(), EngineError> {
    if path.symlink_metadata().is_ok_and(|m| m.is_dir()) {
        std::fs::remove_dir_all(path).at(path)
    } else {
        std::fs::remove_file(path).at(path)
    }
}

impl Store {
    /// Check every object against its name and every entry against its objects; remove damaged
    /// objects (a pack holding one goes whole), unreadable entries and entries naming a missing
    /// object (call while holding the project lock). Returns what was checked and dropped.
    pub fn verify(&self) -> Result<Verified, EngineError> {
        let mut report = Verified::default();
        let (objects, strays) = self.loose_objects()?;
        for stray in strays {
            // a link, a folder or a misnamed file among the objects: removed itself (a link,
            // never what it points to), as damage
            remove_any(&stray)?;
            report.dropped_objects.push(file_name(&stray));
        }
        for (name, obj) in objects {
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
                pack::remove_pack(&idx)?;
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

    /// Keep only the given keys and the objects they reference, and the objects `also_live`
    /// names. A pack none of whose objects is referenced is removed; one mostly unreferenced
    /// (more than half its bytes) is returned with the objects still referenced, for
    /// `pack_writer::rewrite` to copy out before it goes. Returns (entries, objects) removed, and
    /// those packs.
    pub fn gc(
        &self,
        keep: &std::collections::BTreeSet<String>,
        also_live: &std::collections::BTreeSet<String>,
    ) -> Result<(usize, usize, Vec<(PathBuf, Vec<String>)>), EngineError> {
        let mut live = also_live.clone();
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
        let (objects, strays) = self.loose_objects()?;
        for stray in strays {
            remove_any(&stray)?;
        }
        for (name, obj) in objects {
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
                pack::remove_pack(&idx)?;
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

    /// The loose objects: (hash, path), sorted; and the strays beside them (links, folders,
    /// files not named by a hash), which are never followed.
    #[allow(clippy::type_complexity)]
    fn loose_objects(&self) -> Result<(Vec<(String, PathBuf)>, Vec<PathBuf>), EngineError> {
        let (mut out, mut strays) = (Vec::new(), Vec::new());
        for sub in read_dir_sorted(&self.dir.join("objects"))? {
            let prefix = file_name(&sub);
            if prefix == "packs" && !is_link(&sub) {
                continue;
            }
            let hex_prefix = prefix.len() == 2 && prefix.bytes().all(|b| b.is_ascii_hexdigit());
            if !hex_prefix || is_link(&sub) || !sub.is_dir() {
                strays.push(sub);
                continue;
            }
            for obj in read_dir_sorted(&sub)? {
                let name = format!("{prefix}{}", file_name(&obj));
                let plain_file = obj.symlink_metadata().is_ok_and(|m| m.is_file());
                match plain_file && is_sha256(&name) {
                    true => out.push((name, obj)),
                    false => strays.push(obj),
                }
            }
        }
        Ok((out, strays))
    }

    /// The loose entries: (key, path), sorted.
    fn loose_entries(&self) -> Result<Vec<(String, PathBuf)>, EngineError> {
        Ok(read_dir_sorted(&self.dir.join("entries"))?
            .into_iter()
            .filter(|e| {
                e.symlink_metadata()
                    .is_ok_and(|m| m.is_file() || m.is_symlink())
            })
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

/// Whether a path is a symbolic link.
fn is_link(path: &Path) -> bool {
    path.symlink_metadata().is_ok_and(|m| m.is_symlink())
}

/// A folder's entries, sorted; none for a missing folder or one reached through a link (the
/// store is never followed out of itself).
fn read_dir_sorted(dir: &Path) -> Result<Vec<PathBuf>, EngineError> {
    if !dir.exists() || is_link(dir) {
        return Ok(Vec::new());
    }
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .at(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .collect();
    out.sort();
    Ok(out)
}
