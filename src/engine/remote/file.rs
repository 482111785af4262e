//! The `file://` remote: a folder on a shared filesystem, laid out like the local store.
//!
//! Create-if-absent is a hard link of a fully written temp file to the final name: `link(2)`
//! fails with `EEXIST` when the name exists, and the name appears complete or not at all, so
//! a killed writer leaves at most a stray temp file (under `tmp/`, never read).

use super::backend::{Backend, RemoteError};
use crate::engine::atomic::unique_name;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};

pub struct FileRemote {
    pub root: PathBuf,
}

impl FileRemote {
    pub fn new(root: &Path) -> FileRemote {
        FileRemote {
            root: root.to_path_buf(),
        }
    }

    fn path(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }

    /// Write `bytes` to a private temp file under `tmp/` on the same filesystem.
    fn stage(&self, bytes: &[u8]) -> Result<PathBuf, RemoteError> {
        let tmp = self.root.join("tmp");
        std::fs::create_dir_all(&tmp).map_err(|e| self.io_error(&tmp, e))?;
        let staged = tmp.join(unique_name(&format!("put-{}", host_tag())));
        std::fs::write(&staged, bytes).map_err(|e| self.io_error(&staged, e))?;
        Ok(staged)
    }

    fn io_error(&self, path: &Path, e: std::io::Error) -> RemoteError {
        let m = format!("{}: {e}", path.display());
        match e.kind() {
            ErrorKind::PermissionDenied | ErrorKind::ReadOnlyFilesystem => {
                RemoteError::Unavailable(m)
            }
            ErrorKind::NotFound if !self.root.exists() => RemoteError::Unavailable(m),
            _ => RemoteError::Other(m),
        }
    }

    fn parent_of(&self, path: &Path) -> Result<(), RemoteError> {
        let parent = path.parent().expect("remote names have a parent");
        std::fs::create_dir_all(parent).map_err(|e| self.io_error(parent, e))
    }
}

/// Temp names must not collide between machines sharing the folder: pid + counter + host.
fn host_tag() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .map(|h| h.trim().to_string())
        .unwrap_or_default()
}

impl Backend for FileRemote {
    fn describe(&self) -> String {
        format!("file://{}", self.root.display())
    }

    fn get(&self, name: &str) -> Result<Option<Vec<u8>>, RemoteError> {
        if !self.root.is_dir() {
            return Err(RemoteError::Unavailable(format!(
                "{} is not a folder",
                self.root.display()
            )));
        }
        let path = self.path(name);
        match std::fs::read(&path) {
            Ok(b) => Ok(Some(b)),
            Err(e) if e.kind() == ErrorKind::NotFound => Ok(None),
            Err(e) => Err(self.io_error(&path, e)),
        }
    }

    fn exists(&self, name: &str) -> Result<bool, RemoteError> {
        if !self.root.is_dir() {
            return Err(RemoteError::Unavailable(format!(
                "{} is not a folder",
                self.root.display()
            )));
        }
        Ok(self.path(name).exists())
    }

    fn put_if_absent(&self, name: &str, bytes: &[u8]) -> Result<bool, RemoteError> {
        let path = self.path(name);
        let staged = self.stage(bytes)?;
        let linked =
            self.parent_of(&path)
                .and_then(|()| match std::fs::hard_link(&staged, &path) {
                    Ok(()) => Ok(true),
                    Err(e) if e.kind() == ErrorKind::AlreadyExists => Ok(false),
                    Err(e) => Err(self.io_error(&path, e)),
                });
        let _ = std::fs::remove_file(&staged);
        linked
    }

    fn put_overwrite(&self, name: &str, bytes: &[u8]) -> Result<(), RemoteError> {
        let path = self.path(name);
        let staged = self.stage(bytes)?;
        let moved = self
            .parent_of(&path)
            .and_then(|()| std::fs::rename(&staged, &path).map_err(|e| self.io_error(&path, e)));
        if moved.is_err() {
            let _ = std::fs::remove_file(&staged);
        }
        moved
    }

    fn check_present(&self) -> Result<(), RemoteError> {
        match self.root.is_dir() {
            true => Ok(()),
            false => Err(RemoteError::Unavailable(format!(
                "{} is not a folder",
                self.root.display()
            ))),
        }
    }

    fn hint(&self) -> String {
        format!(
            "create {} (readable, and writable unless the remote is read-only) or fix the remote URL",
            self.root.display()
        )
    }
}
