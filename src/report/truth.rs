//! Truth values from the validate stage's `validation`, flattened to (path, ours, truth) rows the tables use.

use crate::artifacts::validation::{ParameterCheck, Validation};

/// One checked quantity: where it sits in validation.json, the recovered value, the truth.
#[derive(Debug, Clone, PartialEq)]
pub struct TruthRow {
    pub path: String,
    pub ours: Option<f64>,
    pub truth: f64,
    pub ok: Option<bool>,
}

/// Every quantity with a numeric truth: `mu_pp`, then `parameters[<material>.<quantity>]` in order.
pub fn rows(validation: &Validation) -> Vec<TruthRow> {
    let finite = |x: f64| x.is_finite().then_some(x);
    let mut out = Vec::new();
    if let Some(m) = &validation.mu_pp {
        out.push(TruthRow {
            path: "mu_pp".into(),
            ours: m.recovered.and_then(finite),
            truth: m.truth,
            ok: None,
        });
    }
    for p in validation.parameters.iter().flatten() {
        if let ParameterCheck::Value {
            material,
            quantity,
            recovered,
            truth,
            within_interval,
            ..
        } = p
        {
            out.push(TruthRow {
                path: format!("parameters[{material}.{quantity}]"),
                ours: finite(*recovered),
                truth: *truth,
                ok: *within_interval,
            });
        }
    }
    out
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
    use crate::artifacts::validation::MuPpCheck;

    #[test]
    fn reads_the_validate_stage_layout() {
        let v: Validation = serde_json::from_value(serde_json::json!({"truth": true,
            "parameters": [{"material": "316", "quantity": "mu_weighted", "truth": 0.337, "recovered": 0.336,
                            "error": -0.001, "low": 0.33, "high": 0.34, "within_interval": true},
                           {"material": "316", "quantity": "mu_fast", "truth": 0.337, "recovered": 0.338,
                            "error": 0.001, "low": null, "high": null, "within_interval": null},
                           {"material": "316", "quantity": "restitution_rolling", "truth_law": "{}"}],
            "mu_pp": {"truth": 1.4, "recovered": 1.37}}))
        .unwrap();
        let r = rows(&v);
        assert_eq!(r.len(), 3);
        let w = r
            .iter()
            .find(|x| x.path == "parameters[316.mu_weighted]")
            .expect("labelled by material and quantity");
        assert_eq!((w.ours, w.ok), (Some(0.336), Some(true)));
        assert_eq!(lookup(&r, &["316", "mu_fast"]), Some(0.337));
        assert_eq!(lookup(&r, &["mu_pp"]), Some(1.4));
        assert_eq!(lookup(&r, &["440c", "mu_fast"]), None);
    }

    #[test]
    fn no_truth_has_no_rows() {
        let mut v = Validation::no_truth();
        assert!(rows(&v).is_empty());
        v.mu_pp = Some(MuPpCheck {
            recovered: None,
            truth: 1.4,
        });
        assert_eq!(rows(&v)[0].ours, None);
    }
}
