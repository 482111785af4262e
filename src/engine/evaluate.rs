//! Walking the DAG: hash inputs, compute keys, look them up in the store, run what is missing.
//!
//! Stages are visited in waves of the topological order; the stages of one wave (and the items
//! of a per-item stage) run in parallel on the rayon pool. Keys are computed from the content of
//! upstream outputs, so a stage rerun with byte-identical output leaves its descendants fresh
//! (early cutoff), and a key seen before is found in the store without running (run-cache).

use super::context::{Context, Evaluated};
use super::dag;
use super::error::EngineError;
use super::execute::{execute, load_shared, run_key, store_outputs, Bound, Source};
use super::hash_on_read;
use super::hashing::sha256_hex;
use super::inputs::hash_path;
use super::key::{items_digest, ItemKeys, StageKey};
use super::lockfile::LockStage;
use super::materialize::is_current;
use super::pack_writer::PackWriter;
use super::pipeline::{InputSpec, StageSpec};
use super::provenance;
use super::store::{Entry, Stored};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet};
use std::time::Instant;

/// What to do with one stage.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Action {
    /// Only find out whether it is fresh.
    Check,
    /// Run what is missing from the store (everything if `force`), then write its outputs.
    Run { force: bool },
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

/// One stage: bind its inputs, compute its keys, run what is missing (when asked), then write or
/// check its outputs.
fn evaluate_stage(
    ctx: &Context,
    spec: &StageSpec,
    done: &BTreeMap<String, Evaluated>,
    action: Action,
) -> Result<Evaluated, EngineError> {
    let started = Instant::now();
    let seed = stage_seed(ctx.pipeline.seed, &spec.name);
    let defer = matches!(action, Action::Run { .. }) && hash_on_read::allowed(ctx, spec);
    let (mut bound, waiting, unhashed) = bind_inputs(ctx, spec, done, defer)?;
    if !waiting.is_empty() {
        return Ok(Evaluated {
            waiting_on: waiting.into_iter().collect(),
            pending: Some(key_parts(ctx, spec, seed, BTreeMap::new())),
            ..Evaluated::default()
        });
    }
    bind_provenance(ctx, spec, done, &mut bound);
    // a streamed input new to the hash cache: the stage runs first and hashes it as it reads
    let ran_first = match unhashed.is_empty() {
        true => None,
        false => Some(hash_on_read::run_first(
            ctx, spec, &mut bound, unhashed, seed,
        )?),
    };
    let units = unit_keys(ctx, spec, &bound, seed)?;
    // ...and its outputs are committed under the key made from what it read
    let (action, ran_first) = match ran_first {
        Some(outputs) => {
            ctx.store.commit(&units[0].1, outputs)?;
            (Action::Run { force: false }, 1)
        }
        None => (action, 0),
    };
    let items: BTreeMap<String, String> = units
        .iter()
        .filter_map(|(item, k)| item.clone().map(|i| (i, k.clone())))
        .collect();
    let key = match &spec.foreach {
        None => units[0].1.clone(),
        Some(_) => items_digest(&items),
    };
    // a per-item stage whose every item was committed before: its one index entry (item keys
    // → outputs) is read instead of one entry per item
    let force = matches!(action, Action::Run { force: true });
    let index = (spec.foreach.is_some() && !units.is_empty() && !force)
        .then(|| ctx.store.entry_checked(&key, &ctx.hashes))
        .flatten()
        .filter(|e| e.fits(spec.outputs.keys(), Some(false)));
    let Units {
        outputs,
        executed,
        complete,
        missing,
    } = match index {
        Some(index) => Units {
            outputs: index.outputs,
            executed: 0,
            complete: true,
            missing: Vec::new(),
        },
        None => lookup_or_run(ctx, spec, &bound, &units, &key, action, seed)?,
    };
    let executed = executed + ran_first;
    let current = LockStage {
        key,
        outputs,
        items,
        ..key_parts(
            ctx,
            spec,
            seed,
            bound.into_iter().map(|(n, b)| (n, b.stored)).collect(),
        )
    };
    let stale_outputs = if complete {
        write_or_check_outputs(ctx, spec, &current, action)?
    } else {
        Vec::new()
    };
    if let Action::Run { .. } = action {
        report_finished(ctx, spec, started, executed, units.len());
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

/// What a stage's units came to: the stage's outputs (when every unit has an entry), how many
/// ran, and the items still without an entry.
struct Units {
    outputs: BTreeMap<String, Stored>,
    executed: usize,
    complete: bool,
    missing: Vec<Option<String>>,
}

/// Look every unit up (store, then remote), run the missing ones (all with `force`), and, once
/// every item of a per-item stage is committed, write the stage's index entry under `key` —
/// after the items' own entries, so a kill leaves either no index or a complete one.
fn lookup_or_run(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
    units: &[(Option<String>, String)],
    key: &str,
    action: Action,
    seed: u64,
) -> Result<Units, EngineError> {
    // an entry holds exactly the declared outputs (per item, each a file); any other is damage
    let files = spec.foreach.as_ref().map(|_| true);
    let fits = |e: &Entry| e.fits(spec.outputs.keys(), files);
    let mut entries: Vec<Option<Entry>> = units
        .par_iter()
        .map(|(_, k)| {
            let remote = ctx.remote.as_deref();
            super::remote::lookup(&ctx.store, &ctx.hashes, remote, k, &fits)
        })
        .collect();
    // the entry packs read for these lookups are not needed while the stage runs
    ctx.store.forget_entry_packs();
    let missing: Vec<Option<String>> = units
        .iter()
        .zip(&entries)
        .filter(|(_, e)| e.is_none())
        .map(|((item, _), _)| item.clone())
        .collect();
    let executed = match action {
        Action::Run { force } => run_units(ctx, spec, bound, units, &mut entries, force, seed)?,
        Action::Check => 0,
    };
    let complete = entries.iter().all(Option::is_some);
    let outputs = if complete {
        let entries: Vec<&Entry> = entries.iter().flatten().collect();
        gather_outputs(spec, units, &entries)?
    } else {
        BTreeMap::new()
    };
    if complete && spec.foreach.is_some() && !units.is_empty() {
        if let Action::Run { .. } = action {
            ctx.store.commit(key, outputs.clone())?;
        }
    }
    Ok(Units {
        outputs,
        executed,
        complete,
        missing,
    })
}

/// Bind every path input (hashed) and every upstream output that is known; the second value
/// names the upstream stages whose outputs are not known yet, the third the streamed path
/// inputs left unhashed for the stage to hash as it reads them (only if `defer`).
fn bind_inputs(
    ctx: &Context,
    spec: &StageSpec,
    done: &BTreeMap<String, Evaluated>,
    defer: bool,
) -> Result<BoundInputs, EngineError> {
    let mut bound: BTreeMap<String, Bound> = BTreeMap::new();
    let mut waiting = BTreeSet::new();
    let mut unhashed = Vec::new();
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
                        ctx.pipeline.show(path)
                    )));
                }
                if defer && hash_on_read::streamed(ctx, spec, name) {
                    if let Some(u) = hash_on_read::unhashed(ctx, name, path)? {
                        unhashed.push(u);
                        continue;
                    }
                }
                let stored = hash_path(path, &ctx.hashes)?;
                let source = Source::Path(path.clone());
                bound.insert(name.clone(), Bound { stored, source });
            }
            InputSpec::Stage { stage, output } => {
                let upstream = done
                    .get(stage)
                    .filter(|e| e.complete)
                    .and_then(|e| e.current.as_ref());
                match upstream {
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
    Ok((bound, waiting, unhashed))
}

/// `bind_inputs`' answer: the bound inputs, the stages waited on, the inputs left unhashed.
type BoundInputs = (
    BTreeMap<String, Bound>,
    BTreeSet<String>,
    Vec<hash_on_read::Unhashed>,
);

/// Bind the `engine:provenance` inputs (made once every upstream stage is known).
fn bind_provenance(
    ctx: &Context,
    spec: &StageSpec,
    done: &BTreeMap<String, Evaluated>,
    bound: &mut BTreeMap<String, Bound>,
) {
    for (name, input) in &spec.inputs {
        if *input == InputSpec::Provenance {
            let bytes = provenance::record(ctx, spec, done);
            let stored = Stored::File {
                sha256: sha256_hex(&bytes),
            };
            let source = Source::Memory(bytes);
            bound.insert(name.clone(), Bound { stored, source });
        }
    }
}

/// The key parts known without the outputs: kind, code, version, seed, params, cmd and `inputs`.
fn key_parts(
    ctx: &Context,
    spec: &StageSpec,
    seed: u64,
    inputs: BTreeMap<String, Stored>,
) -> LockStage {
    LockStage {
        kind: spec.kind.clone(),
        key: String::new(),
        code: ctx.catalog.fingerprint(&spec.kind).to_string(),
        groove_version: ctx.catalog.version.clone(),
        seed,
        params: spec.canonical_params.clone(),
        cmd: spec.cmd.clone(),
        inputs,
        outputs: BTreeMap::new(),
        items: BTreeMap::new(),
    }
}

/// The keys to look up: one for the whole stage, or one per item of a per-item stage.
fn unit_keys(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
    seed: u64,
) -> Result<Vec<(Option<String>, String)>, EngineError> {
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
            code: ctx.catalog.fingerprint(&spec.kind),
        }
        .digest()
    };
    let Some(f) = &spec.foreach else {
        return Ok(vec![(None, key_of(&digests, None))]);
    };
    let per_item = per_item_inputs(spec, bound)?;
    // the primary per-item input is an absent optional input: no items
    let Some((_, items)) = per_item.first().filter(|(first, _)| *first == f) else {
        return Ok(Vec::new());
    };
    let item_keys = ItemKeys::new(&StageKey {
        kind: &spec.kind,
        params: &spec.canonical_params,
        cmd: spec.cmd.as_deref(),
        inputs: &digests,
        outputs: spec.outputs.keys().map(String::as_str).collect(),
        item: None,
        seed,
        groove_version: &ctx.catalog.version,
        code: ctx.catalog.fingerprint(&spec.kind),
    });
    let mut units = Vec::with_capacity(items.len());
    let mut d = digests.clone();
    for item in items.keys() {
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
        units.push((Some(item.clone()), item_keys.digest(&d, Some(item))));
    }
    Ok(units)
}

