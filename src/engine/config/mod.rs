//! Reading `pipeline.toml` in two layers: a serde mirror ([`raw`]) and one validation step ([`validate`]).
//!
//! Files of this folder:
//!
//! - `raw.rs`: The serde mirror of `pipeline.toml`
//! - `span.rs`: byte offsets of `pipeline.toml` to line numbers, and errors located at a line
//! - `validate.rs`: The validation step

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
    let bytes = std::fs::read(path).map_err(|e| {
        EngineError::Usage(format!(
            "cannot read {}: {e}; pass --config FILE, run in the folder of pipeline.toml, or pass --data DIR to run the built-in pipeline on a dataset",
            path.display()
        ))
    })?;
    load_bytes(path, bytes, overrides, catalog)
}

/// Parse and validate pipeline text as if it were the file `path` (relative paths inside it
/// resolve against `path`'s folder, which need not hold a file).
pub fn load_bytes(
    path: &Path,
    bytes: Vec<u8>,
    overrides: &Overrides,
    catalog: &Catalog,
) -> Result<Pipeline, EngineError> {
    let abs = validate::normalize(&std::path::absolute(path).at(path)?);
    let text = match String::from_utf8(bytes) {
        Ok(text) => text,
        Err(e) => {
            let at = e.utf8_error().valid_up_to();
            let bytes = e.as_bytes();
            let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
            let file = span::Source::new(&abs, "");
            return Err(file.error(
                line,
                format!(
                    "is not UTF-8 text (byte 0x{:02x}); save the file as UTF-8",
                    bytes[at]
                ),
            ));
        }
    };
    let file = span::Source::new(&abs, &text);
    let raw: raw::RawPipeline = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| file.line_of(s.start)).unwrap_or(1);
        file.error(line, e.message().trim().to_string())
    })?;
    validate::validate(raw, &file, overrides, catalog)
}
