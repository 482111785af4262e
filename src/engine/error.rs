//! The engine's error: a bad config (with its TOML line), IO, or a failed stage.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum EngineError {
    /// A problem in `pipeline.toml`, located at a line.
    #[error("{file}:{line}: {message}")]
    Config {
        file: String,
        line: usize,
        message: String,
    },
    /// A problem with the command line or the project as a whole.
    #[error("{0}")]
    Usage(String),
    /// A file or folder groove could not read or write, with what to do about it.
    #[error("{}: {source}; {}", path.display(), io_hint(source.kind()))]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A store object a stage needed is missing or its bytes have another hash. `groove run`
    /// answers it by checking every object the run names and running again what made it.
    #[error("the store's object {sha256} is {} ({why}); run `groove verify` to drop it, then `groove run` again", if *.missing { "missing" } else { "damaged" })]
    DamagedObject {
        sha256: String,
        missing: bool,
        why: String,
    },
    /// A stage (or one item of a per-item stage) failed.
    #[error("stage `{stage}`{}: {message}", item.as_deref().map(|i| format!(" item `{i}`")).unwrap_or_default())]
    StageFailed {
        stage: String,
        item: Option<String>,
        message: String,
    },
}

impl EngineError {
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        EngineError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// What to do about an IO error of this kind.
fn io_hint(kind: std::io::ErrorKind) -> &'static str {
    use std::io::ErrorKind as K;
    match kind {
        K::NotFound => "check that the path exists, or fix it in pipeline.toml or the command line",
        K::PermissionDenied => "check the permissions of the file and of its folder",
        K::StorageFull | K::QuotaExceeded => {
            "free disk space (`groove gc` drops what the store no longer needs), then run again"
        }
        K::ReadOnlyFilesystem => "the file system is read-only: put the project on a writable one",
        K::AlreadyExists => "move it out of the way, then run again",
        _ => "check the file and its folder (disk, mount, permissions), then run again",
    }
}

/// Attach a path to an IO result.
pub trait IoContext<T> {
    fn at(self, path: &Path) -> Result<T, EngineError>;
}

impl<T> IoContext<T> for std::io::Result<T> {
    fn at(self, path: &Path) -> Result<T, EngineError> {
        self.map_err(|e| EngineError::io(path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_io_error_names_the_path_and_says_what_to_do() {
        let e = EngineError::io(
            Path::new("/data/runs.csv"),
            std::io::Error::from(std::io::ErrorKind::PermissionDenied),
        );
        let text = e.to_string();
        assert!(text.starts_with("/data/runs.csv: "), "{text}");
        assert!(
            text.ends_with("check the permissions of the file and of its folder"),
            "{text}"
        );
        let full = EngineError::io(
            Path::new("store"),
            std::io::Error::from(std::io::ErrorKind::StorageFull),
        );
        assert!(full.to_string().contains("free disk space"), "{full}");
    }
}
