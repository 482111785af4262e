//! The validated pipeline: stages with resolved paths, bound inputs and canonical params.

use std::collections::BTreeMap;
use std::path::PathBuf;

/// A whole `pipeline.toml` after validation. Paths are absolute.
#[derive(Debug, Clone)]
pub struct Pipeline {
    pub config_path: PathBuf,
    /// The folder of `pipeline.toml`: relative paths resolve here, the store lives in `.groove/`.
    pub root: PathBuf,
    pub seed: u64,
    pub data_dir: PathBuf,
    pub reports_dir: PathBuf,
    /// Stages by name (sorted).
    pub stages: BTreeMap<String, StageSpec>,
}

/// One `[stages.NAME]` table.
#[derive(Debug, Clone)]
pub struct StageSpec {
    pub name: String,
    pub kind: String,
    /// Line of the stage's table in `pipeline.toml` (1-based).
    pub line: usize,
    /// Per-item stage: the name of the Collection input it maps over.
    pub foreach: Option<String>,
    /// More Collection inputs stepped through with `foreach`, item by item (same item names).
    pub foreach_with: Vec<String>,
    pub inputs: BTreeMap<String, InputSpec>,
    /// Every output the stage produces, with the path it is materialized to, if any.
    pub outputs: BTreeMap<String, Option<PathBuf>>,
    pub params: toml::Table,
    /// The params with defaults filled in, as they enter the cache key.
    pub canonical_params: serde_json::Value,
    /// The shell command of a `command` stage.
    pub cmd: Option<String>,
}

/// What an input is bound to.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum InputSpec {
    /// A file or a directory (its top-level regular files) in the project or dataset.
    Path { path: PathBuf, optional: bool },
    /// `"<stage>:<output>"`.
    Stage { stage: String, output: String },
    /// `"engine:provenance"`: the engine's provenance record.
    Provenance,
}

impl StageSpec {
    /// Is this input passed one item at a time?
    pub fn is_item_input(&self, input: &str) -> bool {
        self.foreach.as_deref() == Some(input) || self.foreach_with.iter().any(|f| f == input)
    }
}

impl Pipeline {
    /// Names of the stages this stage reads from directly.
    pub fn deps(&self, stage: &str) -> Vec<&str> {
        let mut deps: Vec<&str> = self.stages[stage]
            .inputs
            .values()
            .filter_map(|i| match i {
                InputSpec::Stage { stage, .. } => Some(stage.as_str()),
                _ => None,
            })
            .collect();
        deps.sort_unstable();
        deps.dedup();
        deps
    }

    /// A path as provenance records it: `${data}/…` inside the dataset folder (so the same data
    /// gives the same record wherever it lives, and with `--data`), else as [`Pipeline::show`].
    pub fn show_portable(&self, path: &std::path::Path) -> String {
        match path.strip_prefix(&self.data_dir) {
            Ok(rel) if rel.as_os_str().is_empty() => "${data}".to_string(),
            Ok(rel) => format!("${{data}}/{}", rel.to_string_lossy().replace('\\', "/")),
            Err(_) => self.show(path),
        }
    }

    /// The usage error for a stage name the pipeline does not define, with the names it does.
    pub fn no_stage(&self, name: &str) -> super::EngineError {
        super::EngineError::Usage(format!(
            "no stage `{name}` in {}; stages: {}",
            self.show(&self.config_path),
            self.stages.keys().cloned().collect::<Vec<_>>().join(", ")
        ))
    }

    /// A path shown relative to the project root when it lies inside it.
    pub fn show(&self, path: &std::path::Path) -> String {
        path.strip_prefix(&self.root)
            .unwrap_or(path)
            .to_string_lossy()
            .replace('\\', "/")
    }
}
