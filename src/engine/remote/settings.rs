//! `[remote]` in `pipeline.toml`, merged with `GROOVE_REMOTE*` and the command-line flags.
//!
//! ```toml
//! [remote]
//! url = "file:///shared/groove-cache"   # or "s3://bucket/prefix"
//! read_only = false                     # true: look up, never upload
//! required = false                      # true: a remote error fails the run (exit 2)
//! jobs = 8                              # concurrent uploads
//! shared = "group"                      # file://: folders g+rws, files g+rw (a group share)
//! ```
//! Precedence: `--remote URL` / `--no-remote`, then `GROOVE_REMOTE`, then `[remote] url`.

use super::{Settings, DEFAULT_JOBS, ENV_READ_ONLY, ENV_URL};
use crate::engine::config::span::Source;
use crate::engine::error::EngineError;
use serde::Deserialize;
use std::path::Path;
use toml::Spanned;

#[derive(Debug, Deserialize)]
struct Doc {
    remote: Option<Spanned<RawRemote>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRemote {
    url: Option<String>,
    #[serde(default)]
    read_only: bool,
    #[serde(default)]
    required: bool,
    jobs: Option<usize>,
    shared: Option<String>,
}

/// The command line's say in it.
#[derive(Debug, Clone, Default)]
pub struct Flags {
    pub url: Option<String>,
    pub no_remote: bool,
    pub read_only: bool,
    pub required: bool,
}

/// The remote to use, if any. Errors name `pipeline.toml`'s line.
pub fn resolve(config_path: &Path, flags: &Flags) -> Result<Option<Settings>, EngineError> {
    let text = std::fs::read_to_string(config_path).unwrap_or_default();
    let file = Source::new(config_path, &text);
    let doc: Doc = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| file.line_of(s.start)).unwrap_or(1);
        file.error(line, format!("[remote]: {}", e.message().trim()))
    })?;
    let raw = doc.remote.map(|r| {
        let line = file.line_of(r.span().start);
        (r.into_inner(), line)
    });
    if flags.no_remote {
        return Ok(None);
    }
    let env_url = std::env::var(ENV_URL).ok().filter(|s| !s.is_empty());
    let env_ro = std::env::var(ENV_READ_ONLY)
        .map(|v| matches!(v.as_str(), "1" | "true" | "yes"))
        .unwrap_or(false);
    let (toml_url, toml_ro, toml_req, jobs, shared_group) = match &raw {
        Some((r, line)) => {
            if r.jobs == Some(0) {
                return Err(file.error(*line, "[remote] jobs must be at least 1"));
            }
            let shared_group = match r.shared.as_deref() {
                None => false,
                Some("group") => true,
                Some(other) => {
                    return Err(file.error(
                        *line,
                        format!("[remote] shared = \"{other}\" is not a sharing mode; write shared = \"group\" (folders and files writable by the remote's group) or leave it out"),
                    ))
                }
            };
            (r.url.clone(), r.read_only, r.required, r.jobs, shared_group)
        }
        None => (None, false, false, None, false),
    };
    let Some(url) = flags.url.clone().or(env_url).or(toml_url) else {
        if flags.required {
            return Err(EngineError::Usage(format!(
                "--remote-required but no remote is set; pass --remote URL, set {ENV_URL}, or add [remote] url to pipeline.toml"
            )));
        }
        return Ok(None);
    };
    Ok(Some(Settings {
        url,
        read_only: flags.read_only || env_ro || toml_ro,
        required: flags.required || toml_req,
        jobs: jobs.unwrap_or(DEFAULT_JOBS),
        shared_group,
    }))
}
