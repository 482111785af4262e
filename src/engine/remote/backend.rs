//! What a remote must do: get an object by name, tell whether one exists, create one if absent.
//!
//! There is deliberately no way to list: every lookup is by a name derived from a key or a
//! sha256, so a remote with millions of objects costs the same as an empty one.

use std::sync::atomic::{AtomicU64, Ordering};

/// Why a remote request failed. `Unavailable` (unreachable, refused credentials) turns the
/// remote off for the rest of the run after one warning; `Other` is one failed request.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RemoteError {
    Unavailable(String),
    Other(String),
}

impl std::fmt::Display for RemoteError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RemoteError::Unavailable(m) | RemoteError::Other(m) => f.write_str(m),
        }
    }
}

/// One object store: names are `/`-separated paths below the remote's root.
pub trait Backend: Send + Sync {
    /// The remote as the user wrote it (for messages).
    fn describe(&self) -> String;
    /// The object's bytes, `None` when absent.
    fn get(&self, name: &str) -> Result<Option<Vec<u8>>, RemoteError>;
    /// Whether the object exists, without transferring its body.
    fn exists(&self, name: &str) -> Result<bool, RemoteError>;
    /// Create the object unless it exists, atomically (readers see all of it or nothing).
    /// `Ok(true)` when this call created it, `Ok(false)` when it was already there.
    fn put_if_absent(&self, name: &str, bytes: &[u8]) -> Result<bool, RemoteError>;
    /// Replace an object (only used to repair a blob found corrupt: its name is its sha256, so
    /// every writer writes the same bytes).
    fn put_overwrite(&self, name: &str, bytes: &[u8]) -> Result<(), RemoteError>;
    /// What to set when requests are refused or the remote cannot be reached.
    fn hint(&self) -> String;
    /// Whether the remote is there at all, without a request where that costs one (a bucket
    /// that is missing shows at its first request instead).
    fn check_present(&self) -> Result<(), RemoteError> {
        Ok(())
    }
}

/// Request and byte counts of one run, for the closing line and the benchmark.
#[derive(Debug, Default)]
pub struct Counters {
    pub gets: AtomicU64,
    pub heads: AtomicU64,
    pub puts: AtomicU64,
    pub bytes_down: AtomicU64,
    pub bytes_up: AtomicU64,
}

/// A snapshot of [`Counters`].
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Requests {
    pub gets: u64,
    pub heads: u64,
    pub puts: u64,
    /// Always 0: no backend can list.
    pub lists: u64,
    pub bytes_down: u64,
    pub bytes_up: u64,
}

impl Counters {
    pub fn snapshot(&self) -> Requests {
        Requests {
            gets: self.gets.load(Ordering::Relaxed),
            heads: self.heads.load(Ordering::Relaxed),
            puts: self.puts.load(Ordering::Relaxed),
            lists: 0,
            bytes_down: self.bytes_down.load(Ordering::Relaxed),
            bytes_up: self.bytes_up.load(Ordering::Relaxed),
        }
    }
}

/// A backend that counts what it is asked to do.
pub struct Counted<B: ?Sized> {
    pub counters: Counters,
    pub inner: Box<B>,
}

impl Counted<dyn Backend> {
    pub fn new(inner: Box<dyn Backend>) -> Self {
        Counted {
            counters: Counters::default(),
            inner,
        }
    }

    pub fn get(&self, name: &str) -> Result<Option<Vec<u8>>, RemoteError> {
        self.counters.gets.fetch_add(1, Ordering::Relaxed);
        let got = self.inner.get(name)?;
        if let Some(b) = &got {
            self.counters
                .bytes_down
                .fetch_add(b.len() as u64, Ordering::Relaxed);
        }
        Ok(got)
    }

    pub fn exists(&self, name: &str) -> Result<bool, RemoteError> {
        self.counters.heads.fetch_add(1, Ordering::Relaxed);
        self.inner.exists(name)
    }

    pub fn put_if_absent(&self, name: &str, bytes: &[u8]) -> Result<bool, RemoteError> {
        self.counters.puts.fetch_add(1, Ordering::Relaxed);
        self.counters
            .bytes_up
            .fetch_add(bytes.len() as u64, Ordering::Relaxed);
        self.inner.put_if_absent(name, bytes)
    }

    pub fn put_overwrite(&self, name: &str, bytes: &[u8]) -> Result<(), RemoteError> {
        self.counters.puts.fetch_add(1, Ordering::Relaxed);
        self.counters
            .bytes_up
            .fetch_add(bytes.len() as u64, Ordering::Relaxed);
        self.inner.put_overwrite(name, bytes)
    }
}

/// The name of a key's entry on a remote (the local store's layout).
pub fn entry_name(key: &str) -> String {
    format!("entries/{key}.json")
}

/// The name of a blob on a remote (the local store's layout).
pub fn blob_name(sha256: &str) -> String {
    format!("objects/{}/{}", &sha256[..2], &sha256[2..])
}
