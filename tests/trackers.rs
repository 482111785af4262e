//! Tracker exports made by the real tools (tests/fixtures/trackers/, made by make_fixtures.py with
//! trackpy 0.7 from rendered videos of runs with a known truth): every layout (one trackpy file of
//! all runs with a `run` column, one file per run with a manifest of two materials, TrackMate XML,
//! TrackMate's CSV under its default name) gives the same recordings and fits as the interchange
//! format of the same positions, dropped tracks are listed, and a wrong axis stops with advice.
//! Pixel-locked trackpy positions fit right or are flagged (never averaged in wrong), with the
//! restart count in the report; the residual-structure threshold and the restarts are measured on
//! a synthesized null; one wild run cannot move the T-vs-v0 line by more than its share.

use groove::artifacts::FitStatus;
use groove::fit::{fit_single, FitOptions, SingleFit};
use groove::ingest::{self, Axis, IngestParams, Ingested};
use groove::recording::Recording;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[path = "support/cli.rs"]
mod cli;
#[path = "support/ingest_stage.rs"]
mod ingest_stage;
use ingest_stage::folder_files;

type Files = BTreeMap<String, Vec<u8>>;

/// The rendered videos' pixel size and frame rate (make_fixtures.py).
const M_PER_PX: f64 = 2.0e-5;
const FPS: f64 = 10_000.0;
/// The pixel-locked videos' pixel size (trackpy_locked/, make_fixtures.py).
const LOCKED_M_PER_PX: f64 = 1.875e-5;

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/trackers")
}

fn folder(name: &str) -> Files {
    folder_files(&fixtures().join(name))
}

/// The fixtures' calibration: the groove along image x, nothing else (the manifests give the rest).
fn params() -> IngestParams {
    params_at(M_PER_PX)
}

/// The calibration of videos with pixels of `m_per_px`.
fn params_at(m_per_px: f64) -> IngestParams {
    let mut p = IngestParams::default();
    p.calibration.m_per_px = Some(m_per_px);
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
    interchange_at(rows, materials, M_PER_PX)
}

/// [`interchange_of`] for videos with pixels of `m_per_px`.
fn interchange_at(
    rows: &[(String, i64, i64, f64)],
    materials: &[(String, String)],
    m_per_px: f64,
) -> Files {
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
                r.3 * m_per_px
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
    truth_of("truth.toml", "truth/runs_truth.csv")
}

/// The true v0 of every run (`runs_csv`) and μ of every material (`truth_toml`).
fn truth_of(truth_toml: &str, runs_csv: &str) -> (BTreeMap<String, f64>, BTreeMap<String, f64>) {
    let csv = std::fs::read_to_string(fixtures().join(runs_csv)).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let v = head.iter().position(|h| *h == "v0_mps").unwrap();
    let v0 = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[0].to_string(), f[v].parse::<f64>().unwrap())
        })
        .collect();
    let t: toml::Table = std::fs::read_to_string(fixtures().join(truth_toml))
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
        assert_eq!(f.status, FitStatus::Converged, "{f:?}");
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
    let got = ingest_ok(&files, &params_at(LOCKED_M_PER_PX));
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
    let want = ingest_ok(
        &interchange_at(&rows, &materials, LOCKED_M_PER_PX),
        &IngestParams::default(),
    );
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
    cli::command(Path::new(env!("CARGO_BIN_EXE_groove")), project, args)
        .output()
        .unwrap()
}

/// A project running ingest → fit → aggregate → figures → report on a copy of a fixture folder.
fn project(fixture: &str, ingest_params: &str) -> tempfile::TempDir {
    project_of(folder(fixture), ingest_params)
}

