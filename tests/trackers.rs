//! Tracker exports made by the real tools (tests/fixtures/trackers/, made by make_fixtures.py with
//! trackpy 0.7 from rendered videos of runs with a known truth): every layout (one trackpy file of
//! all runs with a `run` column, one file per run with a manifest of two materials, TrackMate XML,
//! TrackMate's CSV under its default name) gives the same recordings and fits as the interchange
//! format of the same positions, dropped tracks are listed, and a wrong axis stops with advice.

use groove::fit::{fit_single, FitOptions, SingleFit};
use groove::ingest::{self, Axis, IngestParams, Ingested};
use groove::recording::Recording;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

type Files = BTreeMap<String, Vec<u8>>;

/// The rendered videos' pixel size and frame rate (make_fixtures.py).
const M_PER_PX: f64 = 2.0e-5;
const FPS: f64 = 10_000.0;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/trackers")
}

fn folder(name: &str) -> Files {
    let mut files = Files::new();
    for e in std::fs::read_dir(fixtures().join(name)).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            files.insert(n, std::fs::read(&p).unwrap());
        }
    }
    files
}

/// The fixtures' calibration: the groove along image x, nothing else (the manifests give the rest).
fn params() -> IngestParams {
    let mut p = IngestParams::default();
    p.calibration.m_per_px = Some(M_PER_PX);
    p.calibration.axis = Axis::X;
    p
}

fn ingest_ok(files: &Files, p: &IngestParams) -> Ingested {
    ingest::ingest(files, p).unwrap_or_else(|e| panic!("ingest failed: {e}"))
}

/// (run, material) of the manifest runs.csv of a fixture folder, read as plain text.
fn manifest(files: &Files) -> Vec<(String, String)> {
    let text = String::from_utf8(files["runs.csv"].clone()).unwrap();
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n).unwrap();
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[col("run")].to_string(), f[col("material")].to_string())
        })
        .collect()
}

/// One trackpy CSV as (run, particle, frame, x) rows, parsed here by hand.
fn trackpy_rows(text: &str, run_of_file: &str) -> Vec<(String, i64, i64, f64)> {
    let mut lines = text.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |n: &str| head.iter().position(|h| *h == n);
    let (x, frame, particle, run) = (
        col("x").unwrap(),
        col("frame").unwrap(),
        col("particle").unwrap(),
        col("run"),
    );
    lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                run.map_or(run_of_file.to_string(), |r| f[r].to_string()),
                f[particle].parse().unwrap(),
                f[frame].parse().unwrap(),
                f[x].parse().unwrap(),
            )
        })
        .collect()
}

/// The interchange format (runs.csv + trajectories.csv) of trackpy rows, converted here
/// independently of ingest: z = x · m_per_px, t = (frame − first frame) / fps. Each run must be
/// one trackpy track (the fixtures are).
fn interchange_of(rows: &[(String, i64, i64, f64)], materials: &[(String, String)]) -> Files {
    let mut runs = String::from("run,experiment,material,diameter_m,fps\n");
    let mut traj = String::from("run,particle,frame,t_s,z_m\n");
    for (run, material) in materials {
        let mine: Vec<&(String, i64, i64, f64)> = rows.iter().filter(|r| &r.0 == run).collect();
        if mine.is_empty() {
            continue;
        }
        let tracks: std::collections::BTreeSet<i64> = mine.iter().map(|r| r.1).collect();
        assert_eq!(tracks.len(), 1, "run {run} has tracks {tracks:?}");
        runs += &format!("{run},single,{material},0.0003,{FPS}\n");
        let f0 = mine.iter().map(|r| r.2).min().unwrap();
        for r in mine {
            traj += &format!(
                "{run},0,{},{:e},{:e}\n",
                r.2,
                (r.2 - f0) as f64 / FPS,
                r.3 * M_PER_PX
            );
        }
    }
    Files::from([
        ("runs.csv".to_string(), runs.into_bytes()),
        ("trajectories.csv".to_string(), traj.into_bytes()),
    ])
}

