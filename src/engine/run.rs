//! `groove run`: take the project lock, run what is stale, write outputs, update `pipeline.lock`.

use super::catalog::Catalog;
use super::context::{lock_digests_path, lock_path, Context};
use super::dag;
use super::error::{EngineError, IoContext};
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
    /// The shared remote cache to use, if any.
    pub remote: Option<super::remote::Settings>,
    /// Run the stages that must run as Slurm job steps inside one allocation.
    pub slurm: bool,
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
    /// The remote's closing line (hits, misses, errors, requests), when a remote was used.
    pub remote_line: Option<String>,
    pub remote: Option<super::remote::Tally>,
    /// Slurm allocations taken and job steps run, when the Slurm executor was used.
    pub slurm_line: Option<String>,
}

fn check_names(pipeline: &Pipeline, names: &[String]) -> Result<(), EngineError> {
    for n in names {
        if !pipeline.stages.contains_key(n) {
            return Err(pipeline.no_stage(n));
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
    let mut ctx = Context::new(catalog, pipeline, progress);
    ctx.store.sweep_tmp()?;
    attach_backends(&mut ctx, opts)?;
    // temp files of a killed run's atomic writes
    super::materialize::sweep_leftovers(&pipeline.root, "pipeline.lock")?;
    super::materialize::sweep_leftovers(&store_dir, "hashes.json")?;
    super::materialize::sweep_leftovers(&store_dir, super::object_stamps::FILE)?;
    // ...and the outputs a killed run had staged beside their paths but not swapped in
    let outputs = pipeline.stages.values().flat_map(|s| s.outputs.values());
    super::materialize::sweep_leftovers_of(outputs.flatten().map(|p| p.as_path()));
    let pool = worker_pool(&ctx, opts.jobs)?;
    // objects are checked when read, not at lookup; a Slurm step reads them in another process,
    // whose failure would not say which object was damaged, so that executor checks at lookup
    ctx.store.trust_objects = ctx.steps.is_none();
    let (done, errors) = loop {
        let (done, mut errors) = pool.install(|| {
            evaluate(
                &ctx,
                &selected,
                |s| Action::Run {
                    force: force.contains(s),
                },
                |_, _| {},
            )
        });
        if errors.is_empty() {
            if let Err(e) = publish(&ctx, &done) {
                errors.push(e);
            }
        }
        let damaged = damaged_objects(&errors);
        if damaged.is_empty() || !ctx.store.trust_objects {
            break (done, errors);
        }
        // a stage needed an object that is gone or damaged: drop it, check every object this
        // run names at lookup, and run again what made the damaged ones (what the first pass
        // committed is reused)
        for h in &damaged {
            ctx.store.remove_object(h);
        }
        ctx.progress.note(&format!(
            "the store's object {} was missing or damaged: checking every stored object this run names and running again what made it",
            damaged.join(", ")
        ));
        ctx.store.trust_objects = false;
    };
    let mut summary = tally(&done);
    close(&mut ctx, &mut summary, errors.len(), &store_dir)?;
    if let (Some(cache), Some(settings)) = (&ctx.remote, &opts.remote) {
        if settings.required {
            if let Some(first) = cache.first_error() {
                return Err(EngineError::Usage(format!(
                    "the remote {} is required (--remote-required) but failed: {first}; fix it or drop --remote-required",
                    cache.describe()
                )));
            }
        }
    }
    let mut errors = errors.into_iter();
    if let Some(first) = errors.next() {
        for e in errors {
            ctx.progress.note(&format!("error: {e}"));
        }
        return Err(first);
    }
    Ok(summary)
}

/// The objects that `errors` found missing or damaged.
fn damaged_objects(errors: &[EngineError]) -> Vec<String> {
    errors
        .iter()
        .filter_map(|e| match e {
            EngineError::DamagedObject { sha256, .. } => Some(sha256.clone()),
            _ => None,
        })
        .collect()
}

/// The remote cache (and its pusher) and the Slurm executor the options ask for.
fn attach_backends(ctx: &mut Context, opts: &RunOptions) -> Result<(), EngineError> {
    if let Some(settings) = &opts.remote {
        let cache = std::sync::Arc::new(super::remote::open(settings, &ctx.pipeline.root)?);
        if !settings.read_only {
            ctx.pusher = Some(super::remote::push::Pusher::start(
                std::sync::Arc::clone(&cache),
                &ctx.store,
                settings.jobs,
            ));
        }
        ctx.remote = Some(cache);
    }
    if opts.slurm {
        let config = super::slurm::config::load(&ctx.pipeline.config_path)?;
        ctx.steps = Some(Box::new(super::slurm::SlurmExecutor::new(config)?));
    }
    Ok(())
}

/// The worker threads: `jobs`, else one per core (with Slurm, as many as the allocation has CPUs).
fn worker_pool(ctx: &Context, jobs: Option<usize>) -> Result<rayon::ThreadPool, EngineError> {
    let jobs = jobs
        .unwrap_or_else(|| {
            let cores = std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1);
            match &ctx.steps {
                Some(s) => cores.max(s.slots()),
                None => cores,
            }
        })
        .max(1);
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| {
            EngineError::Usage(format!(
                "cannot start {jobs} worker threads: {e}; try a smaller --jobs"
            ))
        })
}