/// Every per-item input that is present, as (name, item → hash), the `foreach` input first.
fn per_item_inputs<'b>(
    spec: &'b StageSpec,
    bound: &'b BTreeMap<String, Bound>,
) -> Result<Vec<(&'b String, &'b BTreeMap<String, String>)>, EngineError> {
    let mut per_item = Vec::new();
    for name in spec.foreach.iter().chain(&spec.foreach_with) {
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
    Ok(per_item)
}

/// Run the keys without a store entry (every key if `force`), items in parallel; fills
/// `entries` and returns how many keys ran.
fn run_units(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
    units: &[(Option<String>, String)],
    entries: &mut [Option<Entry>],
    force: bool,
    seed: u64,
) -> Result<usize, EngineError> {
    let todo: Vec<usize> = (0..units.len())
        .filter(|&i| force || entries[i].is_none())
        .collect();
    if todo.is_empty() {
        return Ok(0);
    }
    ctx.progress.started(&spec.name, todo.len());
    let results: Vec<Result<Entry, EngineError>> = match &ctx.steps {
        // elsewhere: job steps of a Slurm allocation
        Some(runner) => {
            let units: Vec<(Option<String>, String)> =
                todo.iter().map(|&i| units[i].clone()).collect();
            let job = step_job(ctx, spec, bound, &units, seed)?;
            runner.run_units(&ctx.store, &job, spec.foreach.is_some())
        }
        None => run_here(ctx, spec, bound, units, &todo, seed)?,
    };
    // every committed key is pushed, even when another key of the stage failed
    let mut executed = 0;
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
    match first_error {
        Some(e) => Err(e),
        None => Ok(executed),
    }
}

/// Run keys in this process, items in parallel on the rayon pool. Many items of a per-item
/// stage are run in chunks of `ITEM_CHUNK`: each chunk's blobs go into one pack and its entries
/// into one entry pack (`engine::pack`), so a kill loses at most the chunk being run.
fn run_here(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
    units: &[(Option<String>, String)],
    todo: &[usize],
    seed: u64,
) -> Result<Vec<Result<Entry, EngineError>>, EngineError> {
    let shared = load_shared(ctx, spec, bound)?;
    let finished = std::sync::atomic::AtomicUsize::new(0);
    let done_one = || {
        if spec.foreach.is_some() {
            let n = finished.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            ctx.progress.item_done(&spec.name, n, todo.len());
        }
    };
    if spec.foreach.is_none() || todo.len() < super::pack::PACK_MIN {
        return Ok(todo
            .par_iter()
            .with_max_len(ITEM_GRAIN)
            .map(|&i| {
                let (item, key) = (units[i].0.as_deref(), &units[i].1);
                let result = execute(ctx, spec, bound, &shared, item, key, seed);
                done_one();
                result
            })
            .collect());
    }
    let mut results = Vec::with_capacity(todo.len());
    for chunk in todo.chunks(ITEM_CHUNK) {
        let writer = PackWriter::new(&ctx.store);
        let stored: Vec<Result<BTreeMap<String, Stored>, EngineError>> = chunk
            .par_iter()
            .with_max_len(ITEM_GRAIN)
            .map(|&i| {
                let item = units[i].0.as_deref();
                let outputs = run_key(ctx, spec, bound, &shared, item, seed, &writer);
                done_one();
                store_outputs(&writer, &outputs?)
            })
            .collect();
        writer.finish()?;
        let batch: Vec<(String, BTreeMap<String, Stored>)> = chunk
            .iter()
            .zip(&stored)
            .filter_map(|(&i, r)| r.as_ref().ok().map(|s| (units[i].1.clone(), s.clone())))
            .collect();
        let mut committed = ctx.store.commit_many(batch)?.into_iter();
        results.extend(
            stored
                .into_iter()
                .map(|r| r.map(|_| committed.next().expect("one entry per stored unit"))),
        );
    }
    Ok(results)
}

/// Items of a per-item stage run (and packed) together.
const ITEM_CHUNK: usize = 4096;

/// Items a thread takes at a time. Rayon otherwise splits a range only about as many times as
/// there are threads, and a thread that has begun a quarter of a chunk goes through it alone
/// while the others, out of work, sleep: at 10,000 fits, one core idled 0.15 s at the end of
/// each chunk. A few items at a time leave every one to be stolen.
const ITEM_GRAIN: usize = 4;

/// The stage's outputs from its complete entries: a per-item stage's files gathered into
/// Collections named by item.
fn gather_outputs(
    spec: &StageSpec,
    units: &[(Option<String>, String)],
    entries: &[&Entry],
) -> Result<BTreeMap<String, Stored>, EngineError> {
    let mut outputs = BTreeMap::new();
    for name in spec.outputs.keys() {
        let stored = match &spec.foreach {
            None => entries[0].outputs[name].clone(),
            Some(_) => Stored::Collection {
                items: units
                    .iter()
                    .zip(entries)
                    .map(|((item, _), e)| match &e.outputs[name] {
                        Stored::File { sha256 } => {
                            Ok((item.clone().unwrap_or_default(), sha256.clone()))
                        }
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
    Ok(outputs)
}

/// Name the outputs whose path does not hold the stored content (`Check`). A `Run` writes
/// nothing here: the runner materializes every output together once the whole run succeeded.
fn write_or_check_outputs(
    ctx: &Context,
    spec: &StageSpec,
    current: &LockStage,
    action: Action,
) -> Result<Vec<String>, EngineError> {
    let mut stale_outputs = Vec::new();
    for (name, path) in &spec.outputs {
        let Some(path) = path else { continue };
        let stored = &current.outputs[name];
        match action {
            Action::Run { .. } => {}
            Action::Check if !is_current(path, stored, &ctx.hashes) => {
                stale_outputs.push(name.clone())
            }
            Action::Check => {}
        }
    }
    Ok(stale_outputs)
}

/// The progress line of a stage that was run or reused.
fn report_finished(
    ctx: &Context,
    spec: &StageSpec,
    started: Instant,
    executed: usize,
    total: usize,
) {
    let secs = started.elapsed().as_secs_f64();
    let what = match executed {
        0 => format!("reused ({secs:.2} s)"),
        n if spec.foreach.is_some() => format!("ran {n} of {total} items in {secs:.2} s"),
        _ => format!("ran in {secs:.2} s"),
    };
    ctx.progress.finished(&spec.name, &what);
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
        // the pipeline's own data folder when it has none on disk (a pipeline of command
        // stages): the step resolves the same default, while `--data` must name a folder
        data: ctx
            .pipeline
            .data_dir
            .exists()
            .then(|| ctx.pipeline.data_dir.clone()),
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
