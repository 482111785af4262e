//! sha256 hex digests, and the file-hash cache keyed by (path, size, mtime, inode, ctime).
//!
//! A file whose size, modification time, inode and change time are unchanged is not read
//! again, so an unchanged large recording costs one `stat`; a `touch` changes the mtime, the
//! file is rehashed, the hash is unchanged, and nothing downstream reruns.

use super::error::{EngineError, IoContext};
pub use super::stage::FileStamp;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Whether `s` names an object: 64 lowercase hex digits, as `sha256_hex` writes them. Anything
/// else read from a store, a remote or a lock is damage, never a path.
pub fn is_sha256(s: &str) -> bool {
    s.len() == 64 && s.bytes().all(|b| matches!(b, b'0'..=b'9' | b'a'..=b'f'))
}
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

/// A sha256 fed through a small buffer: many short writes (item names and hashes) cost one
/// hasher update per 16 KB, and nothing the size of the input is allocated.
pub struct BufHasher {
    hasher: Sha256,
    buf: Vec<u8>,
}

impl Default for BufHasher {
    fn default() -> Self {
        BufHasher::from(Sha256::new())
    }
}

impl From<Sha256> for BufHasher {
    /// Continue a hasher already fed.
    fn from(hasher: Sha256) -> Self {
        BufHasher {
            hasher,
            buf: Vec::with_capacity(1 << 14),
        }
    }
}

impl BufHasher {
    pub fn put(&mut self, bytes: &[u8]) {
        if self.buf.len() + bytes.len() > self.buf.capacity() {
            self.hasher.update(&self.buf);
            self.buf.clear();
            if bytes.len() > self.buf.capacity() {
                self.hasher.update(bytes);
                return;
            }
        }
        self.buf.extend_from_slice(bytes);
    }

    /// Lowercase hex of the digest of everything put.
    pub fn hex(mut self) -> String {
        self.hasher.update(&self.buf);
        hex(&self.hasher.finalize())
    }
}