/// Results went to the store as stages finished; the project's outputs and pipeline.lock change
/// only now that every selected stage succeeded (all outputs together, then the lock), so a
/// failed or killed run leaves the last good report whole and the lock as it was.
fn publish(
    ctx: &Context,
    done: &std::collections::BTreeMap<String, super::context::Evaluated>,
) -> Result<(), EngineError> {
    materialize_all(ctx, done)?;
    // unchanged (a no-op): the lock is not read, copied, serialized or compared (6.9 MB at
    // 10,000 runs) when its digests are at hand: each done stage's record is digested instead
    let ran = |name: &String, ev: &super::context::Evaluated| {
        ev.complete && ev.current.is_some() && {
            let current = ev.current.as_ref().expect("checked");
            match &ctx.lock_digests {
                Some(d) => d.get(name) != Some(&super::lock_digests::stage_digest(current)),
                None => ctx.lock().stages.get(name) != Some(current),
            }
        }
    };
    let unchanged = ctx.lock_file_read
        && !done.iter().any(|(name, ev)| ran(name, ev))
        && match &ctx.lock_digests {
            Some(d) => d.keys().all(|name| ctx.pipeline.stages.contains_key(name)),
            None => ctx
                .lock()
                .stages
                .keys()
                .all(|name| ctx.pipeline.stages.contains_key(name)),
        };
    let (lock_file, digests) = (lock_path(ctx.pipeline), lock_digests_path(ctx.pipeline));
    // The digests only spare a later run the lock's parse: a failure to write them (a full
    // disk, a read-only store) costs that run the parse, never a result, so it is not an error;
    // digests left from before name another stamp of the lock and are not used.
    if unchanged {
        // digests taken once, so that the next run that changes nothing reads no lock
        if ctx.lock_digests.is_none() {
            let _ = super::lock_digests::save(&digests, &lock_file, ctx.lock());
        }
        return Ok(());
    }
    // each stage of the pipeline: its record of this run if it completed, else the lock's (the
    // lock's records that are replaced are not copied: at 100,000 runs each is tens of MB)
    let now = |name: &String| {
        done.get(name)
            .filter(|ev| ev.complete)
            .and_then(|ev| ev.current.as_ref())
    };
    // the lock is read (6.9 MB at 10,000 runs) only for a record this run did not make: with
    // its digests at hand, which stages it holds is known without reading it
    let needs_old = ctx.pipeline.stages.keys().any(|name| {
        now(name).is_none()
            && ctx
                .lock_digests
                .as_ref()
                .is_none_or(|d| d.contains_key(name))
    });
    let none = super::lockfile::PipelineLock::default();
    let old = if needs_old { ctx.lock() } else { &none };
    let mut lock = super::lockfile::PipelineLock::default();
    for name in ctx.pipeline.stages.keys() {
        if let Some(stage) = now(name).or_else(|| old.stages.get(name)) {
            lock.stages.insert(name.clone(), stage.clone());
        }
    }
    lock.save(&lock_file)?;
    let _ = super::lock_digests::save(&digests, &lock_file, &lock);
    Ok(())
}

