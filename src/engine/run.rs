//! `groove run`: take the project lock, run what is stale, write outputs, update `pipeline.lock`.

use super::catalog::Catalog;
use super::dag;
use super::error::{EngineError, IoContext};
use super::context::{lock_path, Context};
use super::evaluate::{evaluate, Action};
use super::pipeline::Pipeline;
use super::progress::Progress;
use super::project_lock;
use super::status::{self, StageStatus, State};
use std::collections::BTreeSet;
use std::io::Write;

#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Stages to bring up to date (with what they need); empty = all.
    pub targets: Vec<String>,
    /// Stages to run even when their result is in the store.
    pub force: Vec<String>,
    /// Worker threads; `None` = one per core.
    pub jobs: Option<usize>,
    /// Only say what would run.
    pub dry_run: bool,
    /// Print no progress (library use, tests).
    pub quiet: bool,
}

#[derive(Debug, Clone, Default)]
pub struct RunSummary {
    /// Stages that executed at least one key.
    pub ran: Vec<String>,
    /// Stages whose results all came from the store.
    pub reused: Vec<String>,
    /// For `--dry-run`: the stale stages and why.
    pub would_run: Vec<StageStatus>,
    pub elapsed_s: f64,
}

fn check_names(pipeline: &Pipeline, names: &[String]) -> Result<(), EngineError> {
    for n in names {
        if !pipeline.stages.contains_key(n) {
            return Err(EngineError::Usage(format!(
                "no stage `{n}` in {}; stages: {}",
                pipeline.show(&pipeline.config_path),
                pipeline
                    .stages
                    .keys()
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    Ok(())
}

pub fn run(
    catalog: &Catalog,
    pipeline: &Pipeline,
    opts: &RunOptions,
) -> Result<RunSummary, EngineError> {
    check_names(pipeline, &opts.targets)?;
    check_names(pipeline, &opts.force)?;
    let selected: BTreeSet<String> = if opts.targets.is_empty() {
        pipeline.stages.keys().cloned().collect()
    } else {
        dag::with_ancestors(pipeline, &opts.targets)
    };
    let force: BTreeSet<&str> = opts.force.iter().map(String::as_str).collect();
    if opts.dry_run {
        let statuses = status::status(catalog, pipeline, Some(&selected))?;
        return Ok(RunSummary {
            would_run: statuses
                .into_iter()
                .filter(|s| s.state == State::Stale || force.contains(s.stage.as_str()))
                .collect(),
            ..RunSummary::default()
        });
    }
    let progress = Progress::new(selected.len() as u64, opts.quiet);
    let store_dir = pipeline.root.join(".groove");
    let _lock = project_lock::acquire(&store_dir, |holder| {
        progress.note(&format!(
            "another groove run holds this project ({holder}); waiting for it to finish"
        ))
    })?;
    // read pipeline.lock only now that no other run can be writing it
    let ctx = Context::new(catalog, pipeline, progress);
    ctx.store.sweep_tmp()?;
    // temp files of a killed run's atomic writes
    super::materialize::sweep_leftovers(&pipeline.root, "pipeline.lock")?;
    super::materialize::sweep_leftovers(&store_dir, "hashes.json")?;
    let jobs = opts
        .jobs
        .unwrap_or_else(|| {
            std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1)
        })
        .max(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| {
            EngineError::Usage(format!(
                "cannot start {jobs} worker threads: {e}; try a smaller --jobs"
            ))
        })?;
    // the lock is saved after waves that ran something (at most once a second after the first
    // time) and at the end, so a killed run loses little bookkeeping and never corrupts it
    let mut lock = ctx.lock.clone();
    let mut last_save: Option<std::time::Instant> = None;
    let mut save_error = None;
    let (done, errors) = pool.install(|| {
        evaluate(
            &ctx,
            &selected,
            |s| Action::Run {
                force: force.contains(s),
            },
            |done, wave| {
                let ran = record(&mut lock, done, wave.iter());
                let due = last_save.is_none_or(|t| t.elapsed().as_secs_f64() >= 1.0);
                if ran && due && save_error.is_none() {
                    save_error = lock.save(&lock_path(pipeline)).err();
                    last_save = Some(std::time::Instant::now());
                }
            },
        )
    });
    if let Some(e) = save_error {
        return Err(e);
    }
    record(&mut lock, &done, done.keys());
    lock.stages
        .retain(|name, _| pipeline.stages.contains_key(name));
    lock.save(&lock_path(pipeline))?;
    let mut summary = RunSummary::default();
    for (name, ev) in &done {
        if ev.complete && ev.current.is_some() {
            if ev.executed > 0 {
                summary.ran.push(name.clone());
            } else {
                summary.reused.push(name.clone());
            }
        }
    }
    ctx.hashes.save()?;
    ctx.progress.finish();
    summary.elapsed_s = ctx.progress.start.elapsed().as_secs_f64();

    let mut log = ctx.progress.lines();
    log.push(format!(
        "run: {} ran, {} reused, {} failed, {:.3} s",
        summary.ran.len(),
        summary.reused.len(),
        errors.len(),
        summary.elapsed_s
    ));
    append_log(&store_dir.join("run.log"), &log)?;

    let mut errors = errors.into_iter();
    if let Some(first) = errors.next() {
        for e in errors {
            ctx.progress.note(&format!("error: {e}"));
        }
        return Err(first);
    }
    Ok(summary)
}

/// Put the named completed stages into the lock; true when one of them ran something.
fn record<'a>(
    lock: &mut super::lockfile::PipelineLock,
    done: &std::collections::BTreeMap<String, super::context::Evaluated>,
    names: impl Iterator<Item = &'a String>,
) -> bool {
    let mut ran = false;
    for name in names {
        let Some(ev) = done.get(name) else { continue };
        if let (true, Some(current)) = (ev.complete, &ev.current) {
            if lock.stages.get(name) != Some(current) {
                lock.stages.insert(name.clone(), current.clone());
                ran |= ev.executed > 0;
            }
        }
    }
    ran
}

fn append_log(path: &std::path::Path, lines: &[String]) -> Result<(), EngineError> {
    let mut f = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .at(path)?;
    let mut text = lines.join("\n");
    text.push('\n');
    f.write_all(text.as_bytes()).at(path)
}
