//! The serde mirror of `pipeline.toml`: the file's shape with spans, before any meaning is checked.

use serde::Deserialize;
use std::collections::BTreeMap;
use toml::Spanned;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawPipeline {
    pub project: Option<Spanned<RawProject>>,
    #[serde(default)]
    pub stages: BTreeMap<Spanned<String>, Spanned<RawStage>>,
    /// `[remote]`: read by `engine::remote::settings`.
    pub remote: Option<toml::Value>,
    /// `[slurm]`: read by `engine::slurm::config`.
    pub slurm: Option<toml::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawProject {
    #[serde(default)]
    pub seed: u64,
    pub data: Option<Spanned<String>>,
    pub reports: Option<Spanned<String>>,
    /// Params every stage whose kind takes them inherits, unless it sets its own.
    #[serde(default)]
    pub params: BTreeMap<Spanned<String>, Spanned<toml::Value>>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawStage {
    pub kind: Spanned<String>,
    pub foreach: Option<Spanned<Foreach>>,
    #[serde(default)]
    pub inputs: BTreeMap<Spanned<String>, Spanned<RawInput>>,
    #[serde(default)]
    pub outputs: BTreeMap<Spanned<String>, Spanned<String>>,
    #[serde(default)]
    pub params: BTreeMap<Spanned<String>, Spanned<toml::Value>>,
    pub cmd: Option<Spanned<String>>,
    /// `[stages.NAME.slurm]`: read by `engine::slurm::config`.
    pub slurm: Option<toml::Value>,
}

/// An input binding: `"path"`, `"stage:output"`, `"engine:provenance"`, or `{ path, optional }`.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum RawInput {
    Text(String),
    Table(RawPathInput),
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawPathInput {
    pub path: String,
    #[serde(default)]
    pub optional: bool,
}

/// `foreach = "runs"`, or `foreach = ["runs", "fits"]` to step through several per-item inputs
/// with the same item names together.
#[derive(Debug, Deserialize)]
#[serde(untagged)]
pub enum Foreach {
    One(String),
    Many(Vec<String>),
}