/// The recordings agree: same runs, metadata, frames; t and z within 1e-15 s / 1e-15 m.
fn assert_same_recordings(got: &[Recording], want: &[Recording]) {
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.info.run, w.info.run);
        assert_eq!(g.info.material, w.info.material);
        assert_eq!(g.info.fps, w.info.fps);
        assert_eq!(g.info.diameter_m, w.info.diameter_m);
        assert_eq!(g.tracks.len(), 1);
        let (gt, wt) = (&g.tracks[0], &w.tracks[0]);
        assert_eq!(gt.frame, wt.frame, "{}", g.info.run);
        for k in 0..gt.frame.len() {
            assert!((gt.t_s[k] - wt.t_s[k]).abs() < 1e-15);
            assert!(
                (gt.z_m[k] - wt.z_m[k]).abs() < 1e-15,
                "{} {} {}",
                g.info.run,
                gt.z_m[k],
                wt.z_m[k]
            );
        }
    }
}

fn fits(recs: &[Recording]) -> Vec<SingleFit> {
    recs.iter()
        .map(|r| fit_single(r, &FitOptions::default()))
        .collect()
}

/// The fits agree to 1e-9 (relative) in v0, μ and T.
fn assert_same_fits(got: &[SingleFit], want: &[SingleFit]) {
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(want) {
        assert_eq!(
            (&g.run, &g.material, &g.status),
            (&w.run, &w.material, &w.status)
        );
        for (a, b) in [(g.v0_mps, w.v0_mps), (g.mu, w.mu), (g.t_drag_s, w.t_drag_s)] {
            assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1e-3),
                "{}: {a} vs {b}",
                g.run
            );
        }
    }
}

/// The true v0 of every run (truth/runs_truth.csv) and μ of every material (truth.toml).
fn truth() -> (BTreeMap<String, f64>, BTreeMap<String, f64>) {
    let csv = std::fs::read_to_string(fixtures().join("truth/runs_truth.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let v = head.iter().position(|h| *h == "v0_mps").unwrap();
    let v0 = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0].to_string(), f[v].parse::<f64>().unwrap())
        })
        .collect();
    let t: toml::Table = std::fs::read_to_string(fixtures().join("truth.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let mu = t["materials"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            (
                m["name"].as_str().unwrap().to_string(),
                m["friction"]["mu"].as_float().unwrap(),
            )
        })
        .collect();
    (v0, mu)
}

#[test]
fn trackpy_file_of_all_runs_gives_the_interchange_fits_and_the_truth() {
    let files = folder("trackpy_all");
    let materials = manifest(&files);
    let got = ingest_ok(&files, &params());
    assert_eq!(got.recordings.len(), 6);
    let rows = trackpy_rows(std::str::from_utf8(&files["tracks.csv"]).unwrap(), "");
    let want = ingest_ok(&interchange_of(&rows, &materials), &IngestParams::default());
    assert_same_recordings(&got.recordings, &want.recordings);
    let (fg, fw) = (fits(&got.recordings), fits(&want.recordings));
    assert_same_fits(&fg, &fw);
    // A good spot diameter: every run fits near its truth.
    let (v0, mu) = truth();
    for f in &fg {
        assert_eq!(f.status, "converged", "{f:?}");
        let v = v0[&f.run];
        assert!(
            (f.v0_mps - v).abs() < 0.01 * v.abs(),
            "{}: v0 {} truth {v}",
            f.run,
            f.v0_mps
        );
        assert!(
            (f.mu - mu[&f.material]).abs() < 0.03,
            "{}: mu {} truth {}",
            f.run,
            f.mu,
            mu[&f.material]
        );
    }
}

#[test]
fn one_trackpy_file_per_run_with_a_manifest_of_two_materials() {
    let files = folder("trackpy_locked");
    let materials = manifest(&files);
    let kinds: std::collections::BTreeSet<&str> = materials.iter().map(|m| m.1.as_str()).collect();
    assert_eq!(kinds.len(), 2, "the manifest holds two materials");
    let got = ingest_ok(&files, &params());
    assert_eq!(got.recordings.len(), materials.len());
    for r in &got.recordings {
        let m = &materials.iter().find(|m| m.0 == r.info.run).unwrap().1;
        assert_eq!(
            &r.info.material, m,
            "the manifest labels run {}",
            r.info.run
        );
    }
    let mut rows = Vec::new();
    for (run, _) in &materials {
        let text = String::from_utf8(files[&format!("{run}.csv")].clone()).unwrap();
        rows.extend(trackpy_rows(&text, run));
    }
    let want = ingest_ok(&interchange_of(&rows, &materials), &IngestParams::default());
    assert_same_recordings(&got.recordings, &want.recordings);
    assert_same_fits(&fits(&got.recordings), &fits(&want.recordings));
}

