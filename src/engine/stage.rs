//! The contract between the engine and a stage kind: typed params in, artifacts (bytes) out.
//!
//! A stage is a pure function of its params and input artifacts. It never touches the file
//! system: the engine reads inputs into memory (or, for an input the kind streams, hands it a
//! reader that checks the content against the key), calls `run`, checks every declared output is
//! present, and writes the outputs into the store atomically.

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::PathBuf;

/// One artifact: a single file's bytes, or a collection of named items (e.g. one per run).
/// Collection item names are file-name safe (`[A-Za-z0-9._-]`), and iterate in sorted order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Artifact {
    File(Vec<u8>),
    Collection(BTreeMap<String, Vec<u8>>),
    /// A collection whose items the stage already put in the store (`StageInput::put_item`) as
    /// it made them, so that they were never all held at once: item → sha256. Only ever an
    /// output; a stage reading it as an input gets a `Collection`.
    InStore(BTreeMap<String, String>),
    /// A path input left on disk, for a kind that reads it in pieces (`StageKind::streamed_inputs`):
    /// file name → the file, with the sha256 its key was made from or, on the first run over it,
    /// where to record the digest of what was read (a single-file input is one entry). Reading
    /// it checks the content (`InputFile`). Only ever an input.
    OnDisk(BTreeMap<String, InputFile>),
}

/// What a stage says when an input came as `Artifact::InStore` (never an input) or as
/// `Artifact::OnDisk` (given only to a kind that asks for it).
pub const IN_STORE_INPUT: &str =
    "an input came as stored items or as files left on disk, which the engine never passes to this kind (a bug in groove, please report it)";

/// One file of a path input that a kind reads itself (`StageKind::streamed_inputs`). Whichever
/// way it is read, the bytes are checked: against the sha256 its key was made from; or, when the
/// engine's file-hash cache holds that sha256 under the file's stat (size, mtime, inode: the
/// stamp a no-op already trusts), by that stat at the open and the same stat and change time at
/// the end, without hashing again; or, for a file the engine has not hashed yet (the first run
/// over it), by recording the digest of what was read, from which the engine then makes the key
/// (`engine::hash_on_read`). A file edited while groove runs is an error, never a result under
/// the wrong key.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputFile {
    pub path: PathBuf,
    check: Check,
}

#[derive(Debug, Clone, PartialEq, Eq)]
enum Check {
    /// Hashed as read, the digest settled at the end.
    Hashed(Expect),
    /// The engine's file-hash cache holds the sha256 the key was made from under this stat: the
    /// file must have it when opened and keep it (and its change time) to the end of the read.
    Vouched(FileStamp),
}

/// What a hashed read's digest must be.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Expect {
    /// This sha256.
    Sha256(String),
    /// Anything (not hashed yet): each read to the end adds its digest here.
    Record(Seen),
}

impl Expect {
    /// Settle a read that reached the end with `digest`: whether it is the content expected (a
    /// file not hashed yet records it and is always so).
    fn settle(&self, digest: String) -> bool {
        match self {
            Expect::Sha256(sha256) => digest == *sha256,
            Expect::Record(seen) => {
                seen.push(digest);
                true
            }
        }
    }
}

/// The digests of every read of an `InputFile` that reached the end of the file, shared with
/// the engine (two different ones mean the file changed between reads).
#[derive(Debug, Clone, Default)]
pub struct Seen(std::sync::Arc<std::sync::Mutex<Vec<String>>>);

impl PartialEq for Seen {
    fn eq(&self, other: &Self) -> bool {
        std::sync::Arc::ptr_eq(&self.0, &other.0)
    }
}
impl Eq for Seen {}

impl Seen {
    /// The digests recorded so far, in the order the reads ended.
    pub fn digests(&self) -> Vec<String> {
        self.0.lock().map(|d| d.clone()).unwrap_or_default()
    }
    fn push(&self, digest: String) {
        if let Ok(mut d) = self.0.lock() {
            d.push(digest);
        }
    }
}

impl InputFile {
    /// A file whose content must have `sha256`.
    pub fn checked(path: PathBuf, sha256: String) -> InputFile {
        InputFile {
            path,
            check: Check::Hashed(Expect::Sha256(sha256)),
        }
    }

