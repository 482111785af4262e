//! Hostile input through the `groove` binary (issue 16): each reproducer of the issue, applied to a
//! copy of a project that has run once, ends within `LIMIT` with exit 2 and a message naming the
//! place — never a panic, never a hang — and leaves every file of the project (reports, lock,
//! config, data, store) byte-identical. A stray file or symlinked tables in the data folder are
//! not errors.
//!
//! The dataset is synthesized once from tests/fixtures/truths/hostile_small.toml and one project
//! runs the whole pipeline on it once; every test works on its own copy.

#[path = "support/files.rs"]
mod files;
#[path = "support/parquet.rs"]
mod parquet;

use files::{
    assert_names, copy_tree, edit_line, edit_lines, repo, scratch, set_cell, set_field, text,
    tree_hashes, GROOVE,
};
use groove::engine::hashing::sha256_hex;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

/// The longest a reproducer may take (the bound).
const LIMIT: Duration = Duration::from_secs(10);

/// Runs the binary in `cwd`, killing it (and failing) if it takes longer than `limit`.
fn groove_within(cwd: &Path, args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(GROOVE)
        .args(args)
        .current_dir(cwd)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the groove binary starts");
    let started = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if started.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().unwrap();
            panic!(
                "groove {args:?} ran longer than {limit:?}; stderr:\n{}",
                text(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// The project after one successful run of the whole pipeline.
fn base() -> &'static Path {
    static BASE: OnceLock<PathBuf> = OnceLock::new();
    BASE.get_or_init(|| {
        let dataset = scratch("hostile").join("dataset");
        let truth = repo().join("tests/fixtures/truths/hostile_small.toml");
        let out = groove_within(
            scratch("hostile"),
            &[
                "synth",
                "--truth",
                truth.to_str().unwrap(),
                "--out",
                dataset.to_str().unwrap(),
            ],
            Duration::from_secs(600),
        );
        assert!(out.status.success(), "synth: {}", text(&out.stderr));
        let project = scratch("hostile").join("base");
        std::fs::create_dir_all(project.join("data")).unwrap();
        std::fs::copy(repo().join("pipeline.toml"), project.join("pipeline.toml")).unwrap();
        for name in ["runs.csv", "trajectories.csv"] {
            std::fs::copy(dataset.join(name), project.join("data").join(name)).unwrap();
        }
        let out = groove_within(&project, &["run"], Duration::from_secs(1800));
        assert!(out.status.success(), "the base run: {}", text(&out.stderr));
        project
    })
}

fn copy_of_base(name: &str) -> PathBuf {
    let to = scratch("hostile").join(name);
    let _ = std::fs::remove_dir_all(&to);
    copy_tree(base(), &to);
    to
}

/// Spoils a copy of the base project, runs it, and checks the acceptance: exit 2 within
/// `LIMIT`, no panic, and every file of the project as it was before the run. Returns stderr.
fn refused(name: &str, spoil: impl FnOnce(&Path)) -> String {
    let setup = |p: &Path| {
        spoil(p);
        assert!(p.join("reports/report.html").is_file() && p.join("pipeline.lock").is_file());
    };
    let (_, out) = case(name, setup, &["run"], LIMIT, 2, &[]);
    text(&out.stderr)
}

/// The first run id of `experiment` in runs.csv.
fn first_run(project: &Path, experiment: &str) -> String {
    let runs = std::fs::read_to_string(project.join("data/runs.csv")).unwrap();
    runs.lines()
        .skip(1)
        .map(|l| l.split(',').collect::<Vec<_>>())
        .find(|f| f[1] == experiment)
        .map(|f| f[0].to_string())
        .unwrap()
}

// ------------------------------------------------------------------------ the reproducers

#[test]
fn a_position_of_1e308_exits_2_at_its_cell() {
    let err = refused("z_1e308", |p| {
        set_cell(&p.join("data/trajectories.csv"), 101, 4, "1e308")
    });
    assert_names(&err, &["trajectories.csv row 101, column z_m"]);
}

#[test]
fn huge_times_exit_2_at_their_cell() {
    for value in ["1e308", "-1e308", "9.2e18", "-9.2e18", "1e20"] {
        let err = refused(&format!("t_{value}"), |p| {
            set_cell(&p.join("data/trajectories.csv"), 101, 3, value)
        });
        assert_names(&err, &["trajectories.csv row 101, column t_s"]);
    }
}

#[test]
fn a_far_frame_at_a_matching_time_exits_2() {
    let err = refused("far_frame", |p| {
        edit_line(&p.join("data/trajectories.csv"), 101, |l| {
            set_field(&set_field(l, 2, "100000000"), 3, "10000")
        })
    });
    assert_names(&err, &["trajectories.csv row 101, column t_s"]);
}

#[test]
fn a_frame_rate_typed_in_khz_exits_2_saying_so() {
    let err = refused("fps_khz", |p| {
        set_cell(&p.join("data/runs.csv"), 2, 4, "10")
    });
    assert_names(&err, &["runs.csv row 2, column fps", "kHz", "10000"]);
}

#[test]
fn a_run_whose_times_are_all_zero_exits_2() {
    let err = refused("t_zero", |p| {
        let run = first_run(p, "single");
        edit_lines(&p.join("data/trajectories.csv"), |k, l| {
            vec![if k > 1 && l.starts_with(&format!("{run},")) {
                set_field(l, 3, "0")
            } else {
                l.into()
            }]
        })
    });
    assert_names(&err, &["trajectories.csv row 3, column t_s", "not after"]);
}

#[test]
fn time_going_backwards_exits_2() {
    let err = refused("t_backwards", |p| {
        let path = p.join("data/trajectories.csv");
        let lines: Vec<String> = std::fs::read_to_string(&path)
            .unwrap()
            .lines()
            .map(String::from)
            .collect();
        let t = |k: usize| lines[k - 1].split(',').nth(3).unwrap().to_string();
        let (t101, t102) = (t(101), t(102));
        edit_lines(&path, |k, l| {
            vec![match k {
                101 => set_field(l, 3, &t102),
                102 => set_field(l, 3, &t101),
                _ => l.into(),
            }]
        })
    });
    assert_names(
        &err,
        &[
            "trajectories.csv row 102, column t_s",
            "time goes backwards",
        ],
    );
}

#[test]
fn a_collision_run_without_its_target_exits_2() {
    let err = refused("no_target", |p| {
        let run = first_run(p, "collision");
        edit_lines(&p.join("data/trajectories.csv"), |_, l| {
            if l.starts_with(&format!("{run},1,")) {
                vec![]
            } else {
                vec![l.into()]
            }
        })
    });
    assert_names(
        &err,
        &[
            "trajectories.csv",
            "column frame",
            "has 0 frames of particle 1 (the target)",
        ],
    );
}

#[test]
fn a_row_with_an_extra_field_exits_2_in_groove_words() {
    let err = refused("extra_field", |p| {
        edit_lines(&p.join("data/trajectories.csv"), |k, l| {
            vec![if k == 50 { format!("{l},7") } else { l.into() }]
        })
    });
    assert_names(
        &err,
        &[
            "trajectories.csv row 50",
            "6 fields but the header names 5 columns",
        ],
    );
    assert!(!err.contains("Schema") && !err.contains("cSV"), "{err}");
}

#[test]
fn invalid_utf8_in_the_header_exits_2_naming_row_and_column() {
    let err = refused("utf8", |p| {
        let path = p.join("data/runs.csv");
        let mut bytes = std::fs::read(&path).unwrap();
        let at = bytes.windows(8).position(|w| w == b"material").unwrap();
        bytes[at + 3] = 0xe9; // "mat\xe9rial", Latin-1
        std::fs::write(&path, bytes).unwrap();
    });
    assert_names(
        &err,
        &[
            "runs.csv row 1, column",
            "not UTF-8",
            "save the file as UTF-8",
        ],
    );
}

#[test]
fn numbers_stored_as_text_in_parquet_exit_2() {
    let err = refused("parquet_text", |p| {
        let csv = std::fs::read_to_string(p.join("data/trajectories.csv")).unwrap();
        let bytes = parquet::trajectories_parquet(&csv, true);
        std::fs::remove_file(p.join("data/trajectories.csv")).unwrap();
        std::fs::write(p.join("data/trajectories.parquet"), bytes).unwrap();
    });
    assert_names(
        &err,
        &["trajectories.parquet, column t_s", "stored as text"],
    );
}

// ------------------------------------------------------------------------ a hostile world

#[test]
fn symlinked_tables_are_followed() {
    let project = copy_of_base("symlinks");
    let elsewhere = scratch("hostile").join("symlinks-elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let reports = tree_hashes(&project.join("reports"));
    for name in ["runs.csv", "trajectories.csv"] {
        std::fs::rename(project.join("data").join(name), elsewhere.join(name)).unwrap();
        std::os::unix::fs::symlink(elsewhere.join(name), project.join("data").join(name)).unwrap();
    }
    let out = groove_within(&project, &["run"], LIMIT);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("0 stages run"),
        "{}",
        text(&out.stdout)
    );
    assert_eq!(tree_hashes(&project.join("reports")), reports);
}

#[test]
fn a_stray_file_in_the_data_folder_is_ignored_and_named() {
    let project = copy_of_base("stray");
    let reports = tree_hashes(&project.join("reports"));
    std::fs::write(project.join("data/notes (copy).txt"), "kick 3 was odd").unwrap();
    let out = groove_within(&project, &["run"], LIMIT);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("0 stages run"),
        "{}",
        text(&out.stdout)
    );
    assert_names(&text(&out.stderr), &["notes (copy).txt is not read"]);
    assert_eq!(tree_hashes(&project.join("reports")), reports);
}

// ------------------------------------------------------------------------ the engine's part

/// Runs `args` in a copy of the base project after `setup`, expecting `code`; returns the
/// output and checks that no file outside `may_change` (relative paths) changed.
fn engine_case(
    name: &str,
    setup: impl FnOnce(&Path),
    args: &[&str],
    code: i32,
    may_change: &[&str],
) -> (PathBuf, Output) {
    case(name, setup, args, Duration::from_secs(60), code, may_change)
}

/// Runs `args` within `limit` in a copy of the base project after `setup`, expecting `code` and
/// no panic; no file outside `may_change` (relative paths) may change.
fn case(
    name: &str,
    setup: impl FnOnce(&Path),
    args: &[&str],
    limit: Duration,
    code: i32,
    may_change: &[&str],
) -> (PathBuf, Output) {
    let project = copy_of_base(name);
    setup(&project);
    let before = tree_hashes(&project);
    let out = groove_within(&project, args, limit);
    let stderr = text(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(code),
        "{name}: exit code; stderr:\n{stderr}"
    );
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    let after = tree_hashes(&project);
    let changed: Vec<&String> = before
        .keys()
        .chain(after.keys())
        .filter(|k| before.get(*k) != after.get(*k))
        .filter(|k| !may_change.iter().any(|m| k.starts_with(m)))
        .collect();
    assert!(changed.is_empty(), "{name}: files changed: {changed:?}");
    (project, out)
}

fn append_config(project: &Path, extra: &str) {
    let mut toml = std::fs::read_to_string(project.join("pipeline.toml")).unwrap();
    toml += extra;
    std::fs::write(project.join("pipeline.toml"), toml).unwrap();
}

#[test]
fn a_stage_failing_after_others_finished_leaves_reports_and_lock_whole() {
    // a new seed reruns every stage with new numbers; a command stage after aggregate fails
    let (_, out) = engine_case(
        "half_updated",
        |p| {
            let toml = std::fs::read_to_string(p.join("pipeline.toml")).unwrap();
            std::fs::write(
                p.join("pipeline.toml"),
                toml.replace("seed = 20261122", "seed = 7"),
            )
            .unwrap();
            append_config(p, "\n[stages.boom]\nkind = \"command\"\ncmd = \"cat {in.s} > {out.o}; exit 3\"\ninputs = { s = \"aggregate:summary\" }\noutputs = { o = \"${reports}/boom.txt\" }\n");
        },
        &["run"],
        2,
        &[".groove/"],
    );
    assert_names(&text(&out.stderr), &["boom"]);
}

#[test]
fn outputs_outside_the_project_or_onto_inputs_are_config_errors() {
    for (name, target, says) in [
        ("escape", "../../outside.txt", "outside the project folder"),
        (
            "absolute",
            "/tmp/groove-hostile-absolute.txt",
            "outside the project folder",
        ),
        ("onto_data", "${data}/runs.csv", "dataset folder"),
        ("onto_lock", "pipeline.lock", "pipeline.lock"),
        ("onto_config", "pipeline.toml", "pipeline config"),
        ("onto_store", ".groove/x", "the store"),
    ] {
        let (_, out) = engine_case(
            &format!("out_{name}"),
            |p| {
                let toml = std::fs::read_to_string(p.join("pipeline.toml")).unwrap();
                let toml = toml.replace(
                    "summary = \"${reports}/summary.json\"",
                    &format!("summary = \"{target}\""),
                );
                std::fs::write(p.join("pipeline.toml"), toml).unwrap();
            },
            &["run"],
            2,
            &["pipeline.toml"],
        );
        let err = text(&out.stderr);
        assert!(
            err.contains("pipeline.toml:") && err.contains(says),
            "{name}: {err}"
        );
    }
    assert!(!Path::new("/tmp/groove-hostile-absolute.txt").exists());
}

#[test]
fn reports_in_the_data_folder_are_refused() {
    let (_, out) = engine_case("out_is_data", |_| {}, &["run", "--out", "data"], 2, &[]);
    assert_names(&text(&out.stderr), &["dataset folder"]);
}

#[test]
fn a_file_output_never_replaces_a_folder() {
    let (project, out) = engine_case(
        "folder_kept",
        |p| {
            std::fs::create_dir_all(p.join("reports/keep")).unwrap();
            std::fs::write(p.join("reports/keep/mine.txt"), "mine").unwrap();
            let toml = std::fs::read_to_string(p.join("pipeline.toml")).unwrap();
            let toml = toml.replace(
                "summary = \"${reports}/summary.json\"",
                "summary = \"${reports}/keep\"",
            );
            std::fs::write(p.join("pipeline.toml"), toml).unwrap();
        },
        &["run"],
        2,
        &[".groove/"],
    );
    assert_names(&text(&out.stderr), &["never replaces a folder"]);
    assert_eq!(
        std::fs::read_to_string(project.join("reports/keep/mine.txt")).unwrap(),
        "mine"
    );
}

#[test]
fn publish_refuses_a_file_and_sweeps_its_own_leftovers() {
    let (project, out) = engine_case(
        "publish_file",
        |p| std::fs::write(p.join("../publish_file-target"), "precious").unwrap(),
        &["publish", "--to", "../publish_file-target"],
        2,
        &[],
    );
    assert_names(&text(&out.stderr), &["is a file"]);
    let parent = project.parent().unwrap();
    assert_eq!(
        std::fs::read_to_string(parent.join("publish_file-target")).unwrap(),
        "precious"
    );
    // a kill during an earlier publish left a half-built bundle beside the target
    let leftover = parent.join(".publish_file-bundle.groove-new-1-1");
    std::fs::create_dir_all(&leftover).unwrap();
    let out = groove_within(
        &project,
        &["publish", "--to", "../publish_file-bundle"],
        LIMIT,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(!leftover.exists(), "the leftover of a killed publish stays");
    assert!(parent.join("publish_file-bundle/SHA256SUMS").is_file());
}

/// The store object holding `rel` (a file of the project).
/// `groove status` finds no stage stale.
fn assert_every_stage_fresh(project: &Path) {
    let status = groove_within(project, &["status", "--json"], LIMIT);
    assert!(
        !text(&status.stdout).contains("\"stale\""),
        "{}",
        text(&status.stdout)
    );
}

fn object_of(project: &Path, rel: &str) -> PathBuf {
    let h = sha256_hex(&std::fs::read(project.join(rel)).unwrap());
    project.join(".groove/objects").join(&h[..2]).join(&h[2..])
}

#[test]
fn a_damaged_object_is_a_miss_and_the_stage_reruns() {
    let project = copy_of_base("damaged_object");
    let good = std::fs::read(project.join("reports/fits.csv")).unwrap();
    let object = object_of(&project, "reports/fits.csv");
    let mut bytes = std::fs::read(&object).unwrap();
    bytes[10] ^= 0x20;
    std::fs::write(&object, bytes).unwrap();
    std::fs::remove_file(project.join("reports/fits.csv")).unwrap();
    let out = groove_within(&project, &["run"], Duration::from_secs(60));
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        std::fs::read(project.join("reports/fits.csv")).unwrap(),
        good
    );
    assert_eq!(
        sha256_hex(&std::fs::read(&object).unwrap()),
        sha256_hex(&good),
        "the object is repaired"
    );
    assert_every_stage_fresh(&project);
}

#[test]
fn verify_drops_damaged_objects_and_says_so() {
    let project = copy_of_base("verify");
    let clean = groove_within(&project, &["verify"], Duration::from_secs(60));
    assert!(clean.status.success(), "{}", text(&clean.stdout));
    assert!(text(&clean.stdout).contains("the store is sound"));
    let object = object_of(&project, "reports/summary.json");
    let mut bytes = std::fs::read(&object).unwrap();
    bytes[3] ^= 0x01;
    std::fs::write(&object, bytes).unwrap();
    let out = groove_within(&project, &["verify"], Duration::from_secs(60));
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stdout));
    let name = object
        .parent()
        .unwrap()
        .file_name()
        .unwrap()
        .to_string_lossy()
        .into_owned()
        + &object.file_name().unwrap().to_string_lossy();
    assert!(
        text(&out.stdout).contains(&format!("dropped damaged object {name}")),
        "{}",
        text(&out.stdout)
    );
    assert!(!object.exists());
    let rerun = groove_within(&project, &["run"], Duration::from_secs(60));
    assert!(rerun.status.success(), "{}", text(&rerun.stderr));
    assert_every_stage_fresh(&project);
}