/// [`project`] on the dataset `files`.
fn project_of(files: Files, ingest_params: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let data = dir.path().join("data");
    std::fs::create_dir(&data).unwrap();
    for (name, bytes) in files {
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

// ------------------------------------------------------------ pixel locking (issue 12's case)

/// A fit is right within the stated tolerances: converged, v0 within 2 % of the truth and μ within
/// 0.03, or within three of its own standard errors (a slow run's few sliding frames may not
/// determine μ to 0.03; its weight in the weighted mean is as small as its error is large).
const V0_TOL: f64 = 0.02;
const MU_TOL: f64 = 0.03;

fn fit_is_right(f: &SingleFit, v0: f64, mu: f64) -> bool {
    let mu_se = f.mu_se.unwrap_or(f64::INFINITY);
    f.termination.is_converged()
        && (f.v0_mps - v0).abs() <= V0_TOL * v0.abs()
        && (f.mu - mu).abs() <= MU_TOL.max(3.0 * mu_se)
        && mu_se.is_finite()
}

/// Fits of the pixel-locked fixture `name` (trackpy_locked/ or trackpy_locked_9px/), checked:
/// every fit is right or suspect with its reasons and left out, a kept restart is right, the
/// restart count is in the aggregate notes, and the weighted μ per material is within 0.01 of the
/// truth. Returns (runs whose first fit looked wrong, runs a restart recovered).
fn check_pixel_locked(name: &str) -> (usize, usize) {
    use groove::fit::aggregate::{aggregate_single, restart_note, AggregateOptions};
    let files = folder(name);
    let got = ingest_ok(&files, &params_at(LOCKED_M_PER_PX));
    let fs = fits(&got.recordings);
    let (v0, mu) = truth_of("truth_locked.toml", "truth/runs_truth_locked.csv");
    let summary = aggregate_single(&fs, &AggregateOptions::default(), 7);
    let recovered = fs.iter().filter(|f| f.restarted).count();
    let looked_wrong = recovered + fs.iter().filter(|f| f.status == FitStatus::Suspect).count();
    for f in &fs {
        eprintln!(
            "{} ({}): v0 {:.5} (truth {:.5}) mu {:.4} (truth {}) T {:.4} status {} restarted {} {:?}",
            f.run,
            f.material,
            f.v0_mps,
            v0[&f.run],
            f.mu,
            mu[&f.material],
            f.t_drag_s,
            f.status,
            f.restarted,
            f.suspect
        );
    }
    eprintln!("pixel-locked runs whose first fit looked wrong: {looked_wrong}; recovered by a restart: {recovered}");
    // The fixture is the issue's case: a slow run near 0.02 m/s in each material.
    let slow: Vec<&SingleFit> = fs.iter().filter(|f| v0[&f.run].abs() < 0.025).collect();
    assert!(slow.len() >= 2, "{:?}", v0);
    // Every fit is either right (and averaged in) or suspect with its reasons (and left out,
    // listed with them); a wrong fit is never averaged in.
    for f in &fs {
        let left = summary.materials[&f.material]
            .left_out
            .iter()
            .find(|l| l.run == f.run);
        if f.status == FitStatus::Converged {
            assert!(
                fit_is_right(f, v0[&f.run], mu[&f.material]),
                "a wrong fit is averaged in: {f:?}"
            );
            assert!(left.is_none(), "{}", f.run);
        } else {
            assert_eq!(f.status, FitStatus::Suspect, "{f:?}");
            assert!(!f.suspect.is_empty(), "{f:?}");
            assert_eq!(left.map(|l| l.why.clone()), Some(f.suspect.join("; ")));
        }
        // a restart that is kept is right
        if f.restarted {
            assert!(fit_is_right(f, v0[&f.run], mu[&f.material]), "{f:?}");
        }
    }
    // The count of recovered runs is said in the aggregate stage's notes (and so the report).
    let note = restart_note(&fs);
    if looked_wrong > 0 {
        let note = note.unwrap();
        assert!(
            note.starts_with(&format!(
                "{recovered} of {looked_wrong} single runs whose first fit looked wrong"
            )),
            "{note}"
        );
    } else {
        assert_eq!(note, None);
    }
    for (m, s) in &summary.materials {
        let w = s.mu_weighted.value;
        assert!(
            (w - mu[m]).abs() < 0.01,
            "material {m}: weighted mu {w}, truth {}",
            mu[m]
        );
    }
    (looked_wrong, recovered)
}

/// Issue 12's case at ~3 µm (trackpy at 11 px, 2.7 µm RMS): every first fit is right.
#[test]
fn pixel_locked_trackpy_runs_give_mu_per_material_and_flag_what_cannot_be_fitted() {
    let (looked_wrong, _) = check_pixel_locked("trackpy_locked");
    assert_eq!(looked_wrong, 0);
}

/// The same videos tracked at 9 px (5.8 µm RMS): the two slow runs' first fits look wrong (the
/// issue's failure, from the real trackpy); the restarts recover the 18 mm/s one, and the 10 mm/s
/// one, whose μ the frames do not determine, stays suspect and out of the mean.
#[test]
fn more_strongly_locked_trackpy_runs_are_recovered_or_flagged() {
    let (looked_wrong, recovered) = check_pixel_locked("trackpy_locked_9px");
    assert_eq!((looked_wrong, recovered), (2, 1));
}

// ------------------------------------------------------------ the structure threshold's null

/// Positions seen through a tracker that pulls each one towards its pixel centre by `lock` of its
/// offset (pixel locking: trackpy with too small a diameter), on pixels of `pixel_m`.
fn pixel_locked(z_m: f64, pixel_m: f64, lock: f64) -> f64 {
    let x = z_m / pixel_m;
    let c = x.round();
    (c + (x - c) * (1.0 - lock)) * pixel_m
}

/// One run of the null: the baseline physics (|v0| 5–100 mm/s, direction by `k`'s parity, μ
/// 0.25–0.40, T 60 ms, 600 frames at 10 kfps, kicked within a frame of the first) seen with
/// `error`: white noise of 1 or 3 µm, or pixel locking (pixels of 18.75–20 µm pulled 30–70 % of
/// the way to their centres, 1–4 µm RMS, plus 0.3 µm white noise). (v0, μ, t, z).
fn null_run(
    k: usize,
    error: &str,
    rng: &mut rand_chacha::ChaCha8Rng,
) -> (f64, f64, Vec<f64>, Vec<f64>) {
    use groove::physics::{simulate, Friction, Model, State, Term};
    use rand::Rng;
    use rand_distr::{Distribution, Normal};
    let unit = Normal::new(0.0, 1.0).unwrap();
    let dir = if k.is_multiple_of(2) { 1.0 } else { -1.0 };
    let v0 = dir * rng.random_range(0.005..0.1);
    let mu = rng.random_range(0.25..0.40);
    let model = Model {
        groove: FitOptions::default().groove(),
        friction: Friction::Constant { mu },
        variation: Default::default(),
        terms: vec![Term::LinearDrag { t_s: 0.06 }],
    };
    let t_first = rng.random_range(0.0..1e-4);
    let t: Vec<f64> = (0..600).map(|i| t_first + i as f64 * 1e-4).collect();
    let z_start = if dir > 0.0 { 1e-3 } else { 11e-3 } + rng.random_range(0.0..1e-3);
    let init = State {
        z_m: z_start,
        v_mps: v0,
        va_mps: 0.0,
    };
    let sim = simulate(&model, init, &t);
    let (pixel, lock) = (
        rng.random_range(1.875e-5..2.0e-5),
        rng.random_range(0.3..0.7),
    );
    let z = sim
        .z_m
        .iter()
        .map(|&z| match error {
            "white 1 µm" => z + 1e-6 * unit.sample(rng),
            "white 3 µm" => z + 3e-6 * unit.sample(rng),
            _ => pixel_locked(z, pixel, lock) + 0.3e-6 * unit.sample(rng),
        })
        .collect();
    (v0, mu, t.iter().map(|v| v - t_first).collect(), z)
}

/// The null behind `quality::STRUCTURE_FACTOR`: 1500 clean runs of [`null_run`], a third with
/// each kind of error, fitted by groove. Among the fits that are right, at most 1 % may have
/// residual structure above the threshold (a false suspect).
#[test]
fn the_structure_threshold_flags_under_one_percent_of_clean_runs() {
    use groove::fit::quality::{structure_ratio, STRUCTURE_FACTOR};
    use groove::fit::single::fit_track;
    use groove::fit::track_problem::Workspace;
    use rand::SeedableRng;
    let opts = FitOptions::default();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    let mut ws = Workspace::default();
    let mut ratios: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    let (mut n_right, mut n_all, mut flagged) = (0, 0, 0);
    for k in 0..1500 {
        let error = ["white 1 µm", "white 3 µm", "pixel-locked"][k % 3];
        let (v0, mu, t, z) = null_run(k, error, &mut rng);
        let f = fit_track(&t, &z, 1e4, &opts, &mut ws);
        n_all += 1;
        if !fit_is_right(&f, v0, mu) {
            continue;
        }
        n_right += 1;
        let x = [f.z0_m, f.t0_s, f.v0_mps, 0.0, f.mu, f.t_drag_s];
        let r = structure_ratio(&t, &z, &x, opts.groove()).unwrap();
        ratios.entry(error).or_default().push(r);
        if r > STRUCTURE_FACTOR {
            flagged += 1;
        }
    }
    for (error, r) in &mut ratios {
        r.sort_by(f64::total_cmp);
        let above = |c: f64| r.iter().filter(|&&v| v > c).count();
        eprintln!(
            "{error}: above 20, 25, 30, 35: {}, {}, {}, {}",
            above(20.0),
            above(25.0),
            above(30.0),
            above(35.0)
        );
        // at most 1 % false suspects with every kind of error, not only over the mix
        assert!(
            above(STRUCTURE_FACTOR) * 100 <= r.len(),
            "{error}: {} of {} right fits above {STRUCTURE_FACTOR}",
            above(STRUCTURE_FACTOR),
            r.len()
        );
        let q = |p: f64| r[((r.len() - 1) as f64 * p).round() as usize];
        eprintln!(
            "{error}: {} right fits, structure ratio median {:.1}, 99 % {:.1}, 99.9 % {:.1}, max {:.1}",
            r.len(),
            q(0.5),
            q(0.99),
            q(0.999),
            q(1.0)
        );
    }
    eprintln!("{flagged} of {n_right} right fits above {STRUCTURE_FACTOR} ({n_all} runs)");
    // the null is not vacuous: most runs fit right, with every kind of error
    assert!(n_right * 10 >= n_all * 9, "{n_right} of {n_all}");
    assert_eq!(ratios.len(), 3);
    assert!(
        flagged * 100 <= n_right,
        "{flagged} of {n_right} clean runs flagged for structure"
    );
}

/// What the restarts add, measured on 400 pixel-locked runs of the null: how many runs whose first
/// fit is suspect the restarts (with each loss) bring back to a right, clean fit, and that no
/// restart that is kept is wrong.
#[test]
fn restarts_recover_pixel_locked_runs_whose_first_fit_is_suspect() {
    use groove::fit::single::{fit_track_using, Restarts};
    use groove::fit::track_problem::Workspace;
    use groove::lsq::loss::Loss;
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(21);
    let mut ws = Workspace::default();
    let variants = [
        ("huber, no restarts", Loss::Huber, Restarts::None),
        ("huber, grid", Loss::Huber, Restarts::Grid),
        ("linear, grid", Loss::Linear, Restarts::Grid),
        ("soft_l1, grid", Loss::SoftL1, Restarts::Grid),
    ];
    let mut counts = vec![(0usize, 0usize, 0usize); variants.len()];
    for k in 0..400 {
        let (v0, mu, t, z) = null_run(k, "pixel-locked", &mut rng);
        for (c, (_, loss, restarts)) in counts.iter_mut().zip(&variants) {
            let (loss, restarts) = (*loss, *restarts);
            let opts = FitOptions {
                loss,
                ..FitOptions::default()
            };
            let f = fit_track_using(&t, &z, 1e4, &opts, &mut ws, restarts);
            if f.restarted || f.status == FitStatus::Suspect {
                c.0 += 1;
            }
            if f.restarted {
                c.1 += 1;
                assert!(fit_is_right(&f, v0, mu), "a kept restart is wrong: {f:?}");
            }
            if f.status == FitStatus::Converged && !fit_is_right(&f, v0, mu) {
                c.2 += 1;
                eprintln!(
                    "passes wrong ({loss:?}, {restarts:?}): v0 {v0:.4} μ {mu:.3} → v0 {:.4} μ {:.3} ± {:.3}",
                    f.v0_mps,
                    f.mu,
                    f.mu_se.unwrap_or(f64::NAN)
                );
            }
        }
    }
    for ((name, _, _), (looked_wrong, recovered, wrong)) in variants.iter().zip(&counts) {
        eprintln!(
            "{name}: {recovered} of {looked_wrong} suspect first fits recovered; {wrong} wrong fits pass as converged"
        );
    }
    // the same runs look wrong at first whatever the restarts; without restarts none is
    // recovered, the grid recovers some
    assert_eq!(counts[0].0, counts[1].0, "{counts:?}");
    assert!(
        counts[0].0 >= 10,
        "the null holds suspect first fits: {counts:?}"
    );
    assert_eq!(counts[0].1, 0);
    assert!(counts[1].1 > 0, "{counts:?}");
    // the shipped choice (Huber, grid) lets at most 1 % of the runs pass wrong
    assert!(counts[1].2 * 100 <= 400, "{counts:?}");
}

// ------------------------------------------------------------ the T–v0 line against a wild run

/// A converged single fit of material 316 at speed `v0` with drag time `t`.
fn planted(run: &str, v0: f64, t: f64) -> SingleFit {
    SingleFit {
        run: run.into(),
        material: "316".into(),
        groove: FitOptions::default().groove(),
        v0_mps: v0,
        v0_se: Some(1e-4),
        mu: 0.34,
        mu_se: Some(0.01),
        t_drag_s: t,
        t_drag_se: Some(1e-3),
        z0_m: 1e-3,
        z0_se: Some(1e-7),
        t0_s: 5e-5,
        t0_se: Some(1e-6),
        t1_s: 0.01,
        rms_m: 1e-6,
        scale_m: 1e-6,
        outlier_cut_m: 5e-6,
        n_frames: 600,
        n_used: 600,
        n_outliers: 0,
        iterations: 10,
        termination: groove::fit::Termination::SmallStep,
        status: FitStatus::Converged,
        suspect: Vec::new(),
        restarted: false,
    }
}

#[test]
fn one_wild_run_moves_the_t_vs_v0_line_by_less_than_its_share_and_a_suspect_one_not_at_all() {
    use groove::fit::aggregate::{aggregate_single, AggregateOptions};
    // 20 runs on T = 0.05 + 1.1·|v0| (scatter ±2 ms), |v0| 10–100 mm/s, both directions
    let mut fs: Vec<SingleFit> = (0..20)
        .map(|i| {
            let v = 0.01 + 0.09 * i as f64 / 19.0;
            let t = 0.05 + 1.1 * v + if i % 3 == 0 { 2e-3 } else { -1e-3 };
            planted(&format!("r{i:02}"), if i % 2 == 0 { v } else { -v }, t)
        })
        .collect();
    let opts = AggregateOptions::default();
    let slope = |fs: &[SingleFit]| {
        let s = aggregate_single(fs, &opts, 3);
        s.materials["316"].t_vs_v0.slope_s_per_mps
    };
    let calm = slope(&fs);
    assert!((calm.value - 1.1).abs() < 0.05, "{calm:?}");
    // A wild run at the fastest speed (the most leverage), T = 1 s instead of 0.16 s. Least
    // squares would pull the slope to about 4.5; its share (1/21 of that pull) is about 0.16.
    let mut wild = fs.clone();
    wild.push(planted("r99", 0.1, 1.0));
    let (x, y): (Vec<f64>, Vec<f64>) = wild.iter().map(|f| (f.v0_mps.abs(), f.t_drag_s)).unzip();
    let all: Vec<usize> = (0..wild.len()).collect();
    let ols = groove::stats::ols_indexed(&x, &y, &all).1;
    let share = (ols - calm.value).abs() / wild.len() as f64;
    let got = slope(&wild);
    eprintln!(
        "slope: calm {:.3}, with the wild run {:.3} (least squares {ols:.3}, share {share:.3})",
        calm.value, got.value
    );
    assert!(ols > 3.0, "{ols}");
    assert!(
        (got.value - calm.value).abs() < share,
        "{got:?} vs {calm:?}"
    );
    let iv = got.interval.unwrap();
    assert!(iv.contains(1.1) && iv.hi - iv.lo < 0.5, "{iv:?}");
    // The same run flagged suspect is left out: the line is the calm one, to the bit.
    let last = wild.last_mut().unwrap();
    last.status = FitStatus::Suspect;
    last.suspect = vec!["μ = 1.0000e-4 is at its bound".into()];
    assert_eq!(slope(&wild), calm);
    fs.push(wild.pop().unwrap());
    let s = aggregate_single(&fs, &opts, 3);
    assert_eq!(s.materials["316"].left_out.len(), 1);
    assert_eq!(s.materials["316"].n_converged, 20);
}

// ------------------------------------------------------------ the restart count in the report

/// Synthesized pixel-locked runs of material 316 in the interchange format: the first `n_wrong`
/// runs of the null whose first fit (without restarts) is suspect, and `n_good` runs whose first
/// fit is clean.
fn locked_dataset(n_wrong: usize, n_good: usize) -> Files {
    use groove::fit::single::{fit_track_using, Restarts};
    use groove::fit::track_problem::Workspace;
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(33);
    let mut ws = Workspace::default();
    let (mut wrong, mut good) = (0, 0);
    let mut runs = String::from("run,experiment,material,diameter_m,fps\n");
    let mut traj = String::from("run,particle,frame,t_s,z_m\n");
    for k in 0.. {
        if wrong == n_wrong && good == n_good {
            break;
        }
        let (_, _, t, z) = null_run(k, "pixel-locked", &mut rng);
        let first = fit_track_using(&t, &z, FPS, &FitOptions::default(), &mut ws, Restarts::None);
        let keep = match first.status {
            FitStatus::Suspect if wrong < n_wrong => {
                wrong += 1;
                true
            }
            FitStatus::Converged if good < n_good => {
                good += 1;
                true
            }
            _ => false,
        };
        if keep {
            let run = format!("locked-{k:04}");
            runs += &format!("{run},single,316,0.0003,{FPS}\n");
            for (i, (t, z)) in t.iter().zip(&z).enumerate() {
                traj += &format!("{run},0,{i},{t:e},{z:e}\n");
            }
        }
    }
    Files::from([
        ("runs.csv".to_string(), runs.into_bytes()),
        ("trajectories.csv".to_string(), traj.into_bytes()),
    ])
}

#[test]
fn the_report_says_how_many_suspect_first_fits_the_restarts_recovered() {
    use groove::fit::aggregate::restart_note;
    let files = locked_dataset(6, 4);
    let recs = ingest_ok(&files, &IngestParams::default()).recordings;
    let fs = fits(&recs);
    let recovered = fs.iter().filter(|f| f.restarted).count();
    let still = fs.iter().filter(|f| f.status == FitStatus::Suspect).count();
    eprintln!("{recovered} recovered, {still} still suspect");
    // every one of the six wrong first fits is either recovered or still suspect
    assert_eq!(recovered + still, 6);
    let note = restart_note(&fs).unwrap();
    assert!(
        note.starts_with(&format!(
            "{recovered} of 6 single runs whose first fit looked wrong"
        )) && note.ends_with(&format!(
            "{still} stay suspect and are left out of the aggregates"
        )),
        "{note}"
    );
    let p = project_of(files, "{ }");
    let out = groove(p.path(), &["run"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary = std::fs::read_to_string(p.path().join("reports/summary.json")).unwrap();
    assert!(summary.contains(&note), "{summary}");
    let md = std::fs::read_to_string(p.path().join("reports/report.md")).unwrap();
    assert!(md.contains(&note), "{md}");
}

/// The TrackMate CSV fixture with one more track (id 99) in `frames`, its x position `x_of(frame)`.
fn trackmate_with_track(frames: std::ops::Range<i64>, x_of: impl Fn(i64) -> f64) -> Files {
    let mut files = folder("trackmate_csv");
    let name = "Spots in tracks statistics.csv";
    let mut text = String::from_utf8(files[name].clone()).unwrap();
    for f in frames {
        text += &format!(
            "ID{},{},99,5000.0,{},300.0,0.0,{},{f},150.0,1,50.0\n",
            90_000 + f,
            90_000 + f,
            x_of(f),
            f as f64 * 1e-4
        );
    }
    files.insert(name.to_string(), text.into_bytes());
    files
}

#[test]
fn a_still_track_longer_than_the_sphere_s_is_left_out_and_said() {
    let base = ingest_ok(&folder("trackmate_csv"), &IngestParams::default());
    let frames = base.recordings[0].tracks[0].frame.clone();
    let (lo, hi) = (frames[0], *frames.last().unwrap());
    // a speck of dust: tracked from before the sphere's first frame to after its last, jittering
    // by a few hundredths of a micron
    let files = trackmate_with_track(lo - 20..hi + 21, |f| {
        4000.0 + 0.03 * ((f * f * 7919 + 31 * f + 101).rem_euclid(97)) as f64 / 97.0
    });
    let got = ingest_ok(&files, &IngestParams::default());
    assert_eq!(
        got.recordings[0].tracks, base.recordings[0].tracks,
        "the moving track is the one kept, whole"
    );
    let said: Vec<&str> = got.skipped.iter().map(|s| s.reason.as_str()).collect();
    let note = said
        .iter()
        .find(|r| r.starts_with("track 99 "))
        .unwrap_or_else(|| panic!("the still track is not said: {said:?}"));
    assert!(
        note.contains("left out") && note.contains("still object"),
        "{note}"
    );
}

/// A trackpy export of runs whose tracks wander as much along x as along y (cells, colloids):
/// four runs on ellipses, two wider along x and two along y.
fn wandering_tracks() -> Files {
    let mut runs = String::from("run,material,diameter_m,fps,experiment\n");
    let mut tracks = String::from("run,x,y,frame,particle\n");
    for k in 0..4 {
        let run = format!("cell-{k}");
        runs += &format!("{run},316,0.0003,10000,single\n");
        let (ax, ay) = if k % 2 == 0 {
            (100.0, 130.0)
        } else {
            (130.0, 100.0)
        };
        for f in 0..200 {
            let phase = f as f64 / 200.0 * std::f64::consts::TAU;
            tracks += &format!(
                "{run},{},{},{f},0\n",
                500.0 + ax * phase.cos(),
                500.0 + ay * phase.sin()
            );
        }
    }
    BTreeMap::from([
        ("runs.csv".to_string(), runs.into_bytes()),
        ("tracks.csv".to_string(), tracks.into_bytes()),
    ])
}

#[test]
fn the_axis_advice_does_not_flip_on_tracks_that_wander_along_both_axes() {
    let files = wandering_tracks();
    for axis in [Axis::X, Axis::Y] {
        let mut p = params();
        p.calibration.axis = axis;
        let err = ingest::ingest(&files, &p)
            .expect_err("not groove recordings")
            .to_string();
        assert!(err.contains("cannot be confirmed"), "{axis:?}: {err}");
        assert!(err.contains("as cells or colloids do"), "{axis:?}: {err}");
        assert!(
            !err.contains("set calibration.axis"),
            "{axis:?}: advice to flip: {err}"
        );
    }
}
