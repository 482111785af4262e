//! `groove diff [A] [B]`: two results compared number by number — did μ move, and by how many
//! standard errors?
//!
//! A and B are result folders (a reports folder, or a published bundle), or git revisions (the
//! reports committed there: `git show REV:./reports/summary.json`). Every number of summary.json
//! and diagnosis.json is paired by its path; an estimate (`{value, se}`, `{value, stderr}`,
//! `{value, interval: {lo, hi}}`, `{value, lo, hi}`, or a number `x` beside `x_se`) carries its
//! standard error, an interval's taken as its half-width over the normal quantile of the
//! summary's bootstrap level (95 % when none is given). A change is also said in units of the
//! combined standard error √(se_A² + se_B²). Accepted findings that appeared or disappeared and
//! params that changed (from each side's pipeline.lock) are listed.

use groove::engine::EngineError;
use serde::Serialize;
use serde_json::Value;
use statrs::distribution::{ContinuousCDF, Normal};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The result files compared.
const FILES: [&str; 2] = ["summary.json", "diagnosis.json"];
/// Keys whose string value names an element of a list (a run, a finding), in order of preference.
const ID_KEYS: [&str; 6] = ["run", "effect", "material", "name", "term", "parameter"];

/// One side of the comparison: where it came from and its files' JSON.
struct Side {
    label: String,
    files: BTreeMap<&'static str, Value>,
    lock: Option<Value>,
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
    fn changed(&self) -> bool {
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

/// `diff`: prints the comparison; exit 1 when `fail_above` is given and exceeded.
pub fn diff(
    a: Option<&str>,
    b: Option<&str>,
    json: bool,
    all: bool,
    fail_above: Option<f64>,
) -> Result<ExitCode, EngineError> {
    if let Some(t) = fail_above {
        if !(t > 0.0) || !t.is_finite() {
            return Err(EngineError::Usage(format!(
                "--fail-above {t}: give a positive number of standard errors, e.g. --fail-above 3"
            )));
        }
    }
    let a = side(a.unwrap_or("HEAD"))?;
    let b = side(b.unwrap_or("reports"))?;
    let d = compare(&a, &b);
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&d).expect("the diff serializes")
        );
    } else {
        print!("{}", render(&d, all, fail_above));
    }
    let over: Vec<&Row> = match fail_above {
        Some(t) => d
            .numbers
            .iter()
            .filter(|r| r.sigma.is_some_and(|s| s.abs() > t))
            .collect(),
        None => Vec::new(),
    };
    if over.is_empty() {
        return Ok(ExitCode::SUCCESS);
    }
    let names: Vec<String> = over
        .iter()
        .take(5)
        .map(|r| format!("{} {}", r.file, r.path))
        .collect();
    eprintln!(
        "groove: {} estimate{} moved by more than {} σ: {}{}",
        over.len(),
        if over.len() == 1 { "" } else { "s" },
        fail_above.unwrap_or_default(),
        names.join(", "),
        if over.len() > 5 { ", …" } else { "" }
    );
    Ok(ExitCode::from(1))
}

/// A side from a folder (its files, or those of its `reports/`) or a git revision.
fn side(spec: &str) -> Result<Side, EngineError> {
    let path = Path::new(spec);
    if path.is_dir() {
        return folder_side(spec, path);
    }
    if path.exists() {
        return Err(EngineError::Usage(format!(
            "{spec} is a file; give the folder that holds summary.json and diagnosis.json, or a git revision"
        )));
    }
    git_side(spec)
}

fn read_json(path: &Path) -> Result<Option<Value>, EngineError> {
    match std::fs::read(path) {
        Ok(bytes) => serde_json::from_slice(&bytes).map(Some).map_err(|e| {
            EngineError::Usage(format!(
                "{} is not JSON ({e}); rerun `groove run` to write it again",
                path.display()
            ))
        }),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(EngineError::Usage(format!(
            "cannot read {}: {e}",
            path.display()
        ))),
    }
}

fn folder_side(spec: &str, dir: &Path) -> Result<Side, EngineError> {
    let holds = |d: &Path| FILES.iter().any(|f| d.join(f).is_file());
    let dir: PathBuf = if holds(dir) {
        dir.to_path_buf()
    } else if holds(&dir.join("reports")) {
        dir.join("reports")
    } else {
        return Err(EngineError::Usage(format!(
            "{spec} holds neither summary.json nor diagnosis.json (nor does {spec}/reports); give a reports folder or a published bundle"
        )));
    };
    let mut files = BTreeMap::new();
    for f in FILES {
        if let Some(v) = read_json(&dir.join(f))? {
            files.insert(f, v);
        }
    }
    // a bundle holds its lock; a reports folder's lock is its project's, one folder up
    let lock = match read_json(&dir.join("pipeline.lock"))? {
        Some(l) => Some(l),
        None => match dir.parent() {
            Some(p) => read_json(&p.join("pipeline.lock"))?,
            None => None,
        },
    };
    Ok(Side {
        label: spec.to_string(),
        files,
        lock,
    })
}