    /// A file whose content the engine's file-hash cache vouches for as long as it has `stamp`
    /// (the key was made from the sha256 the cache holds under that stat).
    pub fn vouched(path: PathBuf, stamp: FileStamp) -> InputFile {
        InputFile {
            path,
            check: Check::Vouched(stamp),
        }
    }

    /// A file not hashed yet: every read of it to the end records its digest in `seen`.
    pub fn recorded(path: PathBuf, seen: Seen) -> InputFile {
        InputFile {
            path,
            check: Check::Hashed(Expect::Record(seen)),
        }
    }

    /// The whole file, checked.
    pub fn read(&self) -> Result<Vec<u8>, StageError> {
        use std::io::Read;
        let mut reader = self.open()?;
        // the whole file at once, as `std::fs::read` would (growing by doubling could hold twice it)
        let size = reader.file.metadata().map_or(0, |m| m.len());
        let mut bytes = Vec::with_capacity(usize::try_from(size).unwrap_or(0));
        reader.read_to_end(&mut bytes).map_err(|e| match e.kind() {
            std::io::ErrorKind::InvalidData => StageError(self.changed()),
            _ => self.unreadable(e),
        })?;
        Ok(bytes)
    }

    /// The file as a reader that checks what it gives and, at the end of the file, fails with an
    /// error (kind `InvalidData`) if the content is not the one the key was made from (hashed as
    /// read, or its stat unchanged for a vouched file; a file not hashed yet records the
    /// digest). A caller that stops early has checked nothing, and must not keep what it read.
    pub fn open(&self) -> Result<CheckedRead, StageError> {
        let file = std::fs::File::open(&self.path).map_err(|e| self.unreadable(e))?;
        let state = match &self.check {
            Check::Vouched(stamp) => {
                let meta = file.metadata().map_err(|e| self.unreadable(e))?;
                if FileStamp::of(&meta) != *stamp {
                    return Err(StageError(self.changed()));
                }
                Reading::Stat(meta)
            }
            Check::Hashed(expect) => Reading::Hashing(Sha256::new(), expect.clone()),
        };
        Ok(CheckedRead {
            file,
            state,
            changed: self.changed(),
        })
    }

    fn unreadable(&self, e: std::io::Error) -> StageError {
        StageError(format!(
            "{} cannot be read ({e}); check that it exists and is readable",
            self.path.display()
        ))
    }

    fn changed(&self) -> String {
        format!(
            "{} changed while groove was running; run again",
            self.path.display()
        )
    }
}

/// `InputFile::open`'s reader.
pub struct CheckedRead {
    file: std::fs::File,
    state: Reading,
    changed: String,
}

/// Where a `CheckedRead` is.
enum Reading {
    /// Hashing what it gives, to check or record at the end.
    Hashing(Sha256, Expect),
    /// A vouched file: its stat when opened, to compare at the end.
    Stat(std::fs::Metadata),
    /// The end was reached and the content checked.
    Done,
}

impl CheckedRead {
    /// The file's length now.
    pub fn file_len(&self) -> std::io::Result<u64> {
        Ok(self.file.metadata()?.len())
    }

    /// `buf.len()` bytes from `offset`, read apart from the pass in order (which this does not
    /// move). Unchecked: a caller keeps what it reads here only if the same bytes come by in
    /// the checked pass too (a Parquet reader's footer, read first to plan the pass).
    pub fn read_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        use std::os::unix::fs::FileExt;
        self.file.read_exact_at(buf, offset)
    }
}

impl std::io::Read for CheckedRead {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0); // not the end of the file: nothing to check yet
        }
        let n = std::io::Read::read(&mut self.file, buf)?;
        let same = match (n, std::mem::replace(&mut self.state, Reading::Done)) {
            (0, Reading::Hashing(hasher, expect)) => {
                expect.settle(hex_digest(hasher.finalize().as_slice()))
            }
            (0, Reading::Stat(at_open)) => {
                let now = self.file.metadata()?;
                FileStamp::of(&now) == FileStamp::of(&at_open)
            }
            (_, Reading::Hashing(mut hasher, expect)) => {
                hasher.update(&buf[..n]);
                self.state = Reading::Hashing(hasher, expect);
                true
            }
            (_, state) => {
                self.state = state;
                true
            }
        };
        if !same {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                self.changed.clone(),
            ));
        }
        Ok(n)
    }
}

