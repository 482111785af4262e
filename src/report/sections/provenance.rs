//! Section 6: provenance — groove version and commit, every input's hash, each stage's key, seeds.

use super::{Block, Table};
use crate::report::inputs::ReportData;
use crate::report::value::text;
use serde_json::Value;

fn scalar(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "—".into(),
        other => other.to_string(),
    }
}

pub fn block(d: &ReportData) -> Block {
    let mut b = Block::new("provenance", "6. Provenance");
    let Some(p) = &d.provenance else {
        b.missing = Some(
            "no provenance input (bind `provenance = \"engine:provenance\"` in pipeline.toml)"
                .into(),
        );
        return b;
    };
    let mut t = Table::new("Code and seed", &["item", "value"]);
    for k in ["groove_version", "code_commit", "seed"] {
        if let Some(v) = p.get(k) {
            t.push(vec![k.replace('_', " "), scalar(v)]);
        }
    }
    b.table(t);
    if let Some(Value::Array(inputs)) = p.get("inputs") {
        let mut t = Table::new("Inputs (sha256 of the bytes read)", &["path", "sha256"]);
        for i in inputs {
            t.push(vec![
                text(i, &["path"]).unwrap_or("?").into(),
                text(i, &["sha256"]).unwrap_or("?").into(),
            ]);
        }
        b.table(t);
    }
    if let Some(Value::Array(stages)) = p.get("stages") {
        let mut t = Table::new("Stages and their cache keys", &["stage", "kind", "key"]);
        for s in stages {
            t.push(vec![
                text(s, &["stage"]).unwrap_or("?").into(),
                text(s, &["kind"]).unwrap_or("?").into(),
                text(s, &["key"]).unwrap_or("?").into(),
            ]);
        }
        b.table(t);
    }
    if let Some(Value::Object(fp)) = p.get("fingerprints") {
        let mut t = Table::new(
            "Code fingerprint of each stage kind",
            &["kind", "fingerprint"],
        );
        for (k, v) in fp {
            t.push(vec![k.clone(), scalar(v)]);
        }
        b.table(t);
    }
    b.para("Every value here is deterministic: the report carries no run times (they go to the console and the run log), so the same inputs and code give a byte-identical report.");
    b
}