#[test]
fn an_empty_config_changes_nothing_and_gc_keeps_the_store() {
    let (project, out) = engine_case(
        "empty_config",
        |p| std::fs::write(p.join("pipeline.toml"), "").unwrap(),
        &["run"],
        2,
        &[],
    );
    assert_names(&text(&out.stderr), &["pipeline.toml:1: defines no stages"]);
    let before = tree_hashes(&project);
    let gc = groove_within(&project, &["gc"], LIMIT);
    assert_eq!(gc.status.code(), Some(2));
    assert_eq!(tree_hashes(&project), before);

    // a valid config with the lock gone: gc refuses rather than dropping every entry
    let (_, out) = engine_case(
        "gc_without_lock",
        |p| std::fs::remove_file(p.join("pipeline.lock")).unwrap(),
        &["gc"],
        2,
        &[],
    );
    assert_names(&text(&out.stderr), &["nothing was removed"]);
}

#[test]
fn invalid_utf8_in_the_config_names_its_line() {
    let (_, out) = engine_case(
        "config_utf8",
        |p| {
            let mut bytes = std::fs::read(p.join("pipeline.toml")).unwrap();
            let at = bytes.windows(6).position(|w| w == b"ingest").unwrap();
            bytes[at] = 0xff;
            std::fs::write(p.join("pipeline.toml"), bytes).unwrap();
        },
        &["run"],
        2,
        &[],
    );
    assert_names(&text(&out.stderr), &["is not UTF-8"]);
    assert_names(&text(&out.stderr), &["pipeline.toml:"]);
}

