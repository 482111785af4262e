//! Walking the DAG: hash inputs, compute keys, look them up in the store, run what is missing.
//!
//! Stages are visited in waves of the topological order; the stages of one wave (and the items
//! of a per-item stage) run in parallel on the rayon pool. Keys are computed from the content of
//! upstream outputs, so a stage rerun with byte-identical output leaves its descendants fresh
//! (early cutoff), and a key seen before is found in the store without running (run-cache).

use super::catalog::Catalog;
use super::dag;
use super::error::EngineError;
use super::execute::{execute, load_shared, Bound, Source};
use super::hashing::{sha256_hex, HashCache};
use super::inputs::hash_path;
use super::key::{items_digest, StageKey};
use super::lockfile::{LockStage, PipelineLock};
use super::materialize::{is_current, materialize};
use super::pipeline::{InputSpec, Pipeline, StageSpec};
use super::progress::Progress;
use super::provenance;
use super::store::{Entry, Store, Stored};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

/// Everything one evaluation needs.
pub struct Context<'a> {
    pub catalog: &'a Catalog,
    pub pipeline: &'a Pipeline,
    pub store: Store,
    pub hashes: HashCache,
    /// `pipeline.lock` as it was before this evaluation.
    pub lock: PipelineLock,
    pub progress: Progress,
    /// The shared remote cache, looked up after the local store (`None`: local only).
    pub remote: Option<std::sync::Arc<super::remote::RemoteCache>>,
    /// Uploads each local commit to the remote (`None`: no remote, or read-only).
    pub pusher: Option<super::remote::push::Pusher>,
    /// Runs the keys that must run elsewhere, as Slurm job steps (`None`: on this machine).
    pub steps: Option<Box<dyn super::slurm::job::StepRunner>>,
}

impl<'a> Context<'a> {
    pub fn new(catalog: &'a Catalog, pipeline: &'a Pipeline, progress: Progress) -> Context<'a> {
        let store = Store::at(&pipeline.root);
        let hashes = HashCache::load(&store.dir.join("hashes.json"));
        Context {
            catalog,
            pipeline,
            store,
            hashes,
            lock: PipelineLock::load(&lock_path(pipeline)),
            progress,
            remote: None,
            pusher: None,
            steps: None,
        }
    }
}

pub fn lock_path(pipeline: &Pipeline) -> std::path::PathBuf {
    pipeline.root.join("pipeline.lock")
}

/// What to do with one stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Only find out whether it is fresh.
    Check,
    /// Run what is missing from the store (everything if `force`), then write its outputs.
    Run { force: bool },
}

/// What became of one stage.
#[derive(Debug, Default)]
pub struct Evaluated {
    /// The key and its parts; `None` while an upstream stage's outputs are unknown.
    pub current: Option<LockStage>,
    /// Upstream stages whose outputs are unknown.
    pub waiting_on: Vec<String>,
    /// While waiting: the key parts known without the inputs (kind, params, cmd, code, seed).
    pub pending: Option<LockStage>,
    /// Every key has a complete entry in the store, so `current.outputs` is known.
    pub complete: bool,
    /// Keys that had no entry when the evaluation began (item names; `None` = the whole stage).
    pub missing: Vec<Option<String>>,
    /// Keys run in this evaluation.
    pub executed: usize,
    /// Outputs whose materialized path does not hold the stored content.
    pub stale_outputs: Vec<String>,
    pub failed: bool,
}

/// The seed a stage receives: the pipeline seed mixed with the stage name.
pub fn stage_seed(seed: u64, stage: &str) -> u64 {
    let h = sha256_hex(stage.as_bytes());
    seed ^ u64::from_str_radix(&h[..16], 16).expect("hex digits")
}

