//! Build script: computes each stage kind's code fingerprint and the last commit that touched the code.
//!
//! Files of this folder:
//!
//! - `code_deps.rs`: The source files a stage kind uses
//!
//! A kind's fingerprint is the sha256 of every source file its adapter `src/stages/<kind>.rs`
//! uses, found by following its module paths (`build/code_deps.rs`), so editing a module
//! invalidates exactly the kinds that use it and no list can drift. The engine's own `command`
//! kind is fingerprinted from `src/engine/command.rs`. The results are written to
//! `$OUT_DIR/code_identity.rs` and included by `engine::identity`.

#[path = "build/code_deps.rs"]
mod code_deps;

use std::path::{Path, PathBuf};
use std::process::Command;

fn main() {
    let root =
        PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    println!("cargo:rerun-if-changed=src");
    println!("cargo:rerun-if-changed=Cargo.toml");
    println!("cargo:rerun-if-changed=src/build.rs");

    let mut fingerprints = code_deps::kind_fingerprints(&root);
    fingerprints.insert(
        "command".into(),
        code_deps::fingerprint(&root, &[root.join("src/engine/command.rs")]),
    );
    // fallback for a kind whose adapter file is not named after it: any code change invalidates it
    fingerprints.insert(
        "*".into(),
        code_deps::fingerprint(&root, &[root.join("src")]),
    );

    let commit = code_commit(&root);
    let mut out = String::from("/// Code fingerprint of every built-in kind, sorted by kind.\n");
    out.push_str("pub const FINGERPRINTS: &[(&str, &str)] = &[\n");
    for (kind, hex) in &fingerprints {
        out.push_str(&format!("    ({kind:?}, {hex:?}),\n"));
    }
    out.push_str("];\n/// The last commit that touched the code (src, Cargo.toml, Cargo.lock).\n");
    out.push_str(&format!("pub const CODE_COMMIT: &str = {commit:?};\n"));
    let out_dir = PathBuf::from(std::env::var("OUT_DIR").expect("cargo sets OUT_DIR"));
    std::fs::write(out_dir.join("code_identity.rs"), out).expect("write code_identity.rs");
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
