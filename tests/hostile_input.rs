//! Hostile input at the ingest level (issue 16): every value a broken export or a typing slip
//! produces is refused with the file, row and column and a fix — never a panic, never accepted
//! silently — and the numerics downstream guard their own preconditions when handed such a run
//! without ingest. Each reproducer of the issue is one test here; the same reproducers through the
//! binary (exit 2, reports untouched) are in `tests/hostile_project.rs`.

use groove::ingest::{self, IngestParams};
use groove::recording::{Experiment, Recording, RunInfo, Track};
use polars::prelude::*;
use std::collections::BTreeMap;
use std::io::Cursor;
use std::time::{Duration, Instant};

type Files = BTreeMap<String, Vec<u8>>;

const FPS: f64 = 1000.0;
const FRAMES: i64 = 40;

/// A small good dataset: runs `s1`, `s2` (single) and `c1` (collision, particles 0 and 1), each
/// particle at frames 0..40, t = frame / 1000, z a slow drift. Data lines are in this order:
/// s1 (rows 2..41), s2 (rows 42..81), c1 particle 0 (82..121), c1 particle 1 (122..161).
fn lines() -> Vec<String> {
    let mut out = Vec::new();
    for (run, particle, z0) in [
        ("s1", 0, 0.001),
        ("s2", 0, 0.002),
        ("c1", 0, 0.0),
        ("c1", 1, 0.004),
    ] {
        for f in 0..FRAMES {
            let t = f as f64 / FPS;
            out.push(format!("{run},{particle},{f},{t},{}", z0 + 0.01 * t));
        }
    }
    out
}

const RUNS: &str = "run,experiment,material,diameter_m,fps,setup\n\
                    s1,single,316,3e-4,1000,\n\
                    s2,single,316,3e-4,1000,\n\
                    c1,collision,316,3e-4,1000,rolling\n";

fn files_with(runs: &str, lines: &[String]) -> Files {
    Files::from([
        ("runs.csv".to_string(), runs.as_bytes().to_vec()),
        (
            "trajectories.csv".to_string(),
            format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
        ),
    ])
}

fn good() -> Files {
    files_with(RUNS, &lines())
}

/// The dataset with data line `k` (0-based; file row k + 2) having field `field` set to `value`.
fn with_cell(k: usize, field: usize, value: &str) -> Files {
    let mut ls = lines();
    let mut cells: Vec<String> = ls[k].split(',').map(str::to_string).collect();
    cells[field] = value.to_string();
    ls[k] = cells.join(",");
    files_with(RUNS, &ls)
}

/// Ingests, asserting it is fast and does not panic; the error message if refused.
fn refused(files: &Files) -> String {
    let started = Instant::now();
    let result = ingest::ingest(files, &IngestParams::default());
    assert!(
        started.elapsed() < Duration::from_secs(10),
        "ingest took {:?}",
        started.elapsed()
    );
    match result {
        Ok(i) => panic!("ingest accepted bad input ({} runs)", i.recordings.len()),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(
            message.contains(p),
            "error {message:?} does not contain {p:?}"
        );
    }
}