impl std::io::Write for BufHasher {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.put(bytes);
        Ok(bytes.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Puts `map` as compact JSON, the bytes `serde_json::to_vec` gives (keys in the map's order),
/// without serde's per-string machinery: keys and digests on a 10,000-item no-op.
pub fn put_json_map(h: &mut BufHasher, map: &BTreeMap<String, String>) {
    h.put(b"{");
    for (i, (k, v)) in map.iter().enumerate() {
        if i > 0 {
            h.put(b",");
        }
        put_json_str(h, k);
        h.put(b":");
        put_json_str(h, v);
    }
    h.put(b"}");
}

/// Puts `s` as a JSON string, as `serde_json` writes it.
pub fn put_json_str(h: &mut BufHasher, s: &str) {
    if s.bytes().any(|b| b < 0x20 || b == b'"' || b == b'\\') {
        serde_json::to_writer(&mut *h, s).expect("a string serializes");
        return;
    }
    h.put(b"\"");
    h.put(s.as_bytes());
    h.put(b"\"");
}

/// sha256 of `map` as compact JSON (`put_json_map`).
pub fn json_map_sha256(map: &BTreeMap<String, String>) -> String {
    let mut h = BufHasher::default();
    put_json_map(&mut h, map);
    h.hex()
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

/// The stat of the file at `path` (a symlink followed): what the cache trusts to say a file is
/// unchanged.
pub fn stat_of(path: &Path) -> Result<FileStamp, EngineError> {
    Ok(FileStamp::of(&std::fs::metadata(path).at(path)?))
}

/// A cached hash and the stat it was taken at, as `hashes.json` holds them (the stat's fields
/// flat: `#[serde(flatten)]` would lose the i128 mtime on reading).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
struct Stamp {
    size: u64,
    mtime_ns: i128,
    inode: u64,
    /// 0 in a cache written before the change time was kept: such a stamp matches no file, and
    /// the file is hashed once more.
    #[serde(default)]
    ctime_ns: i128,
    sha256: String,
}

impl Stamp {
    fn new(stat: FileStamp, sha256: String) -> Stamp {
        let FileStamp {
            size,
            mtime_ns,
            inode,
            ctime_ns,
        } = stat;
        Stamp {
            size,
            mtime_ns,
            inode,
            ctime_ns,
            sha256,
        }
    }

    fn stat(&self) -> FileStamp {
        FileStamp {
            size: self.size,
            mtime_ns: self.mtime_ns,
            inode: self.inode,
            ctime_ns: self.ctime_ns,
        }
    }
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
        let stat = stat_of(path)?;
        if let Some(sha256) = self.cached(path, stat) {
            return Ok(sha256);
        }
        let sha256 = hash_reader(std::fs::File::open(path).at(path)?).at(path)?;
        self.remember(path, stat, sha256.clone());
        Ok(sha256)
    }

    /// The sha256 the cache holds for `path` as `stat` describes it (`None`: not hashed since).
    pub fn cached(&self, path: &Path, stat: FileStamp) -> Option<String> {
        let key = path.to_string_lossy();
        let entries = self.entries.lock().expect("hash cache lock");
        let s = entries.get(&*key)?;
        (s.stat() == stat).then(|| s.sha256.clone())
    }

    /// The stat under which the cache holds `sha256` for `path` (`None`: it holds another digest
    /// or none), so that a read may trust that stat instead of hashing again (`InputFile::vouched`).
    pub fn vouched(&self, path: &Path, sha256: &str) -> Option<FileStamp> {
        let key = path.to_string_lossy();
        let entries = self.entries.lock().expect("hash cache lock");
        let s = entries.get(&*key)?;
        (s.sha256 == sha256).then(|| s.stat())
    }

    /// Whether the cache has ever hashed `path` (whatever its content now).
    pub fn knows(&self, path: &Path) -> bool {
        let key = path.to_string_lossy();
        self.entries
            .lock()
            .expect("hash cache lock")
            .contains_key(&*key)
    }

    /// Remember that `path`, as `stat` describes it, has content `sha256`.
    pub fn remember(&self, path: &Path, stat: FileStamp, sha256: String) {
        let stamp = Stamp::new(stat, sha256);
        self.entries
            .lock()
            .expect("hash cache lock")
            .insert(path.to_string_lossy().into_owned(), stamp);
        *self.dirty.lock().expect("hash cache lock") = true;
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

/// A file's stamp as a tuple (size, mtime in ns, inode, ctime in ns), as `lock_digests` stores
/// it.
pub(super) fn stamp_of(meta: &std::fs::Metadata) -> (u64, i128, u64, i128) {
    let FileStamp {
        size,
        mtime_ns,
        inode,
        ctime_ns,
    } = FileStamp::of(meta);
    (size, mtime_ns, inode, ctime_ns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_maps_are_the_bytes_serde_json_writes() {
        let odd = [
            "",
            "a\"b",
            "back\\slash",
            "tab\there",
            "nl\n",
            "\u{1}\u{1f}",
            "é ✓ /",
            "\u{7f}",
        ];
        let mut map: BTreeMap<String, String> = odd
            .iter()
            .enumerate()
            .map(|(i, s)| (format!("{s}{i}"), s.to_string()))
            .collect();
        map.insert("single-316-001".into(), "ab".repeat(32));
        for (k, v) in &map {
            let mut h = BufHasher::default();
            put_json_str(&mut h, k);
            put_json_str(&mut h, v);
            let mut want = serde_json::to_vec(k).unwrap();
            want.extend(serde_json::to_vec(v).unwrap());
            assert_eq!(h.hex(), sha256_hex(&want), "{k:?}");
        }
        // more than the buffer holds, in writes from empty to over the buffer's size (those
        // go to the hasher directly)
        let long: BTreeMap<String, String> = (0..2000)
            .map(|i| (format!("item-{i:05}"), "x".repeat(i * 7919 % 40_000)))
            .collect();
        assert!(long.values().any(|v| v.len() > 1 << 14));
        assert_eq!(
            json_map_sha256(&long),
            sha256_hex(&serde_json::to_vec(&long).unwrap())
        );
        assert_eq!(
            json_map_sha256(&map),
            sha256_hex(&serde_json::to_vec(&map).unwrap())
        );
        let empty = BTreeMap::new();
        assert_eq!(json_map_sha256(&empty), sha256_hex(b"{}"));
    }

    #[test]
    fn the_hash_cache_keeps_its_file_format_and_trusts_only_the_same_stat() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.csv");
        std::fs::write(&file, "t,z\n").unwrap();
        let stat = stat_of(&file).unwrap();
        // a cache as earlier versions wrote it, without the change time: read, never trusted
        let cache_path = dir.path().join("hashes.json");
        let old = serde_json::json!({
            file.to_string_lossy(): {
                "size": stat.size, "mtime_ns": stat.mtime_ns, "inode": stat.inode, "sha256": "ab"
            }
        });
        std::fs::write(&cache_path, serde_json::to_vec(&old).unwrap()).unwrap();
        let cache = HashCache::load(&cache_path);
        assert!(cache.knows(&file));
        assert_eq!(cache.cached(&file, stat), None);
        assert_eq!(cache.hash_file(&file).unwrap(), sha256_hex(b"t,z\n"));
        // one object per path, the stat's fields flat
        let flat = serde_json::json!({
            file.to_string_lossy(): {
                "size": stat.size, "mtime_ns": stat.mtime_ns, "inode": stat.inode,
                "ctime_ns": stat.ctime_ns, "sha256": "ab"
            }
        });
        std::fs::write(&cache_path, serde_json::to_vec(&flat).unwrap()).unwrap();
        let cache = HashCache::load(&cache_path);
        assert_eq!(cache.cached(&file, stat), Some("ab".to_string()));
        let other = FileStamp {
            size: stat.size + 1,
            ..stat
        };
        assert_eq!(cache.cached(&file, other), None);
        let changed = FileStamp {
            ctime_ns: stat.ctime_ns + 1,
            ..stat
        };
        assert_eq!(cache.cached(&file, changed), None);
        // written back in the same form
        cache.remember(&file, other, "cd".into());
        cache.save().unwrap();
        let back: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&cache_path).unwrap()).unwrap();
        let entry = &back[file.to_string_lossy().as_ref()];
        assert_eq!(entry["size"], stat.size + 1);
        assert_eq!(entry["inode"], stat.inode);
        assert_eq!(
            entry["ctime_ns"].as_i64().map(i128::from),
            Some(stat.ctime_ns)
        );
        assert_eq!(entry["sha256"], "cd");
        assert_eq!(
            HashCache::load(&cache_path).cached(&file, other),
            Some("cd".into())
        );
    }
}
