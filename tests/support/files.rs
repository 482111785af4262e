//! Folders and tables on disk for the suites that drive the built binary (e2e, daily_cli,
//! hostile_project): running the binary, a scratch folder under the target's tmp folder, a
//! dataset synthesized into it, tree copies and hashes, line and cell edits of a CSV, and the
//! check that an error message names its place.
#![allow(dead_code)]

#[path = "cli.rs"]
pub mod cli;

use groove::engine::hashing::sha256_hex;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;
use std::sync::OnceLock;

pub const GROOVE: &str = env!("CARGO_BIN_EXE_groove");

pub fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The folder all tests of one test binary work in: `name` under the target's tmp folder,
/// cleared once per test process (one binary, one name).
pub fn scratch(name: &str) -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    let dir = DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch folder can be made");
        dir
    });
    assert!(
        dir.ends_with(name),
        "one test binary uses one scratch folder"
    );
    dir
}

pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Runs the tests' binary in `cwd` (without the environment's remote settings).
pub fn groove(cwd: &Path, args: &[&str]) -> Output {
    cli::command(Path::new(GROOVE), cwd, args)
        .output()
        .expect("the groove binary starts")
}

/// Asserts that `out` is a success (showing what it said otherwise) and gives its stdout.
pub fn ok(out: &Output, what: &str) -> String {
    assert!(
        out.status.success(),
        "{what} failed ({:?})\nstdout:\n{}\nstderr:\n{}",
        out.status.code(),
        text(&out.stdout),
        text(&out.stderr)
    );
    text(&out.stdout)
}

/// `groove synth` of the truth fixture `tests/fixtures/truths/NAME.toml` into `out`, run in
/// `cwd`.
pub fn synth(cwd: &Path, fixture: &str, out: &Path) {
    let truth = repo().join(format!("tests/fixtures/truths/{fixture}.toml"));
    ok(
        &groove(
            cwd,
            &[
                "synth",
                "--truth",
                truth.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        ),
        "groove synth",
    );
}

/// Copies the folder `from` to `to`, recursively.
pub fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let path = entry.unwrap().path();
        let target = to.join(path.file_name().unwrap());
        if path.is_dir() {
            copy_tree(&path, &target);
        } else {
            std::fs::copy(&path, &target).unwrap();
        }
    }
}

/// sha256 of every file under `dir` by path relative to it (empty if `dir` is missing), except
/// the store's caches, lock and log (which a run may touch without changing anything the user
/// sees).
pub fn tree_hashes(dir: &Path) -> BTreeMap<String, String> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries {
            let path = entry.unwrap().path();
            let rel = path
                .strip_prefix(root)
                .unwrap()
                .to_string_lossy()
                .into_owned();
            if [".groove/hashes.json", ".groove/run.log", ".groove/lock"].contains(&rel.as_str()) {
                continue;
            }
            if path.is_dir() {
                walk(root, &path, out);
            } else {
                out.insert(rel, sha256_hex(&std::fs::read(&path).unwrap()));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// Rewrites a file's lines: `edit(line_number, line)` returns the new lines for it (none to
/// delete it). Line 1 is the header.
pub fn edit_lines(path: &Path, mut edit: impl FnMut(usize, &str) -> Vec<String>) {
    let content = std::fs::read_to_string(path).unwrap();
    let mut out = String::new();
    for (k, line) in content.lines().enumerate() {
        for l in edit(k + 1, line) {
            out += &l;
            out.push('\n');
        }
    }
    std::fs::write(path, out).unwrap();
}

/// Replaces line `line` (1-based, the header is line 1) of a file.
pub fn edit_line(path: &Path, line: usize, edit: impl FnOnce(&str) -> String) {
    let mut edit = Some(edit);
    edit_lines(path, |k, l| {
        vec![match (k == line).then(|| edit.take()).flatten() {
            Some(f) => f(l),
            None => l.into(),
        }]
    });
}

/// The line with field `field` (0-based) replaced.
pub fn set_field(line: &str, field: usize, value: &str) -> String {
    let mut cells: Vec<&str> = line.split(',').collect();
    cells[field] = value;
    cells.join(",")
}

/// Sets field `field` (0-based) of line `line` (1-based, the header is line 1) of a CSV file.
pub fn set_cell(path: &Path, line: usize, field: usize, value: &str) {
    edit_line(path, line, |l| set_field(l, field, value));
}

/// Asserts that an error message contains every one of `parts`.
pub fn assert_names(stderr: &str, parts: &[&str]) {
    for p in parts {
        assert!(
            stderr.contains(p),
            "the error does not name `{p}`:\n{stderr}"
        );
    }
}
