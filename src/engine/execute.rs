//! Running one key of a stage: load its inputs, call the kind (or the command), check that every
//! declared output was produced, store the outputs and commit the entry.

use super::command;
use super::context::Context;
use super::error::EngineError;
use super::hashing::sha256_hex;
use super::inputs::{load_path, on_disk};
use super::memo::Memo;
use super::pack_writer::PackWriter;
use super::pipeline::StageSpec;
use super::stage::{Artifact, ObjectMemo, StageError, StageInput, StageOutputs};
use super::store::{Entry, Stored};
use std::collections::BTreeMap;

/// Where an input's bytes come from.
pub enum Source {
    Path(std::path::PathBuf),
    Store,
    Memory(Vec<u8>),
}

pub struct Bound {
    pub stored: Stored,
    pub source: Source,
}

/// Load every input except the per-item one.
pub fn load_shared(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
) -> Result<BTreeMap<String, Artifact>, EngineError> {
    let streamed = match ctx.catalog.kind(&spec.kind) {
        Some(kind) => kind.streamed_inputs(),
        None => &[],
    };
    let mut out = BTreeMap::new();
    for (name, b) in bound {
        if spec.is_item_input(name) {
            continue;
        }
        let artifact = match &b.source {
            Source::Path(p) if streamed.contains(&name.as_str()) => {
                on_disk(p, &b.stored, &ctx.hashes)
            }
            Source::Path(p) => load_path(p, &b.stored)?,
            Source::Store => ctx.store.load(&b.stored)?,
            Source::Memory(bytes) => Artifact::File(bytes.clone()),
        };
        out.insert(name.clone(), artifact);
    }
    Ok(out)
}

/// Run one key (the whole stage or one item), check its outputs, store them, commit the entry.
pub fn execute(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
    shared: &BTreeMap<String, Artifact>,
    item: Option<&str>,
    key: &str,
    seed: u64,
) -> Result<Entry, EngineError> {
    let writer = PackWriter::new(&ctx.store);
    let outputs = run_key(ctx, spec, bound, shared, item, seed, &writer)?;
    let stored = store_outputs(&writer, &outputs)?;
    writer.finish()?;
    ctx.store.commit(key, stored)
}

/// Store a key's checked outputs through `writer` (the caller finishes it before committing).
pub fn store_outputs(
    writer: &PackWriter,
    outputs: &StageOutputs,
) -> Result<BTreeMap<String, Stored>, EngineError> {
    let mut stored = BTreeMap::new();
    for (name, artifact) in outputs {
        let record = match artifact {
            Artifact::File(bytes) => Stored::File {
                sha256: writer.add(bytes)?,
            },
            Artifact::Collection(items) => Stored::Collection {
                items: items
                    .iter()
                    .map(|(item, bytes)| Ok((item.clone(), writer.add(bytes)?)))
                    .collect::<Result<_, EngineError>>()?,
            },
            // put by the stage as it ran (`StageInput::put_item`), through the same writer
            Artifact::InStore(items) => Stored::Collection {
                items: items.clone(),
            },
            Artifact::OnDisk(_) => unreachable!("refused by run_key"),
        };
        stored.insert(name.clone(), record);
    }
    Ok(stored)
}

/// A stage's message, unless an input file it read is a link out of the project: the message
/// may quote that file (a header, a cell), so it is replaced by where the link leads and how to
/// see the message (a file copied in is quoted as any other).
fn unquoted(ctx: &Context, bound: &BTreeMap<String, Bound>, message: String) -> String {
    let linked: Vec<(std::path::PathBuf, std::path::PathBuf)> = bound
        .values()
        .filter_map(|b| match &b.source {
            Source::Path(p) => Some(super::inputs::linked_from_outside(
                &ctx.pipeline.root,
                p,
                &b.stored,
            )),
            _ => None,
        })
        .flatten()
        .collect();
    let Some((link, target)) = linked.first() else {
        return message;
    };
    let shown = |p: &std::path::Path| ctx.pipeline.show(p);
    format!(
        "it failed on its input, and {} is a link to {}, outside the project, so its message is not shown (it may quote that file); copy the file into the project in place of the link to see the message",
        shown(link),
        target.display()
    )
}