// ------------------------------------------------- messages of the store and config probe

/// Invariant: bad input exits 2 naming its place, with nothing lost. A run id that cannot name
/// a file (`../x`, `.`, `..`, one with a line break) is refused at its cell.
#[test]
fn a_run_id_that_is_a_path_exits_2_at_its_cell() {
    for (k, id) in ["../x", ".", "..", "\"a\nb\"", "a/b"].iter().enumerate() {
        let err = refused(&format!("run_id_{k}"), |p| {
            set_cell(&p.join("data/runs.csv"), 2, 0, id)
        });
        assert_names(&err, &["runs.csv row 2, column run", "rename the run"]);
    }
}

/// Invariant: bad input exits 2 naming its place. A header that names one column twice is
/// refused (it was read silently, one of the two columns dropped).
#[test]
fn a_header_naming_a_column_twice_exits_2() {
    let err = refused("dup_column", |p| {
        edit_line(&p.join("data/runs.csv"), 1, |l| set_field(l, 3, "fps"))
    });
    assert_names(&err, &["runs.csv row 1, column fps", "twice"]);
}

/// Invariant: bad input exits 2 naming its place. A NaN param never reaches a stage.
#[test]
fn a_nan_param_exits_2_at_its_line() {
    let (_, out) = engine_case(
        "nan_param",
        |p| {
            let path = p.join("pipeline.toml");
            let text = std::fs::read_to_string(&path).unwrap();
            let text = text.replacen(
                "params = { format = \"auto\" }",
                "params = { format = \"auto\", x = nan }",
                1,
            );
            std::fs::write(path, text).unwrap();
        },
        &["run"],
        2,
        &[],
    );
    assert_names(
        &text(&out.stderr),
        &["pipeline.toml:", "`x` = nan", "finite number"],
    );
}

