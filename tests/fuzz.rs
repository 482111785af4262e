//! Fuzzing by property tests (issue 16): the CSV and Parquet readers, the trackpy and TrackMate
//! readers, and `pipeline.toml` through the library's config loader, fed mutated and generated
//! bytes. Each case must return (a result or an error) without a panic and within `LIMIT`.
//!
//! Each property runs 1,000 cases by default (a few seconds in CI); set `PROPTEST_CASES` for
//! more, e.g. `PROPTEST_CASES=100000 cargo test --locked --test fuzz` for 100,000 per property.

#[path = "support/parquet.rs"]
mod parquet;

use groove::engine::config::{self, Overrides};
use groove::engine::Catalog;
use groove::ingest::{self, Format, IngestParams};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};

type Files = BTreeMap<String, Vec<u8>>;

/// The longest one case may take (a hang shows as a failure, not a stuck CI job... as long as the
/// case returns at all; the time is measured per case).
const LIMIT: Duration = Duration::from_secs(5);

fn config() -> Config {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1000);
    // A fixed seed unless PROPTEST_RNG_SEED names another, so that CI runs the same cases each
    // time and a failure it shows can be run again. Explore with other seeds:
    // PROPTEST_RNG_SEED=<u64> (seeds 112, 118, 125, 127 and 128 at PROPTEST_CASES=5000 once
    // made polars abort the process on a damaged Parquet page header; `parquet_pages` checks
    // the headers now).
    let rng_seed = match std::env::var_os("PROPTEST_RNG_SEED") {
        Some(_) => Config::default().rng_seed,
        None => RngSeed::Fixed(20_261_126),
    };
    Config {
        cases,
        failure_persistence: None,
        rng_seed,
        ..Config::default()
    }
}

// ------------------------------------------------------------------------- seed inputs

const RUNS_CSV: &str = "run,experiment,material,diameter_m,fps,setup\n\
                        s1,single,316,3e-4,1000,\n\
                        c1,collision,440c,3e-4,1000,contact\n";

fn trajectories_csv() -> String {
    let mut s = String::from("run,particle,frame,t_s,z_m\n");
    for (run, particle) in [("s1", 0), ("c1", 0), ("c1", 1)] {
        for f in 0..25 {
            let t = f as f64 / 1000.0;
            s += &format!(
                "{run},{particle},{f},{t},{}\n",
                1e-3 * particle as f64 + 0.02 * t
            );
        }
    }
    s
}

fn trackpy_csv() -> String {
    let mut s = String::from(",y,x,mass,size,ecc,signal,raw_mass,ep,frame,particle\n");
    for f in 0..25 {
        s += &format!(
            "{f},100.0,{},50,2,0.1,10,60,0.01,{f},3\n",
            20.0 + 0.7 * f as f64
        );
    }
    s
}

fn trackmate_csv() -> String {
    let mut s = String::from(
        "LABEL,ID,TRACK_ID,QUALITY,POSITION_X,POSITION_Y,POSITION_Z,POSITION_T,FRAME\n",
    );
    s += "Label,Spot ID,Track ID,Quality,X,Y,Z,T,Frame\n";
    s += "Label,Spot ID,Track ID,Quality,X,Y,Z,T,Frame\n";
    s += ",,,(quality),(micron),(micron),(micron),(sec),\n";
    for f in 0..25 {
        s += &format!(
            "ID{f},{f},0,1.0,{},5.0,0.0,{}E-3,{f}\n",
            20.0 + 0.7 * f as f64,
            f
        );
    }
    s
}

fn trajectories_parquet() -> Vec<u8> {
    parquet::trajectories_parquet(&trajectories_csv(), false)
}

fn tracker_params() -> IngestParams {
    let mut p = IngestParams::default();
    p.calibration.m_per_px = Some(1e-5);
    p.calibration.fps = Some(1000.0);
    p.calibration.material = Some("316".into());
    p.calibration.diameter_m = Some(3e-4);
    p
}

// ------------------------------------------------------------------------- mutations

