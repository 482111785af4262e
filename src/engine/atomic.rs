//! Atomic file writes: a name no other writer uses, and write-then-rename.

use super::error::{EngineError, IoContext};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};

static UNIQUE: AtomicU64 = AtomicU64::new(0);

/// A name no other writer uses: process id and a counter.
pub fn unique_name(prefix: &str) -> String {
    format!(
        "{prefix}-{}-{}",
        std::process::id(),
        UNIQUE.fetch_add(1, Ordering::Relaxed)
    )
}

/// Write a file by writing a sibling temp file and renaming it over the target; a write or rename
/// that fails removes the temp file.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), EngineError> {
    let parent = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(parent).at(parent)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = parent.join(unique_name(&format!(".{name}.groove-tmp")));
    if let Err(e) = std::fs::write(&tmp, bytes) {
        // a write that failed part way (a full disk) leaves no temp file behind
        let _ = std::fs::remove_file(&tmp);
        return Err(EngineError::io(&tmp, e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        EngineError::io(path, e)
    })
}
