//! The engine through the built `groove` binary: staleness, reasons, early cutoff, run-cache,
//! kill -9 safety, concurrent runs, config errors, publish. Each test builds a project of
//! `command` stages (sh) in a temp dir; stages append their name to `trace.txt` when they run,
//! so a test sees exactly which stages (and items) executed.

#[path = "support/project.rs"]
mod project;

use project::{Project, PER_ITEM_PIPELINE};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const GROOVE: &str = env!("CARGO_BIN_EXE_groove");

/// The per-item pipeline (ingest, fit per run, summary), then plot decorates the summary; side is
/// an independent branch.
fn pipeline() -> String {
    format!("{PER_ITEM_PIPELINE}{PLOT_AND_SIDE}")
}

const PLOT_AND_SIDE: &str = r#"
[stages.plot]
kind = "command"
cmd = "echo plot >> trace.txt; cat {in.table} > {out.plot}; echo {params.title} >> {out.plot}"
inputs = { table = "summary:table" }
outputs = { plot = "${reports}/plot.txt" }
params = { title = "first" }

[stages.side]
kind = "command"
cmd = "echo side >> trace.txt; tr a-z A-Z < {in.settings} > {out.note}"
inputs = { settings = "settings.txt" }
outputs = { note = "${reports}/note.txt" }
"#;

impl Project {
    /// The standard per-item project with three recordings.
    fn standard() -> Project {
        Project::with_data(&pipeline())
    }

    /// A pipeline with the standard dataset and settings.
    fn with_data(pipeline: &str) -> Project {
        let p = Project::new(pipeline);
        p.write("data/run_a.csv", "t,z\n0,0.0\n1,0.5\n");
        p.write("data/run_b.csv", "t,z\n0,0.0\n1,0.7\n");
        p.write("data/run_c.csv", "t,z\n0,0.0\n1,0.9\n");
        p.write("data/truth/truth.toml", "ignored = true\n");
        p.write("settings.txt", "hello\n");
        p
    }
}

fn strings(v: &[&str]) -> Vec<String> {
    v.iter().map(|s| s.to_string()).collect()
}

#[test]
fn first_run_runs_everything_then_nothing_changed_runs_nothing() {
    let p = Project::standard();
    let out = p.stdout(&["run"]);
    assert!(out.contains("5 stages run, 0 reused"), "{out}");
    assert_eq!(
        p.take_trace(),
        strings(&[
            "fit run_a.csv",
            "fit run_b.csv",
            "fit run_c.csv",
            "ingest",
            "plot",
            "side",
            "summary"
        ])
    );
    // the truth folder is below the dataset: not an input of ingest
    assert!(!p.path("reports/runs/truth").exists());
    assert_eq!(p.read("reports/note.txt"), "HELLO\n");
    assert!(p.read("reports/plot.txt").ends_with("scale 1\nfirst\n"));
    let lock_before = p.read("pipeline.lock");

    let out = p.stdout(&["run"]);
    assert!(out.contains("0 stages run, 5 reused"), "{out}");
    assert_eq!(p.take_trace(), Vec::<String>::new());
    assert!(p.status().iter().all(|s| s.1 == "fresh" && s.2.is_empty()));
    assert_eq!(
        p.read("pipeline.lock"),
        lock_before,
        "the lock is deterministic"
    );
}

#[test]
fn one_byte_of_one_recording_reruns_that_item_and_downstream_only() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    p.edit("data/run_b.csv", "0.7", "0.8");

    assert_eq!(p.stale(), strings(&["ingest", "fit", "summary", "plot"]));
    let why = p.reasons("ingest");
    assert!(
        why.contains("input `dataset` changed") && why.contains("`run_b.csv`"),
        "{why}"
    );
    assert!(!why.contains("run_a.csv"), "{why}");
    assert!(p.reasons("fit").contains("waits on `ingest`"));

    p.stdout(&["run"]);
    assert_eq!(
        p.take_trace(),
        strings(&["fit run_b.csv", "ingest", "plot", "summary"])
    );
    assert!(p.stale().is_empty());
}