/// `git show REV:./PATH` from the current folder; `None` when the revision lacks the file.
fn git_show(rev: &str, path: &str) -> Result<Option<Vec<u8>>, EngineError> {
    let out = std::process::Command::new("git")
        .args(["show", &format!("{rev}:./{path}")])
        .output()
        .map_err(|e| {
            EngineError::Usage(format!(
                "`{rev}` is not a folder, and git cannot be started to read it as a revision ({e})"
            ))
        })?;
    Ok(out.status.success().then_some(out.stdout))
}

fn git_side(rev: &str) -> Result<Side, EngineError> {
    let known = std::process::Command::new("git")
        .args([
            "rev-parse",
            "--verify",
            "--quiet",
            &format!("{rev}^{{commit}}"),
        ])
        .output()
        .is_ok_and(|o| o.status.success());
    if !known {
        return Err(EngineError::Usage(format!(
            "`{rev}` is neither a folder nor a git revision here; give a reports folder, a published bundle, or a commit (e.g. HEAD~1)"
        )));
    }
    let parse = |what: &str, bytes: Vec<u8>| {
        serde_json::from_slice::<Value>(&bytes)
            .map_err(|e| EngineError::Usage(format!("{what} at {rev} is not JSON ({e})")))
    };
    let mut files = BTreeMap::new();
    for f in FILES {
        if let Some(bytes) = git_show(rev, &format!("reports/{f}"))? {
            files.insert(f, parse(f, bytes)?);
        }
    }
    if files.is_empty() {
        return Err(EngineError::Usage(format!(
            "revision {rev} has no reports/summary.json or reports/diagnosis.json under this folder; give a folder instead"
        )));
    }
    let lock = git_show(rev, "pipeline.lock")?
        .map(|b| parse("pipeline.lock", b))
        .transpose()?;
    Ok(Side {
        label: format!("{rev} (git)"),
        files,
        lock,
    })
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

fn compare(a: &Side, b: &Side) -> Diff {
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
fn shown(x: Option<f64>) -> String {
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

fn with_se(v: Option<f64>, se: Option<f64>) -> String {
    match se {
        Some(se) => format!("{} ± {se:.2e}", shown(v)),
        None => shown(v),
    }
}

/// The human-readable comparison.
fn render(d: &Diff, all: bool, fail_above: Option<f64>) -> String {
    let mut s = format!("groove diff: A = {}, B = {}\n", d.a, d.b);
    if d.params.is_empty() {
        s.push_str("params: unchanged (or not known: no pipeline.lock beside a result)\n");
    } else {
        s.push_str("params changed:\n");
        for p in &d.params {
            s.push_str(&format!(
                "  {}: {} → {}\n",
                p.name,
                p.a.as_deref().unwrap_or("(none)"),
                p.b.as_deref().unwrap_or("(none)")
            ));
        }
    }
    let list = |v: &[String]| match v {
        [] => "none".to_string(),
        v => v.join(", "),
    };
    s.push_str(&format!(
        "findings accepted: appeared {}; disappeared {}\n",
        list(&d.findings_appeared),
        list(&d.findings_disappeared)
    ));
    let changed = d.numbers.iter().filter(|r| r.changed()).count();
    s.push_str(&format!(
        "numbers: {changed} of {} changed{}\n",
        d.numbers.len(),
        if all || changed == d.numbers.len() {
            ""
        } else {
            " (the unchanged are not shown; --all shows them)"
        }
    ));
    for r in d.numbers.iter().filter(|r| all || r.changed()) {
        let sigma = r.sigma.map_or(String::new(), |z| format!("  {z:+.2} σ"));
        let flag = match (fail_above, r.sigma) {
            (Some(t), Some(z)) if z.abs() > t => "  !",
            _ => "",
        };
        s.push_str(&format!(
            "  {} {}: {} → {}  (change {}){sigma}{flag}\n",
            r.file,
            r.path,
            with_se(r.a, r.a_se),
            with_se(r.b, r.b_se),
            match r.change {
                Some(c) if c >= 0.0 => format!("+{}", shown(Some(c))),
                c => shown(c),
            },
        ));
    }
    s
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
        let text = render(&d, false, Some(1.5));
        assert!(
            text.contains("summary.json mu:") && text.contains("+2.00 σ  !"),
            "{text}"
        );
        assert!(text.contains("fit.loss: \"l2\" → \"huber\""), "{text}");
    }
}