/// What says a file is unchanged without reading it: its size, mtime, inode and status-change
/// time (the engine's file-hash cache keys its digests by them). The change time is there
/// because a write moves it even when the mtime is set back (`rsync --inplace --times`,
/// `touch -r`), as git's index trusts it; a `chmod` or a new hard link moves it too, which costs
/// a rehash, never a rerun.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileStamp {
    pub size: u64,
    pub mtime_ns: i128,
    pub inode: u64,
    pub ctime_ns: i128,
}

impl FileStamp {
    #[cfg(unix)]
    pub fn of(meta: &std::fs::Metadata) -> FileStamp {
        use std::os::unix::fs::MetadataExt;
        FileStamp {
            size: meta.size(),
            mtime_ns: i128::from(meta.mtime()) * 1_000_000_000 + i128::from(meta.mtime_nsec()),
            inode: meta.ino(),
            ctime_ns: i128::from(meta.ctime()) * 1_000_000_000 + i128::from(meta.ctime_nsec()),
        }
    }

    #[cfg(not(unix))]
    pub fn of(meta: &std::fs::Metadata) -> FileStamp {
        let mtime_ns = meta
            .modified()
            .ok()
            .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
            .map(|d| d.as_nanos() as i128)
            .unwrap_or(0);
        FileStamp {
            size: meta.len(),
            mtime_ns,
            inode: 0,
            ctime_ns: 0,
        }
    }
}

/// Lowercase hex of a digest (as `engine::hashing` writes hashes; repeated here so that the
/// contract stays one file kinds may use).
fn hex_digest(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// What a stage receives.
pub struct StageInput<'a> {
    /// The stage's params, already checked by `StageKind::canonical_params`.
    pub params: &'a toml::Table,
    /// Input artifacts by the input names the kind declares. For a per-item stage each
    /// `foreach` input holds only the current item, as `Artifact::File`.
    pub inputs: BTreeMap<&'a str, &'a Artifact>,
    /// For a per-item stage: the current item's name.
    pub item: Option<&'a str>,
    /// The pipeline seed (from `pipeline.toml`), mixed with the stage name by the engine.
    pub seed: u64,
    /// Where a long stage says what it is doing (the engine's progress line); `None` when nobody
    /// listens (tests, a Slurm job step).
    pub progress: Option<&'a (dyn Fn(&str) + Sync)>,
    /// Puts one item's bytes in the store now and gives its sha256, for a stage that makes many
    /// items and need not hold them all (it returns them as `Artifact::InStore`); `None` when
    /// there is no store (tests): the stage then returns a `Collection`.
    pub put_item: Option<&'a (dyn Fn(&[u8]) -> Result<String, StageError> + Sync)>,
    /// The objects an earlier run of this stage (same kind, code, version and params) made from
    /// the same bytes, for a stage that reads one big input and would rather not make again
    /// what its unchanged parts made; `None` without a store.
    pub memo: Option<&'a dyn ObjectMemo>,
}

/// A stage's memo of the objects it made, by a key the kind computes from everything an object
/// is made of (a cryptographic digest of the bytes read and whatever else went in). What the
/// kind puts is kept for the next run of the stage; a key found gives its object's sha256 only
/// while the store holds the object. Never needed for a correct result: a miss is made again.
pub trait ObjectMemo: Sync {
    fn get(&self, key: &[u8; 32]) -> Option<String>;
    fn put(&self, key: [u8; 32], sha256: &str);
    /// The bytes of an object `get` gave, checked against its name; `None` if it is gone or
    /// damaged (then it is made again).
    fn read(&self, sha256: &str) -> Option<Vec<u8>>;
}

impl StageInput<'_> {
    /// Tell the progress line what the stage is doing now. Never part of an output.
    pub fn report(&self, what: &str) {
        if let Some(p) = self.progress {
            p(what);
        }
    }
}

/// What a stage returns: artifacts by output name. Every declared output must be present.
pub type StageOutputs = BTreeMap<String, Artifact>;

/// A failure of a stage on its inputs (bad data, a numerical breakdown). Lowercase, says how to fix.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct StageError(pub String);

/// An invalid params table: which key, what is wrong, how to fix.
#[derive(Debug, thiserror::Error)]
#[error("param `{key}`: {message}")]
pub struct ParamError {
    pub key: String,
    pub message: String,
}