#[test]
fn param_change_reruns_stage_and_descendants_and_reverting_reuses_the_store() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    let table_1 = p.read("reports/table.txt");
    p.edit("pipeline.toml", "scale = 1", "scale = 2");

    assert_eq!(p.stale(), strings(&["summary", "plot"]));
    assert!(
        p.reasons("summary")
            .contains("param `scale` changed: 1 → 2"),
        "{}",
        p.reasons("summary")
    );
    assert!(p.reasons("plot").contains("waits on `summary`"));
    p.stdout(&["run"]);
    assert_eq!(p.take_trace(), strings(&["plot", "summary"]));
    assert!(p.read("reports/table.txt").ends_with("scale 2\n"));

    // back to 1: found in the store, nothing runs, the old outputs come back
    p.edit("pipeline.toml", "scale = 2", "scale = 1");
    let why = p.reasons("summary");
    assert!(
        why.contains("param `scale` changed: 2 → 1") && why.contains("already in the store"),
        "{why}"
    );
    let out = p.stdout(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
    assert_eq!(p.take_trace(), Vec::<String>::new());
    assert_eq!(p.read("reports/table.txt"), table_1);
    assert!(p.stale().is_empty());
}

#[test]
fn identical_output_after_a_rerun_leaves_downstream_fresh() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    // a new command that writes the same bytes: fit reruns, summary does not (early cutoff)
    p.edit(
        "pipeline.toml",
        "cksum < {in.runs} > {out.fit}",
        "cksum < {in.runs} > {out.fit}; true",
    );
    // status cannot know fit's new output without running it, so downstream waits on fit
    assert_eq!(p.stale(), strings(&["fit", "summary", "plot"]));
    assert!(
        p.reasons("fit").contains("cmd changed"),
        "{}",
        p.reasons("fit")
    );
    assert!(p.reasons("summary").contains("waits on `fit`"));
    p.stdout(&["run"]);
    assert_eq!(
        p.take_trace(),
        strings(&["fit run_a.csv", "fit run_b.csv", "fit run_c.csv"])
    );
    assert!(p.stale().is_empty());
}

#[test]
fn touch_reruns_nothing() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    let file = std::fs::File::options()
        .append(true)
        .open(p.path("data/run_a.csv"))
        .unwrap();
    file.set_modified(std::time::SystemTime::now() + Duration::from_secs(3600))
        .unwrap();
    drop(file);
    assert!(p.stale().is_empty());
    p.stdout(&["run"]);
    assert_eq!(p.take_trace(), Vec::<String>::new());
}

#[test]
fn an_edit_that_keeps_size_and_sets_the_mtime_back_is_still_seen() {
    // as `rsync --inplace --times` or `touch -r` leave a file: new bytes in place, the same
    // size, inode and mtime; only the change time tells
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    let path = p.path("data/run_a.csv");
    let before = std::fs::read(&path).unwrap();
    let mtime = std::fs::metadata(&path).unwrap().modified().unwrap();
    let mut after = before.clone();
    let last = after.iter().rposition(|b| b.is_ascii_digit()).unwrap();
    after[last] = if after[last] == b'9' {
        b'8'
    } else {
        after[last] + 1
    };
    std::thread::sleep(Duration::from_millis(20));
    let mut file = std::fs::File::options().write(true).open(&path).unwrap();
    std::io::Write::write_all(&mut file, &after).unwrap();
    file.set_modified(mtime).unwrap();
    drop(file);
    let meta = std::fs::metadata(&path).unwrap();
    assert_eq!(
        (meta.len(), meta.modified().unwrap()),
        (before.len() as u64, mtime)
    );
    assert_eq!(p.stale().first().map(String::as_str), Some("ingest"));
    p.stdout(&["run"]);
    let trace = p.take_trace();
    assert!(trace.contains(&"fit run_a.csv".to_string()), "{trace:?}");
    assert!(!trace.contains(&"fit run_b.csv".to_string()), "{trace:?}");
}

#[test]
fn a_deleted_output_is_restored_from_the_store_without_running() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    std::fs::remove_file(p.path("reports/plot.txt")).unwrap();
    std::fs::remove_dir_all(p.path("reports/fits")).unwrap();
    assert!(p
        .reasons("plot")
        .contains("output `plot`: reports/plot.txt is missing or was modified"));
    p.stdout(&["run"]);
    assert_eq!(p.take_trace(), Vec::<String>::new());
    assert!(p.read("reports/plot.txt").ends_with("first\n"));
    assert_eq!(
        std::fs::read_dir(p.path("reports/fits")).unwrap().count(),
        3
    );
}

