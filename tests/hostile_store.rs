//! A damaged or crafted store, remote or output folder, through the built `groove` binary: each
//! test names the engine invariant it checks (listed under "Invariants" in `engine`'s docs).
//! Every project lives in a sandbox folder of its own, and a test that crafts names or hashes
//! meant to reach outside lists the whole sandbox afterwards: nothing outside the project, its
//! store and the remote may appear, change or vanish.

#[path = "support/project.rs"]
mod project;

use project::{files, Project, PER_ITEM_PIPELINE};
use std::path::{Path, PathBuf};

/// The per-item pipeline and an independent one-file stage.
fn pipeline() -> String {
    format!(
        "{PER_ITEM_PIPELINE}{}",
        r#"
[stages.side]
kind = "command"
cmd = "echo side >> trace.txt; tr a-z A-Z < {in.settings} > {out.note}"
inputs = { settings = "settings.txt" }
outputs = { note = "${reports}/note.txt" }
"#
    )
}

/// A sandbox folder and a project inside it (with its data), run once.
fn sandboxed() -> (tempfile::TempDir, Project) {
    let sandbox = tempfile::tempdir().unwrap();
    let p = Project::new_in(&sandbox.path().join("work"), &pipeline());
    p.write("data/run_a.csv", "t,z\n0,0.0\n1,0.5\n");
    p.write("data/run_b.csv", "t,z\n0,0.0\n1,0.7\n");
    p.write("settings.txt", "hello\n");
    p.ok(&["run"]);
    p.take_trace();
    (sandbox, p)
}

/// Every file in the sandbox outside the folders `inside` (relative to the sandbox, sorted).
fn outside(sandbox: &Path, inside: &[&Path]) -> Vec<PathBuf> {
    files(sandbox, &[])
        .into_iter()
        .filter(|f| !inside.iter().any(|d| sandbox.join(f).starts_with(d)))
        .collect()
}

fn lock(p: &Project) -> serde_json::Value {
    serde_json::from_str(&p.read("pipeline.lock")).unwrap()
}

/// The store key of a stage (per-item stage: of its first item).
fn key_of(p: &Project, stage: &str) -> String {
    let l = lock(p);
    let s = &l["stages"][stage];
    match s["items"].as_object() {
        Some(items) => items.values().next().unwrap().as_str().unwrap().into(),
        None => s["key"].as_str().unwrap().into(),
    }
}

/// The remote folder of a sandbox (created: a missing one is an error for `push`).
fn remote_in(sandbox: &tempfile::TempDir) -> PathBuf {
    let remote = sandbox.path().join("remote");
    std::fs::create_dir_all(&remote).unwrap();
    remote
}

fn url(remote: &Path) -> String {
    format!("file://{}", remote.display())
}

/// A string of 64 characters that resolves, as `objects/<2>/<62>` below `.groove`, to `target`
/// (a path relative to the project's parent folder).
fn hash_reaching(target: &str) -> String {
    // `.groove/objects/..` is `.groove`; from there `objects/../../..` is the project's parent
    let tail = format!("objects/../../../{target}");
    let pad = 62 - tail.len();
    format!("..{}{}{tail}", "/".repeat(pad % 2), "./".repeat(pad / 2))
}

/// Invariant: no store or remote entry can make groove write, read or delete outside the
/// project and its store. A local entry naming an object by a path that reaches a file beside
/// the project is damage: the stage runs again and the file stays.
#[test]
fn a_store_hash_that_is_a_path_deletes_nothing_outside() {
    let (sandbox, p) = sandboxed();
    let victim = sandbox.path().join("work/victim.txt");
    std::fs::write(&victim, "keep me\n").unwrap();
    let h = hash_reaching("victim.txt");
    assert_eq!(h.len(), 64);
    let entry = p.path(&format!(".groove/entries/{}.json", key_of(&p, "side")));
    let text = std::fs::read_to_string(&entry).unwrap();
    let sha = serde_json::from_str::<serde_json::Value>(&text).unwrap()["outputs"]["note"]
        ["sha256"]
        .as_str()
        .unwrap()
        .to_string();
    std::fs::write(&entry, text.replace(&sha, &h)).unwrap();
    p.write("reports/note.txt", "edited by hand\n");
    for verb in [&["run"][..], &["status"], &["verify"], &["gc"], &["run"]] {
        let out = p.groove(verb);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!err.contains("panicked"), "{verb:?}: {err}");
        assert!(out.status.success(), "{verb:?}: {err}");
        assert_eq!(std::fs::read_to_string(&victim).unwrap(), "keep me\n");
    }
    assert_eq!(p.read("reports/note.txt"), "HELLO\n");
    assert!(p.stale().is_empty());
}

