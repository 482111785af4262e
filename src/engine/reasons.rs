//! Why a stage is stale, in words: which input, param or code changed, old → new where cheap.

use super::context::Evaluated;
use super::lockfile::LockStage;
use super::pipeline::{InputSpec, Pipeline, StageSpec};
use super::store::Stored;
use std::collections::BTreeSet;

fn short(hash: &str) -> &str {
    &hash[..hash.len().min(8)]
}

fn compact(v: &serde_json::Value) -> String {
    serde_json::to_string(v).unwrap_or_default()
}

/// Every reason the stage is not fresh; empty means fresh.
pub fn reasons(
    pipeline: &Pipeline,
    spec: &StageSpec,
    ev: &Evaluated,
    old: Option<&LockStage>,
) -> Vec<String> {
    let mut out = Vec::new();
    if ev.failed {
        out.push("failed".to_string());
        return out;
    }
    let Some(cur) = &ev.current else {
        if let (Some(pending), Some(old)) = (&ev.pending, old) {
            let without_inputs = LockStage {
                inputs: Default::default(),
                ..old.clone()
            };
            out.extend(changes(pipeline, spec, &without_inputs, pending));
        }
        for w in &ev.waiting_on {
            out.push(format!("waits on `{w}`, which is stale"));
        }
        return out;
    };
    match old {
        None => out.push("never run (not in pipeline.lock)".to_string()),
        Some(old) if old.key != cur.key => out.extend(differences(pipeline, spec, old, cur)),
        Some(_) => {}
    }
    let key_changed = old.is_none_or(|o| o.key != cur.key);
    if !ev.complete {
        if !key_changed {
            out.push(
                "its result is missing from the store (after `groove clean` or `groove gc`)"
                    .to_string(),
            );
        } else if spec.foreach.is_some() && old.is_some() {
            let n = ev.missing.len();
            out.push(format!("{n} of {} items to run", cur.items.len()));
        }
    } else if key_changed {
        out.push("the result for these inputs is already in the store; `groove run` restores it without running".to_string());
    }
    for name in &ev.stale_outputs {
        let path = spec.outputs[name]
            .as_deref()
            .map(|p| pipeline.show(p))
            .unwrap_or_default();
        out.push(format!(
            "output `{name}`: {path} is missing or was modified"
        ));
    }
    out
}

/// What differs between the last run and now.
fn differences(
    pipeline: &Pipeline,
    spec: &StageSpec,
    old: &LockStage,
    cur: &LockStage,
) -> Vec<String> {
    let mut out = changes(pipeline, spec, old, cur);
    if out.is_empty() {
        out.push("the stage's definition changed (its outputs)".to_string());
    }
    out
}

/// Each changed part of a stage key, old → new.
fn changes(pipeline: &Pipeline, spec: &StageSpec, old: &LockStage, cur: &LockStage) -> Vec<String> {
    let mut out = Vec::new();
    if old.kind != cur.kind {
        out.push(format!("kind changed: {} → {}", old.kind, cur.kind));
    }
    if old.code != cur.code {
        out.push(format!(
            "code of kind `{}` changed (fingerprint {} → {})",
            cur.kind,
            short(&old.code),
            short(&cur.code)
        ));
    }
    if old.groove_version != cur.groove_version {
        out.push(format!(
            "groove version changed: {} → {}",
            old.groove_version, cur.groove_version
        ));
    }
    if old.seed != cur.seed {
        out.push(format!("seed changed: {} → {}", old.seed, cur.seed));
    }
    if old.cmd != cur.cmd {
        out.push(format!(
            "cmd changed: `{}` → `{}`",
            old.cmd.as_deref().unwrap_or(""),
            cur.cmd.as_deref().unwrap_or("")
        ));
    }
    let empty = serde_json::Map::new();
    let old_params = old.params.as_object().unwrap_or(&empty);
    let cur_params = cur.params.as_object().unwrap_or(&empty);
    let names: BTreeSet<&String> = old_params.keys().chain(cur_params.keys()).collect();
    for name in names {
        match (old_params.get(name), cur_params.get(name)) {
            (Some(a), Some(b)) if a != b => out.push(format!(
                "param `{name}` changed: {} → {}",
                compact(a),
                compact(b)
            )),
            (None, Some(b)) => out.push(format!("param `{name}` added: {}", compact(b))),
            (Some(a), None) => out.push(format!("param `{name}` removed (was {})", compact(a))),
            _ => {}
        }
    }
    let names: BTreeSet<&String> = old.inputs.keys().chain(cur.inputs.keys()).collect();
    for name in names {
        let from = match spec.inputs.get(name.as_str()) {
            Some(InputSpec::Stage { stage, output }) => format!(" (from {stage}:{output})"),
            Some(InputSpec::Path { path, .. }) => format!(" ({})", pipeline.show(path)),
            Some(InputSpec::Provenance) => " (engine:provenance)".to_string(),
            None => String::new(),
        };
        match (old.inputs.get(name), cur.inputs.get(name)) {
            (None, Some(_)) => out.push(format!("input `{name}` added{from}")),
            (Some(_), None) => out.push(format!("input `{name}` is now absent{from}")),
            (Some(a), Some(b)) if a != b => {
                out.push(format!("input `{name}` changed{from}: {}", describe(a, b)))
            }
            _ => {}
        }
    }
    out
}

/// Which items of a collection changed, or the old → new hash of a file.
fn describe(a: &Stored, b: &Stored) -> String {
    match (a, b) {
        (Stored::Collection { items: x }, Stored::Collection { items: y }) => {
            let mut parts = Vec::new();
            for (name, h) in y {
                match x.get(name) {
                    None => parts.push(format!("`{name}` added")),
                    Some(old) if old != h => {
                        parts.push(format!("`{name}` {} → {}", short(old), short(h)))
                    }
                    _ => {}
                }
            }
            for name in x.keys().filter(|n| !y.contains_key(*n)) {
                parts.push(format!("`{name}` removed"));
            }
            let n = parts.len();
            if n > 6 {
                parts.truncate(5);
                parts.push(format!("and {} more", n - 5));
            }
            format!("items {}", parts.join(", "))
        }
        _ => format!("sha256 {} → {}", short(&a.digest()), short(&b.digest())),
    }
}
