//! The `engine:provenance` input: a JSON record of the code, the seed, every data input's hash,
//! every upstream stage's key and the params every stage ran with (this one's too). Sorted and free of times, so it changes only when they do.

use super::context::{Context, Evaluated};
use super::dag;
use super::inputs::hash_path;
use super::pipeline::{InputSpec, StageSpec};
use super::store::Stored;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

#[derive(Serialize)]
struct Provenance {
    groove_version: String,
    code_commit: String,
    fingerprints: BTreeMap<String, String>,
    seed: u64,
    inputs: Vec<InputHash>,
    stages: Vec<StageKeyRecord>,
    /// The checked params (defaults filled in) of this stage and every stage upstream, by name.
    params: BTreeMap<String, serde_json::Value>,
}

#[derive(Serialize, PartialEq, Eq, PartialOrd, Ord)]
struct InputHash {
    path: String,
    sha256: String,
}

#[derive(Serialize)]
struct StageKeyRecord {
    stage: String,
    kind: String,
    key: String,
}

/// The provenance bytes for `spec`, whose upstream stages are all evaluated.
pub fn record(ctx: &Context, spec: &StageSpec, done: &BTreeMap<String, Evaluated>) -> Vec<u8> {
    let pipeline = ctx.pipeline;
    let ancestors = dag::with_ancestors(pipeline, std::slice::from_ref(&spec.name));
    let mut inputs = BTreeSet::new();
    let mut stages = Vec::new();
    let mut params = BTreeMap::new();
    for name in &ancestors {
        let stage = &pipeline.stages[name];
        params.insert(name.clone(), stage.canonical_params.clone());
        for input in stage.inputs.values() {
            let InputSpec::Path { path, .. } = input else {
                continue;
            };
            let Ok(stored) = hash_path(path, &ctx.hashes) else {
                continue;
            };
            let shown = pipeline.show_portable(path);
            match stored {
                Stored::File { sha256 } => {
                    inputs.insert(InputHash {
                        path: shown,
                        sha256,
                    });
                }
                Stored::Collection { items } => {
                    for (item, sha256) in items {
                        inputs.insert(InputHash {
                            path: format!("{shown}/{item}"),
                            sha256,
                        });
                    }
                }
            }
        }
        if name != &spec.name {
            if let Some(current) = done.get(name).and_then(|e| e.current.as_ref()) {
                stages.push(StageKeyRecord {
                    stage: name.clone(),
                    kind: stage.kind.clone(),
                    key: current.key.clone(),
                });
            }
        }
    }
    let record = Provenance {
        groove_version: ctx.catalog.version.clone(),
        code_commit: ctx.catalog.code_commit.clone(),
        fingerprints: ctx.catalog.all_fingerprints(),
        seed: pipeline.seed,
        inputs: inputs.into_iter().collect(),
        stages,
        params,
    };
    let mut bytes = serde_json::to_vec_pretty(&record).expect("provenance serializes");
    bytes.push(b'\n');
    bytes
}
