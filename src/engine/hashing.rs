//! sha256 hex digests, and the file-hash cache keyed by (path, size, mtime, inode).
//!
//! A file whose size, modification time and inode are unchanged is not read again, so an
//! unchanged large recording costs one `stat`; a `touch` changes the mtime, the file is rehashed,
//! the hash is unchanged, and nothing downstream reruns.

use super::error::{EngineError, IoContext};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Lowercase hex sha256 of some bytes.
pub fn sha256_hex(bytes: &[u8]) -> String {
    hex(&Sha256::digest(bytes))
}

/// Lowercase hex sha256 of everything a reader gives, read a megabyte at a time (a 2.6 GB
/// recording is never held whole).
pub fn hash_reader(mut read: impl std::io::Read) -> std::io::Result<String> {
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        match read.read(&mut buf) {
            Ok(0) => return Ok(hex(&hasher.finalize())),
            Ok(n) => hasher.update(&buf[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
}

pub fn hex(bytes: &[u8]) -> String {
    const DIGITS: &[u8; 16] = b"0123456789abcdef";
    let mut s = String::with_capacity(bytes.len() * 2);
    for b in bytes {
        s.push(DIGITS[(b >> 4) as usize] as char);
        s.push(DIGITS[(b & 15) as usize] as char);
    }
    s
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
struct Stamp {
    size: u64,
    mtime_ns: i128,
    inode: u64,
    sha256: String,
}

/// The file-hash cache, stored as `.groove/hashes.json`.
pub struct HashCache {
    path: PathBuf,
    entries: Mutex<BTreeMap<String, Stamp>>,
    dirty: Mutex<bool>,
}

impl HashCache {
    /// Load the cache (an unreadable or missing cache is empty). Stamps of store objects (files
    /// under `objects/` beside the cache), which earlier versions kept, are dropped: an object is
    /// named by its hash and checked when read, and 10,000 such stamps made a no-op parse 5 MB.
    pub fn load(path: &Path) -> HashCache {
        let mut entries: BTreeMap<String, Stamp> = std::fs::read(path)
            .ok()
            .and_then(|b| serde_json::from_slice(&b).ok())
            .unwrap_or_default();
        let objects = path.with_file_name("objects");
        let objects = objects.to_string_lossy();
        let before = entries.len();
        entries.retain(|k, _| !k.starts_with(&*objects));
        let dirty = entries.len() != before;
        HashCache {
            path: path.to_path_buf(),
            entries: Mutex::new(entries),
            dirty: Mutex::new(dirty),
        }
    }

    /// The sha256 of a regular file, from the cache when its stamp is unchanged.
    pub fn hash_file(&self, path: &Path) -> Result<String, EngineError> {
        let meta = std::fs::metadata(path).at(path)?;
        let (size, mtime_ns, inode) = stamp_of(&meta);
        let key = path.to_string_lossy().into_owned();
        if let Some(s) = self.entries.lock().expect("hash cache lock").get(&key) {
            if s.size == size && s.mtime_ns == mtime_ns && s.inode == inode {
                return Ok(s.sha256.clone());
            }
        }
        let sha256 = hash_reader(std::fs::File::open(path).at(path)?).at(path)?;
        let stamp = Stamp {
            size,
            mtime_ns,
            inode,
            sha256: sha256.clone(),
        };
        self.entries
            .lock()
            .expect("hash cache lock")
            .insert(key, stamp);
        *self.dirty.lock().expect("hash cache lock") = true;
        Ok(sha256)
    }

    /// Write the cache back if it changed (atomically; a lost update only costs a rehash).
    pub fn save(&self) -> Result<(), EngineError> {
        if !*self.dirty.lock().expect("hash cache lock") {
            return Ok(());
        }
        let bytes = serde_json::to_vec(&*self.entries.lock().expect("hash cache lock"))
            .expect("hash cache serializes");
        super::atomic::write_atomic(&self.path, &bytes)
    }
}

#[cfg(unix)]
pub(super) fn stamp_of(meta: &std::fs::Metadata) -> (u64, i128, u64) {
    use std::os::unix::fs::MetadataExt;
    let mtime_ns = meta.mtime() as i128 * 1_000_000_000 + meta.mtime_nsec() as i128;
    (meta.size(), mtime_ns, meta.ino())
}

#[cfg(not(unix))]
pub(super) fn stamp_of(meta: &std::fs::Metadata) -> (u64, i128, u64) {
    let mtime_ns = meta
        .modified()
        .ok()
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map(|d| d.as_nanos() as i128)
        .unwrap_or(0);
    (meta.len(), mtime_ns, 0)
}
