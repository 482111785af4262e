//! Two results compared number by number (`groove diff`, and the report's section on a
//! baseline): did μ move, and by how many standard errors?
//!
//! Every number of summary.json and diagnosis.json is paired by its path; an estimate (`{value,
//! se}`, `{value, stderr}`, `{value, interval: {lo, hi}}`, `{value, lo, hi}`, or a number `x`
//! beside `x_se`) carries its standard error, an interval's taken as its half-width over the
//! normal quantile of the summary's bootstrap level (95 % when none is given). A change is also
//! said in units of the combined standard error √(se_A² + se_B²). Accepted findings that appeared
//! or disappeared and params that changed (from each side's pipeline.lock) are listed.

use serde::Serialize;
use serde_json::Value;
use statrs::distribution::{ContinuousCDF, Normal};
use std::collections::{BTreeMap, BTreeSet};

/// The result files compared.
pub const FILES: [&str; 2] = ["summary.json", "diagnosis.json"];
/// Keys whose string value names an element of a list (a run, a finding), in order of preference.
const ID_KEYS: [&str; 6] = ["run", "effect", "material", "name", "term", "parameter"];

/// One side of the comparison: where it came from and its files' JSON.
pub struct Side {
    pub label: String,
    pub files: BTreeMap<&'static str, Value>,
    pub lock: Option<Value>,
}

/// A number and its standard error, when it has one.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Num {
    value: Option<f64>,
    se: Option<f64>,
}

/// One compared number.
#[derive(Debug, Clone, Serialize)]
pub struct Row {
    pub file: String,
    pub path: String,
    pub a: Option<f64>,
    pub b: Option<f64>,
    pub a_se: Option<f64>,
    pub b_se: Option<f64>,
    /// b − a.
    pub change: Option<f64>,
    /// The change over √(a_se² + b_se²).
    pub sigma: Option<f64>,
}

impl Row {
    /// Whether the value or its standard error differs.
    pub fn changed(&self) -> bool {
        self.a != self.b || self.a_se != self.b_se
    }
}

/// One changed param of a stage (JSON text of each side's value, `None` when absent).
#[derive(Debug, Clone, Serialize)]
pub struct ParamChange {
    pub name: String,
    pub a: Option<String>,
    pub b: Option<String>,
}

/// What `diff` found.
#[derive(Debug, Clone, Serialize)]
pub struct Diff {
    pub a: String,
    pub b: String,
    pub params: Vec<ParamChange>,
    pub findings_appeared: Vec<String>,
    pub findings_disappeared: Vec<String>,
    pub numbers: Vec<Row>,
}

/// The normal quantile an interval of `level` spans on each side (1.96 for 0.95).
fn z_of(level: f64) -> f64 {
    let normal = Normal::new(0.0, 1.0).expect("the standard normal");
    normal.inverse_cdf(0.5 + level / 2.0)
}

/// The standard error an interval implies.
fn se_of_interval(lo: Option<f64>, hi: Option<f64>, z: f64) -> Option<f64> {
    match (lo, hi) {
        (Some(lo), Some(hi)) if hi >= lo => Some((hi - lo) / (2.0 * z)),
        _ => None,
    }
}

/// Every number of `v` by path (`a.b.c`; list elements by their id key, else their index).
fn flatten(v: &Value, path: &str, z: f64, out: &mut BTreeMap<String, Num>) {
    let join = |k: &str| match path {
        "" => k.to_string(),
        p => format!("{p}.{k}"),
    };
    match v {
        Value::Number(n) => {
            out.insert(
                path.to_string(),
                Num {
                    value: n.as_f64(),
                    se: None,
                },
            );
        }
        Value::Null => {
            out.insert(
                path.to_string(),
                Num {
                    value: None,
                    se: None,
                },
            );
        }
        Value::Object(m) => {
            if let Some(value) = m.get("value").filter(|v| v.is_number() || v.is_null()) {
                let num = |k: &str| m.get(k).and_then(Value::as_f64);
                let se = num("se")
                    .or_else(|| num("stderr"))
                    .or_else(|| match m.get("interval") {
                        Some(i) => se_of_interval(
                            i.get("lo").and_then(Value::as_f64),
                            i.get("hi").and_then(Value::as_f64),
                            z,
                        ),
                        None => se_of_interval(num("lo"), num("hi"), z),
                    });
                out.insert(
                    path.to_string(),
                    Num {
                        value: value.as_f64(),
                        se,
                    },
                );
                return;
            }
            for (k, child) in m {
                if k.ends_with("_se") && m.contains_key(&k[..k.len() - 3]) {
                    continue;
                }
                let se_key = format!("{k}_se");
                match (child, m.get(&se_key)) {
                    (Value::Number(n), Some(se)) => {
                        out.insert(
                            join(k),
                            Num {
                                value: n.as_f64(),
                                se: se.as_f64(),
                            },
                        );
                    }
                    _ => flatten(child, &join(k), z, out),
                }
            }
        }
        Value::Array(items) => {
            let id = |x: &Value| {
                ID_KEYS
                    .iter()
                    .find_map(|k| x.get(k).and_then(Value::as_str).map(str::to_string))
            };
            let ids: Vec<Option<String>> = items.iter().map(id).collect();
            for (i, (x, name)) in items.iter().zip(&ids).enumerate() {
                let label = match name {
                    Some(n) if ids.iter().filter(|o| o.as_ref() == Some(n)).count() == 1 => {
                        n.clone()
                    }
                    Some(n) => format!("{n}[{i}]"),
                    None => format!("[{i}]"),
                };
                flatten(x, &join(&label), z, out);
            }
        }
        Value::Bool(_) | Value::String(_) => {}
    }
}