#[test]
fn the_good_dataset_is_accepted() {
    let got = ingest::ingest(&good(), &IngestParams::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(got.recordings.len(), 3);
    assert!(got.skipped.is_empty());
}

#[test]
fn huge_positions_are_refused_at_their_cell() {
    for value in ["1e308", "-1e308", "12.5", "1e20"] {
        let e = refused(&with_cell(5, 4, value));
        assert_mentions(&e, &["trajectories.csv row 7, column z_m", "metres"]);
    }
}

#[test]
fn huge_times_are_refused_at_their_cell() {
    for value in ["1e308", "-1e308", "9.2e18", "-9.2e18", "1e20", "61"] {
        let e = refused(&with_cell(5, 3, value));
        assert_mentions(&e, &["trajectories.csv row 7, column t_s", "seconds"]);
    }
}

#[test]
fn a_far_frame_with_a_matching_time_is_refused() {
    // frame 100000000 at t_s = 10000 is what frame/fps says at 10 kHz: the time itself is absurd
    let mut ls = lines();
    ls[39] = "s1,0,100000000,10000,0.0014".into();
    let runs = RUNS.replace("1000,", "10000,");
    let e = refused(&files_with(&runs, &ls));
    assert_mentions(&e, &["trajectories.csv row 41, column t_s"]);
}

#[test]
fn a_frame_rate_in_khz_is_refused_with_the_fix() {
    let runs = RUNS.replace("s2,single,316,3e-4,1000,", "s2,single,316,3e-4,10,");
    let e = refused(&files_with(&runs, &lines()));
    assert_mentions(&e, &["runs.csv row 3, column fps", "kHz", "10000"]);
}

#[test]
fn implausible_diameters_are_refused() {
    for (value, hint) in [
        ("0.3", "millimetres"),
        ("300", "millimetres"),
        ("3e-9", "3e-4"),
    ] {
        let runs = RUNS.replace("s1,single,316,3e-4", &format!("s1,single,316,{value}"));
        let e = refused(&files_with(&runs, &lines()));
        assert_mentions(&e, &["runs.csv row 2, column diameter_m", hint]);
    }
}

#[test]
fn times_that_disagree_with_frame_over_fps_are_refused() {
    // every t_s of run s2 is 0
    let ls: Vec<String> = lines()
        .into_iter()
        .map(|l| {
            if l.starts_with("s2,") {
                let c: Vec<&str> = l.split(',').collect();
                format!("{},{},{},0,{}", c[0], c[1], c[2], c[4])
            } else {
                l
            }
        })
        .collect();
    let e = refused(&files_with(RUNS, &ls));
    assert_mentions(&e, &["trajectories.csv row 43, column t_s", "not after"]);

    // t_s in milliseconds: consistent order, wrong clock
    let ls: Vec<String> = lines()
        .into_iter()
        .map(|l| {
            if l.starts_with("s1,") {
                let c: Vec<&str> = l.split(',').collect();
                let t: f64 = c[3].parse().unwrap();
                format!("{},{},{},{},{}", c[0], c[1], c[2], t * 1000.0, c[4])
            } else {
                l
            }
        })
        .collect();
    let e = refused(&files_with(RUNS, &ls));
    assert_mentions(
        &e,
        &[
            "trajectories.csv row 3, column t_s",
            "frames per second",
            "runs.csv row 2",
        ],
    );
}

#[test]
fn the_clock_tolerance_accepts_rounded_times_and_a_rounded_frame_rate() {
    // times written to 4 decimals at 29.97 fps declared as 30: well within the tolerance
    let ls: Vec<String> = (0..FRAMES)
        .map(|f| {
            format!(
                "s1,0,{f},{:.4},{}",
                f as f64 / 29.97,
                0.001 + 1e-5 * f as f64
            )
        })
        .collect();
    let runs = "run,experiment,material,diameter_m,fps\ns1,single,316,3e-4,60\n";
    let ls60: Vec<String> = (0..FRAMES)
        .map(|f| {
            format!(
                "s1,0,{f},{:.4},{}",
                f as f64 / 59.94,
                0.001 + 1e-5 * f as f64
            )
        })
        .collect();
    assert!(ingest::ingest(&files_with(runs, &ls60), &IngestParams::default()).is_ok());
    let runs30 = "run,experiment,material,diameter_m,fps\ns1,single,316,3e-4,50\n";
    let ls50: Vec<String> = (0..FRAMES)
        .map(|f| {
            format!(
                "s1,0,{f},{:.5},{}",
                f as f64 / 50.04,
                0.001 + 1e-5 * f as f64
            )
        })
        .collect();
    assert!(ingest::ingest(&files_with(runs30, &ls50), &IngestParams::default()).is_ok());
    drop(ls);
}

#[test]
fn time_going_backwards_is_refused() {
    let mut ls = lines();
    // swap the times of frames 10 and 11 of s1 (rows 12 and 13)
    ls[10] = "s1,0,10,0.011,0.00111".into();
    ls[11] = "s1,0,11,0.010,0.00110".into();
    let e = refused(&files_with(RUNS, &ls));
    assert_mentions(
        &e,
        &[
            "trajectories.csv row 13, column t_s",
            "time goes backwards",
            "row 12",
        ],
    );
}

#[test]
fn a_collision_run_without_its_target_is_refused() {
    let ls: Vec<String> = lines()
        .into_iter()
        .filter(|l| !l.starts_with("c1,1,"))
        .collect();
    let e = refused(&files_with(RUNS, &ls));
    assert_mentions(
        &e,
        &[
            "trajectories.csv row 82, column frame",
            "run \"c1\" has 0 frames of particle 1 (the target)",
        ],
    );
}

#[test]
fn numbers_stored_as_text_in_parquet_are_refused() {
    let ls = lines();
    let col = |k: usize| -> Vec<String> {
        ls.iter()
            .map(|l| l.split(',').nth(k).unwrap().to_string())
            .collect()
    };
    let parse = |k: usize| -> Vec<f64> { col(k).iter().map(|s| s.parse().unwrap()).collect() };
    let mut df = DataFrame::new(
        ls.len(),
        vec![
            Column::new("run".into(), col(0)),
            Column::new(
                "particle".into(),
                parse(1).iter().map(|&x| x as i64).collect::<Vec<_>>(),
            ),
            Column::new(
                "frame".into(),
                parse(2).iter().map(|&x| x as i64).collect::<Vec<_>>(),
            ),
            Column::new("t_s".into(), col(3)), // numbers as strings
            Column::new("z_m".into(), parse(4)),
        ],
    )
    .unwrap();
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes).finish(&mut df).unwrap();
    let mut files = good();
    files.remove("trajectories.csv");
    files.insert("trajectories.parquet".into(), bytes);
    let e = refused(&files);
    assert_mentions(
        &e,
        &[
            "trajectories.parquet, column t_s",
            "stored as text",
            "float64",
        ],
    );
}

