//! Build script: computes each stage kind's code fingerprint and the last commit that touched the code.
//!
//! A kind's fingerprint is the sha256 of its adapter `src/stages/<kind>.rs` plus every path named
//! on that file's `// groove:uses a/b src/c.rs` line (directories: every `.rs` file below them,
//! in sorted order). Editing `src/fit` thus invalidates the stages that use it and nothing else.
//! The engine's own `command` kind is fingerprinted from `src/engine/command.rs`.
//! The results are written to `$OUT_DIR/code_identity.rs` and included by `engine::identity`.

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let root =
        PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.toml");
    println!("cargo:rerun-if-changed=src/build.rs");

    let mut fingerprints: BTreeMap<String, String> = BTreeMap::new();
    let stages_dir = root.join("src/stages");
    let mut stage_files: Vec<PathBuf> = fs::read_dir(&stages_dir)
        .map(|entries| entries.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    stage_files.sort();
    for file in stage_files {
        let is_rs = file.extension().is_some_and(|e| e == "rs");
        let stem = file
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("")
            .to_string();
        if !is_rs || stem == "mod" {
            continue;
        }
        let mut paths = vec![file.clone()];
        paths.extend(uses_line(&file).into_iter().map(|p| root.join(p)));
        fingerprints.insert(stem, fingerprint(&root, &paths));
    }
    fingerprints.insert(
        "command".into(),
        fingerprint(&root, &[root.join("src/engine/command.rs")]),
    );
    // fallback for a kind whose adapter file is not named after it: any code change invalidates it
    fingerprints.insert("*".into(), fingerprint(&root, &[root.join("src")]));

    let commit = code_commit(&root);
    let mut out = String::from("/// Code fingerprint of every built-in kind, sorted by kind.\n");
    out.push_str("pub const FINGERPRINTS: &[(&str, &str)] = &[\n");
    for (kind, hex) in &fingerprints {
        out.push_str(&format!("    ({kind:?}, {hex:?}),\n"));
    }
    out.push_str("];\n/// The last commit that touched the code (src, Cargo.toml, Cargo.lock).\n");
    out.push_str(&format!("pub const CODE_COMMIT: &str = {commit:?};\n"));
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    fs::write(out_dir.join("code_identity.rs"), out).expect("write code_identity.rs");
}

/// The paths on a `// groove:uses ...` line among the first lines of a stage file.
fn uses_line(file: &Path) -> Vec<String> {
    let text = fs::read_to_string(file).unwrap_or_default();
    text.lines()
        .take(10)
        .find_map(|l| l.trim().strip_prefix("// groove:uses"))
        .map(|rest| rest.split_whitespace().map(str::to_string).collect())
        .unwrap_or_default()
}

/// sha256 over (relative path, contents) of every file under `paths`, sorted and deduplicated.
fn fingerprint(root: &Path, paths: &[PathBuf]) -> String {
    let mut files = Vec::new();
    for p in paths {
        collect_rs(p, &mut files);
    }
    files.sort();
    files.dedup();
    let mut h = Sha256::new();
    for f in files {
        let rel = f
            .strip_prefix(root)
            .unwrap_or(&f)
            .to_string_lossy()
            .replace('\\', "/");
        let bytes = fs::read(&f).unwrap_or_default();
        h.update((rel.len() as u64).to_le_bytes());
        h.update(rel.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

fn collect_rs(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        if let Ok(entries) = fs::read_dir(p) {
            for e in entries.flatten() {
                collect_rs(&e.path(), out);
            }
        }
    } else if p.is_file() {
        out.push(p.to_path_buf());
    }
}

/// `git log -1 --format=%H -- src Cargo.toml Cargo.lock`, or "unknown" without git.
fn code_commit(root: &Path) -> String {
    let git = |args: &[&str]| -> Option<String> {
        let out = Command::new("git")
            .args(args)
            .current_dir(root)
            .output()
            .ok()?;
        let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
        (out.status.success() && !s.is_empty()).then_some(s)
    };
    // rebuild when HEAD moves, so a commit is seen even when no source file changed
    for dir_arg in ["--git-dir", "--git-common-dir"] {
        if let Some(dir) = git(&["rev-parse", dir_arg]) {
            let dir = root.join(dir);
            for f in ["HEAD", "packed-refs", "refs/heads"] {
                if dir.join(f).exists() {
                    println!("cargo:rerun-if-changed={}", dir.join(f).display());
                }
            }
        }
    }
    if let Some(branch) = git(&["symbolic-ref", "-q", "HEAD"]) {
        if let Some(dir) = git(&["rev-parse", "--git-common-dir"]) {
            let f = root.join(dir).join(branch);
            if f.exists() {
                println!("cargo:rerun-if-changed={}", f.display());
            }
        }
    }
    git(&[
        "log",
        "-1",
        "--format=%H",
        "--",
        "src",
        "Cargo.toml",
        "Cargo.lock",
    ])
    .unwrap_or_else(|| "unknown".to_string())
}
