//! A shared remote cache: the store's entries and blobs on a shared folder (`file://`) or in an
//! S3 bucket (`s3://`, cargo feature `s3`), looked up after the local store and pushed to after
//! each local commit.
//!
//! [`backend`] is what a remote must do (get, exists, create-if-absent; never list), [`file`]
//! and `s3` are the two backends, [`cache`] does lookups with sha256 verification and the
//! counts, [`push`] uploads with bounded concurrency (blobs first, entry last), [`sync`] is
//! `groove push` / `groove pull`.

pub mod backend;
pub mod cache;
pub mod file;
pub mod push;
#[cfg(feature = "s3")]
pub mod s3;
pub mod settings;
pub mod sync;

pub use cache::{Mode, RemoteCache, Tally};

use crate::engine::error::EngineError;
use std::path::Path;

/// The environment variable naming a remote (`file:///…` or `s3://bucket/prefix`).
pub const ENV_URL: &str = "GROOVE_REMOTE";
/// Set to `1` (or `true`) for read-only use of the remote.
pub const ENV_READ_ONLY: &str = "GROOVE_REMOTE_READ_ONLY";

/// Where the remote is and how it is used, from `[remote]`, the environment and the flags.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Settings {
    pub url: String,
    pub read_only: bool,
    pub required: bool,
    /// Concurrent uploads.
    pub jobs: usize,
}

/// The default number of concurrent uploads.
pub const DEFAULT_JOBS: usize = 8;

/// Open the remote a URL names; relative `file://` paths resolve against `base`.
pub fn open(settings: &Settings, base: &Path) -> Result<RemoteCache, EngineError> {
    let mode = Mode {
        read_only: settings.read_only,
        required: settings.required,
    };
    Ok(RemoteCache::new(backend_for(&settings.url, base)?, mode))
}

/// The backend of a URL.
pub fn backend_for(url: &str, base: &Path) -> Result<Box<dyn backend::Backend>, EngineError> {
    if let Some(path) = url.strip_prefix("file://") {
        if path.is_empty() {
            return Err(EngineError::Usage(format!(
                "remote `{url}` names no folder; write file:///absolute/path or file://relative/path"
            )));
        }
        let normalize = crate::engine::config::validate::normalize;
        let base = &normalize(&std::path::absolute(base).unwrap_or_else(|_| base.into()));
        let root = normalize(&base.join(path));
        if root.starts_with(base) {
            return Err(EngineError::Usage(format!(
                "remote `{url}` is {}, inside the project: a remote is a folder outside it that other clones share; write file:///shared/path or file://../shared-cache",
                match &root == base {
                    true => "the project folder itself".to_string(),
                    false => format!("{}", root.display()),
                }
            )));
        }
        return Ok(Box::new(file::FileRemote::new(&root)));
    }
    if let Some(rest) = url.strip_prefix("s3://") {
        return s3_backend(url, rest);
    }
    Err(EngineError::Usage(format!(
        "remote `{url}` is not a remote URL; write file:///shared/path or s3://bucket/prefix"
    )))
}

#[cfg(feature = "s3")]
fn s3_backend(url: &str, rest: &str) -> Result<Box<dyn backend::Backend>, EngineError> {
    Ok(Box::new(s3::S3Remote::from_env(url, rest)?))
}

#[cfg(not(feature = "s3"))]
fn s3_backend(url: &str, _rest: &str) -> Result<Box<dyn backend::Backend>, EngineError> {
    Err(EngineError::Usage(format!(
        "remote `{url}`: this groove was built without S3 support; build it with `cargo build --release --features s3`, or use a file:// remote"
    )))
}

/// A key's entry: from the local store, else from the remote (verified and committed locally).
/// Either counts only when `fits` (the stage's declared outputs): any other is damage, a miss.
pub fn lookup(
    store: &crate::engine::store::Store,
    hashes: &crate::engine::hashing::HashCache,
    remote: Option<&RemoteCache>,
    key: &str,
    fits: &dyn Fn(&crate::engine::store::Entry) -> bool,
) -> Option<crate::engine::store::Entry> {
    // a local entry counts only with every object sound; a fetched one is checked the same way
    // (a damaged local object the fetch did not replace makes it a miss: the stage reruns)
    store
        .entry_checked(key, hashes)
        .filter(|e| fits(e))
        .or_else(|| {
            remote
                .and_then(|r| r.fetch(store, key, fits))
                .and_then(|_| store.entry_checked(key, hashes))
                .filter(|e| fits(e))
        })
}
