//! Byte offsets of `pipeline.toml` to line numbers, and errors located at a line.

use crate::engine::error::EngineError;
use std::path::{Path, PathBuf};

/// The pipeline file being read: its path and the offsets where its lines start.
pub struct Source {
    pub path: PathBuf,
    line_starts: Vec<usize>,
}

impl Source {
    pub fn new(path: &Path, text: &str) -> Source {
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        Source {
            path: path.to_path_buf(),
            line_starts,
        }
    }

    /// The 1-based line holding byte `offset`.
    pub fn line_of(&self, offset: usize) -> usize {
        self.line_starts.partition_point(|&s| s <= offset).max(1)
    }

    pub fn error(&self, line: usize, message: impl Into<String>) -> EngineError {
        let name = self
            .path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| self.path.display().to_string());
        EngineError::Config {
            file: name,
            line,
            message: message.into(),
        }
    }
}
