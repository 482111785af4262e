//! `[slurm]` in `pipeline.toml`: the allocation, and job-step resources per stage kind,
//! overridable per stage with `[stages.NAME.slurm]`.
//!
//! ```toml
//! [slurm]
//! partition = "debug"      # the allocation's partition (default: the cluster's default)
//! time = "02:00:00"        # the allocation's time limit
//! cpus = 8                 # CPUs of the allocation (tasks of one CPU each); default 2
//! mem = "16G"              # memory of the allocation (default: the partition's default)
//! job_name = "groove"      # the allocation's job name
//!
//! [slurm.kinds.command]    # job-step resources of every stage of a kind
//! cpus = 1
//! mem = "2G"
//! time = "00:30:00"
//! batch = 16               # items of a per-item stage per job step (default: spread over the CPUs)
//!
//! [stages.track.slurm]     # one stage's own resources (override its kind's)
//! cpus = 2
//! partition = "gpu"        # a stage on another partition gets its own allocation there
//! ```

use crate::engine::config::span::Source;
use crate::engine::error::EngineError;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use toml::Spanned;

/// Resources of the job steps of one stage.
#[derive(Debug, Clone, Default, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StepResources {
    pub partition: Option<String>,
    pub time: Option<String>,
    pub cpus: Option<u32>,
    pub mem: Option<String>,
    /// Items per step for per-item stages.
    pub batch: Option<usize>,
}

impl StepResources {
    /// `self`, with what it leaves unset taken from `base`.
    fn over(&self, base: &StepResources) -> StepResources {
        StepResources {
            partition: self.partition.clone().or_else(|| base.partition.clone()),
            time: self.time.clone().or_else(|| base.time.clone()),
            cpus: self.cpus.or(base.cpus),
            mem: self.mem.clone().or_else(|| base.mem.clone()),
            batch: self.batch.or(base.batch),
        }
    }
}

/// The allocation.
#[derive(Debug, Clone, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AllocationSpec {
    pub partition: Option<String>,
    pub time: Option<String>,
    #[serde(default = "default_cpus")]
    pub cpus: u32,
    pub mem: Option<String>,
    #[serde(default = "default_job_name")]
    pub job_name: String,
    #[serde(default)]
    pub kinds: BTreeMap<String, StepResources>,
}

fn default_cpus() -> u32 {
    2
}

fn default_job_name() -> String {
    "groove".into()
}

impl Default for AllocationSpec {
    fn default() -> Self {
        AllocationSpec {
            partition: None,
            time: None,
            cpus: default_cpus(),
            mem: None,
            job_name: default_job_name(),
            kinds: BTreeMap::new(),
        }
    }
}

/// `[slurm]` and every stage's resources, resolved.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SlurmConfig {
    pub allocation: AllocationSpec,
    /// Stage name → its step resources (stage over kind over defaults).
    pub stages: BTreeMap<String, StepResources>,
}

#[derive(Debug, Deserialize)]
struct Doc {
    slurm: Option<Spanned<AllocationSpec>>,
    #[serde(default)]
    stages: BTreeMap<String, StageDoc>,
}

#[derive(Debug, Deserialize)]
struct StageDoc {
    kind: Option<String>,
    slurm: Option<Spanned<StepResources>>,
}

/// Read `[slurm]` and `[stages.*.slurm]` from the pipeline file. Errors name the line.
pub fn load(config_path: &Path) -> Result<SlurmConfig, EngineError> {
    let text = std::fs::read_to_string(config_path)
        .map_err(|e| EngineError::Usage(format!("cannot read {}: {e}", config_path.display())))?;
    let file = Source::new(config_path, &text);
    let doc: Doc = toml::from_str(&text).map_err(|e| {
        let line = e.span().map(|s| file.line_of(s.start)).unwrap_or(1);
        file.error(line, format!("[slurm]: {}", e.message().trim()))
    })?;
    let allocation = match doc.slurm {
        Some(s) => {
            let line = file.line_of(s.span().start);
            let a = s.into_inner();
            if a.cpus == 0 {
                return Err(file.error(line, "[slurm] cpus must be at least 1"));
            }
            a
        }
        None => AllocationSpec::default(),
    };
    let mut stages = BTreeMap::new();
    for (name, st) in doc.stages {
        let kind = st
            .kind
            .as_deref()
            .and_then(|k| allocation.kinds.get(k))
            .cloned()
            .unwrap_or_default();
        let own = match st.slurm {
            Some(s) => {
                let line = file.line_of(s.span().start);
                let r = s.into_inner();
                if r.cpus == Some(0) || r.batch == Some(0) {
                    return Err(file.error(
                        line,
                        format!("stage `{name}`: slurm cpus and batch must be at least 1"),
                    ));
                }
                r
            }
            None => StepResources::default(),
        };
        let mut r = own.over(&kind);
        r.cpus = Some(r.cpus.unwrap_or(1).min(allocation.cpus));
        stages.insert(name, r);
    }
    Ok(SlurmConfig { allocation, stages })
}