#[test]
fn invalid_utf8_is_named_at_its_row_and_column() {
    let mut files = good();
    let mut bytes = files["trajectories.csv"].clone();
    // the header's `z_m` → `z\xffm`
    let at = bytes.windows(3).position(|w| w == b"z_m").unwrap();
    bytes[at + 1] = 0xff;
    files.insert("trajectories.csv".into(), bytes);
    let e = refused(&files);
    assert_mentions(
        &e,
        &[
            "trajectories.csv row 1, column",
            "header row is not UTF-8",
            "save the file as UTF-8",
        ],
    );

    let mut files = good();
    let text = String::from_utf8(files["runs.csv"].clone()).unwrap();
    let mut bytes = text
        .replace("s2,single,316", "s2,single,31\u{1}")
        .into_bytes();
    let at = bytes.iter().position(|&b| b == 1).unwrap();
    bytes[at] = 0xc3; // a lone lead byte
    files.insert("runs.csv".into(), bytes);
    let e = refused(&files);
    assert_mentions(
        &e,
        &["runs.csv row 3, column material", "is not UTF-8 text"],
    );
}

#[test]
fn extra_fields_are_said_in_groove_words() {
    let mut ls = lines();
    ls[20] = format!("{},0.5", ls[20]);
    let e = refused(&files_with(RUNS, &ls));
    assert_mentions(
        &e,
        &[
            "trajectories.csv row 22",
            "6 fields but the header names 5 columns",
            "double quotes",
        ],
    );
    assert!(!e.contains("Schema"), "{e}");
}

#[test]
fn no_message_has_a_lowercased_acronym() {
    let cases = [
        with_cell(3, 3, "\"x"),
        files_with(RUNS, &["\"".to_string()]),
        Files::from([
            ("runs.csv".to_string(), b"run,\"a".to_vec()),
            ("trajectories.csv".to_string(), b"\"\"\"".to_vec()),
        ]),
    ];
    for files in cases {
        if let Err(e) = ingest::ingest(&files, &IngestParams::default()) {
            let e = e.to_string();
            assert!(!e.contains("cSV") && !e.contains("Schema"), "{e}");
        }
    }
}