/// The effects of the accepted findings in a diagnosis.
fn accepted(diagnosis: Option<&Value>) -> BTreeSet<String> {
    diagnosis
        .and_then(|d| d.get("findings"))
        .and_then(Value::as_array)
        .into_iter()
        .flatten()
        .filter(|f| f.get("accepted").and_then(Value::as_bool) == Some(true))
        .filter_map(|f| f.get("effect").and_then(Value::as_str).map(str::to_string))
        .collect()
}

/// Each stage's params and seed from a lock, as `stage.param` → JSON text.
fn params(lock: Option<&Value>) -> BTreeMap<String, String> {
    let mut out = BTreeMap::new();
    let Some(stages) = lock
        .and_then(|l| l.get("stages"))
        .and_then(Value::as_object)
    else {
        return out;
    };
    for (stage, s) in stages {
        if let Some(p) = s.get("params").and_then(Value::as_object) {
            for (k, v) in p {
                out.insert(format!("{stage}.{k}"), v.to_string());
            }
        }
        if let Some(seed) = s.get("seed") {
            out.insert(format!("{stage}.seed"), seed.to_string());
        }
    }
    out
}

fn level_z(side: &Side) -> f64 {
    let level = side
        .files
        .get("summary.json")
        .and_then(|s| s.pointer("/bootstrap/level"))
        .and_then(Value::as_f64)
        .filter(|l| *l > 0.0 && *l < 1.0)
        .unwrap_or(0.95);
    z_of(level)
}

/// The comparison of `a` (the baseline) and `b`.
pub fn compare(a: &Side, b: &Side) -> Diff {
    let mut numbers = Vec::new();
    for f in FILES {
        let mut na = BTreeMap::new();
        let mut nb = BTreeMap::new();
        if let Some(v) = a.files.get(f) {
            flatten(v, "", level_z(a), &mut na);
        }
        if let Some(v) = b.files.get(f) {
            flatten(v, "", level_z(b), &mut nb);
        }
        let paths: BTreeSet<&String> = na.keys().chain(nb.keys()).collect();
        for p in paths {
            let (x, y) = (na.get(p), nb.get(p));
            let (av, bv) = (x.and_then(|n| n.value), y.and_then(|n| n.value));
            let (ase, bse) = (x.and_then(|n| n.se), y.and_then(|n| n.se));
            let change = match (av, bv) {
                (Some(a), Some(b)) => Some(b - a),
                _ => None,
            };
            let combined = match (ase, bse) {
                (None, None) => None,
                (s, t) => Some((s.unwrap_or(0.0).powi(2) + t.unwrap_or(0.0).powi(2)).sqrt()),
            };
            let sigma = match (change, combined) {
                (Some(c), Some(s)) if s > 0.0 => Some(c / s),
                _ => None,
            };
            numbers.push(Row {
                file: f.to_string(),
                path: p.clone(),
                a: av,
                b: bv,
                a_se: ase,
                b_se: bse,
                change,
                sigma,
            });
        }
    }
    let (fa, fb) = (
        accepted(a.files.get("diagnosis.json")),
        accepted(b.files.get("diagnosis.json")),
    );
    let (pa, pb) = (params(a.lock.as_ref()), params(b.lock.as_ref()));
    let names: BTreeSet<&String> = pa.keys().chain(pb.keys()).collect();
    let params = names
        .into_iter()
        .filter(|n| pa.get(*n) != pb.get(*n))
        .map(|n| ParamChange {
            name: n.clone(),
            a: pa.get(n).cloned(),
            b: pb.get(n).cloned(),
        })
        .collect();
    Diff {
        a: a.label.clone(),
        b: b.label.clone(),
        params,
        findings_appeared: fb.difference(&fa).cloned().collect(),
        findings_disappeared: fa.difference(&fb).cloned().collect(),
        numbers,
    }
}