/// Invariant: bad input exits 2 naming its place. `reports = "${data}"` says the project's
/// folders take no variables (it said "unknown variable `${data}`; use `${data}`").
#[test]
fn a_variable_in_the_project_folders_exits_2_saying_so() {
    let (_, out) = engine_case(
        "reports_var",
        |p| {
            let path = p.join("pipeline.toml");
            let text = std::fs::read_to_string(&path).unwrap();
            std::fs::write(
                path,
                text.replacen("reports = \"reports\"", "reports = \"${data}\"", 1),
            )
            .unwrap();
        },
        &["run"],
        2,
        &[],
    );
    let err = text(&out.stderr);
    assert_names(&err, &["pipeline.toml:7", "take no variables"]);
    assert!(!err.contains("unknown variable"), "{err}");
}

/// Invariant: no store or remote entry can make groove write outside the project and its
/// store, and the project is no remote. `file://.` (the project itself) is refused.
#[test]
fn the_project_folder_as_remote_exits_2() {
    for url in ["file://.", "file://reports/cache", "file://.groove"] {
        let (_, out) = engine_case(
            &format!("remote_{}", url.len()),
            |_| {},
            &["run", "--remote", url],
            2,
            &[],
        );
        assert_names(&text(&out.stderr), &["inside the project"]);
    }
}