/// Invariant: anything else read from a store is damage, dropped and made again, never a
/// panic. Short, odd and non-hex hashes, item names with separators or `..`, and unknown
/// outputs in a local entry each make the stage run again.
#[test]
fn malformed_store_entries_are_damage_not_panics() {
    let (_sandbox, p) = sandboxed();
    let key = key_of(&p, "side");
    let entry = p.path(&format!(".groove/entries/{key}.json"));
    let good = std::fs::read_to_string(&entry).unwrap();
    let v: serde_json::Value = serde_json::from_str(&good).unwrap();
    let sha = v["outputs"]["note"]["sha256"].as_str().unwrap().to_string();
    let crafted = [
        good.replace(&sha, "a"),
        good.replace(&sha, "é"),
        good.replace(&sha, &sha.to_uppercase()),
        good.replace(&sha, &format!("{}zz", &sha[..62])),
        good.replace("\"note\"", "\"other\""),
        good.replace("\"note\"", "\"../note\""),
        r#"{"outputs": {}}"#.to_string(),
    ];
    for text in crafted {
        std::fs::write(&entry, &text).unwrap();
        p.write("reports/note.txt", "edited by hand\n");
        let out = p.groove(&["run"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{text}: {err}");
        assert_eq!(p.take_trace(), vec!["side".to_string()], "{text}");
        assert_eq!(p.read("reports/note.txt"), "HELLO\n", "{text}");
    }
}

/// Invariant: no store or remote entry can make groove write, read or delete outside the
/// project and its store. Crafted remote entries whose item names climb out (`../`) or are
/// absolute write nothing anywhere in the sandbox, with `--remote-read-only` too; the stage
/// runs locally instead.
#[test]
fn crafted_remote_item_names_write_nothing_outside() {
    let (sandbox, a) = sandboxed();
    let remote = remote_in(&sandbox);
    a.ok(&["push", "--remote", &url(&remote)]);
    let key = lock(&a)["stages"]["ingest"]["key"]
        .as_str()
        .unwrap()
        .to_string();
    let entry_file = remote.join(format!("entries/{key}.json"));
    let good = std::fs::read_to_string(&entry_file).unwrap();
    let absolute = sandbox.path().join("absolute.csv");
    let mut clones = Vec::new();
    for (k, name) in [
        "../../../escaped.csv".to_string(),
        "../escaped.csv".to_string(),
        absolute.display().to_string(),
        "sub/dir.csv".to_string(),
        "..".to_string(),
        "line\nbreak.csv".to_string(),
    ]
    .iter()
    .enumerate()
    {
        let name_json = serde_json::to_string(name).unwrap();
        std::fs::write(&entry_file, good.replacen("\"run_a.csv\"", &name_json, 1)).unwrap();
        for read_only in [false, true] {
            let b = Project::new_in(
                &sandbox.path().join(format!("b{k}{read_only}")),
                &pipeline(),
            );
            b.write("data/run_a.csv", "t,z\n0,0.0\n1,0.5\n");
            b.write("data/run_b.csv", "t,z\n0,0.0\n1,0.7\n");
            b.write("settings.txt", "hello\n");
            let u = url(&remote);
            let mut args = vec!["run", "--remote", &u];
            if read_only {
                args.push("--remote-read-only");
            }
            b.ok(&args);
            assert!(b.take_trace().contains(&"ingest".to_string()), "{name:?}");
            assert_eq!(
                files(&b.path("reports/runs"), &[]),
                vec![PathBuf::from("run_a.csv"), PathBuf::from("run_b.csv")]
            );
            clones.push(b);
        }
    }
    // every file of the sandbox lies in a project or the remote: nothing was written elsewhere
    let mut inside: Vec<&Path> = vec![a.root(), &remote];
    inside.extend(clones.iter().map(|b| b.root()));
    let stray = outside(sandbox.path(), &inside);
    assert!(stray.is_empty(), "written outside: {stray:?}");
    assert!(!absolute.exists());
    // ...nor inside a project, beside its reports
    let crafted: Vec<PathBuf> = files(sandbox.path(), &[])
        .into_iter()
        .filter(|f| {
            let n = f.file_name().unwrap().to_string_lossy();
            ["escaped", "absolute", "dir.csv", "break"]
                .iter()
                .any(|c| n.contains(c))
        })
        .collect();
    assert!(crafted.is_empty(), "crafted names written: {crafted:?}");
}

/// Invariant: the set of outputs of an entry matches its stage's declaration. A remote entry
/// missing an output is a miss, never committed locally: the stage runs, every verb works.
#[test]
fn a_remote_entry_missing_an_output_is_not_committed() {
    let (sandbox, a) = sandboxed();
    let remote = remote_in(&sandbox);
    a.ok(&["push", "--remote", &url(&remote)]);
    let key = key_of(&a, "summary");
    let entry_file = remote.join(format!("entries/{key}.json"));
    std::fs::write(&entry_file, r#"{"outputs": {}}"#).unwrap();
    let b = Project::new_in(&sandbox.path().join("b"), &pipeline());
    b.write("data/run_a.csv", "t,z\n0,0.0\n1,0.5\n");
    b.write("data/run_b.csv", "t,z\n0,0.0\n1,0.7\n");
    b.write("settings.txt", "hello\n");
    b.ok(&["run", "--remote", &url(&remote), "--remote-read-only"]);
    assert_eq!(b.take_trace(), vec!["summary".to_string()]);
    assert_eq!(b.read("reports/table.txt"), a.read("reports/table.txt"));
    assert!(
        !b.path(&format!(".groove/entries/{key}.json")).exists() || {
            let e: serde_json::Value =
                serde_json::from_str(&b.read(&format!(".groove/entries/{key}.json"))).unwrap();
            e["outputs"]["table"].is_object()
        }
    );
    for verb in ["status", "verify", "gc", "dag"] {
        let out = b.groove(&[verb]);
        assert!(
            out.status.success() && !String::from_utf8_lossy(&out.stderr).contains("panicked"),
            "{verb}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert!(b.stale().is_empty());
}

/// Invariant: `verify` and `gc` never follow a link out of the store. A linked folder among the
/// objects (or the packs) is removed as a link; what it points to stays whole.
#[test]
fn verify_and_gc_never_follow_a_link_out_of_the_store() {
    let (sandbox, p) = sandboxed();
    let precious = sandbox.path().join("precious");
    std::fs::create_dir_all(&precious).unwrap();
    std::fs::write(precious.join("cdef"), "thesis\n").unwrap();
    std::fs::write(precious.join("x.idx"), "not an index\n").unwrap();
    let objects = p.path(".groove/objects");
    for verb in ["verify", "gc"] {
        for link in [
            objects.join("ab"),
            objects.join("packs"),
            objects.join("zz"),
        ] {
            let _ = std::fs::remove_dir_all(&link);
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink(&precious, &link).unwrap();
        }
        // verify exits 1 when it dropped something (here the links), gc 0
        let out = p.groove(&[verb]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(matches!(out.status.code(), Some(0 | 1)), "{verb}: {err}");
        assert!(!err.contains("panicked"), "{verb}: {err}");
        assert_eq!(
            files(&precious, &[]),
            vec![PathBuf::from("cdef"), PathBuf::from("x.idx")],
            "{verb}"
        );
        assert_eq!(
            std::fs::read_to_string(precious.join("cdef")).unwrap(),
            "thesis\n"
        );
    }
    p.ok(&["run"]);
    assert!(p.stale().is_empty());
}

/// Invariant: groove never deletes a file it did not write. Moving the reports folder onto one
/// that holds the user's own files stops the run (exit 2) naming the file, and changes nothing.
#[test]
fn a_folder_output_never_replaces_the_users_folder() {
    let (_sandbox, p) = sandboxed();
    p.write("thesis/runs/chapter1.tex", "my thesis\n");
    p.edit(
        "pipeline.toml",
        "reports = \"reports\"",
        "reports = \"thesis\"",
    );
    let out = p.groove(&["run"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("thesis/runs/chapter1.tex") && err.contains("move it away"),
        "{err}"
    );
    assert_eq!(p.read("thesis/runs/chapter1.tex"), "my thesis\n");
    // a file the output held before (by the lock) or with the bytes it gives is groove's
    std::fs::remove_file(p.path("thesis/runs/chapter1.tex")).unwrap();
    std::fs::copy(
        p.path("reports/runs/run_a.csv"),
        p.path("thesis/runs/run_a.csv"),
    )
    .unwrap();
    p.ok(&["run"]);
    assert_eq!(
        p.read("thesis/runs/run_b.csv"),
        p.read("reports/runs/run_b.csv")
    );
    // the folder now holds what groove wrote: a changed recording replaces it
    p.edit("data/run_b.csv", "0.7", "0.8");
    p.ok(&["run"]);
    assert!(p.read("thesis/runs/run_b.csv").contains("0.8"));
}

/// Invariant: groove never deletes a file it did not write. The same through `--out`, the
/// reports folder given on the command line.
#[test]
fn out_onto_a_users_folder_stops_and_keeps_it() {
    let (sandbox, p) = sandboxed();
    let thesis = sandbox.path().join("thesis");
    std::fs::create_dir_all(thesis.join("runs")).unwrap();
    std::fs::write(thesis.join("runs/figure.pdf"), "figure\n").unwrap();
    let out = p.groove(&["run", "--out", thesis.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("figure.pdf"), "{err}");
    assert_eq!(
        std::fs::read_to_string(thesis.join("runs/figure.pdf")).unwrap(),
        "figure\n"
    );
}

/// Invariant: staged outputs a killed run left (`.NAME.groove-new-*`) are removed by the next
/// run, even one that writes nothing there.
#[test]
fn staged_leftovers_are_removed_by_the_next_run() {
    let (_sandbox, p) = sandboxed();
    p.write("reports/.note.txt.groove-new-1-2", "half\n");
    std::fs::create_dir_all(p.path("reports/.runs.groove-new-3-4")).unwrap();
    p.write("reports/.runs.groove-old-5-6/run_a.csv", "old\n");
    p.write("reports/.mine.groove-new-7-8", "not an output's\n");
    p.ok(&["run"]);
    let mut left: Vec<String> = std::fs::read_dir(p.path("reports"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        vec![
            ".mine.groove-new-7-8",
            "fits",
            "note.txt",
            "runs",
            "table.txt"
        ]
    );
}

/// Invariant: `run`, `status`, `publish` and `pull` agree about state. A store whose objects
/// are gone (what a `clean` killed half-way left) makes `run` run the stages again, never say
/// "reused" over missing objects.
#[test]
fn a_store_without_its_objects_is_not_reused() {
    let (sandbox, p) = sandboxed();
    std::fs::remove_dir_all(p.path(".groove/objects")).unwrap();
    let out = p.ok(&["run"]);
    assert!(!out.contains("0 stages run"), "{out}");
    assert!(p.stale().is_empty());
    let bundle = sandbox.path().join("bundle");
    p.ok(&["publish", "--to", bundle.to_str().unwrap()]);
    let out = p.ok(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
}

/// Invariant: `run`, `status`, `publish` and `pull` agree about state. `pull` replaces a
/// damaged local object by the remote's sound one instead of counting the entry a hit over it.
#[test]
fn pull_replaces_a_damaged_local_object() {
    let (sandbox, p) = sandboxed();
    let remote = remote_in(&sandbox);
    p.ok(&["push", "--remote", &url(&remote)]);
    let key = key_of(&p, "side");
    let e: serde_json::Value =
        serde_json::from_str(&p.read(&format!(".groove/entries/{key}.json"))).unwrap();
    let sha = e["outputs"]["note"]["sha256"].as_str().unwrap().to_string();
    let object = format!(".groove/objects/{}/{}", &sha[..2], &sha[2..]);
    p.write(&object, "HELLX\n");
    assert_eq!(p.stale(), vec!["side".to_string()]);
    p.ok(&["pull", "--remote", &url(&remote)]);
    assert_eq!(p.read(&object), "HELLO\n");
    assert!(p.stale().is_empty());
    let out = p.ok(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
}

/// Invariant: read-only commands stay read-only. `status`, `publish` and `dag` work when the
/// store cannot be written (here: the hash cache's file is a folder, so it cannot be saved).
#[test]
fn status_publish_and_dag_work_on_a_store_that_cannot_be_written() {
    let (sandbox, p) = sandboxed();
    let _ = std::fs::remove_file(p.path(".groove/hashes.json"));
    std::fs::create_dir_all(p.path(".groove/hashes.json/x")).unwrap();
    p.write("settings.txt", "hello\n"); // a new stamp: the cache would change
    assert!(p.stale().is_empty());
    p.ok(&["dag"]);
    let bundle = sandbox.path().join("bundle");
    p.ok(&["publish", "--to", bundle.to_str().unwrap()]);
    assert!(bundle.join("note.txt").is_file());
}

/// Invariant: a remote that is not there is an error for the verbs that need one. `push` to a
/// missing remote exits 2 naming it.
#[test]
fn push_to_a_missing_remote_exits_2() {
    let (sandbox, p) = sandboxed();
    let missing = sandbox.path().join("no/such/remote");
    let out = p.groove(&["push", "--remote", &url(&missing)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("no/such/remote"), "{err}");
    assert!(!missing.exists());
}

/// Invariant: a remote that is not there is an error for the verbs that need one. `pull` from a
/// missing remote exits 2 naming it, whether the local store lacks results (the lookups fail) or
/// holds them all (no lookup is needed), and creates nothing.
#[test]
fn pull_from_a_missing_remote_exits_2() {
    let (sandbox, p) = sandboxed();
    let missing = sandbox.path().join("no/such/remote");
    for complete in [true, false] {
        if !complete {
            p.ok(&["clean"]);
        }
        let out = p.groove(&["pull", "--remote", &url(&missing)]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(2),
            "complete store {complete}: {err}"
        );
        assert!(err.contains("cannot pull from the remote"), "{err}");
        assert!(err.contains("no/such/remote"), "{err}");
        assert!(!missing.exists());
    }
}

/// Invariant: nothing outside the project is quoted. An input file that is a link to a file
/// outside the project fails its stage without the stage's message (which may quote the file);
/// the message names the link and where it leads. The same bytes copied in are quoted as usual.
#[test]
fn a_failing_input_linked_from_outside_is_not_quoted() {
    let sandbox = tempfile::tempdir().unwrap();
    let secret = sandbox.path().join("secret.txt");
    std::fs::write(&secret, "the-secret-line\n").unwrap();
    let p = Project::new_in(
        &sandbox.path().join("work"),
        r#"
[stages.read]
kind = "command"
cmd = "head -1 {in.settings} >&2; exit 3"
inputs = { settings = "settings.txt" }
outputs = { note = "${reports}/note.txt" }
"#,
    );
    std::os::unix::fs::symlink(&secret, p.path("settings.txt")).unwrap();
    let out = p.groove(&["run"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(!err.contains("the-secret-line"), "{err}");
    assert!(err.contains("settings.txt is a link to"), "{err}");
    assert!(err.contains("secret.txt, outside the project"), "{err}");
    // a copy inside the project is quoted: the check above is about the link, not the stage
    std::fs::remove_file(p.path("settings.txt")).unwrap();
    std::fs::copy(&secret, p.path("settings.txt")).unwrap();
    let out = p.groove(&["run"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("the-secret-line"), "{err}");
}

/// Invariant: `run`, `status`, `publish` and `pull` agree about state. A reused object whose
/// bytes changed on disk (the same size) is not reused by `run`: the stage that made it runs
/// again, where before `run` said "reused" while `status` said stale. The object is made anew
/// and the next run reuses everything.
#[test]
fn run_does_not_reuse_an_object_whose_bytes_changed() {
    let (_sandbox, p) = sandboxed();
    let out = p.ok(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
    let key = key_of(&p, "side");
    let e: serde_json::Value =
        serde_json::from_str(&p.read(&format!(".groove/entries/{key}.json"))).unwrap();
    let sha = e["outputs"]["note"]["sha256"].as_str().unwrap().to_string();
    let object = format!(".groove/objects/{}/{}", &sha[..2], &sha[2..]);
    assert_eq!(p.read(&object), "HELLO\n");
    p.write(&object, "HELLX\n");
    assert_eq!(p.stale(), vec!["side".to_string()]);
    let out = p.ok(&["run"]);
    assert!(out.contains("1 stage run"), "{out}");
    assert_eq!(p.take_trace(), vec!["side".to_string()]);
    assert_eq!(p.read(&object), "HELLO\n");
    assert!(p.stale().is_empty());
    let out = p.ok(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
}

/// Invariant: the file-hash cache is best-effort. A run whose results are all in place does not
/// fail because the cache cannot be written (here it is a folder; on a full disk it cannot grow).
#[test]
fn a_no_op_run_succeeds_when_the_hash_cache_cannot_be_written() {
    let (_sandbox, p) = sandboxed();
    // the same bytes with a new stamp: the no-op rehashes the file and has a cache to save
    p.write("settings.txt", "hello\n");
    let cache = p.path(".groove/hashes.json");
    std::fs::remove_file(&cache).unwrap();
    std::fs::create_dir(&cache).unwrap();
    let out = p.groove(&["run"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("0 stages run")
            || String::from_utf8_lossy(&out.stdout).contains("0 stages run"),
        "{stderr}"
    );
    assert!(stderr.contains("file-hash cache was not saved"), "{stderr}");
    assert!(p.take_trace().is_empty(), "nothing reran");
}
