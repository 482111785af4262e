//! Reading `pipeline.toml` in two layers: a serde mirror ([`raw`]) and one validation step ([`validate`]).

pub mod raw;
pub mod span;
pub mod validate;

use super::catalog::Catalog;
use super::error::{EngineError, IoContext};
use super::pipeline::Pipeline;
use std::path::{Path, PathBuf};

/// Command-line replacements for the project's folders (relative to the current directory).
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub data: Option<PathBuf>,
    pub reports: Option<PathBuf>,
}

/// Read, parse and validate a pipeline file.
pub fn load(
    path: &Path,
    overrides: &Overrides,
    catalog: &Catalog,
) -> Result<Pipeline, EngineError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        EngineError::Usage(format!(
            "cannot read {}: {e}; pass --config FILE or run in the folder of pipeline.toml",
            path.display()
        ))
    })?;
    let abs = validate::normalize(&std::path::absolute(path).at(path)?);
    let file = span::Source::new(&abs, &text);
    let raw: raw::RawPipeline = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| file.line_of(s.start)).unwrap_or(1);
        file.error(line, e.message().trim().to_string())
    })?;
    validate::validate(raw, &file, overrides, catalog)
}