// ------------------------------------------------------------------- memory bounds

/// A header of 5,000 columns is refused before the table is parsed (the parser held an empty
/// cell per header column per row: 200,000 columns over 2,000 rows took 7.5 GB), naming the
/// file, the limit and the variable that raises it.
#[test]
fn a_header_wider_than_the_limit_exits_2_before_the_table_is_read() {
    let err = refused("wide_header", |p| {
        let runs = std::fs::read_to_string(p.join("data/runs.csv")).unwrap();
        let (header, rows) = runs.split_once('\n').unwrap();
        let extra: Vec<String> = (0..5000).map(|i| format!("x{i}")).collect();
        let wide = format!("{header},{}\n{rows}", extra.join(","));
        std::fs::write(p.join("data/runs.csv"), wide).unwrap();
    });
    let columns = "the header names 5007 columns, more than the 1000 groove reads";
    assert!(
        err.contains("runs.csv row 1") && err.contains(columns),
        "{err}"
    );
    assert!(err.contains("GROOVE_INGEST_MAX_COLUMNS=5007"), "{err}");
}

/// A runs.csv of 257 MB (sparse: its size, not its bytes, is the point) is refused before it
/// is read whole, naming its size, the limit and the variable that raises it.
#[test]
fn a_file_read_whole_above_the_limit_exits_2_before_it_is_read() {
    let err = refused("huge_runs", |p| {
        let f = std::fs::OpenOptions::new()
            .append(true)
            .open(p.join("data/runs.csv"))
            .unwrap();
        f.set_len(257 << 20).unwrap();
    });
    assert!(
        err.contains("runs.csv: is 257 MB, more than the 256 MB ingest reads whole"),
        "{err}"
    );
    assert!(err.contains("GROOVE_INGEST_MAX_WHOLE_MB=257"), "{err}");
}
