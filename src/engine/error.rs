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
    #[error("{}: {source}", path.display())]
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

/// Attach a path to an IO result.
pub trait IoContext<T> {
    fn at(self, path: &Path) -> Result<T, EngineError>;
}

impl<T> IoContext<T> for std::io::Result<T> {
    fn at(self, path: &Path) -> Result<T, EngineError> {
        self.map_err(|e| EngineError::io(path, e))
    }
}