/// Evaluate the selected stages wave by wave. Failed stages are reported and their
/// descendants wait; independent stages still complete.
/// `after_wave` sees the results so far and the names in the wave just done (the runner saves
/// `pipeline.lock` there).
pub fn evaluate(
    ctx: &Context,
    selected: &BTreeSet<String>,
    action: impl Fn(&str) -> Action + Sync,
    mut after_wave: impl FnMut(&BTreeMap<String, Evaluated>, &[String]),
) -> (BTreeMap<String, Evaluated>, Vec<EngineError>) {
    let waves = dag::order(ctx.pipeline).expect("validated pipelines have no cycle");
    let mut done: BTreeMap<String, Evaluated> = BTreeMap::new();
    let mut errors = Vec::new();
    for wave in waves {
        let results: Vec<(String, Result<Evaluated, EngineError>)> = wave
            .par_iter()
            .filter(|s| selected.contains(*s))
            .map(|s| {
                (
                    s.clone(),
                    evaluate_stage(ctx, &ctx.pipeline.stages[s], &done, action(s)),
                )
            })
            .collect();
        for (stage, result) in results {
            match result {
                Ok(e) => {
                    done.insert(stage, e);
                }
                Err(e) => {
                    errors.push(e);
                    done.insert(
                        stage,
                        Evaluated {
                            failed: true,
                            ..Evaluated::default()
                        },
                    );
                }
            }
        }
        after_wave(&done, &wave);
    }
    (done, errors)
}

