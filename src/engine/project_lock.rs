//! The project lock: one `groove run` (or `gc`, `clean`) at a time per project.
//!
//! An OS file lock on `.groove/lock` (std `File::try_lock`): it is released when the process
//! ends, even by `kill -9`, so there is never a stale lock to remove by hand. The file is opened
//! close-on-exec, so a command stage's child process does not inherit it.

use super::error::{EngineError, IoContext};
use std::fs::{File, OpenOptions, TryLockError};
use std::io::Write;
use std::path::Path;

pub struct ProjectLock {
    _file: File,
}

/// Take the lock, waiting (after telling the user) if another groove process holds it.
pub fn acquire(store_dir: &Path, on_wait: impl FnOnce(&str)) -> Result<ProjectLock, EngineError> {
    std::fs::create_dir_all(store_dir).at(store_dir)?;
    let path = store_dir.join("lock");
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .at(&path)?;
    match file.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => {
            let holder = std::fs::read_to_string(&path).unwrap_or_default();
            on_wait(holder.trim());
            file.lock().at(&path)?;
        }
        Err(TryLockError::Error(e)) => return Err(EngineError::io(&path, e)),
    }
    file.set_len(0).at(&path)?;
    let _ = write!(file, "pid {}", std::process::id());
    Ok(ProjectLock { _file: file })
}

/// Take the lock shared, for a command that only reads the project (`publish`): no run can
/// change the lock or the store while it is held, and several readers may hold it at once.
/// Opened read-only, so it works on a store that cannot be written; a store without a lock file
/// was never run in, and `None` is returned (there is nothing a run could tear).
pub fn acquire_shared(
    store_dir: &Path,
    on_wait: impl FnOnce(&str),
) -> Result<Option<ProjectLock>, EngineError> {
    let path = store_dir.join("lock");
    let file = match File::open(&path) {
        Ok(file) => file,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(EngineError::io(&path, e)),
    };
    match file.try_lock_shared() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => {
            let holder = std::fs::read_to_string(&path).unwrap_or_default();
            on_wait(holder.trim());
            file.lock_shared().at(&path)?;
        }
        Err(TryLockError::Error(e)) => return Err(EngineError::io(&path, e)),
    }
    Ok(Some(ProjectLock { _file: file }))
}
