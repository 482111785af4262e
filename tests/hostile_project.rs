//! Hostile input through the `groove` binary (issue 16): each reproducer of the issue, applied to a
//! copy of a project that has run once, ends within `LIMIT` with exit 2 and a message naming the
//! place — never a panic, never a hang — and leaves every file of the project (reports, lock,
//! config, data, store) byte-identical. A stray file or symlinked tables in the data folder are
//! not errors.
//!
//! The dataset is synthesized once from tests/fixtures/truths/hostile_small.toml and one project
//! runs the whole pipeline on it once; every test works on its own copy.

use groove::engine::hashing::sha256_hex;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

const GROOVE: &str = env!("CARGO_BIN_EXE_groove");
/// The longest a reproducer may take (the bound).
const LIMIT: Duration = Duration::from_secs(10);

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn scratch() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("hostile");
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    })
}

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

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The project after one successful run of the whole pipeline.
fn base() -> &'static Path {
    static BASE: OnceLock<PathBuf> = OnceLock::new();
    BASE.get_or_init(|| {
        let dataset = scratch().join("dataset");
        let truth = repo().join("tests/fixtures/truths/hostile_small.toml");
        let out = groove_within(
            scratch(),
            &["synth", "--truth", truth.to_str().unwrap(), "--out", dataset.to_str().unwrap()],
            Duration::from_secs(600),
        );
        assert!(out.status.success(), "synth: {}", text(&out.stderr));
        let project = scratch().join("base");
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

fn copy_tree(from: &Path, to: &Path) {
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

fn copy_of_base(name: &str) -> PathBuf {
    let to = scratch().join(name);
    let _ = std::fs::remove_dir_all(&to);
    copy_tree(base(), &to);
    to
}

/// sha256 of every file under `dir` by relative path, except the store's caches and log (which
/// a run may touch without changing anything the user sees).
fn tree_hashes(dir: &Path) -> BTreeMap<String, String> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<String, String>) {
        let Ok(entries) = std::fs::read_dir(dir) else { return };
        for entry in entries {
            let path = entry.unwrap().path();
            let rel = path.strip_prefix(root).unwrap().to_string_lossy().into_owned();
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
fn edit_lines(path: &Path, mut edit: impl FnMut(usize, &str) -> Vec<String>) {
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

/// The line with field `field` replaced.
fn set_field(line: &str, field: usize, value: &str) -> String {
    let mut cells: Vec<&str> = line.split(',').collect();
    cells[field] = value;
    cells.join(",")
}

/// Spoils a copy of the base project, runs it, and checks the acceptance: exit 2 within
/// `LIMIT`, no panic, and every file of the project as it was before the run. Returns stderr.
fn refused(name: &str, spoil: impl FnOnce(&Path)) -> String {
    let project = copy_of_base(name);
    spoil(&project);
    let before = tree_hashes(&project);
    assert!(before.contains_key("reports/report.html") && before.contains_key("pipeline.lock"));
    let out = groove_within(&project, &["run"], LIMIT);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{name}: exit code; stderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    let after = tree_hashes(&project);
    let changed: Vec<&String> = before
        .keys()
        .chain(after.keys())
        .filter(|k| before.get(*k) != after.get(*k))
        .collect();
    assert!(changed.is_empty(), "{name}: files changed: {changed:?}");
    stderr
}

fn assert_names(stderr: &str, parts: &[&str]) {
    for p in parts {
        assert!(stderr.contains(p), "the error does not name `{p}`:\n{stderr}");
    }
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
        edit_lines(&p.join("data/trajectories.csv"), |k, l| {
            vec![if k == 101 { set_field(l, 4, "1e308") } else { l.into() }]
        })
    });
    assert_names(&err, &["trajectories.csv row 101, column z_m"]);
}

#[test]
fn huge_times_exit_2_at_their_cell() {
    for value in ["1e308", "-1e308", "9.2e18", "-9.2e18", "1e20"] {
        let err = refused(&format!("t_{value}"), |p| {
            edit_lines(&p.join("data/trajectories.csv"), |k, l| {
                vec![if k == 101 { set_field(l, 3, value) } else { l.into() }]
            })
        });
        assert_names(&err, &["trajectories.csv row 101, column t_s"]);
    }
}

#[test]
fn a_far_frame_at_a_matching_time_exits_2() {
    let err = refused("far_frame", |p| {
        edit_lines(&p.join("data/trajectories.csv"), |k, l| {
            vec![if k == 101 { set_field(&set_field(l, 2, "100000000"), 3, "10000") } else { l.into() }]
        })
    });
    assert_names(&err, &["trajectories.csv row 101, column t_s"]);
}

#[test]
fn a_frame_rate_typed_in_khz_exits_2_saying_so() {
    let err = refused("fps_khz", |p| {
        edit_lines(&p.join("data/runs.csv"), |k, l| {
            vec![if k == 2 { set_field(l, 4, "10") } else { l.into() }]
        })
    });
    assert_names(&err, &["runs.csv row 2, column fps", "kHz", "10000"]);
}

#[test]
fn a_run_whose_times_are_all_zero_exits_2() {
    let err = refused("t_zero", |p| {
        let run = first_run(p, "single");
        edit_lines(&p.join("data/trajectories.csv"), |k, l| {
            vec![if k > 1 && l.starts_with(&format!("{run},")) { set_field(l, 3, "0") } else { l.into() }]
        })
    });
    assert_names(&err, &["trajectories.csv row 3, column t_s", "not after"]);
}

#[test]
fn time_going_backwards_exits_2() {
    let err = refused("t_backwards", |p| {
        let path = p.join("data/trajectories.csv");
        let lines: Vec<String> = std::fs::read_to_string(&path).unwrap().lines().map(String::from).collect();
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
    assert_names(&err, &["trajectories.csv row 102, column t_s", "time goes backwards"]);
}

#[test]
fn a_collision_run_without_its_target_exits_2() {
    let err = refused("no_target", |p| {
        let run = first_run(p, "collision");
        edit_lines(&p.join("data/trajectories.csv"), |_, l| {
            if l.starts_with(&format!("{run},1,")) { vec![] } else { vec![l.into()] }
        })
    });
    assert_names(&err, &["trajectories.csv", "column frame", "has 0 frames of particle 1 (the target)"]);
}

#[test]
fn a_row_with_an_extra_field_exits_2_in_groove_words() {
    let err = refused("extra_field", |p| {
        edit_lines(&p.join("data/trajectories.csv"), |k, l| {
            vec![if k == 50 { format!("{l},7") } else { l.into() }]
        })
    });
    assert_names(&err, &["trajectories.csv row 50", "6 fields but the header names 5 columns"]);
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
    assert_names(&err, &["runs.csv row 1, column", "not UTF-8", "save the file as UTF-8"]);
}

#[test]
fn numbers_stored_as_text_in_parquet_exit_2() {
    use polars::prelude::*;
    let err = refused("parquet_text", |p| {
        let csv = std::fs::read_to_string(p.join("data/trajectories.csv")).unwrap();
        let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
        let col = |k: usize| rows.iter().map(|r| r[k].to_string()).collect::<Vec<_>>();
        let int = |k: usize| rows.iter().map(|r| r[k].parse::<i64>().unwrap()).collect::<Vec<_>>();
        let mut df = DataFrame::new(
            rows.len(),
            vec![
                Column::new("run".into(), col(0)),
                Column::new("particle".into(), int(1)),
                Column::new("frame".into(), int(2)),
                Column::new("t_s".into(), col(3)),
                Column::new("z_m".into(), col(4)),
            ],
        )
        .unwrap();
        let mut bytes = Vec::new();
        ParquetWriter::new(&mut bytes).finish(&mut df).unwrap();
        std::fs::remove_file(p.join("data/trajectories.csv")).unwrap();
        std::fs::write(p.join("data/trajectories.parquet"), bytes).unwrap();
    });
    assert_names(&err, &["trajectories.parquet, column t_s", "stored as text"]);
}

// ------------------------------------------------------------------------ a hostile world

#[test]
fn symlinked_tables_are_followed() {
    let project = copy_of_base("symlinks");
    let elsewhere = scratch().join("symlinks-elsewhere");
    std::fs::create_dir_all(&elsewhere).unwrap();
    let reports = tree_hashes(&project.join("reports"));
    for name in ["runs.csv", "trajectories.csv"] {
        std::fs::rename(project.join("data").join(name), elsewhere.join(name)).unwrap();
        std::os::unix::fs::symlink(elsewhere.join(name), project.join("data").join(name)).unwrap();
    }
    let out = groove_within(&project, &["run"], LIMIT);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("0 stages run"), "{}", text(&out.stdout));
    assert_eq!(tree_hashes(&project.join("reports")), reports);
}

#[test]
fn a_stray_file_in_the_data_folder_is_ignored_and_named() {
    let project = copy_of_base("stray");
    let reports = tree_hashes(&project.join("reports"));
    std::fs::write(project.join("data/notes (copy).txt"), "kick 3 was odd").unwrap();
    let out = groove_within(&project, &["run"], LIMIT);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("0 stages run"), "{}", text(&out.stdout));
    assert!(text(&out.stderr).contains("notes (copy).txt is not read"), "{}", text(&out.stderr));
    assert_eq!(tree_hashes(&project.join("reports")), reports);
}
