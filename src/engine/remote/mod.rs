//! A shared remote cache: the store's entries and blobs on a shared folder (`file://`) or in an
//! S3 bucket (`s3://`, cargo feature `s3`), looked up after the local store and pushed to after
//! each local commit.
//!
//! Files of this folder:
//!
//! - `backend.rs`: What a remote must do
//! - `cache.rs`: The remote cache on top of a backend
//! - `file.rs`: The `file://` remote
//! - `push.rs`: The pusher: uploads committed entries with bounded concurrency
//! - `s3.rs`: The `s3://bucket/prefix` remote
//! - `settings.rs`: `[remote]` in `pipeline.toml`
//! - `sync.rs`: `groove push` and `groove pull`
//!
//! [`backend`] is what a remote must do (get, exists, create-if-absent; never list), [`file`](mod@file)
//! and `s3` are the two backends, [`cache`] does lookups with sha256 verification and the
//! counts, [`push`] uploads with bounded concurrency (blobs first, entry last), [`sync`] is
//! `groove push` / `groove pull`.
//!
//! # In use
//!
//! The store is an action cache (an entry per stage key) plus content-addressed blobs, and a remote
//! holds the same two things in the same layout (`entries/<key>.json`, `objects/ab/cdef…`), in a
//! folder on a shared filesystem or in an S3 bucket:
//!
//! ```toml
//! [remote]
//! url = "file:///shared/groove-cache"   # or "s3://bucket/prefix"; a relative file:// path is relative to pipeline.toml
//! read_only = false                     # true: look up, never upload (untrusted clones, CI that should not write)
//! required = false                      # true: a remote error is exit 2 instead of a warning
//! jobs = 8                              # concurrent uploads
//! ```
//!
//! `--remote URL` replaces the url, `--no-remote` ignores every remote, `--remote-read-only` and
//! `--remote-required` set the modes; the environment has `GROOVE_REMOTE` (a URL) and
//! `GROOVE_REMOTE_READ_ONLY=1`. Precedence: flag, then environment, then `pipeline.toml`.
//!
//! - **Lookup**: local store, then the remote entry by key (one GET), then each blob the local store
//!   lacks (one GET each), every blob checked against its sha256 before anything is written; only then
//!   is the entry committed locally (blobs first, entry by one rename, as for a local run). A missing,
//!   corrupt or unreadable remote object is a miss: the stage runs here, exit 0. groove never lists
//!   a remote, so a bucket of millions of objects costs what an empty one does.
//! - **Push**: after each local commit, in the background with bounded concurrency: one HEAD of the
//!   entry (present: nothing more, so a re-push uploads no body); else for each blob a HEAD and, if
//!   absent, a create-if-absent PUT; the entry is put (create-if-absent) only after all its blobs
//!   are there, so a killed push leaves at most orphan blobs, never an entry without its blobs. Two
//!   machines pushing the same keys both succeed. A blob found corrupt during a lookup is re-uploaded
//!   by the push that follows the local rerun.
//! - `groove push` uploads every result `pipeline.lock` names; `groove pull` fills the local store with
//!   every result the pipeline can reuse (it walks the DAG like `status`, runs nothing).
//! - An unreachable remote or refused credentials give **one** warning naming what to set, and the run
//!   goes on with the local store (exit 2 instead with `--remote-required`). `groove run`, `push` and
//!   `pull` end with a line counting the remote's hits, misses and errors, entries and blobs pushed,
//!   and the GET / HEAD / PUT requests and bytes: `groove: remote file:///… : 9 hits, 0 misses, 0
//!   errors; pushed 0 entries, 0 blobs; 203 GET, 0 HEAD, 0 PUT, 0 LIST; 2.7 MiB down, 0 B up`.
//!
//! **`file://`** needs nothing: create-if-absent is a temp file hard-linked to its name (`link(2)` fails
//! if the name exists), so a reader sees a whole object or none.
//!
//! **`s3://bucket/prefix`** needs the cargo feature `s3`: `cargo build --release --features s3`. It is
//! a feature so that the README's first command does not get slower to build: the S3 client is
//! rusty-s3 (signs requests, no I/O of its own) with ureq (a small blocking HTTP client, rustls) —
//! no async runtime (its cold-build cost is in `tests/bench/ENGINE.md`). Configuration is the usual environment only:
//! `AWS_ACCESS_KEY_ID`, `AWS_SECRET_ACCESS_KEY`, `AWS_SESSION_TOKEN`, `AWS_REGION` (or
//! `AWS_DEFAULT_REGION`; default `us-east-1`) and, for a non-AWS server (MinIO, Ceph, moto),
//! `AWS_ENDPOINT_URL` (or `AWS_ENDPOINT`; path-style URLs, `http://` allowed). `~/.aws/credentials`
//! and `AWS_PROFILE` are not read. Without credentials requests are unsigned (an anonymous, read-only
//! cache of a public bucket: use `--remote-read-only`). Create-if-absent is `PUT` with
//! `If-None-Match: *`. Grant `s3:GetObject`, `s3:PutObject` and `s3:ListBucket` on the bucket:
//! without `ListBucket` S3 answers a miss with 403 instead of 404 (groove still never lists).
//!
//! # Tests and CI
//!
//! `tests/remote.rs` (file:// remotes, in `cargo test`) and, opt-in (`#[ignore]`d), the S3 and
//! shipped-analysis tests in it and every test in `tests/slurm.rs`. `.ci/run` runs them all:
//! `tests/infra/slurm.sh start|stop DIR` installs Debian's `slurm-wlm` and `munge` when absent and
//! runs a one-node cluster as root (no systemd needed); `tests/infra/moto.sh start|stop DIR PORT
//! BUCKET` installs `moto[server]` into a venv and runs a local S3 server on 127.0.0.1,
//! moto accepting any credentials (its optional IAM check reads only the `Authorization` header,
//! not the presigned signatures groove sends, so refused credentials are not exercised there; an
//! unreachable endpoint is); both are stopped by PID. To run them by hand:
//!
//! ```text
//! bash tests/infra/slurm.sh start /tmp/slurm && export SLURM_CONF=/tmp/slurm/slurm.conf
//! bash tests/infra/moto.sh start /tmp/moto 9199 groove-ci && source /tmp/moto/env
//! GROOVE_TEST_S3_BUCKET=groove-ci GROOVE_TEST_MOTO_LOG=/tmp/moto/moto.log \
//!   cargo test --features s3 --test remote --test slurm -- --include-ignored --test-threads=1 --nocapture
//! ```
//!
//! `.ci/run` runs the README's test command, `cargo test --locked --features s3` (one build with the
//! S3 client, so the opt-in suites need no second build), then the opt-in suites with the services up.

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
    /// `[remote] shared = "group"`: a `file://` remote's folders are made group-writable and
    /// setgid, its files group-readable and -writable, whatever the umask (also when its root
    /// folder is setgid).
    pub shared_group: bool,
}

