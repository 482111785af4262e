//! The `file://` remote: a folder on a shared filesystem, laid out like the local store.
//!
//! Create-if-absent is a hard link of a fully written temp file to the final name: `link(2)`
//! fails with `EEXIST` when the name exists, and the name appears complete or not at all, so
//! a killed writer leaves at most a stray temp file (under `tmp/`, never read).
//!
//! A remote on a group share (`[remote] shared = "group"`, or a root folder that is setgid) is
//! kept usable by the whole group: every folder groove makes in it gets group write and setgid
//! (so what is made inside belongs to the group too) and every file group read and write,
//! whatever the umask.

use super::backend::{Backend, RemoteError};
use crate::engine::atomic::unique_name;
use std::io::ErrorKind;
use std::path::{Path, PathBuf};

pub struct FileRemote {
    pub root: PathBuf,
    /// Folders made g+rws, files g+rw.
    group: bool,
}

/// The setgid bit of a folder's mode.
const SETGID: u32 = 0o2000;

impl FileRemote {
    /// The remote at `root`, shared with its group when the root folder is setgid.
    pub fn new(root: &Path) -> FileRemote {
        use std::os::unix::fs::PermissionsExt;
        let setgid = std::fs::metadata(root).is_ok_and(|m| m.permissions().mode() & SETGID != 0);
        FileRemote {
            root: root.to_path_buf(),
            group: setgid,
        }
    }

    /// Also shared with the group when `group` (`[remote] shared = "group"`).
    pub fn shared(self, group: bool) -> FileRemote {
        FileRemote {
            group: self.group || group,
            ..self
        }
    }

    /// Make `dir` and its missing parents; on a group share each folder made gets g+rws.
    fn make_dir(&self, dir: &Path) -> Result<(), RemoteError> {
        if !self.group {
            return std::fs::create_dir_all(dir).map_err(|e| self.io_error(dir, e));
        }
        let missing: Vec<&Path> = dir.ancestors().take_while(|d| !d.is_dir()).collect();
        for d in missing.into_iter().rev() {
            match std::fs::create_dir(d) {
                Ok(()) => self.add_mode(d, 0o2070)?,
                Err(e) if e.kind() == ErrorKind::AlreadyExists => {}
                Err(e) => return Err(self.io_error(d, e)),
            }
        }
        Ok(())
    }

    /// Add `bits` to a path's mode.
    fn add_mode(&self, path: &Path, bits: u32) -> Result<(), RemoteError> {
        use std::os::unix::fs::PermissionsExt;
        let mut p = std::fs::metadata(path)
            .map_err(|e| self.io_error(path, e))?
            .permissions();
        p.set_mode(p.mode() | bits);
        std::fs::set_permissions(path, p).map_err(|e| self.io_error(path, e))
    }

    fn path(&self, name: &str) -> PathBuf {
        self.root.join(name)
    }

    /// Write `bytes` to a private temp file under `tmp/` on the same filesystem.
    fn stage(&self, bytes: &[u8]) -> Result<PathBuf, RemoteError> {
        let tmp = self.root.join("tmp");
        self.make_dir(&tmp)?;
        let staged = tmp.join(unique_name(&format!("put-{}", host_tag())));
        std::fs::write(&staged, bytes).map_err(|e| self.io_error(&staged, e))?;
        if self.group {
            // the final name is a link to (or a rename of) this file: it keeps these bits
            self.add_mode(&staged, 0o060)?;
        }
        Ok(staged)
    }

    fn io_error(&self, path: &Path, e: std::io::Error) -> RemoteError {
        let m = format!("{}: {e}", path.display());
        match e.kind() {
            ErrorKind::PermissionDenied => RemoteError::Unavailable(format!(
                "{}: permission denied, a permission problem of the remote's folders: whoever made them must give you write (on a group share `chmod -R g+rwX,g+s` on the remote, and `[remote] shared = \"group\"` in every clone's pipeline.toml so groove keeps it so)",
                path.display()
            )),
            ErrorKind::ReadOnlyFilesystem => RemoteError::Unavailable(m),
            ErrorKind::NotFound if !self.root.exists() => RemoteError::Unavailable(m),
            _ => RemoteError::Other(m),
        }
    }

    fn parent_of(&self, path: &Path) -> Result<(), RemoteError> {
        let parent = path.parent().expect("remote names have a parent");
        self.make_dir(parent)
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refused_write_is_named_a_permission_problem_with_the_fix() {
        let remote = FileRemote::new(Path::new("/shared/cache"));
        let refused = remote.io_error(
            Path::new("/shared/cache/objects/ab"),
            std::io::Error::from(ErrorKind::PermissionDenied),
        );
        let RemoteError::Unavailable(said) = refused else {
            panic!("{refused}");
        };
        assert!(
            said.starts_with("/shared/cache/objects/ab: permission denied, a permission problem"),
            "{said}"
        );
        assert!(said.contains("[remote] shared = \"group\""), "{said}");
    }
}
