//! Walking the DAG: hash inputs, compute keys, look them up in the store, run what is missing.
//!
//! Stages are visited in waves of the topological order; the stages of one wave (and the items
//! of a per-item stage) run in parallel on the rayon pool. Keys are computed from the content of
//! upstream outputs, so a stage rerun with byte-identical output leaves its descendants fresh
//! (early cutoff), and a key seen before is found in the store without running (run-cache).

use super::catalog::Catalog;
use super::command;
use super::dag;
use super::error::EngineError;
use super::hashing::{sha256_hex, HashCache};
use super::inputs::{hash_path, load_path};
use super::key::{items_digest, StageKey};
use super::lockfile::{LockStage, PipelineLock};
use super::materialize::{is_current, materialize};
use super::pipeline::{InputSpec, Pipeline, StageSpec};
use super::progress::Progress;
use super::provenance;
use super::stage::{Artifact, StageInput, StageOutputs};
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

/// Where an input's bytes come from.
enum Source {
    Path(std::path::PathBuf),
    Store,
    Memory(Vec<u8>),
}

struct Bound {
    stored: Stored,
    source: Source,
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
        Some(f) => match bound.get(f).map(|b| &b.stored) {
            None => Vec::new(),
            Some(Stored::File { .. }) => {
                return Err(EngineError::StageFailed {
                    stage: spec.name.clone(),
                    item: None,
                    message: format!(
                        "foreach input `{f}` is a single file; bind it to a folder or to a per-item output"
                    ),
                })
            }
            Some(Stored::Collection { items }) => items
                .iter()
                .map(|(item, h)| {
                    let mut d = digests.clone();
                    d.insert(f.clone(), h.clone());
                    (Some(item.clone()), key_of(&d, Some(item)))
                })
                .collect(),
        },
    };

    let mut entries: Vec<Option<Entry>> = units.iter().map(|(_, k)| ctx.store.entry(k)).collect();
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
            let shared = load_shared(ctx, spec, &bound)?;
            let results: Vec<Result<Entry, EngineError>> = todo
                .par_iter()
                .map(|&i| {
                    execute(
                        ctx,
                        spec,
                        &bound,
                        &shared,
                        units[i].0.as_deref(),
                        &units[i].1,
                        seed,
                    )
                })
                .collect();
            for (&i, r) in todo.iter().zip(results) {
                entries[i] = Some(r?);
                executed += 1;
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

/// Load every input except the per-item one.
fn load_shared(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
) -> Result<BTreeMap<String, Artifact>, EngineError> {
    let mut out = BTreeMap::new();
    for (name, b) in bound {
        if spec.foreach.as_deref() == Some(name.as_str()) {
            continue;
        }
        let artifact = match &b.source {
            Source::Path(p) => load_path(p, &b.stored)?,
            Source::Store => ctx.store.load(&b.stored)?,
            Source::Memory(bytes) => Artifact::File(bytes.clone()),
        };
        out.insert(name.clone(), artifact);
    }
    Ok(out)
}

/// Run one key (the whole stage or one item), check its outputs, store them, commit the entry.
fn execute(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
    shared: &BTreeMap<String, Artifact>,
    item: Option<&str>,
    key: &str,
    seed: u64,
) -> Result<Entry, EngineError> {
    let failed = |message: String| EngineError::StageFailed {
        stage: spec.name.clone(),
        item: item.map(str::to_string),
        message,
    };
    let item_artifact = match (&spec.foreach, item) {
        (Some(f), Some(item)) => {
            let b = &bound[f];
            let Stored::Collection { items } = &b.stored else {
                unreachable!("checked above")
            };
            let bytes = match &b.source {
                Source::Path(dir) => {
                    let p = dir.join(item);
                    let bytes = std::fs::read(&p).map_err(|e| EngineError::io(&p, e))?;
                    if sha256_hex(&bytes) != items[item] {
                        return Err(EngineError::Usage(format!(
                            "{} changed while groove was running; run again",
                            p.display()
                        )));
                    }
                    bytes
                }
                _ => ctx.store.read_object(&items[item])?,
            };
            Some((f.as_str(), Artifact::File(bytes)))
        }
        _ => None,
    };
    let mut inputs: BTreeMap<&str, &Artifact> =
        shared.iter().map(|(k, v)| (k.as_str(), v)).collect();
    if let Some((name, artifact)) = &item_artifact {
        inputs.insert(name, artifact);
    }
    let outputs: StageOutputs = if spec.kind == "command" {
        command::run(&ctx.store, ctx.pipeline, spec, &inputs, item, seed).map_err(failed)?
    } else {
        let kind = ctx.catalog.kind(&spec.kind).expect("validated kinds exist");
        let input = StageInput {
            params: &spec.params,
            inputs,
            item,
            seed,
        };
        // a panicking kind fails its stage; the other stages and the store are unaffected
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| kind.run(&input))) {
            Ok(result) => result.map_err(|e| failed(e.to_string()))?,
            Err(panic) => {
                let what = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                    .unwrap_or_default();
                return Err(failed(format!(
                    "kind `{}` panicked ({what}); this is a bug in groove, please report it",
                    spec.kind
                )));
            }
        }
    };
    for name in spec.outputs.keys() {
        match outputs.get(name) {
            None => {
                return Err(failed(format!(
                    "produced no output `{name}` (a bug in kind `{}`)",
                    spec.kind
                )))
            }
            Some(Artifact::Collection(_)) if spec.foreach.is_some() => {
                return Err(failed(format!(
                    "output `{name}` of a per-item stage must be one file per item, not a folder"
                )))
            }
            Some(Artifact::Collection(items)) => {
                if let Some(bad) = items.keys().find(|n| !super::inputs::item_name_ok(n)) {
                    return Err(failed(format!("output `{name}` has an item named `{bad}`; item names use only letters, digits, `.`, `_` and `-`")));
                }
            }
            Some(Artifact::File(_)) => {}
        }
    }
    if let Some(extra) = outputs.keys().find(|n| !spec.outputs.contains_key(*n)) {
        return Err(failed(format!(
            "produced undeclared output `{extra}` (a bug in kind `{}`)",
            spec.kind
        )));
    }
    let mut stored = BTreeMap::new();
    for (name, artifact) in &outputs {
        stored.insert(name.clone(), ctx.store.put(artifact)?);
    }
    ctx.store.commit(key, stored)
}
