//! A throw-away groove project in a temp dir, driven through the built binary (shared by the
//! remote-cache and Slurm suites).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const GROOVE: &str = env!("CARGO_BIN_EXE_groove");

/// A per-item pipeline of `command` stages that append their name to `trace.txt` when they run:
/// ingest copies the dataset, fit checksums each run (one key per run), summary gathers them.
pub const PER_ITEM_PIPELINE: &str = r#"[project]
seed = 7
data = "data"
reports = "reports"

[stages.ingest]
kind = "command"
cmd = "echo ingest >> trace.txt; mkdir -p {out.runs}; cp {in.dataset}/* {out.runs}/"
inputs = { dataset = "${data}" }
outputs = { runs = "${reports}/runs" }

[stages.fit]
kind = "command"
foreach = "runs"
cmd = "echo fit {item} >> trace.txt; cksum < {in.runs} > {out.fit}"
inputs = { runs = "ingest:runs" }
outputs = { fit = "${reports}/fits" }

[stages.summary]
kind = "command"
cmd = "echo summary >> trace.txt; cat {in.fits}/* | sort > {out.table}; echo scale {params.scale} >> {out.table}"
inputs = { fits = "fit:fit" }
outputs = { table = "${reports}/table.txt" }
params = { scale = 1 }
"#;

pub struct Project {
    pub dir: tempfile::TempDir,
}

impl Project {
    pub fn new(pipeline: &str) -> Project {
        let p = Project {
            dir: tempfile::tempdir().expect("temp dir"),
        };
        p.write("pipeline.toml", pipeline);
        p
    }

    /// A project made in `parent` (a folder other processes, e.g. Slurm steps, can see).
    pub fn new_in(parent: &Path, pipeline: &str) -> Project {
        std::fs::create_dir_all(parent).unwrap();
        let p = Project {
            dir: tempfile::tempdir_in(parent).expect("temp dir"),
        };
        p.write("pipeline.toml", pipeline);
        p
    }

    pub fn root(&self) -> &Path {
        self.dir.path()
    }

    pub fn path(&self, rel: &str) -> PathBuf {
        self.dir.path().join(rel)
    }

    pub fn write(&self, rel: &str, text: &str) {
        let p = self.path(rel);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }

    pub fn read(&self, rel: &str) -> String {
        std::fs::read_to_string(self.path(rel)).unwrap_or_else(|e| panic!("read {rel}: {e}"))
    }

    pub fn command(&self, args: &[&str]) -> Command {
        let mut c = Command::new(GROOVE);
        c.args(args).current_dir(self.dir.path());
        c.env_remove("GROOVE_REMOTE")
            .env_remove("GROOVE_REMOTE_READ_ONLY");
        c
    }

    pub fn groove(&self, args: &[&str]) -> Output {
        self.command(args).output().expect("run groove")
    }

    /// Run groove, expect exit 0, return stdout + stderr.
    pub fn ok(&self, args: &[&str]) -> String {
        let out = self.groove(args);
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(out.status.success(), "groove {args:?} failed:\n{text}");
        text
    }

    /// The trace lines written since the last call (sorted; the file is cleared).
    pub fn take_trace(&self) -> Vec<String> {
        let p = self.path("trace.txt");
        let text = std::fs::read_to_string(&p).unwrap_or_default();
        let _ = std::fs::remove_file(&p);
        let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
        lines.sort();
        lines
    }

    /// Run groove, expect exit 0, return stdout alone.
    pub fn stdout(&self, args: &[&str]) -> String {
        let out = self.groove(args);
        assert!(
            out.status.success(),
            "groove {args:?} failed: {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    }

    /// `groove status --json` as (stage, state, reasons).
    pub fn status(&self) -> Vec<(String, String, Vec<String>)> {
        let v: serde_json::Value =
            serde_json::from_str(&self.stdout(&["status", "--json"])).unwrap();
        v.as_array()
            .unwrap()
            .iter()
            .map(|s| {
                (
                    s["stage"].as_str().unwrap().to_string(),
                    s["state"].as_str().unwrap().to_string(),
                    s["reasons"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|r| r.as_str().unwrap().to_string())
                        .collect(),
                )
            })
            .collect()
    }

    /// The stale stages.
    pub fn stale(&self) -> Vec<String> {
        self.status()
            .into_iter()
            .filter(|s| s.1 == "stale")
            .map(|s| s.0)
            .collect()
    }

    /// Why `stage` is stale, joined by `; `.
    pub fn reasons(&self, stage: &str) -> String {
        self.status()
            .into_iter()
            .find(|s| s.0 == stage)
            .unwrap()
            .2
            .join("; ")
    }

    /// Replaces the first `from` in file `rel` by `to` (which must be there).
    pub fn edit(&self, rel: &str, from: &str, to: &str) {
        let text = self.read(rel);
        assert!(text.contains(from), "{rel} has no `{from}`");
        self.write(rel, &text.replacen(from, to, 1));
    }
}

/// Every regular file below `dir` (relative, sorted), skipping `skip` folder names.
pub fn files(dir: &Path, skip: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(rd) = std::fs::read_dir(&d) else {
            continue;
        };
        for entry in rd {
            let path = entry.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            if skip.contains(&name.as_str()) {
                continue;
            }
            if path.is_dir() {
                stack.push(path);
            } else {
                out.push(path.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// Assert two folders hold the same files with the same bytes.
pub fn assert_same_tree(a: &Path, b: &Path) {
    let (fa, fb) = (files(a, &[]), files(b, &[]));
    assert_eq!(
        fa,
        fb,
        "the file sets of {} and {} differ",
        a.display(),
        b.display()
    );
    assert!(!fa.is_empty(), "{} is empty", a.display());
    for f in &fa {
        assert!(
            std::fs::read(a.join(f)).unwrap() == std::fs::read(b.join(f)).unwrap(),
            "{} differs between {} and {}",
            f.display(),
            a.display(),
            b.display()
        );
    }
}

/// A number before `word` in `text` (`"9 hits"` → 9), from the first line containing `line`.
pub fn count(text: &str, line: &str, word: &str) -> u64 {
    let l = text
        .lines()
        .find(|l| l.contains(line))
        .unwrap_or_else(|| panic!("no line with `{line}` in:\n{text}"));
    let words: Vec<&str> = l.split([' ', ',', ';']).filter(|w| !w.is_empty()).collect();
    let i = words
        .iter()
        .position(|w| *w == word)
        .unwrap_or_else(|| panic!("no `{word}` in `{l}`"));
    words[i - 1]
        .parse()
        .unwrap_or_else(|_| panic!("no number before `{word}` in `{l}`"))
}
