//! Packs: the many small blobs and entries of one stage run in a few files, not one file each.
//!
//! A stage that makes thousands of items (one recording or one fit per run) would create a file
//! per blob and per entry, and creating files is what a cold campaign spent its time on (ext4
//! allocates an inode per file, slowly when many were just deleted). So a batch of at least
//! `PACK_MIN` new blobs goes into one pack, and a batch of at least `PACK_MIN` entries into one
//! entry pack; smaller batches stay loose (`objects/ab/cdef…`, `entries/<key>.json`).
//!
//! - `objects/packs/<id>.pack`: the blobs back to back; `<id>.idx`: one line per blob,
//!   `sha256 offset length`, sorted by hash; id = the sha256 of the idx. The pack is renamed into
//!   place first and the idx second, so an idx names only a complete pack (a pack without its
//!   idx is an orphan of a kill, removed by `groove gc`). Blobs are still checked against their
//!   names on every read.
//! - `entries/packs/<id>.json`: a map key → entry, id = the sha256 of the file, written by one
//!   rename after the blobs its entries name are in place (`Store::commit_many`).
//!
//! `PackWriter` (`engine::pack_writer`) writes packs; `Store` reads them.

use super::error::{EngineError, IoContext};
use std::collections::{HashMap, HashSet};
use std::os::unix::fs::FileExt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The fewest new blobs (or entries) written as a pack; fewer are written loose.
pub const PACK_MIN: usize = 64;

/// Where a packed blob lies.
#[derive(Clone)]
pub struct Loc {
    pub pack: Arc<PackFile>,
    pub offset: u64,
    pub len: u64,
}

/// An open pack (blobs are read with `pread`, so one handle serves every thread).
pub struct PackFile {
    pub path: PathBuf,
    file: std::fs::File,
}

impl PackFile {
    pub fn read(&self, offset: u64, len: u64) -> std::io::Result<Vec<u8>> {
        let mut buf = vec![0u8; len as usize];
        self.file.read_exact_at(&mut buf, offset)?;
        Ok(buf)
    }
}

/// What the packs of a store hold, as read so far.
#[derive(Default)]
pub struct PackIndex {
    /// The idx and entry-pack files read.
    read: HashSet<PathBuf>,
    pub objects: HashMap<String, Loc>,
}

pub fn object_packs(store_dir: &Path) -> PathBuf {
    store_dir.join("objects").join("packs")
}

pub fn entry_packs(store_dir: &Path) -> PathBuf {
    store_dir.join("entries").join("packs")
}

/// The files of a folder with an extension, sorted (none if the folder is missing).
/// A folder reached through a link, and linked files, are left out: the store is never
/// followed out of itself.
pub fn files_with(dir: &Path, ext: &str) -> Vec<PathBuf> {
    if dir.symlink_metadata().is_ok_and(|m| m.is_symlink()) {
        return Vec::new();
    }
    let Ok(list) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut out: Vec<PathBuf> = list
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .filter(|p| p.symlink_metadata().is_ok_and(|m| m.is_file()))
        .collect();
    out.sort();
    out
}

impl PackIndex {
    /// Read the idx files not read yet. One that cannot be read or parsed is skipped (its blobs
    /// are misses, so what made them runs again).
    pub fn refresh(&mut self, store_dir: &Path) {
        for idx in files_with(&object_packs(store_dir), "idx") {
            if self.read.contains(&idx) {
                continue;
            }
            if let Some(blobs) = read_idx(&idx) {
                self.objects.extend(blobs);
            }
            self.read.insert(idx);
        }
    }

    /// Record a pack this process wrote.
    pub fn add_objects(&mut self, idx: PathBuf, blobs: HashMap<String, Loc>) {
        self.objects.extend(blobs);
        self.read.insert(idx);
    }
}

/// The blobs an idx names, with their pack opened; None if either is unreadable or malformed.
pub fn read_idx(idx: &Path) -> Option<HashMap<String, Loc>> {
    let text = std::fs::read_to_string(idx).ok()?;
    let path = idx.with_extension("pack");
    let file = std::fs::File::open(&path).ok()?;
    let size = file.metadata().ok()?.len();
    let pack = Arc::new(PackFile { path, file });
    let mut out = HashMap::new();
    for line in text.lines() {
        let mut f = line.split(' ');
        let (h, off, len) = (f.next()?, f.next()?, f.next()?);
        let (offset, len): (u64, u64) = (off.parse().ok()?, len.parse().ok()?);
        if !super::hashing::is_sha256(h) || offset.checked_add(len)? > size {
            return None;
        }
        let pack = Arc::clone(&pack);
        out.insert(h.to_string(), Loc { pack, offset, len });
    }
    Some(out)
}

/// Remove a pack: its idx first (so it is never named without its blobs), then its blobs.
pub fn remove_pack(idx: &Path) -> Result<(), EngineError> {
    std::fs::remove_file(idx).at(idx)?;
    let pack = idx.with_extension("pack");
    match std::fs::remove_file(&pack) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(EngineError::io(&pack, e)),
        _ => Ok(()),
    }
}
