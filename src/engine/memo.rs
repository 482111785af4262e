//! A stage's object memo (`StageInput::memo`): which stored object an earlier run of the stage
//! made from which bytes of its input, kept in `.groove/memo/` between runs so that a stage that
//! reads one big changed file makes again only the objects whose bytes changed.
//!
//! One file per stage, read when the stage starts and rewritten (atomically) when it ends well
//! with what this run used and made: the keys a run did not touch are dropped, so the file
//! tracks the current input (≈ 72 bytes per object) and never grows with the history. The
//! file is valid only for the kind, its code fingerprint, the groove version and the params
//! it was written under (its salt); anything else, a damaged file included, reads as empty.
//! A key found gives its object only while the store holds it. The memo is never needed for a
//! correct result: every miss is made from the bytes again, and a crash at any moment leaves
//! either the old file or the new one. `groove gc` keeps the objects the memo files of the
//! lock's stages name (an aggregate's summaries, which no entry names) and removes the files of
//! stages no longer in it.

use super::atomic::write_atomic;
use super::hashing::hex;
use super::stage::ObjectMemo;
use super::store::Store;
use sha2::{Digest, Sha256};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

const MAGIC: &[u8; 16] = b"groove-memo v1\n\0";

/// The memo of one stage for one run.
pub struct Memo<'s> {
    path: PathBuf,
    salt: [u8; 32],
    store: &'s Store,
    /// What the file held (key → object sha256).
    earlier: HashMap<[u8; 32], [u8; 32]>,
    /// What this run found or made, for the file it leaves.
    used: Mutex<Vec<([u8; 32], [u8; 32])>>,
    /// Keys made this run (not found).
    made: std::sync::atomic::AtomicUsize,
}

impl<'s> Memo<'s> {
    /// The memo of stage `stage`, valid for `salt` (what its objects depend on besides the bytes
    /// the kind names: kind, code, version, params).
    pub fn open(store: &'s Store, stage: &str, salt: &[u8]) -> Memo<'s> {
        let salt: [u8; 32] = Sha256::digest(salt).into();
        let path = store.dir.join("memo").join(file_name(stage));
        let earlier = std::fs::read(&path)
            .ok()
            .and_then(|bytes| parse(&bytes, &salt))
            .unwrap_or_default();
        Memo {
            path,
            salt,
            store,
            earlier,
            used: Mutex::new(Vec::new()),
            made: 0.into(),
        }
    }

    /// Leave what this run used and made for the next run (after the stage ended well). The
    /// file is left as it is when it already says exactly that.
    pub fn save(self) -> Result<(), super::error::EngineError> {
        let mut used = self.used.into_inner().expect("memo lock");
        used.sort_unstable();
        used.dedup();
        let unchanged = self.made.into_inner() == 0 && used.len() == self.earlier.len();
        if unchanged || (used.is_empty() && self.earlier.is_empty()) {
            return Ok(());
        }
        let mut bytes = Vec::with_capacity(MAGIC.len() + 32 + 8 + 64 * used.len() + 32);
        bytes.extend(MAGIC);
        bytes.extend(self.salt);
        bytes.extend((used.len() as u64).to_le_bytes());
        for (key, object) in &used {
            bytes.extend(key);
            bytes.extend(object);
        }
        let check = Sha256::digest(&bytes);
        bytes.extend(check);
        write_atomic(&self.path, &bytes)
    }
}

impl ObjectMemo for Memo<'_> {
    fn get(&self, key: &[u8; 32]) -> Option<String> {
        let object = self.earlier.get(key)?;
        let name = hex(object);
        if !self.store.holds(&name) {
            return None;
        }
        self.used.lock().expect("memo lock").push((*key, *object));
        Some(name)
    }

    fn read(&self, sha256: &str) -> Option<Vec<u8>> {
        self.store.read_object(sha256).ok()
    }

    fn put(&self, key: [u8; 32], sha256: &str) {
        let Some(object) = unhex(sha256) else {
            return;
        };
        self.made.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.used.lock().expect("memo lock").push((key, object));
    }
}

/// The name of stage `stage`'s memo file in `.groove/memo/`.
pub fn file_name(stage: &str) -> String {
    hex(&Sha256::digest(stage.as_bytes())[..16])
}

