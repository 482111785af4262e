//! `groove diff [A] [B]`: two results compared number by number — did μ move, and by how many
//! standard errors? (The comparison itself: `groove::report::diff`.)
//!
//! A and B are result folders (a reports folder, or a published bundle), or git revisions (the
//! reports committed there: `git show REV:./reports/summary.json`). A defaults to the bundle the
//! last `groove publish` of this project wrote (while it is there), else the committed reports
//! (`HEAD`); B to the working reports folder.

use groove::engine::EngineError;
use groove::report::diff::{compare, shown, with_se, Diff, Row, Side, FILES};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Where `groove publish` notes the bundle it wrote, under the project folder.
pub const LAST_PUBLISHED: &str = ".groove/published";

/// The default baseline: the bundle the last `groove publish` of the project in the current
/// folder wrote, while it still holds a result; else the committed reports.
fn default_baseline() -> String {
    std::fs::read_to_string(LAST_PUBLISHED)
        .ok()
        .map(|p| p.trim().to_string())
        .filter(|p| FILES.iter().any(|f| Path::new(p).join(f).is_file()))
        .unwrap_or_else(|| "HEAD".to_string())
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
    let a = side(&a.map_or_else(default_baseline, str::to_string))?;
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

    fn side_of(summary: Value, lock: Value) -> Side {
        Side {
            label: "x".into(),
            files: BTreeMap::from([("summary.json", summary)]),
            lock: Some(lock),
        }
    }

    #[test]
    fn the_console_table_flags_an_estimate_moved_above_the_threshold() {
        let a = side_of(
            json!({"mu": {"value": 0.30, "se": 0.003}}),
            json!({"stages": {"fit": {"params": {"loss": "l2"}}}}),
        );
        let b = side_of(
            json!({"mu": {"value": 0.31, "se": 0.004}}),
            json!({"stages": {"fit": {"params": {"loss": "huber"}}}}),
        );
        let text = render(&compare(&a, &b), false, Some(1.5));
        assert!(
            text.contains("summary.json mu:") && text.contains("+2.00 σ  !"),
            "{text}"
        );
        assert!(text.contains("fit.loss: \"l2\" → \"huber\""), "{text}");
    }
}