/// A built-in kind of stage.
pub trait StageKind: Sync + Send {
    /// The `kind = "..."` name in `pipeline.toml`.
    fn kind(&self) -> &'static str;
    /// Input names this kind needs (each bound in `pipeline.toml`), and those it may take.
    fn inputs(&self) -> &'static [&'static str];
    fn optional_inputs(&self) -> &'static [&'static str] {
        &[]
    }
    /// Path inputs this kind reads from disk itself, in pieces, so that a file larger than memory
    /// is never held whole: the engine gives them as `Artifact::OnDisk`.
    fn streamed_inputs(&self) -> &'static [&'static str] {
        &[]
    }
    /// Output names this kind produces.
    fn outputs(&self) -> &'static [&'static str];
    /// Validate the params (unknown key, wrong type, out of range) and return them with every
    /// default filled in, as the canonical JSON value that goes into the cache key.
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError>;
    /// Run the stage.
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError>;
}

/// Deserialize a params table into a typed struct (use `#[serde(deny_unknown_fields, default)]`),
/// returning it and its canonical JSON form. Shared by every built-in kind.
///
/// The error names the offending key: the one named by serde (unknown field), or else the one
/// whose removal makes the table valid (a mistyped value).
pub fn typed_params<P>(params: &toml::Table) -> Result<(P, serde_json::Value), ParamError>
where
    P: serde::de::DeserializeOwned + serde::Serialize,
{
    let parse = |t: &toml::Table| -> Result<P, toml::de::Error> {
        toml::Value::Table(t.clone()).try_into()
    };
    let typed: P = parse(params).map_err(|e| {
        let named = e
            .message()
            .split('`')
            .nth(1)
            .filter(|k| params.contains_key(*k));
        let culprit = named.map(str::to_string).or_else(|| {
            params
                .keys()
                .find(|k| {
                    let mut without = params.clone();
                    without.remove(*k);
                    parse(&without).is_ok()
                })
                .cloned()
        });
        ParamError {
            key: culprit.unwrap_or_else(|| "params".to_string()),
            message: e.message().trim().to_string(),
        }
    })?;
    let json = serde_json::to_value(&typed).map_err(|e| ParamError {
        key: "params".into(),
        message: e.to_string(),
    })?;
    Ok((typed, json))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    #[test]
    fn a_vouched_file_is_read_unhashed_and_a_write_during_the_read_is_a_change() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("t.csv");
        let content = vec![b'7'; 64 * 1024];
        std::fs::write(&path, &content).unwrap();
        let stamp = FileStamp::of(&std::fs::metadata(&path).unwrap());
        let file = InputFile::vouched(path.clone(), stamp);
        assert_eq!(file.read().unwrap(), content);
        let mut whole = Vec::new();
        let mut reader = file.open().unwrap();
        // an empty buffer is not the end of the file: the check still waits for it
        assert_eq!(reader.read(&mut []).unwrap(), 0);
        assert!(matches!(reader.state, Reading::Stat(_)));
        reader.read_to_end(&mut whole).unwrap();
        assert!(matches!(reader.state, Reading::Done));
        assert_eq!(whole, content);
        // rewritten while read, same size, its mtime set back: the change time still moves
        let mut reader = file.open().unwrap();
        let mut head = [0u8; 1024];
        reader.read_exact(&mut head).unwrap();
        let mtime = std::fs::metadata(&path).unwrap().modified().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        std::fs::write(&path, vec![b'8'; 64 * 1024]).unwrap();
        std::fs::File::options()
            .write(true)
            .open(&path)
            .unwrap()
            .set_modified(mtime)
            .unwrap();
        let err = reader.read_to_end(&mut Vec::new()).unwrap_err();
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidData);
        assert!(err.to_string().contains("changed while groove was running"));
        // size, mtime and inode as vouched for; the change time tells the write: an error at
        // the open
        let now = FileStamp::of(&std::fs::metadata(&path).unwrap());
        assert_ne!(now.ctime_ns, stamp.ctime_ns);
        assert_eq!(
            FileStamp {
                ctime_ns: stamp.ctime_ns,
                ..now
            },
            stamp
        );
        let err = file.read().unwrap_err().to_string();
        assert!(err.contains("changed while groove was running"), "{err}");
        let moved = InputFile::vouched(
            path.clone(),
            FileStamp {
                mtime_ns: now.mtime_ns + 1,
                ..now
            },
        );
        let err = moved.read().unwrap_err().to_string();
        assert!(err.contains("changed while groove was running"), "{err}");
    }
}