/// Which completed stages ran and which were reused.
fn tally(done: &std::collections::BTreeMap<String, super::context::Evaluated>) -> RunSummary {
    let mut summary = RunSummary::default();
    for (name, ev) in done {
        if ev.complete && ev.current.is_some() {
            if ev.executed > 0 {
                summary.ran.push(name.clone());
            } else {
                summary.reused.push(name.clone());
            }
        }
    }
    summary
}

/// Save the file-hash cache, finish the pusher, the Slurm allocation and the progress line, and
/// append this run's lines to `.groove/run.log`.
fn close(
    ctx: &mut Context,
    summary: &mut RunSummary,
    failed: usize,
    store_dir: &std::path::Path,
) -> Result<(), EngineError> {
    if let Err(e) = ctx.hashes.save() {
        // the cache only spares rehashing: a run whose results are all in place does not fail
        // on it (a full disk would otherwise fail even a no-op)
        eprintln!("groove: warning: the file-hash cache was not saved ({e}); the next run rehashes what it needs");
    }
    ctx.store.save_stamps();
    if let Some(p) = ctx.pusher.take() {
        p.finish();
    }
    if let Some(steps) = ctx.steps.take() {
        summary.slurm_line = Some(steps.finish());
    }
    ctx.progress.finish();
    summary.elapsed_s = ctx.progress.start.elapsed().as_secs_f64();
    if let Some(cache) = &ctx.remote {
        summary.remote_line = Some(cache.closing_line());
        summary.remote = Some(cache.tally());
    }
    let mut log = ctx.progress.lines();
    log.push(format!(
        "run: {} ran, {} reused, {} failed, {:.3} s",
        summary.ran.len(),
        summary.reused.len(),
        failed,
        summary.elapsed_s
    ));
    append_log(&store_dir.join("run.log"), &log)
}

/// Write every output of the completed stages to its path: all are staged beside their paths
/// first (nothing in the project changes if one cannot be), then swapped in one after another.
fn materialize_all(
    ctx: &Context,
    done: &std::collections::BTreeMap<String, super::context::Evaluated>,
) -> Result<(), EngineError> {
    let pipeline = ctx.pipeline;
    let mut staged = Vec::new();
    let mut result = Ok(());
    'stages: for (name, ev) in done {
        let (true, Some(current)) = (ev.complete, &ev.current) else {
            continue;
        };
        for (output, path) in &pipeline.stages[name].outputs {
            let Some(path) = path else { continue };
            let base = if path.starts_with(&pipeline.reports_dir) {
                &pipeline.reports_dir
            } else {
                &pipeline.root
            };
            // what groove wrote at this path before (a folder output replaces only that)
            let was = || {
                let record = ctx.lock().stages.get(name)?;
                record.outputs.get(output).cloned()
            };
            let step = super::materialize::check_no_symlink_below(base, path).and_then(|()| {
                let stored = &current.outputs[output];
                super::materialize::stage(&ctx.store, path, stored, &was, &ctx.hashes)
            });
            match step {
                Ok(Some(s)) => staged.push(s),
                Ok(None) => {}
                Err(e) => {
                    result = Err(e);
                    break 'stages;
                }
            }
        }
    }
    if let Err(e) = result {
        for s in staged {
            s.discard();
        }
        return Err(e);
    }
    for s in staged {
        s.commit()?;
    }
    Ok(())
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
