//! Truth values from the validate stage's JSON, flattened to (path, ours, truth) rows the tables use.

use super::value::{as_num, num};
use serde_json::Value;

/// One checked quantity: where it sits in validation.json, the recovered value, the truth.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthRow {
    pub path: String,
    pub ours: Option<f64>,
    pub truth: f64,
    pub ok: Option<bool>,
}

/// Every object in `validation` that carries a numeric `truth` (with `recovered`/`fitted`/`value`
/// beside it, and `ok`/`within`/`pass` when the validator judged it).
pub fn rows(validation: &Value) -> Vec<TruthRow> {
    let mut out = Vec::new();
    walk(validation, String::new(), &mut out);
    out
}

fn walk(v: &Value, path: String, out: &mut Vec<TruthRow>) {
    match v {
        Value::Object(m) => {
            if let Some(t) = m.get("truth").and_then(as_num) {
                out.push(TruthRow {
                    path: path.clone(),
                    ours: num(v, &["recovered", "fitted", "estimate", "value", "ours"]),
                    truth: t,
                    ok: ["ok", "within", "within_interval", "pass", "passed"]
                        .iter()
                        .find_map(|k| m.get(*k).and_then(Value::as_bool)),
                });
                return;
            }
            for (k, x) in m {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                walk(x, p, out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                // label an element by its identifying fields, e.g. `parameters[316.mu_fast]`
                let ids: Vec<&str> = ["name", "material", "quantity", "effect"]
                    .iter()
                    .filter_map(|k| x.get(*k).and_then(Value::as_str))
                    .collect();
                let label = if ids.is_empty() {
                    i.to_string()
                } else {
                    ids.join(".")
                };
                walk(x, format!("{path}[{label}]"), out);
            }
        }
        _ => {}
    }
}

/// The truth of the first row whose path contains every token (case-insensitive, as whole path
/// segments or parts of them), e.g. `["440c", "mu"]`.
pub fn lookup(rows: &[TruthRow], tokens: &[&str]) -> Option<f64> {
    rows.iter()
        .find(|r| {
            let segs: Vec<String> = r
                .path
                .split(['.', '[', ']'])
                .filter(|s| !s.is_empty())
                .map(str::to_ascii_lowercase)
                .collect();
            tokens
                .iter()
                .all(|t| segs.iter().any(|s| s == &t.to_ascii_lowercase()))
        })
        .map(|r| r.truth)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn reads_the_validate_stage_layout() {
        let v = json!({"truth": true,
            "parameters": [{"material": "316", "quantity": "mu_weighted", "truth": 0.337, "recovered": 0.336,
                            "low": 0.33, "high": 0.34, "within_interval": true},
                           {"material": "316", "quantity": "mu_fast", "truth": 0.337, "recovered": 0.338},
                           {"material": "316", "quantity": "restitution_rolling", "truth_law": "{}"}],
            "mu_pp": {"truth": 1.4, "recovered": 1.37}});
        let r = rows(&v);
        assert_eq!(r.len(), 3);
        let w = r
            .iter()
            .find(|x| x.path == "parameters[316.mu_weighted]")
            .expect("labelled by material and quantity");
        assert_eq!((w.ours, w.ok), (Some(0.336), Some(true)));
        assert_eq!(lookup(&r, &["316", "mu_fast"]), Some(0.337));
        assert_eq!(lookup(&r, &["mu_pp"]), Some(1.4));
    }

    #[test]
    fn flattens_and_finds_by_tokens() {
        let v = json!({"truth": true, "materials": {"316": {"mu": {"truth": 0.337, "recovered": 0.335, "ok": true}},
                                                    "440c": {"mu": {"truth": 0.293, "recovered": 0.31, "ok": false}}}});
        let r = rows(&v);
        assert_eq!(r.len(), 2);
        assert_eq!(lookup(&r, &["440c", "mu"]), Some(0.293));
        assert_eq!(r[1].ok, Some(false));
        assert_eq!(lookup(&r, &["mu_pp"]), None);
    }
}
