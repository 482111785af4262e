//! The controller side: turn the keys a stage must run into job steps, run them inside the
//! allocation, and open the entries the steps committed.
//!
//! A stage that is not per-item is one step. A per-item stage's keys are cut into batches (at
//! most `batch` items per step; by default spread over the allocation's CPUs), so a step never
//! carries one tiny item. Steps of independent stages and batches run at the same time; Slurm
//! places them on free CPUs of the allocation (`--exact`).

use super::alloc::{Allocations, StepError};
use super::config::{SlurmConfig, StepResources};
use super::job::{StepJob, StepRunner, StepUnit};
use crate::engine::error::EngineError;
use crate::engine::store::{Entry, Store};
use rayon::prelude::*;

pub struct SlurmExecutor {
    pub config: SlurmConfig,
    pub allocations: Allocations,
    /// The groove binary the steps run (must be reachable from the compute nodes).
    pub program: std::path::PathBuf,
}

impl SlurmExecutor {
    pub fn new(config: SlurmConfig) -> Result<SlurmExecutor, EngineError> {
        let program = std::env::current_exe().map_err(|e| {
            EngineError::Usage(format!(
                "cannot find the groove binary for the job steps: {e}"
            ))
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

    /// Run `job.units` as job steps (batched for per-item stages); one result per unit.
    fn run_all(
        &self,
        store: &Store,
        job: &StepJob,
        per_item: bool,
    ) -> Vec<Result<Entry, EngineError>> {
        match self.try_run(store, job, per_item) {
            Ok(results) => results,
            Err(e) => job.units.iter().map(|_| Err(e_clone(&e))).collect(),
        }
    }

    fn try_run(
        &self,
        store: &Store,
        job: &StepJob,
        per_item: bool,
    ) -> Result<Vec<Result<Entry, EngineError>>, EngineError> {
        let resources = self.resources(&job.stage);
        let cpus = resources.cpus.unwrap_or(1).max(1) as usize;
        let slots = (self.config.allocation.cpus as usize / cpus).max(1);
        let units = &job.units;
        let per_step = match (per_item, resources.batch) {
            (false, _) => units.len().max(1),
            (true, Some(b)) => b,
            (true, None) => units.len().div_ceil(slots).max(1),
        };
        let batches: Vec<&[StepUnit]> = units.chunks(per_step).collect();
        let job_dir = store.tmp_dir("slurm")?;
        let outcomes: Vec<Result<(), EngineError>> = batches
            .par_iter()
            .enumerate()
            .map(|(i, batch)| {
                let step = StepJob {
                    units: batch.to_vec(),
                    ..job.clone()
                };
                let file = job_dir.join(format!("step-{i}.json"));
                step.write(&file)?;
                let argv = vec![
                    self.program.display().to_string(),
                    "slurm-step".to_string(),
                    file.display().to_string(),
                ];
                let name = format!("groove:{}", job.stage);
                self.allocations
                    .run_step(&resources, &name, &argv)
                    .map_err(|e| step_error(&job.stage, e))
            })
            .collect();
        let _ = std::fs::remove_dir_all(&job_dir);
        let mut failed_batch = vec![None; batches.len()];
        for (i, o) in outcomes.into_iter().enumerate() {
            if let Err(e) = o {
                if matches!(e, EngineError::Usage(_)) {
                    return Err(e);
                }
                failed_batch[i] = Some(e.to_string());
            }
        }
        // a step exits after its atomic commits: the entries are there, or the step failed
        let mut results = Vec::with_capacity(units.len());
        for (i, batch) in batches.iter().enumerate() {
            for u in batch.iter() {
                let failed = |message: String| EngineError::StageFailed {
                    stage: job.stage.clone(),
                    item: u.item.clone(),
                    message,
                };
                results.push(match (store.entry(&u.key), &failed_batch[i]) {
                    (Some(entry), _) => Ok(entry),
                    (None, Some(msg)) => Err(failed(msg.clone())),
                    (None, None) => Err(failed("its slurm job step exited 0 but committed no store entry; is the project on a filesystem the compute nodes share?".into())),
                });
            }
        }
        Ok(results)
    }
}

/// The same error again (every unit of a stage whose steps could not run gets it).
fn e_clone(e: &EngineError) -> EngineError {
    match e {
        EngineError::StageFailed {
            stage,
            item,
            message,
        } => EngineError::StageFailed {
            stage: stage.clone(),
            item: item.clone(),
            message: message.clone(),
        },
        other => EngineError::Usage(other.to_string()),
    }
}

fn step_error(stage: &str, e: StepError) -> EngineError {
    match e {
        StepError::Failed { job, code, stderr } => EngineError::StageFailed {
            stage: stage.to_string(),
            item: None,
            message: format!(
                "its slurm job step in allocation {job} exited with code {code}; its stderr ends:\n{}",
                if stderr.is_empty() { "(nothing)".into() } else { stderr }
            ),
        },
        StepError::AllocationEnded { job, detail } => EngineError::Usage(format!(
            "the slurm allocation {job} ended (cancelled, preempted or out of time) while stage `{}` ran{}; run the same command again: the rerun resumes and does only the unfinished work",
            stage,
            if detail.is_empty() { String::new() } else { format!(" ({})", detail.replace('\n', "; ")) }
        )),
        StepError::Slurm(m) => EngineError::Usage(m),
    }
}

impl StepRunner for SlurmExecutor {
    fn run_units(
        &self,
        store: &Store,
        job: &StepJob,
        per_item: bool,
    ) -> Vec<Result<Entry, EngineError>> {
        self.run_all(store, job, per_item)
    }

    fn slots(&self) -> usize {
        self.config.allocation.cpus as usize
    }

    /// Release the allocations; `slurm: 1 allocation taken, 57 job steps`.
    fn finish(&self) -> String {
        use std::sync::atomic::Ordering;
        self.allocations.release();
        let taken = self.allocations.taken.load(Ordering::Relaxed);
        let steps = self.allocations.steps.load(Ordering::Relaxed);
        format!(
            "slurm: {taken} allocation{} taken, {steps} job step{}",
            if taken == 1 { "" } else { "s" },
            if steps == 1 { "" } else { "s" }
        )
    }
}
