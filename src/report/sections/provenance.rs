//! Section 6: provenance — groove version and commit, every input's hash, each stage's key and
//! params, seeds.

use super::{Block, Table};
use crate::report::inputs::ReportData;

pub fn block(d: &ReportData) -> Block {
    let mut b = Block::new("provenance", "6. Provenance");
    let Some(p) = &d.provenance else {
        b.missing = Some(
            "no provenance input (bind `provenance = \"engine:provenance\"` in pipeline.toml)"
                .into(),
        );
        return b;
    };
    b.lead = Some(super::leads::provenance(p));
    let mut t = Table::new("Code and seed", &["item", "value"]);
    t.push(vec!["groove version".into(), p.groove_version.clone()]);
    t.push(vec!["code commit".into(), p.code_commit.clone()]);
    t.push(vec!["seed".into(), p.seed.to_string()]);
    b.table(t);
    let mut t = Table::new("Inputs (sha256 of the bytes read)", &["path", "sha256"]);
    for i in &p.inputs {
        t.push(vec![i.path.clone(), i.sha256.clone()]);
    }
    b.table(t);
    let mut t = Table::new("Stages and their cache keys", &["stage", "kind", "key"]);
    for s in &p.stages {
        t.push(vec![s.stage.clone(), s.kind.clone(), s.key.clone()]);
    }
    b.table(t);
    if let Some(t) = super::stage_params::table(p) {
        b.table(t);
    }
    let mut t = Table::new(
        "Code fingerprint of each stage kind",
        &["kind", "fingerprint"],
    );
    for (k, v) in &p.fingerprints {
        t.push(vec![k.clone(), v.clone()]);
    }
    b.table(t);
    b.para("Every value here is deterministic: the report carries no run times (they go to the console and the run log), so the same inputs and code give a byte-identical report.");
    b
}