fn evaluate_stage(
    ctx: &Context,
    spec: &StageSpec,
    done: &BTreeMap<String, Evaluated>,
    action: Action,
) -> Result<Evaluated, EngineError> {
    let started = Instant::now();
    let pipeline = ctx.pipeline;
    let mut bound: BTreeMap<String, Bound> = BTreeMap::new();
    let mut waiting = BTreeSet::new();
    for (name, input) in &spec.inputs {
        match input {
            InputSpec::Path { path, optional } => {
                if !path.exists() {
                    if *optional {
                        continue;
                    }
                    return Err(EngineError::Usage(format!(
                        "stage `{}` input `{name}`: {} does not exist; restore it or fix pipeline.toml",
                        spec.name,
                        pipeline.show(path)
                    )));
                }
                let stored = hash_path(path, &ctx.hashes)?;
                bound.insert(
                    name.clone(),
                    Bound {
                        stored,
                        source: Source::Path(path.clone()),
                    },
                );
            }
            InputSpec::Stage { stage, output } => {
                match done
                    .get(stage)
                    .filter(|e| e.complete)
                    .and_then(|e| e.current.as_ref())
                {
                    Some(up) => {
                        let stored = up.outputs[output].clone();
                        bound.insert(
                            name.clone(),
                            Bound {
                                stored,
                                source: Source::Store,
                            },
                        );
                    }
                    None => {
                        waiting.insert(stage.clone());
                    }
                }
            }
            InputSpec::Provenance => {}
        }
    }
    let code = ctx.catalog.fingerprint(&spec.kind);
    let seed = stage_seed(pipeline.seed, &spec.name);
    let parts = |inputs: BTreeMap<String, Stored>| LockStage {
        kind: spec.kind.clone(),
        key: String::new(),
        code: code.to_string(),
        groove_version: ctx.catalog.version.clone(),
        seed,
        params: spec.canonical_params.clone(),
        cmd: spec.cmd.clone(),
        inputs,
        outputs: BTreeMap::new(),
        items: BTreeMap::new(),
    };
    if !waiting.is_empty() {
        return Ok(Evaluated {
            waiting_on: waiting.into_iter().collect(),
            pending: Some(parts(BTreeMap::new())),
            ..Evaluated::default()
        });
    }
    for (name, input) in &spec.inputs {
        if *input == InputSpec::Provenance {
            let bytes = provenance::record(ctx, spec, done);
            let stored = Stored::File {
                sha256: sha256_hex(&bytes),
            };
            bound.insert(
                name.clone(),
                Bound {
                    stored,
                    source: Source::Memory(bytes),
                },
            );
        }
    }

    let digests: BTreeMap<String, String> = bound
        .iter()
        .map(|(n, b)| (n.clone(), b.stored.digest()))
        .collect();
    let key_of = |inputs: &BTreeMap<String, String>, item: Option<&str>| {
        StageKey {
            kind: &spec.kind,
            params: &spec.canonical_params,
            cmd: spec.cmd.as_deref(),
            inputs,
            outputs: spec.outputs.keys().map(String::as_str).collect(),
            item,
            seed,
            groove_version: &ctx.catalog.version,
            code,
        }
        .digest()
    };
    let units: Vec<(Option<String>, String)> = match &spec.foreach {
        None => vec![(None, key_of(&digests, None))],
        Some(f) => {
            // every per-item input (present) as item → hash; the first one names the items
            let mut per_item: Vec<(&String, &BTreeMap<String, String>)> = Vec::new();
            for name in std::iter::once(f).chain(&spec.foreach_with) {
                match bound.get(name).map(|b| &b.stored) {
                    None => {}
                    Some(Stored::Collection { items }) => per_item.push((name, items)),
                    Some(Stored::File { .. }) => {
                        return Err(EngineError::StageFailed {
                            stage: spec.name.clone(),
                            item: None,
                            message: format!(
                                "foreach input `{name}` is a single file; bind it to a folder or to a per-item output"
                            ),
                        })
                    }
                }
            }
            match per_item.first() {
                Some((first, items)) if *first == f => {
                    let mut units = Vec::new();
                    for item in items.keys() {
                        let mut d = digests.clone();
                        for (name, items) in &per_item {
                            let Some(h) = items.get(item) else {
                                return Err(EngineError::StageFailed {
                                    stage: spec.name.clone(),
                                    item: Some(item.clone()),
                                    message: format!(
                                        "per-item input `{name}` has no item `{item}`; the inputs in `foreach` must have the same items"
                                    ),
                                });
                            };
                            d.insert((*name).clone(), h.clone());
                        }
                        units.push((Some(item.clone()), key_of(&d, Some(item))));
                    }
                    units
                }
                // the primary per-item input is an absent optional input: no items
                _ => Vec::new(),
            }
        }
    };

    let mut entries: Vec<Option<Entry>> = units
        .par_iter()
        .map(|(_, k)| super::remote::lookup(&ctx.store, ctx.remote.as_deref(), k))
        .collect();
    let missing: Vec<Option<String>> = units
        .iter()
        .zip(&entries)
        .filter(|(_, e)| e.is_none())
        .map(|((item, _), _)| item.clone())
        .collect();
    let mut executed = 0;
    if let Action::Run { force } = action {
        let todo: Vec<usize> = (0..units.len())
            .filter(|&i| force || entries[i].is_none())
            .collect();
        if !todo.is_empty() {
            ctx.progress.started(&spec.name, todo.len());
            let results: Vec<Result<Entry, EngineError>> = if let Some(runner) = &ctx.steps {
                let units: Vec<(Option<String>, String)> =
                    todo.iter().map(|&i| units[i].clone()).collect();
                let job = step_job(ctx, spec, &bound, &units, seed)?;
                runner.run_units(&ctx.store, &job, spec.foreach.is_some())
            } else {
            let shared = load_shared(ctx, spec, &bound)?;
            let finished = std::sync::atomic::AtomicUsize::new(0);
            todo
                .par_iter()
                .map(|&i| {
                    let (item, key) = (units[i].0.as_deref(), &units[i].1);
                    let result = execute(ctx, spec, &bound, &shared, item, key, seed);
                    if spec.foreach.is_some() {
                        let n = finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                        ctx.progress.item_done(&spec.name, n, todo.len());
                    }
                    result
                })
                .collect()
            };
            // every committed key is pushed, even when another key of the stage failed
            let mut first_error = None;
            for (&i, r) in todo.iter().zip(results) {
                match r {
                    Ok(entry) => {
                        if let Some(p) = &ctx.pusher {
                            p.submit(&units[i].1, &entry);
                        }
                        entries[i] = Some(entry);
                        executed += 1;
                    }
                    Err(e) => {
                        first_error.get_or_insert(e);
                    }
                }
            }
            if let Some(e) = first_error {
                return Err(e);
            }
        }
    }

    let complete = entries.iter().all(Option::is_some);
    let mut outputs = BTreeMap::new();
    if complete {
        let entries: Vec<&Entry> = entries.iter().flatten().collect();
        for name in spec.outputs.keys() {
            let stored = match &spec.foreach {
                None => entries[0].outputs[name].clone(),
                Some(_) => Stored::Collection {
                    items: units
                        .iter()
                        .zip(&entries)
                        .map(|((item, _), e)| match &e.outputs[name] {
                            Stored::File { sha256 } => Ok((item.clone().unwrap_or_default(), sha256.clone())),
                            Stored::Collection { .. } => Err(EngineError::Usage(format!(
                                "store entry of stage `{}` holds a collection per item; run `groove clean`",
                                spec.name
                            ))),
                        })
                        .collect::<Result<_, _>>()?,
                },
            };
            outputs.insert(name.clone(), stored);
        }
    }
    let items: BTreeMap<String, String> = units
        .iter()
        .filter_map(|(item, k)| item.clone().map(|i| (i, k.clone())))
        .collect();
    let key = match &spec.foreach {
        None => units[0].1.clone(),
        Some(_) => items_digest(&items),
    };
    let current = LockStage {
        key,
        outputs,
        items,
        ..parts(bound.into_iter().map(|(n, b)| (n, b.stored)).collect())
    };

    let mut stale_outputs = Vec::new();
    if complete {
        for (name, path) in &spec.outputs {
            let Some(path) = path else { continue };
            let stored = &current.outputs[name];
            match action {
                Action::Run { .. } => {
                    materialize(&ctx.store, path, stored, &ctx.hashes)?;
                }
                Action::Check => {
                    if !is_current(path, stored, &ctx.hashes) {
                        stale_outputs.push(name.clone());
                    }
                }
            }
        }
    }
    if let Action::Run { .. } = action {
        let secs = started.elapsed().as_secs_f64();
        let what = match (executed, units.len()) {
            (0, _) => format!("reused ({secs:.2} s)"),
            (n, total) if spec.foreach.is_some() => {
                format!("ran {n} of {total} items in {secs:.2} s")
            }
            _ => format!("ran in {secs:.2} s"),
        };
        ctx.progress.finished(&spec.name, &what);
    }
    Ok(Evaluated {
        current: Some(current),
        waiting_on: Vec::new(),
        pending: None,
        complete,
        missing,
        executed,
        stale_outputs,
        failed: false,
    })
}

/// What a job step elsewhere needs to run `units` of a stage: the pipeline and overrides, the
/// inputs (project paths, or store blobs; engine-made bytes are put in the store first).
fn step_job(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, super::execute::Bound>,
    units: &[(Option<String>, String)],
    seed: u64,
) -> Result<super::slurm::job::StepJob, EngineError> {
    use super::execute::Source;
    use super::slurm::job::{StepInput, StepJob, StepUnit};
    let mut inputs = BTreeMap::new();
    for (name, b) in bound {
        let path = match &b.source {
            Source::Path(p) => Some(p.clone()),
            Source::Store => None,
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
    Ok(StepJob {
        config: ctx.pipeline.config_path.clone(),
        data: Some(ctx.pipeline.data_dir.clone()),
        reports: Some(ctx.pipeline.reports_dir.clone()),
        stage: spec.name.clone(),
        code: ctx.catalog.fingerprint(&spec.kind).to_string(),
        seed,
        inputs,
        units: units
            .iter()
            .map(|(item, key)| StepUnit {
                item: item.clone(),
                key: key.clone(),
            })
            .collect(),
    })
}