/// Run one key and check its outputs (not stored yet). Blobs the kind puts as it runs go
/// through `writer`.
pub fn run_key(
    ctx: &Context,
    spec: &StageSpec,
    bound: &BTreeMap<String, Bound>,
    shared: &BTreeMap<String, Artifact>,
    item: Option<&str>,
    seed: u64,
    writer: &PackWriter,
) -> Result<StageOutputs, EngineError> {
    let failed = |message: String| EngineError::StageFailed {
        stage: spec.name.clone(),
        item: item.map(str::to_string),
        message,
    };
    // what the kind or the command says may quote its inputs
    let failed_reading = |message: String| failed(unquoted(ctx, bound, message));
    let mut item_artifacts: Vec<(&str, Artifact)> = Vec::new();
    if let Some(item) = item {
        for name in spec.foreach.iter().chain(&spec.foreach_with) {
            let Some(b) = bound.get(name) else { continue };
            let Stored::Collection { items } = &b.stored else {
                unreachable!("checked when the keys were made")
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
            item_artifacts.push((name.as_str(), Artifact::File(bytes)));
        }
    }
    let mut inputs: BTreeMap<&str, &Artifact> =
        shared.iter().map(|(k, v)| (k.as_str(), v)).collect();
    for (name, artifact) in &item_artifacts {
        inputs.insert(name, artifact);
    }
    // a whole stage keeps a memo of the objects it made (an item has nothing to share)
    let memo = (item.is_none() && spec.kind != "command").then(|| {
        let salt = serde_json::json!({
            "kind": spec.kind,
            "code": ctx.catalog.fingerprint(&spec.kind),
            "groove_version": env!("CARGO_PKG_VERSION"),
            "params": spec.params,
            "seed": seed,
        });
        Memo::open(&ctx.store, &spec.name, salt.to_string().as_bytes())
    });
    let outputs: StageOutputs = if spec.kind == "command" {
        command::run(&ctx.store, ctx.pipeline, spec, &inputs, item, seed).map_err(failed_reading)?
    } else {
        let kind = ctx.catalog.kind(&spec.kind).expect("validated kinds exist");
        // per-item stages already show `done/total items`
        let detail = |what: &str| ctx.progress.detail(&spec.name, what);
        let put = |bytes: &[u8]| writer.add(bytes).map_err(|e| StageError(e.to_string()));
        let input = StageInput {
            params: &spec.params,
            inputs,
            item,
            seed,
            progress: item.is_none().then_some(&detail as &(dyn Fn(&str) + Sync)),
            put_item: Some(&put),
            memo: memo.as_ref().map(|m| m as &dyn ObjectMemo),
        };
        // a panicking kind fails its stage; the other stages and the store are unaffected
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| kind.run(&input))) {
            Ok(result) => result.map_err(|e| failed_reading(e.to_string()))?,
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
            Some(Artifact::OnDisk(_)) => {
                return Err(failed(format!(
                    "output `{name}` is a list of files on disk (a bug in kind `{}`)",
                    spec.kind
                )))
            }
            Some(Artifact::Collection(_) | Artifact::InStore(_)) if spec.foreach.is_some() => {
                return Err(failed(format!(
                    "output `{name}` of a per-item stage must be one file per item, not a folder"
                )))
            }
            // a collection's item names, whether its bytes came back or went to the store
            Some(artifact) => {
                let names: Vec<&String> = match artifact {
                    Artifact::File(_) => Vec::new(),
                    Artifact::Collection(items) => items.keys().collect(),
                    Artifact::InStore(items) => items.keys().collect(),
                    Artifact::OnDisk(_) => unreachable!("refused above"),
                };
                if let Some(bad) = names.into_iter().find(|n| !super::inputs::item_name_ok(n)) {
                    return Err(failed(format!("output `{name}` has an item named `{bad}`; item names use only letters, digits, `.`, `_` and `-`")));
                }
            }
        }
    }
    if let Some(extra) = outputs.keys().find(|n| !spec.outputs.contains_key(*n)) {
        return Err(failed(format!(
            "produced undeclared output `{extra}` (a bug in kind `{}`)",
            spec.kind
        )));
    }
    if let Some(memo) = memo {
        // only a speed-up: a memo not written leaves the next run to make its objects again
        let _ = memo.save();
    }
    Ok(outputs)
}
