//! A throw-away groove project in a temp dir, driven through the built binary (shared by the
//! remote-cache and Slurm suites).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const GROOVE: &str = env!("CARGO_BIN_EXE_groove");

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