#[test]
fn tracker_calibration_in_khz_is_refused_as_a_param() {
    let mut p = IngestParams::default();
    p.calibration.fps = Some(20.0);
    let e = ingest::ingest(&good(), &p).unwrap_err().to_string();
    assert_mentions(&e, &["pipeline.toml", "calibration.fps", "kHz"]);
}

// ------------------------------------------------------------------ numerics guard themselves

/// A recording straight from memory (no ingest), for the downstream guards.
fn recording(fps: f64, t: impl Fn(i64) -> f64, z: impl Fn(i64) -> f64) -> Recording {
    Recording {
        info: RunInfo {
            run: "r".into(),
            experiment: Experiment::Single,
            material: "316".into(),
            diameter_m: 3e-4,
            fps,
            setup: None,
            extra: BTreeMap::new(),
        },
        tracks: vec![Track {
            particle: 0,
            frame: (0..FRAMES).collect(),
            t_s: (0..FRAMES).map(&t).collect(),
            z_m: (0..FRAMES).map(&z).collect(),
        }],
    }
}

#[test]
fn the_fit_flags_rather_than_panics_on_runs_ingest_would_refuse() {
    let opts = groove::fit::FitOptions::default();
    let cases = [
        recording(20.0, |f| f as f64 / 20.0, |f| 1e-3 + 1e-4 * f as f64), // fps typed in kHz
        recording(1000.0, |_| 0.0, |f| 1e-3 + 1e-4 * f as f64),           // every t_s = 0
        recording(1000.0, |f| f as f64 / 1000.0, |_| 1e-3),               // no motion
    ];
    for rec in cases {
        let started = Instant::now();
        let fit = groove::fit::fit_single(&rec, &opts);
        assert!(started.elapsed() < Duration::from_secs(10));
        assert_ne!(
            fit.status,
            groove::artifacts::run_fit::FitStatus::Converged,
            "a run ingest would refuse is flagged, not called converged"
        );
    }
}

#[test]
fn discovery_leaves_out_samples_beyond_the_ingest_limits_instead_of_hanging() {
    let good_run = |name: &str, v: f64| {
        let mut r = recording(
            1000.0,
            |f| f as f64 / 1000.0,
            move |f| 1e-3 + v * f as f64 / 1000.0,
        );
        r.info.run = name.into();
        r
    };
    let mut recs = vec![
        good_run("a", 0.01),
        good_run("b", -0.01),
        good_run("c", 0.02),
    ];
    // one huge time and one huge position, as in the issue's reproducers
    recs[0].tracks[0].t_s[39] = 1e20;
    recs[1].tracks[0].z_m[20] = 1e308;
    let started = Instant::now();
    let (runs, _) = groove::discover::data::prepare_runs(&recs, 20);
    assert!(started.elapsed() < Duration::from_secs(10));
    assert_eq!(runs.len(), 3);
    assert_eq!(runs[0].t_s.len(), 39, "the sample at t = 1e20 is left out");
    assert_eq!(runs[1].z_m.len(), 39, "the sample at z = 1e308 is left out");
    assert!(runs.iter().all(|r| r.t_s.iter().all(|t| t.abs() <= 60.0)));
}

// ------------------------------------------------------------------ parquet vs csv from polars

#[test]
fn damaged_parquet_is_an_error_not_a_panic() {
    let ls = lines();
    let mut df = DataFrame::new(
        ls.len(),
        vec![Column::new(
            "run".into(),
            ls.iter().map(|l| l[..2].to_string()).collect::<Vec<_>>(),
        )],
    )
    .unwrap();
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes).finish(&mut df).unwrap();
    for cut in [0, 4, 8, bytes.len() / 2, bytes.len() - 9, bytes.len() - 1] {
        let mut files = good();
        files.remove("trajectories.csv");
        files.insert("trajectories.parquet".into(), bytes[..cut].to_vec());
        let e = refused(&files);
        assert_mentions(&e, &["trajectories.parquet"]);
    }
    let _ = Cursor::new(());
}
