//! The controller side: turn the keys a stage must run into job steps, run them inside the
//! allocation, and open the entries the steps committed.
//!
//! A stage that is not per-item is one step. A per-item stage's keys are cut into batches (at
//! most `batch` items per step; by default spread over the allocation's CPUs), so a step never
//! carries one tiny item. Steps of independent stages and batches run at the same time; Slurm
//! places them on free CPUs of the allocation (`--exact`).

use super::alloc::{Allocations, StepError};
use super::config::{SlurmConfig, StepResources};
use super::job::{StepInput, StepJob, StepUnit};
use crate::engine::error::EngineError;
use crate::engine::evaluate::Context;
use crate::engine::execute::{Bound, Source};
use crate::engine::pipeline::StageSpec;
use crate::engine::store::Entry;
use rayon::prelude::*;
use std::collections::BTreeMap;

pub struct SlurmExecutor {
    pub config: SlurmConfig,
    pub allocations: Allocations,
    /// The groove binary the steps run (must be reachable from the compute nodes).
    pub program: std::path::PathBuf,
}

impl SlurmExecutor {
    pub fn new(config: SlurmConfig) -> Result<SlurmExecutor, EngineError> {
        let program = std::env::current_exe().map_err(|e| {
            EngineError::Usage(format!("cannot find the groove binary for the job steps: {e}"))
        })?;
        Ok(SlurmExecutor {
            allocations: Allocations::new(config.allocation.clone()),
            config,
            program,
        })
    }

    fn resources(&self, stage: &str) -> StepResources {
        self.config.stages.get(stage).cloned().unwrap_or_default()
    }

    /// Run `units` (item, key) of `spec` as job steps; one result per unit, in order.
    pub fn run_units(
        &self,
        ctx: &Context,
        spec: &StageSpec,
        bound: &BTreeMap<String, Bound>,
        units: &[(Option<String>, String)],
        seed: u64,
    ) -> Vec<Result<Entry, EngineError>> {
        match self.try_run(ctx, spec, bound, units, seed) {
            Ok(results) => results,
            Err(e) => units.iter().map(|_| Err(e_clone(&e))).collect(),
        }
    }

    fn try_run(
        &self,
        ctx: &Context,
        spec: &StageSpec,
        bound: &BTreeMap<String, Bound>,
        units: &[(Option<String>, String)],
        seed: u64,
    ) -> Result<Vec<Result<Entry, EngineError>>, EngineError> {
        let mut inputs = BTreeMap::new();
        for (name, b) in bound {
            let path = match &b.source {
                Source::Path(p) => Some(p.clone()),
                Source::Store => None,
                // engine-made bytes (provenance) travel through the store like any blob
                Source::Memory(bytes) => {
                    ctx.store.put_object(bytes)?;
                    None
                }
            };
            inputs.insert(
                name.clone(),
                StepInput {
                    stored: b.stored.clone(),
                    path,
                },
            );
        }
        let resources = self.resources(&spec.name);
        let cpus = resources.cpus.unwrap_or(1).max(1) as usize;
        let slots = (self.config.allocation.cpus as usize / cpus).max(1);
        let per_step = match (&spec.foreach, resources.batch) {
            (None, _) => units.len().max(1),
            (Some(_), Some(b)) => b,
            (Some(_), None) => units.len().div_ceil(slots).max(1),
        };
        let batches: Vec<&[(Option<String>, String)]> = units.chunks(per_step).collect();
        let job_dir = ctx.store.tmp_dir("slurm")?;
        let outcomes: Vec<Result<(), EngineError>> = batches
            .par_iter()
            .enumerate()
            .map(|(i, batch)| {
                let job = StepJob {
                    config: ctx.pipeline.config_path.clone(),
                    data: Some(ctx.pipeline.data_dir.clone()),
                    reports: Some(ctx.pipeline.reports_dir.clone()),
                    stage: spec.name.clone(),
                    code: ctx.catalog.fingerprint(&spec.kind).to_string(),
                    seed,
                    inputs: inputs.clone(),
                    units: batch
                        .iter()
                        .map(|(item, key)| StepUnit {
                            item: item.clone(),
                            key: key.clone(),
                        })
                        .collect(),
                };
                let file = job_dir.join(format!("step-{i}.json"));
                job.write(&file)?;
                let argv = vec![
                    self.program.display().to_string(),
                    "slurm-step".to_string(),
                    file.display().to_string(),
                ];
                let name = format!("groove:{}", spec.name);
                self.allocations
                    .run_step(&resources, &name, &argv)
                    .map_err(|e| step_error(spec, e))
            })
            .collect();
        let _ = std::fs::remove_dir_all(&job_dir);
        let mut failed_batch = vec![None; batches.len()];
        for (i, o) in outcomes.into_iter().enumerate() {
            if let Err(e) = o {
                failed_batch[i] = Some(e.to_string());
                if matches!(e, EngineError::Usage(_)) {
                    return Err(e);
                }
            }
        }
        // a step exits after its atomic commits: the entries are there, or the step failed
        let mut results = Vec::with_capacity(units.len());
        for (i, batch) in batches.iter().enumerate() {
            for (item, key) in batch.iter() {
                results.push(match (ctx.store.entry(key), &failed_batch[i]) {
                    (Some(entry), _) => Ok(entry),
                    (None, Some(msg)) => Err(EngineError::StageFailed {
                        stage: spec.name.clone(),
                        item: item.clone(),
                        message: msg.clone(),
                    }),
                    (None, None) => Err(EngineError::StageFailed {
                        stage: spec.name.clone(),
                        item: item.clone(),
                        message: "its slurm job step exited 0 but committed no store entry; is the project on a filesystem the compute nodes share?".into(),
                    }),
                });
            }
        }
        Ok(results)
    }
}

/// The same error again (every unit of a stage whose steps could not run gets it).
fn e_clone(e: &EngineError) -> EngineError {
    match e {
        EngineError::StageFailed { stage, item, message } => EngineError::StageFailed {
            stage: stage.clone(),
            item: item.clone(),
            message: message.clone(),
        },
        other => EngineError::Usage(other.to_string()),
    }
}

fn step_error(spec: &StageSpec, e: StepError) -> EngineError {
    match e {
        StepError::Failed { job, code, stderr } => EngineError::StageFailed {
            stage: spec.name.clone(),
            item: None,
            message: format!(
                "its slurm job step in allocation {job} exited with code {code}; its stderr ends:\n{}",
                if stderr.is_empty() { "(nothing)".into() } else { stderr }
            ),
        },
        StepError::AllocationEnded { job, detail } => EngineError::Usage(format!(
            "the slurm allocation {job} ended (cancelled, preempted or out of time) while stage `{}` ran{}; run the same command again: the rerun resumes and does only the unfinished work",
            spec.name,
            if detail.is_empty() { String::new() } else { format!(" ({})", detail.replace('\n', "; ")) }
        )),
        StepError::Slurm(m) => EngineError::Usage(m),
    }
}

impl SlurmExecutor {
    /// `slurm: 1 allocation, 57 job steps`.
    pub fn line(&self) -> String {
        use std::sync::atomic::Ordering;
        let taken = self.allocations.taken.load(Ordering::Relaxed);
        let steps = self.allocations.steps.load(Ordering::Relaxed);
        format!(
            "slurm: {taken} allocation{} taken, {steps} job step{}",
            if taken == 1 { "" } else { "s" },
            if steps == 1 { "" } else { "s" }
        )
    }
}