/// The interchange form of one run of the good trackpy export, which the TrackMate fixtures hold.
fn interchange_of_run(run: &str, material: &str) -> Vec<Recording> {
    let files = folder("trackpy_all");
    let rows = trackpy_rows(std::str::from_utf8(&files["tracks.csv"]).unwrap(), "");
    let materials = vec![(run.to_string(), material.to_string())];
    ingest_ok(&interchange_of(&rows, &materials), &IngestParams::default()).recordings
}

#[test]
fn trackmate_xml_is_read_in_its_own_units_and_its_spurious_track_is_listed() {
    let files = folder("trackmate_xml");
    let materials = manifest(&files);
    assert_eq!(materials.len(), 1);
    // No m_per_px: the XML says its positions are in microns and its frame interval.
    let got = ingest_ok(&files, &IngestParams::default());
    let want = interchange_of_run(&materials[0].0, &materials[0].1);
    assert_same_recordings(&got.recordings, &want);
    assert_same_fits(&fits(&got.recordings), &fits(&want));
    assert_eq!(got.skipped.len(), 1, "{:?}", got.skipped);
    let s = &got.skipped[0];
    assert_eq!(s.run, materials[0].0);
    assert!(
        s.reason.starts_with("track 1 (3 spots, frames ") && s.reason.contains("spurious"),
        "{}",
        s.reason
    );
}

#[test]
fn trackmate_csv_under_its_default_name_gives_the_interchange_fits() {
    let files = folder("trackmate_csv");
    assert!(files.contains_key("Spots in tracks statistics.csv"));
    let materials = manifest(&files);
    let got = ingest_ok(&files, &IngestParams::default());
    assert_eq!(
        got.recordings[0].info.run, materials[0].0,
        "the manifest names the file's run"
    );
    let want = interchange_of_run(&materials[0].0, &materials[0].1);
    assert_same_recordings(&got.recordings, &want);
    assert_same_fits(&fits(&got.recordings), &fits(&want));
    assert!(got.skipped.is_empty(), "{:?}", got.skipped);
}

#[test]
fn a_file_of_several_runs_without_a_run_column_says_to_add_one() {
    let files = folder("trackpy_all");
    let text = String::from_utf8(files["tracks.csv"].clone()).unwrap();
    // Drop the run column: six videos' rows in one file, as a new user writes it.
    let stripped: String = text
        .lines()
        .map(|l| {
            let mut f: Vec<&str> = l.split(',').collect();
            f.remove(1);
            f.join(",") + "\n"
        })
        .collect();
    let files = Files::from([("tracks.csv".to_string(), stripped.into_bytes())]);
    let mut p = params();
    p.calibration.fps = Some(FPS);
    p.calibration.material = Some("316".into());
    p.calibration.diameter_m = Some(3e-4);
    let e = ingest::ingest(&files, &p).unwrap_err().to_string();
    assert!(e.contains("add a column `run`"), "{e}");
    assert!(e.lines().count() < 5, "one problem, not one per row: {e}");
}

#[test]
fn manifest_rows_and_files_must_match() {
    let mut files = folder("trackpy_all");
    let mut runs = String::from_utf8(files["runs.csv"].clone()).unwrap();
    runs += "single-999,316,0.0003,10000,single\n";
    files.insert("runs.csv".into(), runs.into_bytes());
    let e = ingest::ingest(&files, &params()).unwrap_err().to_string();
    assert!(
        e.contains("runs.csv row 8, column run: run \"single-999\" is in no tracker file"),
        "{e}"
    );
}

// ------------------------------------------------------------ through the binary

fn groove(project: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_groove"))
        .current_dir(project)
        .args(args)
        .output()
        .unwrap()
}

