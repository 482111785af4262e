//! The remote cache on top of a backend: look an entry up, fetch and verify its blobs, commit it
//! locally; count hits, misses and errors; warn once when the remote is unusable.
//!
//! Lookup order: the caller has already missed the local store. Then the remote entry by key
//! (one GET), then each blob the local store lacks (one GET each), each verified by sha256
//! before anything is written locally. A missing, corrupt or unparsable object is a miss (the
//! stage reruns), never a failure. Only after every blob is in the local store is the entry
//! committed locally (one rename), so a kill leaves no half entry.

use super::backend::{blob_name, entry_name, Backend, Counted, RemoteError, Requests};
use crate::engine::hashing::is_sha256;
use crate::engine::hashing::sha256_hex;
use crate::engine::store::{Entry, Store, Stored};
use std::collections::BTreeSet;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Mutex;

/// How a remote is used in one run.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mode {
    /// Never write to the remote (untrusted clones, CI that should only read).
    pub read_only: bool,
    /// Any remote error fails the run (exit 2) instead of a warning.
    pub required: bool,
}

/// Outcome counts of one run.
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Tally {
    pub hits: u64,
    pub misses: u64,
    pub errors: u64,
    /// Entries this run created on the remote.
    pub pushed: u64,
    /// Blob bodies this run uploaded.
    pub blobs_uploaded: u64,
    pub requests: Requests,
}

pub struct RemoteCache {
    pub(crate) backend: Counted<dyn Backend>,
    pub mode: Mode,
    hits: AtomicU64,
    misses: AtomicU64,
    pub(crate) errors: AtomicU64,
    pub(crate) pushed: AtomicU64,
    pub(crate) blobs_uploaded: AtomicU64,
    /// Set after an `Unavailable` error: no more requests this run.
    disabled: AtomicBool,
    warned: AtomicBool,
    first_error: Mutex<Option<String>>,
    /// Blobs found missing or corrupt on the remote: a later push of their key re-uploads them.
    pub(crate) repair: Mutex<BTreeSet<String>>,
    warn: Box<dyn Fn(&str) + Send + Sync>,
}

impl RemoteCache {
    pub fn new(backend: Box<dyn Backend>, mode: Mode) -> RemoteCache {
        RemoteCache {
            backend: Counted::new(backend),
            mode,
            hits: AtomicU64::new(0),
            misses: AtomicU64::new(0),
            errors: AtomicU64::new(0),
            pushed: AtomicU64::new(0),
            blobs_uploaded: AtomicU64::new(0),
            disabled: AtomicBool::new(false),
            warned: AtomicBool::new(false),
            first_error: Mutex::new(None),
            repair: Mutex::new(BTreeSet::new()),
            warn: Box::new(|m| eprintln!("groove: warning: {m}")),
        }
    }

    /// Send the one warning somewhere else than stderr (tests, progress display).
    pub fn with_warn(mut self, warn: impl Fn(&str) + Send + Sync + 'static) -> RemoteCache {
        self.warn = Box::new(warn);
        self
    }

    pub fn describe(&self) -> String {
        self.backend.inner.describe()
    }

    /// What to set when the remote cannot be reached or refuses requests.
    pub fn hint(&self) -> String {
        self.backend.inner.hint()
    }

    /// Whether the remote is there at all (a `file://` folder that does not exist is not):
    /// `Err` is the reason, for the verbs whose whole work is the remote.
    pub fn check_present(&self) -> Result<(), String> {
        self.backend
            .inner
            .check_present()
            .map_err(|e| e.to_string())
    }

    pub fn is_disabled(&self) -> bool {
        self.disabled.load(Ordering::Relaxed)
    }

    /// Count a failed request; the first one is warned about, naming what to set.
    pub(crate) fn failed(&self, e: &RemoteError) {
        self.errors.fetch_add(1, Ordering::Relaxed);
        if matches!(e, RemoteError::Unavailable(_)) {
            self.disabled.store(true, Ordering::Relaxed);
        }
        {
            let mut first = self.first_error.lock().expect("remote error lock");
            if first.is_none() {
                *first = Some(e.to_string());
            }
        }
        if !self.warned.swap(true, Ordering::Relaxed) {
            let what = if matches!(e, RemoteError::Unavailable(_)) {
                format!(
                    "remote {} is unusable ({e}); {}; going on with the local store only",
                    self.describe(),
                    self.backend.inner.hint()
                )
            } else {
                format!(
                    "remote {}: {e}; going on (the stage runs locally)",
                    self.describe()
                )
            };
            (self.warn)(&what);
        }
    }

