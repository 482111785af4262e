//! The job-step side: `groove slurm-step FILE` runs the keys the controller wrote into FILE and
//! commits each into the project's store (blobs, then the entry by one rename), then exits.
//! A failing key exits 2 with the error on stderr, which `srun` hands back to the controller.

use super::job::StepJob;
use crate::engine::catalog::Catalog;
use crate::engine::config::{self, Overrides};
use crate::engine::context::Context;
use crate::engine::error::EngineError;
use crate::engine::execute::{execute, load_shared, Bound, Source};
use crate::engine::progress::Progress;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

/// Run one step file. Returns how many keys were committed.
pub fn run_step(catalog: &Catalog, file: &Path) -> Result<usize, EngineError> {
    let job = StepJob::read(file)?;
    let overrides = Overrides {
        data: job.data.clone(),
        reports: job.reports.clone(),
    };
    let pipeline = config::load(&job.config, &overrides, catalog)?;
    let spec = pipeline.stages.get(&job.stage).ok_or_else(|| {
        EngineError::Usage(format!(
            "{} has no stage `{}` any more; do not edit pipeline.toml during a run",
            job.config.display(),
            job.stage
        ))
    })?;
    let code = catalog.fingerprint(&spec.kind);
    if code != job.code {
        return Err(EngineError::Usage(format!(
            "this groove binary has other code for kind `{}` than the controller's; put the same groove binary on the compute nodes",
            spec.kind
        )));
    }
    let ctx = Context::new(catalog, &pipeline, Progress::new(0, true));
    let bound: BTreeMap<String, Bound> = job
        .inputs
        .iter()
        .map(|(name, i)| {
            let source = match &i.path {
                Some(p) => Source::Path(p.clone()),
                None => Source::Store,
            };
            (
                name.clone(),
                Bound {
                    stored: i.stored.clone(),
                    source,
                },
            )
        })
        .collect();
    let shared = load_shared(&ctx, spec, &bound)?;
    let results: Vec<Result<(), EngineError>> = job
        .units
        .par_iter()
        .map(|u| {
            if ctx.store.entry(&u.key).is_some() {
                return Ok(());
            }
            execute(
                &ctx,
                spec,
                &bound,
                &shared,
                u.item.as_deref(),
                &u.key,
                job.seed,
            )
            .map(|_| ())
        })
        .collect();
    let mut done = 0;
    let mut first = None;
    for r in results {
        match r {
            Ok(()) => done += 1,
            Err(e) if first.is_none() => first = Some(e),
            Err(_) => {}
        }
    }
    match first {
        Some(e) => Err(e),
        None => Ok(done),
    }
}
