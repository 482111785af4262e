//! The contract between the engine and a stage kind: typed params in, artifacts (bytes) out.
//!
//! A stage is a pure function of its params and input artifacts. It never touches the file
//! system: the engine reads inputs into memory, calls `run`, checks every declared output is
//! present, and writes the outputs into the store atomically.

use std::collections::BTreeMap;

/// One artifact: a single file's bytes, or a collection of named items (e.g. one per run).
/// Collection item names are file-name safe (`[A-Za-z0-9._-]`), and iterate in sorted order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Artifact {
    File(Vec<u8>),
    Collection(BTreeMap<String, Vec<u8>>),
    /// A collection whose items the stage already put in the store (`StageInput::put_item`) as
    /// it made them, so that they were never all held at once: item → sha256. Only ever an
    /// output; a stage reading it as an input gets a `Collection`.
    InStore(BTreeMap<String, String>),
}

/// What a stage says when an input came as `Artifact::InStore`, which the engine never gives.
pub const IN_STORE_INPUT: &str =
    "an input came as a list of stored items, which the engine never passes (a bug in groove, please report it)";

/// What a stage receives.
pub struct StageInput<'a> {
    /// The stage's params, already checked by `StageKind::canonical_params`.
    pub params: &'a toml::Table,
    /// Input artifacts by the input names the kind declares. For a per-item stage each
    /// `foreach` input holds only the current item, as `Artifact::File`.
    pub inputs: BTreeMap<&'a str, &'a Artifact>,
    /// For a per-item stage: the current item's name.
    pub item: Option<&'a str>,
    /// The pipeline seed (from `pipeline.toml`), mixed with the stage name by the engine.
    pub seed: u64,
    /// Where a long stage says what it is doing (the engine's progress line); `None` when nobody
    /// listens (tests, a Slurm job step).
    pub progress: Option<&'a (dyn Fn(&str) + Sync)>,
    /// Puts one item's bytes in the store now and gives its sha256, for a stage that makes many
    /// items and need not hold them all (it returns them as `Artifact::InStore`); `None` when
    /// there is no store (tests): the stage then returns a `Collection`.
    pub put_item: Option<&'a (dyn Fn(&[u8]) -> Result<String, StageError> + Sync)>,
}

impl StageInput<'_> {
    /// Tell the progress line what the stage is doing now. Never part of an output.
    pub fn report(&self, what: &str) {
        if let Some(p) = self.progress {
            p(what);
        }
    }
}

/// What a stage returns: artifacts by output name. Every declared output must be present.
pub type StageOutputs = BTreeMap<String, Artifact>;

/// A failure of a stage on its inputs (bad data, a numerical breakdown). Lowercase, says how to fix.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct StageError(pub String);

/// An invalid params table: which key, what is wrong, how to fix.
#[derive(Debug, thiserror::Error)]
#[error("param `{key}`: {message}")]
pub struct ParamError {
    pub key: String,
    pub message: String,
}

/// A built-in kind of stage.
pub trait StageKind: Sync + Send {
    /// The `kind = "..."` name in `pipeline.toml`.
    fn kind(&self) -> &'static str;
    /// Input names this kind needs (each bound in `pipeline.toml`), and those it may take.
    fn inputs(&self) -> &'static [&'static str];
    fn optional_inputs(&self) -> &'static [&'static str] {
        &[]
    }
    /// Output names this kind produces.
    fn outputs(&self) -> &'static [&'static str];
    /// Validate the params (unknown key, wrong type, out of range) and return them with every
    /// default filled in, as the canonical JSON value that goes into the cache key.
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError>;
    /// Run the stage.
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError>;
}

/// Deserialize a params table into a typed struct (use `#[serde(deny_unknown_fields, default)]`),
/// returning it and its canonical JSON form. Shared by every built-in kind.
///
/// The error names the offending key: the one named by serde (unknown field), or else the one
/// whose removal makes the table valid (a mistyped value).
pub fn typed_params<P>(params: &toml::Table) -> Result<(P, serde_json::Value), ParamError>
where
    P: serde::de::DeserializeOwned + serde::Serialize,
{
    let parse = |t: &toml::Table| -> Result<P, toml::de::Error> {
        toml::Value::Table(t.clone()).try_into()
    };
    let typed: P = parse(params).map_err(|e| {
        let named = e
            .message()
            .split('`')
            .nth(1)
            .filter(|k| params.contains_key(*k));
        let culprit = named.map(str::to_string).or_else(|| {
            params
                .keys()
                .find(|k| {
                    let mut without = params.clone();
                    without.remove(*k);
                    parse(&without).is_ok()
                })
                .cloned()
        });
        ParamError {
            key: culprit.unwrap_or_else(|| "params".to_string()),
            message: e.message().trim().to_string(),
        }
    })?;
    let json = serde_json::to_value(&typed).map_err(|e| ParamError {
        key: "params".into(),
        message: e.to_string(),
    })?;
    Ok((typed, json))
}