    /// The first error of the run, for `--remote-required`.
    pub fn first_error(&self) -> Option<String> {
        self.first_error.lock().expect("remote error lock").clone()
    }

    /// Look a key up on the remote; on a hit its blobs are verified and the entry committed to
    /// `store`. `None` is a miss (absent, incomplete, corrupt, or not of the shape `fits` wants:
    /// the stage's declared outputs) or an error (counted and warned).
    pub fn fetch(&self, store: &Store, key: &str, fits: &dyn Fn(&Entry) -> bool) -> Option<Entry> {
        if self.is_disabled() {
            return None;
        }
        match self.try_fetch(store, key, fits) {
            Ok(Some(entry)) => {
                self.hits.fetch_add(1, Ordering::Relaxed);
                Some(entry)
            }
            Ok(None) => {
                self.misses.fetch_add(1, Ordering::Relaxed);
                None
            }
            Err(e) => {
                self.failed(&e);
                None
            }
        }
    }

    fn try_fetch(
        &self,
        store: &Store,
        key: &str,
        fits: &dyn Fn(&Entry) -> bool,
    ) -> Result<Option<Entry>, RemoteError> {
        if !is_sha256(key) {
            return Ok(None);
        }
        let Some(bytes) = self.backend.get(&entry_name(key))? else {
            return Ok(None);
        };
        // parsing checks every hash and name (a crafted entry is a miss, never a path)
        let Ok(entry) = serde_json::from_slice::<Entry>(&bytes) else {
            return Ok(None);
        };
        if !fits(&entry) {
            return Ok(None);
        }
        let mut wanted = BTreeSet::new();
        for stored in entry.outputs.values() {
            match stored {
                Stored::File { sha256 } => {
                    wanted.insert(sha256.clone());
                }
                Stored::Collection { items } => wanted.extend(items.values().cloned()),
            }
        }
        for sha in &wanted {
            // a local copy counts only when sound: a damaged one is replaced by the remote's
            if store.read_object(sha).is_ok() {
                continue;
            }
            let Some(blob) = self.backend.get(&blob_name(sha))? else {
                self.repair.lock().expect("repair lock").insert(sha.clone());
                return Ok(None);
            };
            if sha256_hex(&blob) != *sha {
                self.repair.lock().expect("repair lock").insert(sha.clone());
                return Ok(None);
            }
            store
                .put_object(&blob)
                .map_err(|e| RemoteError::Other(format!("local store: {e}")))?;
        }
        let entry = store
            .commit(key, entry.outputs)
            .map_err(|e| RemoteError::Other(format!("local store: {e}")))?;
        Ok(Some(entry))
    }

    pub fn tally(&self) -> Tally {
        Tally {
            hits: self.hits.load(Ordering::Relaxed),
            misses: self.misses.load(Ordering::Relaxed),
            errors: self.errors.load(Ordering::Relaxed),
            pushed: self.pushed.load(Ordering::Relaxed),
            blobs_uploaded: self.blobs_uploaded.load(Ordering::Relaxed),
            requests: self.backend.counters.snapshot(),
        }
    }

    /// The closing line: `remote file:///x: 9 hits, 0 misses, 0 errors; …`.
    pub fn closing_line(&self) -> String {
        let t = self.tally();
        let r = t.requests;
        format!(
            "remote {}{}: {} hits, {} misses, {} errors; pushed {} entries, {} blobs; {} GET, {} HEAD, {} PUT, 0 LIST; {} down, {} up",
            self.describe(),
            if self.mode.read_only { " (read-only)" } else { "" },
            t.hits,
            t.misses,
            t.errors,
            t.pushed,
            t.blobs_uploaded,
            r.gets,
            r.heads,
            r.puts,
            human_bytes(r.bytes_down),
            human_bytes(r.bytes_up)
        )
    }
}

pub fn human_bytes(n: u64) -> String {
    match n {
        n if n >= 1 << 20 => format!("{:.1} MiB", n as f64 / (1u64 << 20) as f64),
        n if n >= 1 << 10 => format!("{:.1} KiB", n as f64 / 1024.0),
        n => format!("{n} B"),
    }
}