/// One edit of a byte string.
#[derive(Debug, Clone)]
enum Edit {
    Set(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
    Truncate(usize),
    Duplicate(usize, usize),
}

/// Bytes that matter to the formats: separators, quotes, line ends, digits, signs, exponents,
/// and a few UTF-8 and Parquet oddities.
fn interesting_byte() -> impl Strategy<Value = u8> {
    prop_oneof![
        4 => prop::sample::select(b",\"\n\r\t .-+eE0123456789[]{}=#'\\".to_vec()),
        1 => any::<u8>(),
    ]
}

/// Tokens a broken export or a typing slip produces.
fn hostile_token() -> impl Strategy<Value = Vec<u8>> {
    prop::sample::select(vec![
        "",
        "nan",
        "NaN",
        "inf",
        "-inf",
        "1e308",
        "-1e308",
        "9.2e18",
        "1e20",
        "1e-400",
        "0",
        "-0",
        "-1",
        "10000",
        "100000000",
        "9223372036854775807",
        "-9223372036854775808",
        "18446744073709551616",
        "\"",
        "\"\"",
        ",",
        ",,",
        "\n",
        "\r\n",
        "x",
        "single",
        "collision",
        "contact",
        "0.5",
        "3e-4",
        "\u{feff}",
        "é",
        "\u{0}",
    ])
    .prop_map(|s| s.as_bytes().to_vec())
    .boxed()
    .prop_union(prop::collection::vec(any::<u8>(), 1..4).boxed())
    .boxed()
}

fn edit() -> impl Strategy<Value = Edit> {
    prop_oneof![
        3 => (any::<usize>(), interesting_byte()).prop_map(|(i, b)| Edit::Set(i, b)),
        3 => (any::<usize>(), hostile_token()).prop_map(|(i, t)| Edit::Insert(i, t)),
        2 => (any::<usize>(), 1..40usize).prop_map(|(i, n)| Edit::Delete(i, n)),
        1 => any::<usize>().prop_map(Edit::Truncate),
        1 => (any::<usize>(), 1..200usize).prop_map(|(i, n)| Edit::Duplicate(i, n)),
    ]
}

fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
    for e in edits {
        let len = bytes.len().max(1);
        match e {
            Edit::Set(i, b) => {
                if !bytes.is_empty() {
                    let i = i % bytes.len();
                    bytes[i] = *b;
                }
            }
            Edit::Insert(i, t) => {
                let i = i % (bytes.len() + 1);
                bytes.splice(i..i, t.iter().copied());
            }
            Edit::Delete(i, n) => {
                let i = i % len;
                let end = (i + n).min(bytes.len());
                if i < end {
                    bytes.drain(i..end);
                }
            }
            Edit::Truncate(i) => bytes.truncate(i % len),
            Edit::Duplicate(i, n) => {
                let i = i % len;
                let end = (i + n).min(bytes.len());
                if i < end {
                    let copy = bytes[i..end].to_vec();
                    bytes.splice(end..end, copy);
                }
            }
        }
    }
    bytes
}

fn edits() -> impl Strategy<Value = Vec<Edit>> {
    prop::collection::vec(edit(), 1..8)
}

/// Ingests, checking time; the outcome does not matter, only that there is one, and that it is
/// the row-by-row path's (the columnar fast path takes a damaged file for a clean one never).
fn ingest_bounded(files: &Files, params: &IngestParams) -> Result<(), TestCaseError> {
    let started = Instant::now();
    let result = ingest::ingest(files, params);
    let took = started.elapsed();
    prop_assert!(took < LIMIT, "ingest took {took:?}");
    let reference = ingest::ingest_row_by_row(files, params);
    match (&result, &reference) {
        (Ok(a), Ok(b)) => prop_assert_eq!(a, b),
        (Err(a), Err(b)) => prop_assert_eq!(a.to_string(), b.to_string()),
        (a, b) => prop_assert!(false, "columnar {a:?} but row by row {b:?}"),
    }
    // The stage's streamed items, in chunks small enough that runs span them, are the items of
    // the same recordings (or the same error).
    let streamed = ingest::ingest_items_in_chunks(files, params, 64);
    match (&result, &streamed) {
        (Ok(a), Ok(b)) => {
            let items: std::collections::BTreeMap<String, Vec<u8>> = a
                .recordings
                .iter()
                .map(|r| {
                    (
                        ingest::item_name(&r.info.run),
                        groove::recording::item::encode(r),
                    )
                })
                .collect();
            prop_assert!(items == b.runs, "streamed items differ ({})", b.how);
            prop_assert_eq!(&a.skipped, &b.skipped);
        }
        (Err(a), Err(b)) => prop_assert_eq!(a.to_string(), b.to_string()),
        (a, b) => prop_assert!(
            false,
            "whole {a:?} but streamed {:?}",
            b.as_ref().map(|i| &i.how)
        ),
    }
    if let Err(e) = result {
        let message = e.to_string();
        prop_assert!(
            !message.contains("Schema") && !message.contains("cSV"),
            "{message}"
        );
        for p in &e.problems {
            prop_assert!(!p.message.is_empty() && !p.fix.is_empty(), "{p:?}");
        }
    }
    Ok(())
}