/// A number as people read it: whole numbers whole, others to 6 significant digits (in
/// scientific notation when very large or small), `—` when absent.
pub fn shown(x: Option<f64>) -> String {
    match x {
        None => "—".to_string(),
        Some(x) if x == x.trunc() && x.abs() < 1e9 => format!("{x:.0}"),
        Some(x) if (1e-3..1e6).contains(&x.abs()) => {
            let digits = (5 - x.abs().log10().floor() as i32).max(0) as usize;
            format!("{x:.digits$}")
        }
        Some(x) => format!("{x:.5e}"),
    }
}

/// A number with its standard error, when it has one.
pub fn with_se(v: Option<f64>, se: Option<f64>) -> String {
    match se {
        Some(se) => format!("{} ± {se:.2e}", shown(v)),
        None => shown(v),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn side_of(summary: Value, diagnosis: Value, lock: Value) -> Side {
        Side {
            label: "x".into(),
            files: BTreeMap::from([("summary.json", summary), ("diagnosis.json", diagnosis)]),
            lock: Some(lock),
        }
    }

    #[test]
    fn estimates_of_every_shape_carry_their_standard_error() {
        let v = json!({
            "a": {"value": 1.0, "se": 0.1},
            "b": {"value": 2.0, "stderr": 0.2},
            "c": {"value": 3.0, "interval": {"lo": 2.0, "hi": 4.0}},
            "d": {"value": 4.0, "lo": 3.0, "hi": 5.0},
            "mu": 0.3, "mu_se": 0.01,
            "runs": [{"run": "r1", "x": 5}, {"run": "r2", "x": 6}],
            "n": 7
        });
        let mut out = BTreeMap::new();
        flatten(&v, "", 2.0, &mut out);
        assert_eq!(out["a"].se, Some(0.1));
        assert_eq!(out["b"].se, Some(0.2));
        assert_eq!(out["c"].se, Some(0.5));
        assert_eq!(out["d"].se, Some(0.5));
        assert_eq!(
            out["mu"],
            Num {
                value: Some(0.3),
                se: Some(0.01)
            }
        );
        assert!(!out.contains_key("mu_se"));
        assert_eq!(out["runs.r2.x"].value, Some(6.0));
        assert_eq!(out["n"].se, None);
        assert!((z_of(0.95) - 1.959964).abs() < 1e-5);
    }

    #[test]
    fn numbers_are_shown_as_people_read_them() {
        assert_eq!(shown(Some(6.0)), "6");
        assert_eq!(shown(Some(0.3342676)), "0.334268");
        assert_eq!(shown(Some(1234.56789)), "1234.57");
        assert_eq!(shown(Some(2.5e-6)), "2.50000e-6");
        assert_eq!(shown(None), "—");
    }

    #[test]
    fn a_moved_estimate_is_said_in_combined_standard_errors() {
        let a = side_of(
            json!({"mu": {"value": 0.30, "se": 0.003}, "n": 5}),
            json!({"findings": [{"effect": "groove_tilt", "accepted": true}]}),
            json!({"stages": {"fit": {"params": {"loss": "l2"}, "seed": 1}}}),
        );
        let b = side_of(
            json!({"mu": {"value": 0.31, "se": 0.004}, "n": 5}),
            json!({"findings": [{"effect": "rolling_resistance", "accepted": true}]}),
            json!({"stages": {"fit": {"params": {"loss": "huber"}, "seed": 1}}}),
        );
        let d = compare(&a, &b);
        let mu = d.numbers.iter().find(|r| r.path == "mu").unwrap();
        // 0.01 / √(0.003² + 0.004²) = 0.01 / 0.005 = 2
        assert!((mu.sigma.unwrap() - 2.0).abs() < 1e-9, "{mu:?}");
        assert!(!d.numbers.iter().find(|r| r.path == "n").unwrap().changed());
        assert_eq!(d.findings_appeared, ["rolling_resistance"]);
        assert_eq!(d.findings_disappeared, ["groove_tilt"]);
        assert_eq!(d.params.len(), 1);
        assert_eq!(d.params[0].name, "fit.loss");
    }
}