/// The default number of concurrent uploads.
pub const DEFAULT_JOBS: usize = 8;

/// Open the remote a URL names; relative `file://` paths resolve against `base`.
pub fn open(settings: &Settings, base: &Path) -> Result<RemoteCache, EngineError> {
    let mode = Mode {
        read_only: settings.read_only,
        required: settings.required,
    };
    let backend = match settings.url.starts_with("file://") {
        true => Box::new(file_remote(&settings.url, base)?.shared(settings.shared_group)),
        false => backend_for(&settings.url, base)?,
    };
    Ok(RemoteCache::new(backend, mode))
}

/// The backend of a URL.
pub fn backend_for(url: &str, base: &Path) -> Result<Box<dyn backend::Backend>, EngineError> {
    if url.starts_with("file://") {
        return Ok(Box::new(file_remote(url, base)?));
    }
    if let Some(rest) = url.strip_prefix("s3://") {
        return s3_backend(url, rest);
    }
    Err(EngineError::Usage(format!(
        "remote `{url}` is not a remote URL; write file:///shared/path or s3://bucket/prefix"
    )))
}

/// The folder a `file://` URL names, refused inside the project.
fn file_remote(url: &str, base: &Path) -> Result<file::FileRemote, EngineError> {
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
        return Ok(file::FileRemote::new(&root));
    }
    Err(EngineError::Usage(format!(
        "remote `{url}` is not a file:// URL"
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