/// A project running ingest → fit → aggregate → figures → report on a copy of a fixture folder.
fn project(fixture: &str, ingest_params: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    std::fs::create_dir(&data).unwrap();
    for (name, bytes) in folder(fixture) {
        std::fs::write(data.join(name), bytes).unwrap();
    }
    let toml = format!(
        r#"[project]
seed = 1
data = "data"
reports = "reports"

[stages.ingest]
kind = "ingest"
inputs = {{ dataset = "${{data}}" }}
params = {ingest_params}

[stages.fit]
kind = "fit"
foreach = "runs"
inputs = {{ runs = "ingest:runs" }}

[stages.aggregate]
kind = "aggregate"
inputs = {{ fits = "fit:fits", runs = "ingest:runs" }}
outputs = {{ summary = "${{reports}}/summary.json", fits_csv = "${{reports}}/fits.csv" }}

[stages.figures]
kind = "figures"
inputs = {{ runs = "ingest:runs", fits = "fit:fits", fits_csv = "aggregate:fits_csv", summary = "aggregate:summary" }}

[stages.report]
kind = "report"
inputs = {{ figures = "figures:figures", runs = "ingest:runs", fits = "fit:fits", fits_csv = "aggregate:fits_csv", summary = "aggregate:summary", skipped = "ingest:skipped" }}
outputs = {{ md = "${{reports}}/report.md" }}
"#
    );
    std::fs::write(dir.path().join("pipeline.toml"), toml).unwrap();
    dir
}

#[test]
fn wrong_axis_exits_2_naming_the_runs_and_the_axis_to_try() {
    let p = project(
        "trackpy_all",
        r#"{ calibration = { m_per_px = 2e-5, axis = "y" } }"#,
    );
    let out = groove(p.path(), &["run"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("calibration.axis = \"y\" looks wrong"),
        "{err}"
    );
    assert!(err.contains("set calibration.axis = \"x\""), "{err}");
    assert!(err.contains("single-316-001"), "{err}");
    assert!(!p.path().join("reports/report.md").exists());
}

#[test]
fn a_dropped_track_and_a_file_name_with_spaces_reach_the_report() {
    let p = project("trackmate_xml", "{ }");
    let out = groove(p.path(), &["run"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(p.path().join("reports/report.md")).unwrap();
    assert!(md.contains("track 1 (3 spots, frames "), "{md}");
    assert!(!md.contains("Nothing was left out"), "{md}");
    let p = project("trackmate_csv", "{ }");
    let out = groove(p.path(), &["run"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let md = std::fs::read_to_string(p.path().join("reports/report.md")).unwrap();
    assert!(md.contains("Nothing was left out"), "{md}");
}

#[test]
fn pixel_locked_trackpy_runs_give_mu_per_material_and_flag_what_cannot_be_fitted() {
    use groove::fit::aggregate::{aggregate_single, AggregateOptions};
    let files = folder("trackpy_locked");
    let got = ingest_ok(&files, &params());
    let fs = fits(&got.recordings);
    let (v0, mu) = truth();
    let summary = aggregate_single(&fs, &AggregateOptions::default(), 7);
    let recovered = fs.iter().filter(|f| f.restarted).count();
    eprintln!(
        "pixel-locked runs recovered by restarts: {recovered} of {}",
        fs.len()
    );
    for f in &fs {
        let listed = summary.materials[&f.material]
            .left_out
            .iter()
            .any(|l| l.run == f.run);
        // A fit far from the truth is never averaged in: it is flagged and listed.
        let mu_se = f.mu_se.unwrap_or(f64::INFINITY);
        let wrong = (f.mu - mu[&f.material]).abs() > 0.05 + 3.0 * mu_se
            || (f.v0_mps - v0[&f.run]).abs() > 0.05 * v0[&f.run].abs();
        if wrong {
            assert_ne!(f.status, "converged", "{f:?}");
        }
        assert_eq!(listed, f.status != "converged", "{}", f.run);
    }
    for (m, s) in &summary.materials {
        let w = s.mu_weighted.value;
        assert!(
            (w - mu[m]).abs() < 0.01,
            "material {m}: weighted mu {w}, truth {}",
            mu[m]
        );
    }
}
