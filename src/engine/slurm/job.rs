//! What one job step is asked to do: a file the controller writes in the shared store's `tmp/`
//! and `groove slurm-step FILE` reads on the compute node.

use crate::engine::atomic::write_atomic;
use crate::engine::error::{EngineError, IoContext};
use crate::engine::store::{Entry, Store, Stored};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One input of the stage: its record, and the project path it is read from (else the store).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StepInput {
    pub stored: Stored,
    pub path: Option<PathBuf>,
}

/// One key to run: the item (per-item stages) and the stage key.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StepUnit {
    pub item: Option<String>,
    pub key: String,
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct StepJob {
    /// The pipeline file (absolute) and the `--data` / `--out` replacements in force.
    pub config: PathBuf,
    pub data: Option<PathBuf>,
    pub reports: Option<PathBuf>,
    pub stage: String,
    /// The kind's code fingerprint the controller keyed with: a different binary refuses.
    pub code: String,
    pub seed: u64,
    pub inputs: BTreeMap<String, StepInput>,
    pub units: Vec<StepUnit>,
}

impl StepJob {
    pub fn write(&self, path: &Path) -> Result<(), EngineError> {
        write_atomic(
            path,
            &serde_json::to_vec(self).expect("a step job serializes"),
        )
    }

    pub fn read(path: &Path) -> Result<StepJob, EngineError> {
        let bytes = std::fs::read(path).at(path)?;
        serde_json::from_slice(&bytes).map_err(|e| {
            EngineError::Usage(format!(
                "{} is not a groove step file ({e}); it is written by `groove run --executor slurm`",
                path.display()
            ))
        })
    }
}

/// Runs a stage's keys outside this process (the Slurm executor). The evaluation holds one as a
/// trait object, so the walk does not depend on how steps are launched.
pub trait StepRunner: Send + Sync {
    /// Run every unit of `job` (which names the stage, its inputs and its keys), committing into
    /// `store`; one result per unit, in order. `per_item`: the units are items of one stage.
    fn run_units(
        &self,
        store: &Store,
        job: &StepJob,
        per_item: bool,
    ) -> Vec<Result<Entry, EngineError>>;
    /// How many stages may run at once.
    fn slots(&self) -> usize;
    /// Give back what was taken (allocations) and say what was used.
    fn finish(&self) -> String;
}
