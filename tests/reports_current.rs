//! The committed `reports/` is what `groove run` makes from the shipped data with this code:
//! a fresh project (the repository's pipeline.toml, the shipped data) reproduces it byte for byte.

use std::path::{Path, PathBuf};
use std::process::Command;

fn files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if path.file_name().is_some_and(|n| n != ".keep") {
                out.push(path.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out.sort();
    out
}

/// The code commit the report names (`| code commit | <hash> |` in report.md).
fn commit_of(reports: &Path) -> String {
    let md = std::fs::read_to_string(reports.join("report.md")).unwrap();
    md.lines()
        .find_map(|l| l.strip_prefix("| code commit | "))
        .and_then(|rest| rest.split(' ').next())
        .unwrap_or("")
        .to_string()
}

fn mask(bytes: Vec<u8>, commit: &str) -> Vec<u8> {
    match (String::from_utf8(bytes.clone()), commit.len()) {
        (Ok(text), n) if n >= 7 => text.replace(commit, "<commit>").into_bytes(),
        _ => bytes,
    }
}

#[test]
fn committed_reports_are_regenerated_byte_for_byte() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let project = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo.join("pipeline.toml"),
        project.path().join("pipeline.toml"),
    )
    .unwrap();
    let out = project.path().join("reports");
    let status = Command::new(env!("CARGO_BIN_EXE_groove"))
        .current_dir(project.path())
        .args(["run", "--data"])
        .arg(repo.join("data"))
        .arg("--out")
        .arg(&out)
        .status()
        .unwrap();
    assert!(status.success(), "groove run failed on the shipped data");
    let committed = repo.join("reports");
    let want = files(&committed);
    assert_eq!(files(&out), want, "the set of report files differs");
    assert!(want.iter().any(|f| f.ends_with("report.html")));
    // The commit that last touched the code is part of the report; a shallow clone can name a
    // different one, so it is masked and everything else compared byte for byte.
    let (commit_a, commit_b) = (commit_of(&committed), commit_of(&out));
    for f in &want {
        let a = mask(std::fs::read(committed.join(f)).unwrap(), &commit_a);
        let b = mask(std::fs::read(out.join(f)).unwrap(), &commit_b);
        assert!(
            a == b,
            "reports/{} differs from a fresh run: regenerate it with `cargo run --release -- run` and commit it",
            f.display()
        );
    }
}