#[test]
fn a_failing_command_exits_2_with_its_stderr_and_keeps_the_last_good_outputs() {
    let p = Project::standard();
    p.stdout(&["run"]);
    let plot = p.read("reports/plot.txt");
    p.edit(
        "pipeline.toml",
        "echo plot >> trace.txt;",
        "echo broken plot >&2; exit 3;",
    );
    let out = p.groove(&["run"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("stage `plot`") && err.contains("broken plot"),
        "{err}"
    );
    assert_eq!(err.matches("broken plot").count(), 1, "printed once: {err}");
    assert_eq!(p.read("reports/plot.txt"), plot);
    assert_eq!(p.stale(), strings(&["plot"]));
}

#[test]
fn run_named_stage_runs_only_what_it_needs() {
    let p = Project::standard();
    p.stdout(&["run", "summary"]);
    assert_eq!(
        p.take_trace(),
        strings(&[
            "fit run_a.csv",
            "fit run_b.csv",
            "fit run_c.csv",
            "ingest",
            "summary"
        ])
    );
    assert_eq!(p.stale(), strings(&["side", "plot"]));
    // --force reruns a fresh stage; --dry-run runs nothing
    let out = p.stdout(&["run", "--dry-run"]);
    assert!(
        out.contains("plot") && out.contains("side") && !out.contains("summary"),
        "{out}"
    );
    assert_eq!(p.take_trace(), Vec::<String>::new());
    p.stdout(&["run", "summary", "--force", "summary"]);
    assert_eq!(p.take_trace(), strings(&["summary"]));
}

#[test]
fn data_and_out_replace_the_project_folders() {
    let p = Project::standard();
    p.write("other/run_z.csv", "t,z\n0,1\n");
    p.stdout(&["run", "--data", "other", "--out", "elsewhere"]);
    let trace = p.take_trace();
    assert!(
        trace.contains(&"fit run_z.csv".to_string()) && trace.len() == 5,
        "{trace:?}"
    );
    assert!(p.path("elsewhere/fits/run_z.csv").is_file());
    assert!(!p.path("reports").exists());
}

/// Wait until a file contains a line, or panic after a timeout.
fn wait_for(path: &Path, needle: &str) {
    let start = Instant::now();
    while !std::fs::read_to_string(path)
        .unwrap_or_default()
        .contains(needle)
    {
        assert!(
            start.elapsed() < Duration::from_secs(30),
            "timed out waiting for {needle}"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

const SLOW: &str = r#"[stages.first]
kind = "command"
cmd = "echo first >> trace.txt; printf 'one\n' > {out.o}"
inputs = { x = "x.txt" }
outputs = { o = "reports/first.txt" }

[stages.slow]
kind = "command"
cmd = "echo slow >> trace.txt; printf 'partial' > {out.o}; sleep 2; printf ' and complete\n' >> {out.o}; cat {in.f} >> {out.o}"
inputs = { f = "first:o" }
outputs = { o = "reports/slow.txt" }
"#;

#[test]
fn kill_9_mid_write_leaves_the_store_consistent_and_the_next_run_completes() {
    let killed = Project::new(SLOW);
    killed.write("x.txt", "x\n");
    let mut child = killed
        .command(&["run", "--jobs", "1"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    wait_for(&killed.path("trace.txt"), "slow");
    std::thread::sleep(Duration::from_millis(200));
    child.kill().unwrap(); // SIGKILL
    child.wait().unwrap();
    // no partial output anywhere the user looks, and only complete entries in the store
    assert!(!killed.path("reports/slow.txt").exists());
    let entries = std::fs::read_dir(killed.path(".groove/entries"))
        .unwrap()
        .count();
    assert_eq!(entries, 1, "only `first` was committed");
    // outputs are materialized only when the whole run succeeded: `first` is in the store but
    // not yet in the project (it is reused, not rerun, below)
    assert!(!killed.path("reports/first.txt").exists());
    assert_eq!(killed.stale(), strings(&["first", "slow"]));

    killed.take_trace();
    killed.stdout(&["run"]);
    assert_eq!(killed.take_trace(), strings(&["slow"]));
    assert!(
        !killed.path(".groove/tmp").exists()
            || std::fs::read_dir(killed.path(".groove/tmp"))
                .unwrap()
                .count()
                == 0
    );

    let clean = Project::new(SLOW);
    clean.write("x.txt", "x\n");
    clean.stdout(&["run"]);
    assert_eq!(
        killed.read("reports/slow.txt"),
        "partial and complete\none\n"
    );
    assert_eq!(
        killed.read("reports/slow.txt"),
        clean.read("reports/slow.txt")
    );
    assert_eq!(killed.read("pipeline.lock"), clean.read("pipeline.lock"));
}

#[test]
fn two_concurrent_runs_do_not_corrupt_the_project() {
    let p = Project::new(SLOW);
    p.write("x.txt", "x\n");
    let a = p
        .command(&["run"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_for(&p.path("trace.txt"), "first");
    let b = p
        .command(&["run"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let (a, b) = (a.wait_with_output().unwrap(), b.wait_with_output().unwrap());
    assert!(a.status.success() && b.status.success());
    let b_err = String::from_utf8_lossy(&b.stderr);
    assert!(
        b_err.contains("waiting"),
        "the second run says it waits: {b_err}"
    );
    // each stage ran once; the second run found everything in the store
    assert_eq!(p.take_trace(), strings(&["first", "slow"]));
    assert!(String::from_utf8_lossy(&b.stdout).contains("0 stages run, 2 reused"));
    assert_eq!(p.read("reports/slow.txt"), "partial and complete\none\n");
    assert!(p.stale().is_empty());
}

/// (what is wrong, pipeline text, the line the error must name, a phrase it must contain)
fn bad_configs() -> Vec<(&'static str, String, &'static str, &'static str)> {
    let good = "[stages.a]\nkind = \"command\"\ncmd = \"cp {in.x} {out.o}\"\ninputs = { x = \"x.txt\" }\noutputs = { o = \"reports/a.txt\" }\n";
    vec![
        (
            "unknown kind",
            format!("{good}\n[stages.b]\nkind = \"fitt\"\n"),
            "kind = \"fitt\"",
            "unknown kind `fitt`",
        ),
        (
            "unknown stage key",
            format!("{good}\n[stages.b]\nkind = \"command\"\nparms = {{ a = 1 }}\n"),
            "parms",
            "unknown field `parms`",
        ),
        (
            "unknown param of a built-in kind",
            format!("{good}\n[stages.b]\nkind = \"ingest\"\ninputs = {{ dataset = \"x.txt\" }}\nparams = {{ formt = \"auto\" }}\n"),
            "formt",
            "param `formt`",
        ),
        (
            "mistyped value",
            "[project]\nseed = \"seven\"\n".to_string(),
            "seed",
            "invalid type",
        ),
        (
            "cycle",
            "[stages.a]\nkind = \"command\"\ncmd = \"cp {in.x} {out.o}\"\ninputs = { x = \"b:o\" }\noutputs = { o = \"r/a\" }\n\n[stages.b]\nkind = \"command\"\ncmd = \"cp {in.x} {out.o}\"\ninputs = { x = \"a:o\" }\noutputs = { o = \"r/b\" }\n".to_string(),
            "[stages.a]",
            "cycle: a -> b -> a",
        ),
        (
            "missing input file",
            good.replace("x.txt", "missing.txt"),
            "inputs = {",
            "missing.txt does not exist",
        ),
        (
            "input from an unknown stage",
            format!("{good}\n[stages.b]\nkind = \"command\"\ncmd = \"cp {{in.x}} {{out.o}}\"\ninputs = {{ x = \"nope:o\" }}\noutputs = {{ o = \"reports/b.txt\" }}\n"),
            "nope:o",
            "no stage `nope`",
        ),
        (
            "two stages one output",
            format!("{good}\n[stages.b]\nkind = \"command\"\ncmd = \"cp {{in.x}} {{out.o}}\"\ninputs = {{ x = \"x.txt\" }}\noutputs = {{ o = \"reports/a.txt\" }}\n"),
            "[stages.b]",
            "both write reports/a.txt",
        ),
        (
            "unknown placeholder",
            good.replace("{out.o}", "{out.p}"),
            "cmd =",
            "`{out.p}` in cmd names no output",
        ),
    ]
}

#[test]
fn bad_pipelines_exit_2_naming_the_line() {
    for (what, text, marker, phrase) in bad_configs() {
        let p = Project::new(&text);
        p.write("x.txt", "x\n");
        let line = text
            .lines()
            .position(|l| l.contains(marker))
            .expect("marker in text")
            + 1;
        let out = p.groove(&["run"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{what}: {err}");
        assert!(
            err.contains(&format!("pipeline.toml:{line}:")),
            "{what}: expected line {line}: {err}"
        );
        assert!(err.contains(phrase), "{what}: expected `{phrase}`: {err}");
        assert_eq!(
            err.lines().filter(|l| l.contains("error")).count(),
            1,
            "{what}: printed once: {err}"
        );
    }
}

#[test]
fn dag_renders_text_dot_and_mermaid() {
    let p = Project::standard();
    let text = p.stdout(&["dag"]);
    assert!(
        text.contains("fit (command foreach runs)") && text.contains("<- runs = ingest:runs"),
        "{text}"
    );
    let dot = p.stdout(&["dag", "--format", "dot"]);
    assert!(
        dot.starts_with("digraph groove {") && dot.contains("\"summary\" -> \"plot\""),
        "{dot}"
    );
    let mermaid = p.stdout(&["dag", "--format", "mermaid"]);
    assert!(
        mermaid.starts_with("graph LR") && mermaid.contains("fit -->|fit → fits| summary"),
        "{mermaid}"
    );
}

#[test]
fn publish_refuses_while_stale_then_writes_a_verified_bundle() {
    let p = Project::standard();
    let out = p.groove(&["publish", "--to", "bundle"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("stale") && err.contains("summary") && err.contains("never run"),
        "{err}"
    );
    assert!(!p.path("bundle").exists());

    p.stdout(&["run"]);
    p.stdout(&["publish", "--to", "bundle"]);
    let sums = p.read("bundle/SHA256SUMS");
    let listed: Vec<&str> = sums
        .lines()
        .map(|l| l.split_once("  ").unwrap().1)
        .collect();
    assert!(
        listed.contains(&"pipeline.lock")
            && listed.contains(&"plot.txt")
            && listed.contains(&"fits/run_b.csv"),
        "{sums}"
    );
    for line in sums.lines() {
        let (hash, rel) = line.split_once("  ").unwrap();
        let bytes = std::fs::read(p.path("bundle").join(rel)).unwrap();
        assert_eq!(hash, groove::engine::hashing::sha256_hex(&bytes), "{rel}");
    }
    assert_eq!(p.read("bundle/pipeline.lock"), p.read("pipeline.lock"));

    // a stale stage blocks publishing again, and names why
    p.edit("pipeline.toml", "title = \"first\"", "title = \"second\"");
    let out = p.groove(&["publish", "--to", "bundle"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("param `title` changed"));
}

#[test]
fn gc_drops_entries_the_lock_does_not_name() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.edit("pipeline.toml", "scale = 1", "scale = 2");
    p.stdout(&["run"]);
    let out = p.stdout(&["gc"]);
    assert!(out.contains("removed 2 store entries"), "{out}");
    p.edit("pipeline.toml", "scale = 2", "scale = 1");
    p.take_trace();
    p.stdout(&["run"]);
    assert_eq!(p.take_trace(), strings(&["plot", "summary"]));
    p.stdout(&["clean"]);
    assert!(p.reasons("ingest").contains("missing from the store"));
}

#[test]
fn every_verb_has_help() {
    for verb in ["run", "status", "dag", "clean", "gc", "synth", "publish"] {
        let out = Command::new(GROOVE)
            .args([verb, "--help"])
            .output()
            .unwrap();
        assert!(out.status.success(), "{verb} --help");
        assert!(String::from_utf8_lossy(&out.stdout).contains("Usage: groove"));
    }
}

#[test]
fn independent_stages_run_at_the_same_time() {
    // each stage waits (up to 20 s) for the other's flag: only a parallel run finishes quickly
    let wait = |me: &str, other: &str| {
        format!(
            "touch {me}.flag; i=0; while [ ! -e {other}.flag ]; do sleep 0.05; i=$((i+1)); if [ $i -gt 400 ]; then exit 1; fi; done; echo {me} > {{out.o}}"
        )
    };
    let p = Project::new(&format!(
        "[stages.a]\nkind = \"command\"\ncmd = \"{}\"\ninputs = {{ x = \"x.txt\" }}\noutputs = {{ o = \"reports/a.txt\" }}\n\n[stages.b]\nkind = \"command\"\ncmd = \"{}\"\ninputs = {{ x = \"x.txt\" }}\noutputs = {{ o = \"reports/b.txt\" }}\n",
        wait("a", "b"),
        wait("b", "a")
    ));
    p.write("x.txt", "x\n");
    p.stdout(&["run", "--jobs", "2"]);
    assert_eq!(p.read("reports/a.txt"), "a\n");
    assert_eq!(p.read("reports/b.txt"), "b\n");
}

#[test]
fn a_stage_stepping_through_two_per_item_inputs_reruns_only_the_changed_item() {
    let p = Project::with_data(&format!(
        "{}\n[stages.resid]\nkind = \"command\"\nforeach = [\"runs\", \"fits\"]\ncmd = \"echo resid {{item}} >> trace.txt; cat {{in.runs}} {{in.fits}} > {{out.r}}\"\ninputs = {{ runs = \"ingest:runs\", fits = \"fit:fit\" }}\noutputs = {{ r = \"${{reports}}/resid\" }}\n",
        pipeline()
    ));
    p.stdout(&["run"]);
    p.take_trace();
    p.edit("data/run_b.csv", "0.7", "0.8");
    p.stdout(&["run"]);
    let resid: Vec<String> = p
        .take_trace()
        .into_iter()
        .filter(|l| l.starts_with("resid"))
        .collect();
    assert_eq!(resid, strings(&["resid run_b.csv"]));
    // each item saw its own recording and its own fit, not the whole collections
    let b = p.read("reports/resid/run_b.csv");
    assert_eq!(
        b,
        format!(
            "{}{}",
            p.read("data/run_b.csv"),
            p.read("reports/fits/run_b.csv")
        )
    );
    assert!(p
        .read("reports/resid/run_a.csv")
        .starts_with("t,z\n0,0.0\n1,0.5\n"));
    assert!(p
        .stdout(&["dag"])
        .contains("resid (command foreach runs, fits)"));
}

/// The store object a per-item output of one item names in the lock.
fn item_object(p: &Project, stage: &str, output: &str, item: &str) -> std::path::PathBuf {
    let lock: serde_json::Value = serde_json::from_str(&p.read("pipeline.lock")).unwrap();
    let h = lock["stages"][stage]["outputs"][output]["items"][item]
        .as_str()
        .unwrap()
        .to_string();
    p.path(".groove/objects").join(&h[..2]).join(&h[2..])
}

#[test]
fn a_per_item_stage_is_found_through_its_one_index_entry_and_a_damaged_item_reruns_alone() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    let lock: serde_json::Value = serde_json::from_str(&p.read("pipeline.lock")).unwrap();
    let fit = &lock["stages"]["fit"];
    // the index: the stage key's entry names every item's output
    let index: serde_json::Value = serde_json::from_str(&p.read(&format!(
        ".groove/entries/{}.json",
        fit["key"].as_str().unwrap()
    )))
    .unwrap();
    assert_eq!(index["outputs"]["fit"], fit["outputs"]["fit"]);
    assert_eq!(fit["outputs"]["fit"]["items"].as_object().unwrap().len(), 3);

    // a damaged item object: a no-op takes a reused object as sound only at the stat its bytes
    // last matched its name at (`engine::object_stamps`), so it reruns only that item (same
    // bytes) and the object is repaired; so does a run that reads it (with the forced
    // summary), damaged or missing
    let object = item_object(&p, "fit", "fit", "run_b.csv");
    let good = std::fs::read(&object).unwrap();
    std::fs::write(&object, b"damaged\n").unwrap();
    let out = p.stdout(&["run"]);
    assert_eq!(p.take_trace(), strings(&["fit run_b.csv"]), "{out}");
    assert_eq!(std::fs::read(&object).unwrap(), good);
    for missing in [false, true] {
        match missing {
            false => std::fs::write(&object, b"damaged\n").unwrap(),
            true => std::fs::remove_file(&object).unwrap(),
        }
        let out = p.stdout(&["run", "--force", "summary"]);
        assert_eq!(
            p.take_trace(),
            strings(&["fit run_b.csv", "summary"]),
            "missing {missing}: {out}"
        );
        assert_eq!(std::fs::read(&object).unwrap(), good);
    }

    // with the index sound, the items' own entries are not read: removing them reruns nothing
    for item in fit["items"].as_object().unwrap().values() {
        std::fs::remove_file(p.path(&format!(".groove/entries/{}.json", item.as_str().unwrap())))
            .unwrap();
    }
    let out = p.stdout(&["run"]);
    assert!(out.contains("0 stages run, 5 reused"), "{out}");
    assert_eq!(p.take_trace(), Vec::<String>::new());
    assert!(p.stale().is_empty());
}

#[test]
fn a_no_op_rewrites_neither_lock_nor_hash_cache_and_the_cache_stamps_no_store_object() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.stdout(&["run"]);
    p.take_trace();
    let mtime = |rel: &str| std::fs::metadata(p.path(rel)).unwrap().modified().unwrap();
    let (lock, lock_t) = (p.read("pipeline.lock"), mtime("pipeline.lock"));
    let (cache, cache_t) = (p.read(".groove/hashes.json"), mtime(".groove/hashes.json"));
    std::thread::sleep(std::time::Duration::from_millis(20));
    let out = p.stdout(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
    assert_eq!(p.take_trace(), Vec::<String>::new());
    assert_eq!(
        (p.read("pipeline.lock"), mtime("pipeline.lock")),
        (lock, lock_t)
    );
    assert_eq!(
        (p.read(".groove/hashes.json"), mtime(".groove/hashes.json")),
        (cache.clone(), cache_t)
    );
    // the hash cache stamps the project's files (here the input recordings), never the
    // store's objects: those are named by their hash and checked when read
    let stamps: serde_json::Map<String, serde_json::Value> = serde_json::from_str(&cache).unwrap();
    assert!(
        stamps.keys().any(|k| k.ends_with("run_b.csv")),
        "{stamps:?}"
    );
    assert!(stamps.keys().all(|k| !k.contains(".groove")), "{stamps:?}");
}

#[test]
fn a_hand_edited_lock_is_noticed_though_a_no_op_trusts_the_lock_digests() {
    let p = Project::standard();
    p.stdout(&["run"]);
    p.take_trace();
    let lock = p.read("pipeline.lock");
    let digests = p.read(".groove/lock-digests.json");
    assert!(digests.contains("\"lock_stamp\"") && digests.contains("\"summary\""));
    // a stage's record taken out of the lock by hand: the lock's stamp no longer matches the
    // digests, so the run reads the lock, sees the missing record and writes it back
    let mut edited: serde_json::Value = serde_json::from_str(&lock).unwrap();
    edited["stages"].as_object_mut().unwrap().remove("summary");
    std::thread::sleep(std::time::Duration::from_millis(20));
    p.write(
        "pipeline.lock",
        &(serde_json::to_string_pretty(&edited).unwrap() + "\n"),
    );
    let out = p.stdout(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
    assert_eq!(p.take_trace(), Vec::<String>::new());
    assert_eq!(p.read("pipeline.lock"), lock);
    // digests missing or garbled: the run reads the lock, changes nothing and takes them again
    for sidecar in ["", "not json"] {
        p.write(".groove/lock-digests.json", sidecar);
        let out = p.stdout(&["run"]);
        assert!(out.contains("0 stages run"), "{out}");
        assert_eq!(p.read("pipeline.lock"), lock);
        assert!(p
            .read(".groove/lock-digests.json")
            .contains("\"lock_stamp\""));
    }
    // a param change still reruns its stage and rewrites the lock and its digests
    let before = p.read(".groove/lock-digests.json");
    p.write(
        "pipeline.toml",
        &p.read("pipeline.toml")
            .replacen("scale = 1", "scale = 3", 1),
    );
    p.stdout(&["run"]);
    assert_ne!(p.read("pipeline.lock"), lock);
    assert_ne!(p.read(".groove/lock-digests.json"), before);
}

/// Files of a folder with an extension.
fn count_ext(dir: &std::path::Path, ext: &str) -> usize {
    std::fs::read_dir(dir).map_or(0, |d| {
        d.filter_map(|e| e.ok())
            .filter(|e| e.path().extension().is_some_and(|x| x == ext))
            .count()
    })
}

#[test]
fn a_stage_of_many_items_is_stored_in_packs_that_serve_edits_verify_and_gc() {
    let p = Project::new(PER_ITEM_PIPELINE);
    let runs: Vec<String> = (0..100).map(|i| format!("run_{i:03}.csv")).collect();
    for (i, r) in runs.iter().enumerate() {
        p.write(&format!("data/{r}"), &format!("t,z\n0,{i}\n"));
    }
    p.stdout(&["run"]);
    assert_eq!(p.take_trace().len(), 102, "ingest, 100 fits, summary");
    // the 100 copied runs and the 100 fits went into packs, the fits' entries into one entry
    // pack: loose entries are only ingest's, fit's index and summary's
    assert_eq!(count_ext(&p.path(".groove/objects/packs"), "idx"), 2);
    assert_eq!(count_ext(&p.path(".groove/objects/packs"), "pack"), 2);
    assert_eq!(count_ext(&p.path(".groove/entries/packs"), "json"), 1);
    assert_eq!(count_ext(&p.path(".groove/entries"), "json"), 3);
    let fits_before = p.read("reports/fits/run_090.csv");
    let table = p.read("reports/table.txt");
    assert_eq!(table.lines().count(), 101, "{table}");

    // one edit, then another: the second run finds the 98 untouched items in the entry pack
    p.write("data/run_005.csv", "t,z\n0,edited\n");
    p.stdout(&["run"]);
    assert_eq!(
        p.take_trace(),
        strings(&["fit run_005.csv", "ingest", "summary"])
    );
    p.write("data/run_007.csv", "t,z\n0,edited\n");
    p.stdout(&["run"]);
    assert_eq!(
        p.take_trace(),
        strings(&["fit run_007.csv", "ingest", "summary"])
    );
    assert_eq!(p.read("reports/fits/run_090.csv"), fits_before);

    // 70 runs edited: their copies and fits go into new packs, and the first two packs hold
    // 28 referenced blobs of 100 each
    for r in &runs[10..80] {
        p.write(&format!("data/{r}"), &format!("t,z\n0,{r}\n"));
    }
    p.stdout(&["run"]);
    assert_eq!(p.take_trace().len(), 72);
    assert_eq!(count_ext(&p.path(".groove/objects/packs"), "idx"), 4);

    // gc keeps what the lock names: the mostly unreferenced packs go, their referenced blobs
    // copied out first (loose, being few); a no-op after it runs nothing and every blob reads
    p.stdout(&["gc"]);
    assert_eq!(count_ext(&p.path(".groove/objects/packs"), "idx"), 2);
    assert_eq!(count_ext(&p.path(".groove/objects/packs"), "pack"), 2);
    let out = p.stdout(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
    assert!(p.stale().is_empty());
    p.stdout(&["run", "--force", "summary"]);
    assert_eq!(p.take_trace(), strings(&["summary"]));
    assert_eq!(p.read("reports/table.txt").lines().count(), 101);
    assert_eq!(p.read("reports/fits/run_090.csv"), fits_before);
    let fits_after_edits = p.read("reports/fits/run_050.csv");

    // a damaged pack: verify drops it and the entries naming its blobs; the next run makes
    // them again, with the same bytes
    let pack = std::fs::read_dir(p.path(".groove/objects/packs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| f.extension().is_some_and(|x| x == "pack"))
        .max_by_key(|f| std::fs::metadata(f).unwrap().len())
        .unwrap();
    let mut bytes = std::fs::read(&pack).unwrap();
    bytes[3] ^= 0x20;
    std::fs::write(&pack, bytes).unwrap();
    let out = p.groove(&["verify"]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(!pack.exists(), "verify removes a damaged pack: {said}");
    assert_eq!(said.matches("dropped damaged object").count(), 1, "{said}");
    p.stdout(&["run", "--force", "summary"]);
    // the stage whose pack it was runs again (ingest, or the 70 edited fits), and summary
    let trace = p.take_trace();
    assert!(
        trace == strings(&["ingest", "summary"])
            || (trace.len() == 71 && trace.contains(&"summary".to_string())),
        "{trace:?}"
    );
    assert_eq!(p.read("reports/fits/run_090.csv"), fits_before);
    assert_eq!(p.read("reports/fits/run_050.csv"), fits_after_edits);
    assert_eq!(p.read("reports/table.txt").lines().count(), 101);
    let out = p.stdout(&["run"]);
    assert!(out.contains("0 stages run"), "{out}");
}
