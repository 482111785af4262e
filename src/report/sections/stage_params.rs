//! Section 6's table of every stage's params as run: the checked params the engine keyed each
//! stage with (defaults filled in), one row per param, stages and params in name order.

use super::Table;
use crate::artifacts::Provenance;
use serde_json::Value;

/// A param's value as a table cell: a code span (numbers, text, lists), `unset` for none.
fn shown(v: &Value) -> String {
    let text = match v {
        Value::Null => return "unset".into(),
        Value::String(s) => s.clone(),
        other => other.to_string(),
    };
    if text.contains('`') {
        text
    } else {
        format!("`{text}`")
    }
}

/// The rows of one value: nested tables flattened to dotted names (`a.b`).
fn rows(stage: &str, prefix: &str, v: &Value, out: &mut Vec<Vec<String>>) {
    match v {
        Value::Object(m) if !m.is_empty() => {
            for (k, x) in m {
                let name = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                rows(stage, &name, x, out);
            }
        }
        Value::Object(_) if prefix.is_empty() => {
            out.push(vec![stage.into(), "—".into(), "no params".into()])
        }
        other => out.push(vec![stage.into(), prefix.into(), shown(other)]),
    }
}

/// The table, or None when the record lists no stage.
pub fn table(p: &Provenance) -> Option<Table> {
    let mut t = Table::new(
        "Params of every stage as run (pipeline.toml with the project's params and each kind's defaults filled in; these are what the stage keys hash)",
        &["stage", "param", "value"],
    );
    for (stage, v) in &p.params {
        rows(stage, "", v, &mut t.rows);
    }
    (!t.rows.is_empty()).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn every_param_of_every_stage_in_name_order() {
        let p: Provenance = serde_json::from_value(json!({
            "groove_version": "0", "code_commit": "c", "fingerprints": {}, "seed": 1,
            "inputs": [], "stages": [],
            "params": {"report": {"title": "a *b*", "source_date_epoch": null},
                       "fit": {"max_iter": 200, "groove": {"k": 2.5}}, "plot": {}}}))
        .unwrap();
        let t = table(&p).unwrap();
        assert_eq!(
            t.rows,
            [
                ["fit", "groove.k", "`2.5`"],
                ["fit", "max_iter", "`200`"],
                ["plot", "—", "no params"],
                ["report", "source_date_epoch", "unset"],
                ["report", "title", "`a *b*`"],
            ]
        );
    }
}