// ------------------------------------------------------------------------- properties

proptest! {
    #![proptest_config(config())]

    #[test]
    fn interchange_csv_never_panics(runs_edits in prop::collection::vec(edit(), 0..4), traj_edits in edits()) {
        let files = Files::from([
            ("runs.csv".to_string(), apply(RUNS_CSV.as_bytes().to_vec(), &runs_edits)),
            ("trajectories.csv".to_string(), apply(trajectories_csv().into_bytes(), &traj_edits)),
        ]);
        ingest_bounded(&files, &IngestParams::default())?;
    }

    #[test]
    fn generated_cells_never_panic(cells in prop::collection::vec((0..75usize, 0..5usize, hostile_token()), 1..6)) {
        let mut lines: Vec<Vec<String>> = trajectories_csv()
            .lines()
            .map(|l| l.split(',').map(str::to_string).collect())
            .collect();
        let data_rows = lines.len() - 1;
        for (row, col, token) in cells {
            lines[1 + row % data_rows][col] = String::from_utf8_lossy(&token).into_owned();
        }
        let text: Vec<String> = lines.iter().map(|l| l.join(",")).collect();
        let files = Files::from([
            ("runs.csv".to_string(), RUNS_CSV.as_bytes().to_vec()),
            ("trajectories.csv".to_string(), text.join("\n").into_bytes()),
        ]);
        ingest_bounded(&files, &IngestParams::default())?;
    }

    #[test]
    fn parquet_never_panics(traj_edits in edits()) {
        let files = Files::from([
            ("runs.csv".to_string(), RUNS_CSV.as_bytes().to_vec()),
            ("trajectories.parquet".to_string(), apply(trajectories_parquet(), &traj_edits)),
        ]);
        ingest_bounded(&files, &IngestParams::default())?;
    }

    #[test]
    fn tracker_files_never_panic(pick in 0..2usize, traj_edits in edits(), explicit in any::<bool>()) {
        let (seed, format) = match pick {
            0 => (trackpy_csv(), Format::Trackpy),
            _ => (trackmate_csv(), Format::Trackmate),
        };
        let mut params = tracker_params();
        if explicit {
            params.format = format;
        }
        let files = Files::from([("run-1.csv".to_string(), apply(seed.into_bytes(), &traj_edits))]);
        ingest_bounded(&files, &params)?;
    }

    #[test]
    fn pipeline_toml_never_panics(toml_edits in edits()) {
        let text = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("pipeline.toml")).unwrap();
        let dir = project();
        let path = dir.path().join("pipeline.toml");
        std::fs::write(&path, apply(text, &toml_edits)).unwrap();
        let started = Instant::now();
        let result = config::load(&path, &Overrides::default(), &Catalog::with_kinds(groove::stages::registry()));
        prop_assert!(started.elapsed() < LIMIT);
        if let Err(e) = result {
            let message = e.to_string();
            prop_assert!(!message.is_empty());
        }
    }
}

/// A project folder with a `data/` folder holding the interchange files, so a valid config
/// validates.
fn project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("data")).unwrap();
    std::fs::write(dir.path().join("data/runs.csv"), RUNS_CSV).unwrap();
    std::fs::write(dir.path().join("data/trajectories.csv"), trajectories_csv()).unwrap();
    dir
}

#[test]
fn the_seed_inputs_are_valid() {
    let interchange = Files::from([
        ("runs.csv".to_string(), RUNS_CSV.as_bytes().to_vec()),
        (
            "trajectories.csv".to_string(),
            trajectories_csv().into_bytes(),
        ),
    ]);
    ingest::ingest(&interchange, &IngestParams::default()).unwrap_or_else(|e| panic!("{e}"));
    let parquet = Files::from([
        ("runs.csv".to_string(), RUNS_CSV.as_bytes().to_vec()),
        ("trajectories.parquet".to_string(), trajectories_parquet()),
    ]);
    ingest::ingest(&parquet, &IngestParams::default()).unwrap_or_else(|e| panic!("{e}"));
    for seed in [trackpy_csv(), trackmate_csv()] {
        let files = Files::from([("run-1.csv".to_string(), seed.into_bytes())]);
        let got = ingest::ingest(&files, &tracker_params()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(got.recordings.len(), 1);
    }
    let dir = project();
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("pipeline.toml"),
        dir.path().join("pipeline.toml"),
    )
    .unwrap();
    config::load(
        &dir.path().join("pipeline.toml"),
        &Overrides::default(),
        &Catalog::with_kinds(groove::stages::registry()),
    )
    .unwrap_or_else(|e| panic!("{e}"));
}