/// The memo files in the store at `store_dir` (by path, in name order), each with the objects
/// it names in name order (under whatever salt it was written; none if it is damaged), for
/// `groove gc`.
pub fn files(store_dir: &Path) -> Vec<(PathBuf, Vec<String>)> {
    let Ok(dir) = std::fs::read_dir(store_dir.join("memo")) else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = dir.flatten().map(|e| e.path()).collect();
    files.sort();
    files
        .into_iter()
        .map(|path| {
            let objects = std::fs::read(&path)
                .ok()
                .and_then(|bytes| {
                    let salt = bytes.get(MAGIC.len()..MAGIC.len() + 32)?.try_into().ok()?;
                    parse(&bytes, &salt)
                })
                .map(|entries| {
                    let mut objects: Vec<String> = entries.values().map(|o| hex(o)).collect();
                    objects.sort_unstable();
                    objects
                })
                .unwrap_or_default();
            (path, objects)
        })
        .collect()
}

/// The entries of a memo file written under `salt`; `None` for another salt or a damaged file.
fn parse(bytes: &[u8], salt: &[u8; 32]) -> Option<HashMap<[u8; 32], [u8; 32]>> {
    let (body, check) = bytes.split_at_checked(bytes.len().checked_sub(32)?)?;
    if Sha256::digest(body)[..] != *check {
        return None;
    }
    let rest = body.strip_prefix(MAGIC)?.strip_prefix(salt)?;
    let (count, entries) = rest.split_at_checked(8)?;
    let count = u64::from_le_bytes(count.try_into().ok()?);
    if entries.len() as u64 != count.checked_mul(64)? {
        return None;
    }
    Some(
        entries
            .chunks_exact(64)
            .map(|e| {
                let (k, o) = e.split_at(32);
                (
                    k.try_into().expect("32 bytes"),
                    o.try_into().expect("32 bytes"),
                )
            })
            .collect(),
    )
}

/// 32 bytes from 64 lowercase hex digits.
fn unhex(s: &str) -> Option<[u8; 32]> {
    let s = s.as_bytes();
    if s.len() != 64 {
        return None;
    }
    let digit = |c: u8| match c {
        b'0'..=b'9' => Some(c - b'0'),
        b'a'..=b'f' => Some(c - b'a' + 10),
        _ => None,
    };
    let mut out = [0u8; 32];
    for (i, o) in out.iter_mut().enumerate() {
        *o = digit(s[2 * i])? << 4 | digit(s[2 * i + 1])?;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn store() -> (PathBuf, Store) {
        let dir = std::env::temp_dir().join(super::super::atomic::unique_name("groove-memo-test"));
        std::fs::create_dir_all(&dir).unwrap();
        let store = Store::in_dir(dir.join(".groove"));
        (dir, store)
    }

    #[test]
    fn a_memo_gives_what_the_last_run_used_and_made_while_the_store_holds_it() {
        let (dir, store) = store();
        let a = store.put_object(b"item a").unwrap();
        let b = store.put_object(b"item b").unwrap();
        let (ka, kb, kc) = ([1u8; 32], [2u8; 32], [3u8; 32]);
        let first = Memo::open(&store, "ingest", b"salt");
        assert_eq!(first.get(&ka), None);
        first.put(ka, &a);
        first.put(kb, &b);
        first.put(kc, &"c".repeat(64)); // an object the store will not hold
        first.save().unwrap();

        // the next run finds a and b, not c; it uses only a, so b is dropped after it
        let second = Memo::open(&store, "ingest", b"salt");
        assert_eq!(second.get(&ka), Some(a.clone()));
        assert_eq!(second.get(&kc), None);
        second.save().unwrap();
        let third = Memo::open(&store, "ingest", b"salt");
        assert_eq!(third.get(&kb), None);
        assert_eq!(third.get(&ka), Some(a.clone()));

        // another stage, another salt, or a damaged file: nothing
        assert_eq!(Memo::open(&store, "other", b"salt").get(&ka), None);
        assert_eq!(Memo::open(&store, "ingest", b"salt 2").get(&ka), None);
        let path = third.path.clone();
        let mut bytes = std::fs::read(&path).unwrap();
        let last = bytes.len() - 40;
        bytes[last] ^= 1;
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(Memo::open(&store, "ingest", b"salt").get(&ka), None);
        std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
        assert_eq!(Memo::open(&store, "ingest", b"salt").get(&ka), None);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn unhex_reads_what_hex_writes() {
        let bytes: [u8; 32] = std::array::from_fn(|i| (i * 37 + 5) as u8);
        assert_eq!(unhex(&hex(&bytes)), Some(bytes));
        assert_eq!(unhex("ab"), None);
        assert_eq!(unhex(&"G".repeat(64)), None);
    }
}
