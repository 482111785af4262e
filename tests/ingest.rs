//! Ingest tests: CSV and Parquet agree, row order does not matter, every bad-input class gives an
//! error naming file, row and column, and trackpy / TrackMate exports of the same trajectories give
//! the same recordings as the interchange format.

use groove::engine::stage::{
    Artifact, FileStamp, InputFile, ObjectMemo, Seen, StageInput, StageKind,
};
use groove::ingest::{self, item_name, Axis, Format, IngestParams};
use groove::recording::{Experiment, Recording, RunInfo, Setup, Track};
use groove::stages::ingest::Ingest;
use polars::prelude::*;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::io::Cursor;

#[path = "support/ingest_stage.rs"]
mod ingest_stage;
use ingest_stage::stage_outputs;

type Files = BTreeMap<String, Vec<u8>>;

// ---------------------------------------------------------------- known recordings

/// A track sampled at `frames`, t = frame / fps, z = f(t).
fn track(
    particle: u32,
    frames: impl Iterator<Item = i64>,
    fps: f64,
    z: impl Fn(f64) -> f64,
) -> Track {
    let frame: Vec<i64> = frames.collect();
    let t_s: Vec<f64> = frame.iter().map(|&f| f as f64 / fps).collect();
    let z_m = t_s.iter().map(|&t| z(t)).collect();
    Track {
        particle,
        frame,
        t_s,
        z_m,
    }
}

fn info(run: &str, experiment: Experiment, material: &str, setup: Option<Setup>) -> RunInfo {
    RunInfo {
        run: run.into(),
        experiment,
        material: material.into(),
        diameter_m: 0.004,
        fps: 200.0,
        setup,
        extra: BTreeMap::new(),
    }
}

/// Three runs with what real recordings hold and ingest must accept: dropped frames, motion in
/// -z, a tracking outlier, a particle leaving the field of view.
fn known_recordings() -> Vec<Recording> {
    let fps = 200.0;
    let s01 = Recording {
        info: info("s01", Experiment::Single, "316", None),
        tracks: vec![track(
            0,
            (0..80).filter(|f| ![10, 11, 30].contains(f)),
            fps,
            |t| {
                0.02 + 0.3 * t - 0.8 * t * t
                    + if (t * fps - 40.0).abs() < 1e-9 {
                        0.005
                    } else {
                        0.0
                    }
            },
        )],
    };
    let s02 = Recording {
        info: info("s02", Experiment::Single, "440c", None),
        tracks: vec![track(0, 0..60, fps, |t| 0.1 - 0.25 * t + 0.4 * t * t)],
    };
    let c01 = Recording {
        info: info("c01", Experiment::Collision, "316", Some(Setup::Rolling)),
        tracks: vec![
            track(0, 0..70, fps, |t| {
                if t < 0.15 {
                    0.2 * t
                } else {
                    0.03 + 0.02 * (t - 0.15)
                }
            }),
            // the target rests, is struck at t = 0.15 s and leaves the view after frame 55
            track(1, 0..56, fps, |t| {
                if t < 0.15 {
                    0.034
                } else {
                    0.034 + 0.18 * (t - 0.15)
                }
            }),
        ],
    };
    vec![c01, s01, s02]
}

// ---------------------------------------------------------------- writers of each format

fn runs_csv(recs: &[Recording]) -> String {
    let mut s = String::from("run,experiment,material,diameter_m,fps,setup\n");
    for r in recs {
        let i = &r.info;
        let exp = match i.experiment {
            Experiment::Single => "single",
            Experiment::Collision => "collision",
        };
        let setup = match i.setup {
            Some(Setup::Rolling) => "rolling",
            Some(Setup::Contact) => "contact",
            None => "",
        };
        s += &format!(
            "{},{exp},{},{},{},{setup}\n",
            i.run, i.material, i.diameter_m, i.fps
        );
    }
    s
}

/// One line per sample (`run,particle,frame,t_s,z_m`), in recording order.
fn trajectory_lines(recs: &[Recording]) -> Vec<String> {
    let mut lines = Vec::new();
    for r in recs {
        for t in &r.tracks {
            for k in 0..t.frame.len() {
                lines.push(format!(
                    "{},{},{},{},{}",
                    r.info.run, t.particle, t.frame[k], t.t_s[k], t.z_m[k]
                ));
            }
        }
    }
    lines
}

fn interchange_csv(recs: &[Recording]) -> Files {
    let traj = format!(
        "run,particle,frame,t_s,z_m\n{}\n",
        trajectory_lines(recs).join("\n")
    );
    Files::from([
        ("runs.csv".to_string(), runs_csv(recs).into_bytes()),
        ("trajectories.csv".to_string(), traj.into_bytes()),
    ])
}

fn parquet_bytes(mut df: DataFrame) -> Vec<u8> {
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes).finish(&mut df).unwrap();
    bytes
}

fn interchange_parquet(recs: &[Recording]) -> Files {
    let n = recs.len();
    let runs = DataFrame::new(
        n,
        vec![
            Column::new(
                "run".into(),
                recs.iter().map(|r| r.info.run.clone()).collect::<Vec<_>>(),
            ),
            Column::new(
                "experiment".into(),
                recs.iter()
                    .map(|r| {
                        if r.info.experiment == Experiment::Single {
                            "single"
                        } else {
                            "collision"
                        }
                    })
                    .collect::<Vec<_>>(),
            ),
            Column::new(
                "material".into(),
                recs.iter()
                    .map(|r| r.info.material.clone())
                    .collect::<Vec<_>>(),
            ),
            Column::new(
                "diameter_m".into(),
                recs.iter().map(|r| r.info.diameter_m).collect::<Vec<_>>(),
            ),
            Column::new(
                "fps".into(),
                recs.iter().map(|r| r.info.fps).collect::<Vec<_>>(),
            ),
            Column::new(
                "setup".into(),
                recs.iter()
                    .map(|r| {
                        r.info.setup.map(|s| {
                            if s == Setup::Rolling {
                                "rolling"
                            } else {
                                "contact"
                            }
                        })
                    })
                    .collect::<Vec<_>>(),
            ),
        ],
    )
    .unwrap();
    let (mut run, mut particle, mut frame, mut t_s, mut z_m) =
        (vec![], vec![], vec![], vec![], vec![]);
    for r in recs {
        for t in &r.tracks {
            for k in 0..t.frame.len() {
                run.push(r.info.run.clone());
                particle.push(t.particle as i64);
                frame.push(t.frame[k]);
                t_s.push(t.t_s[k]);
                z_m.push(t.z_m[k]);
            }
        }
    }
    let m = run.len();
    let traj = DataFrame::new(
        m,
        vec![
            Column::new("run".into(), run),
            Column::new("particle".into(), particle),
            Column::new("frame".into(), frame),
            Column::new("t_s".into(), t_s),
            Column::new("z_m".into(), z_m),
        ],
    )
    .unwrap();
    Files::from([
        ("runs.parquet".to_string(), parquet_bytes(runs)),
        ("trajectories.parquet".to_string(), parquet_bytes(traj)),
    ])
}

/// The calibration the tracker writers below invert.
struct Cal {
    m_per_px: f64,
    axis: Axis,
    direction: f64,
}

impl Cal {
    fn px(&self, z_m: f64) -> f64 {
        z_m / (self.direction * self.m_per_px)
    }
    /// (x, y) in pixels; the other axis sits at a fixed pixel row or column.
    fn xy(&self, z_m: f64) -> (f64, f64) {
        match self.axis {
            Axis::X => (self.px(z_m), 240.5),
            Axis::Y => (320.25, self.px(z_m)),
        }
    }
}

/// A trackpy export of one run: index column, pixels, track ids 7 (particle 0) and 3 (particle 1).
/// In a single run the track is split into fragments 7 and 8 (the tracker lost the sphere) and a
/// spurious short track 99 sits in frames the sphere's track covers.
fn to_trackpy(rec: &Recording, cal: &Cal) -> Vec<u8> {
    let mut s = String::from(",y,x,mass,size,ecc,signal,raw_mass,ep,frame,particle\n");
    let mut index = 0;
    let single = rec.info.experiment == Experiment::Single;
    for t in &rec.tracks {
        for k in 0..t.frame.len() {
            let id = match (t.particle, single) {
                (0, true) if k > t.frame.len() / 2 => 8,
                (0, _) => 7,
                _ => 3,
            };
            let (x, y) = cal.xy(t.z_m[k]);
            s += &format!(
                "{index},{y},{x},812.3,2.1,0.05,41.0,9120.0,0.012,{},{id}\n",
                t.frame[k]
            );
            index += 1;
        }
        if single {
            for k in 5..8 {
                let (x, y) = cal.xy(t.z_m[k] + 0.01);
                s += &format!(
                    "{index},{y},{x},90.0,1.1,0.3,4.0,800.0,0.2,{},99\n",
                    t.frame[k]
                );
                index += 1;
            }
        }
    }
    s.into_bytes()
}

/// Java's `Double.toString`: plain between 1e-3 and 1e7, else `1.0E-4` style.
fn java_double(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-3..1e7).contains(&a) {
        let s = format!("{x}");
        if s.contains('.') {
            s
        } else {
            format!("{s}.0")
        }
    } else {
        let s = format!("{x:E}");
        let (mantissa, exp) = s.split_once('E').unwrap();
        let mantissa = if mantissa.contains('.') {
            mantissa.to_string()
        } else {
            format!("{mantissa}.0")
        };
        format!("{mantissa}E{exp}")
    }
}

/// A TrackMate spot table of one run: four header rows, rows shuffled, two unlinked spurious spots,
/// track ids 0 (particle 0) and 5 (particle 1), positions in pixels.
fn to_trackmate(rec: &Recording, cal: &Cal, fps: f64, seed: u64) -> Vec<u8> {
    let mut rows = Vec::new();
    let mut id = 1000;
    for t in &rec.tracks {
        let track = if t.particle == 0 { 0 } else { 5 };
        for k in 0..t.frame.len() {
            let (x, y) = cal.xy(t.z_m[k]);
            rows.push(format!(
                "ID{id},{id},{track},42.5,{},{},0.0,{},{},3.0",
                java_double(x),
                java_double(y),
                java_double(t.frame[k] as f64 / fps),
                t.frame[k]
            ));
            id += 1;
        }
    }
    rows.push(format!(
        "ID{id},{id},,1.5,{},{},0.0,0.1,20,3.0",
        java_double(12.0),
        java_double(1.0e-4)
    ));
    rows.push(format!(
        "ID{},{},,1.5,{},{},0.0,0.1,21,3.0",
        id + 1,
        id + 1,
        java_double(3.0e7),
        java_double(7.0)
    ));
    rows.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let header =
        "LABEL,ID,TRACK_ID,QUALITY,POSITION_X,POSITION_Y,POSITION_Z,POSITION_T,FRAME,RADIUS\n\
                  Label,Spot ID,Track ID,Quality,X,Y,Z,T,Frame,Radius\n\
                  Label,Spot ID,Track ID,Quality,X,Y,Z,T,Frame,R\n\
                  ,,,(quality),(pixel),(pixel),(pixel),(sec),,(pixel)\n";
    format!("{header}{}\n", rows.join("\n")).into_bytes()
}

// ---------------------------------------------------------------- helpers

fn params() -> IngestParams {
    IngestParams::default()
}

fn run_ok(files: &Files, params: &IngestParams) -> Vec<Recording> {
    match ingest::ingest(files, params) {
        Ok(i) => i.recordings,
        Err(e) => panic!("ingest failed: {e}"),
    }
}

fn run_err(files: &Files) -> String {
    match ingest::ingest(files, &params()) {
        Ok(_) => panic!("ingest accepted bad input"),
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

/// The interchange CSV with trajectory line `k` (0-based data line) replaced by `f(line)`.
fn edit_trajectory(recs: &[Recording], k: usize, f: impl Fn(&str) -> String) -> Files {
    let mut lines = trajectory_lines(recs);
    lines[k] = f(&lines[k]);
    let mut files = interchange_csv(recs);
    files.insert(
        "trajectories.csv".into(),
        format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
    );
    files
}

fn set_field(line: &str, field: usize, value: &str) -> String {
    let mut cells: Vec<&str> = line.split(',').collect();
    cells[field] = value;
    cells.join(",")
}

/// The known recordings sorted by run, as ingest returns them.
fn expected() -> Vec<Recording> {
    let mut recs = known_recordings();
    recs.sort_by(|a, b| a.info.run.cmp(&b.info.run));
    recs
}

// ---------------------------------------------------------------- good input

#[test]
fn interchange_csv_gives_the_known_recordings_exactly() {
    // Numbers are written in shortest round-trip form, so reading them back is exact.
    assert_eq!(
        run_ok(&interchange_csv(&known_recordings()), &params()),
        expected()
    );
}

#[test]
fn csv_and_parquet_read_identically() {
    let recs = known_recordings();
    let from_csv = run_ok(&interchange_csv(&recs), &params());
    let from_parquet = run_ok(&interchange_parquet(&recs), &params());
    assert_eq!(from_csv, from_parquet);
    // Mixed forms too: runs.csv with trajectories.parquet.
    let mut mixed = interchange_csv(&recs);
    mixed.remove("trajectories.csv");
    mixed.insert(
        "trajectories.parquet".into(),
        interchange_parquet(&recs)["trajectories.parquet"].clone(),
    );
    assert_eq!(run_ok(&mixed, &params()), from_csv);
}

/// With a store to put items in, the stage returns each run's item hash (`Artifact::InStore`)
/// and has put exactly the bytes it returns without one: on grouped rows (streamed) and on
/// shuffled rows (read whole).
#[test]
fn with_a_store_the_stage_puts_each_item_and_returns_its_hash() {
    let recs = known_recordings();
    let grouped = interchange_csv(&recs);
    let mut lines = trajectory_lines(&recs);
    lines.shuffle(&mut ChaCha8Rng::seed_from_u64(4));
    let mut shuffled = grouped.clone();
    shuffled.insert(
        "trajectories.csv".into(),
        format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
    );
    for files in [grouped, shuffled] {
        let Artifact::Collection(want) = &stage_outputs(&files, &toml::Table::new())["runs"] else {
            panic!("without a store the runs are a collection")
        };
        let put: std::sync::Mutex<BTreeMap<String, Vec<u8>>> = Default::default();
        let put_item = |bytes: &[u8]| {
            let sha = groove::engine::hashing::sha256_hex(bytes);
            put.lock().unwrap().insert(sha.clone(), bytes.to_vec());
            Ok(sha)
        };
        let dataset = Artifact::Collection(files.clone());
        let params = toml::Table::new();
        let input = StageInput {
            params: &params,
            inputs: BTreeMap::from([("dataset", &dataset)]),
            item: None,
            seed: 1,
            progress: None,
            put_item: Some(&put_item),
            memo: None,
        };
        let out = Ingest.run(&input).unwrap();
        let Artifact::InStore(got) = &out["runs"] else {
            panic!("with a store the runs are put there")
        };
        let put = put.lock().unwrap();
        assert_eq!(got.len(), want.len());
        for (item, bytes) in want {
            assert_eq!(&put[&got[item]], bytes, "{item}");
        }
        assert_eq!(put.len(), want.len());
    }
}

/// The stage's memo as the engine keeps it (`ObjectMemo`), counting what is put.
#[derive(Default)]
struct TestMemo {
    held: std::sync::Mutex<BTreeMap<[u8; 32], String>>,
    puts: std::sync::atomic::AtomicUsize,
}

impl ObjectMemo for TestMemo {
    fn get(&self, key: &[u8; 32]) -> Option<String> {
        self.held.lock().unwrap().get(key).cloned()
    }

    fn read(&self, _: &str) -> Option<Vec<u8>> {
        None
    }

    fn put(&self, key: [u8; 32], sha256: &str) {
        self.puts.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.held.lock().unwrap().insert(key, sha256.to_string());
    }
}

/// With a memo of whole runs, the dataset left on disk: the first read remembers every run
/// between the piece's first and last; a second read finds them all and gives the same items;
/// an edit of one line makes that run again (and only it) and gives the items a read without a
/// memo gives; a run whose rows come in two blocks sends the read whole, and nothing of that read
/// is remembered.
#[test]
fn a_memo_of_whole_runs_finds_the_unchanged_ones_and_gives_the_items_of_a_read_without_it() {
    let recs: Vec<Recording> = (0..8)
        .map(|k| Recording {
            info: info(&format!("s{k:02}"), Experiment::Single, "316", None),
            tracks: vec![track(0, 0..60, 200.0, |t| {
                0.01 * k as f64 + 0.2 * t - 0.3 * t * t
            })],
        })
        .collect();
    let files = interchange_csv(&recs);
    let params = toml::Table::new();
    let store: std::sync::Mutex<BTreeMap<String, Vec<u8>>> = Default::default();
    // the items (name → sha256) and what the stage said of how it read the dataset
    let run = |files: &Files, memo: Option<&TestMemo>| {
        let dir = tempfile::tempdir().unwrap();
        let mut on_disk = BTreeMap::new();
        for (name, bytes) in files {
            let path = dir.path().join(name);
            std::fs::write(&path, bytes).unwrap();
            let sha256 = groove::engine::hashing::sha256_hex(bytes);
            on_disk.insert(name.clone(), InputFile::checked(path, sha256));
        }
        let dataset = Artifact::OnDisk(on_disk);
        let put_item = |bytes: &[u8]| {
            let sha = groove::engine::hashing::sha256_hex(bytes);
            store.lock().unwrap().insert(sha.clone(), bytes.to_vec());
            Ok(sha)
        };
        let said = std::sync::Mutex::new(String::new());
        let progress = |what: &str| *said.lock().unwrap() = what.to_string();
        let input = StageInput {
            params: &params,
            inputs: BTreeMap::from([("dataset", &dataset)]),
            item: None,
            seed: 1,
            progress: Some(&progress),
            put_item: Some(&put_item),
            memo: memo.map(|m| m as &dyn ObjectMemo),
        };
        let out = Ingest.run(&input).unwrap();
        let Artifact::InStore(items) = &out["runs"] else {
            panic!("with a store the runs are put there")
        };
        (items.clone(), said.into_inner().unwrap())
    };
    let memo = TestMemo::default();
    let puts = || memo.puts.load(std::sync::atomic::Ordering::Relaxed);
    let (want, _) = run(&files, None);
    assert_eq!(want.len(), 8);

    let (first, how) = run(&files, Some(&memo));
    assert_eq!(first, want);
    assert!(!how.contains("found"), "{how}");
    // s00 and s07 may go on in the pieces around this one: never remembered
    let mut held: Vec<String> = memo.held.lock().unwrap().values().cloned().collect();
    held.sort();
    let mut middle: Vec<String> = (1..7)
        .map(|k| want[&item_name(&format!("s{k:02}"))].clone())
        .collect();
    middle.sort();
    assert_eq!(held, middle);
    assert_eq!(puts(), 6);

    let (second, how) = run(&files, Some(&memo));
    assert_eq!(second, want);
    assert!(how.contains("6 of 8 runs' items found"), "{how}");
    assert_eq!(puts(), 6, "nothing new to remember");

    // one z value of s03 changed (line 3·60 + 10 of the trajectories, after the header)
    let edited = edit_trajectory(&recs, 3 * 60 + 10, |l| {
        let z: f64 = l.split(',').nth(4).unwrap().parse().unwrap();
        set_field(l, 4, &format!("{}", z + 1e-7))
    });
    let (want_edited, _) = run(&edited, None);
    let s03 = item_name("s03");
    assert_ne!(want_edited[&s03], want[&s03]);
    let (got, how) = run(&edited, Some(&memo));
    assert_eq!(got, want_edited);
    assert!(how.contains("5 of 8 runs' items found"), "{how}");
    assert_eq!(puts(), 7, "the edited run only");

    // s04's first line moved to the end: its rows are two blocks, so the dataset is read whole
    let mut lines = trajectory_lines(&recs);
    let moved = lines.remove(4 * 60);
    lines.push(moved);
    let mut split = files.clone();
    split.insert(
        "trajectories.csv".into(),
        format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
    );
    let (want_split, _) = run(&split, None);
    let (got, how) = run(&split, Some(&memo));
    assert_eq!(got, want_split);
    assert_eq!(got, want, "the same rows in another order");
    assert!(how.contains("read whole"), "{how}");
    assert_eq!(puts(), 7, "a read that stopped remembers nothing");
}

/// The dataset written to a folder and given as the engine gives it to the stage (left on disk,
/// `Artifact::OnDisk`, trajectories.csv read in pieces): the outputs of the same bytes given in
/// memory, whether streamed (grouped rows) or read whole (shuffled rows, or a bad row whose
/// message must be the same); and a file whose content is not the one its key was made from is
/// refused, never read as if it were.
#[test]
fn a_dataset_left_on_disk_gives_the_outputs_of_its_bytes_in_memory() {
    let recs = known_recordings();
    let grouped = interchange_csv(&recs);
    let shuffled = shuffled_trajectories(&grouped, 5);
    let mut bad = grouped.clone();
    let text = String::from_utf8(bad["trajectories.csv"].clone()).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    let broken = lines[3].replacen(',', ",x", 2);
    lines[3] = &broken;
    bad.insert(
        "trajectories.csv".into(),
        format!("{}\n", lines.join("\n")).into_bytes(),
    );
    let params = toml::Table::new();
    // the outputs, and what the stage said of how it read the dataset
    let run = |dataset: &Artifact| {
        let said = std::sync::Mutex::new(String::new());
        let progress = |what: &str| *said.lock().unwrap() = what.to_string();
        let input = StageInput {
            params: &params,
            inputs: BTreeMap::from([("dataset", dataset)]),
            item: None,
            seed: 1,
            progress: Some(&progress),
            put_item: None,
            memo: None,
        };
        let out = Ingest.run(&input).map_err(|e| e.to_string());
        (out, said.into_inner().unwrap())
    };
    let parquet = interchange_parquet(&recs);
    let cases = [
        ("grouped", grouped),
        ("shuffled", shuffled),
        ("bad", bad),
        ("parquet", parquet),
    ];
    for (what, files) in cases {
        let dir = tempfile::tempdir().unwrap();
        let mut on_disk = BTreeMap::new();
        for (name, bytes) in &files {
            let path = dir.path().join(name);
            std::fs::write(&path, bytes).unwrap();
            let sha256 = groove::engine::hashing::sha256_hex(bytes);
            on_disk.insert(name.clone(), InputFile::checked(path, sha256));
        }
        let (in_memory, _) = run(&Artifact::Collection(files.clone()));
        let (from_disk, how) = run(&Artifact::OnDisk(on_disk.clone()));
        assert_eq!(from_disk, in_memory, "{what}");
        match what {
            // streamed from the file, not read whole
            "grouped" => assert!(how.contains("runs, read in 1 chunk of"), "{how}"),
            "parquet" => assert!(
                how.contains("runs, decoded from Parquet in 1 batch"),
                "{how}"
            ),
            "shuffled" => assert!(how.contains("read whole (the rows of a run"), "{how}"),
            _ => assert!(in_memory.unwrap_err().contains("row"), "a bad row is named"),
        }
        // not hashed yet (the engine's first run over a dataset): the same outputs, and each
        // file's digest recorded from what the stage read
        let seen: BTreeMap<String, Seen> =
            files.keys().map(|n| (n.clone(), Seen::default())).collect();
        let recorded = on_disk
            .iter()
            .map(|(n, f)| {
                (
                    n.clone(),
                    InputFile::recorded(f.path.clone(), seen[n].clone()),
                )
            })
            .collect();
        assert_eq!(run(&Artifact::OnDisk(recorded)).0, from_disk, "{what}");
        // (a bad row stops the read before the end: nothing is recorded, the stage fails)
        for (name, bytes) in files.iter().filter(|_| what != "bad") {
            let digests = seen[name].digests();
            let sha256 = groove::engine::hashing::sha256_hex(bytes);
            assert!(!digests.is_empty(), "{what} {name}: no digest recorded");
            assert!(
                digests.iter().all(|d| *d == sha256),
                "{what} {name}: {digests:?}"
            );
        }
        // vouched for by the file-hash cache's stat (an edit's rerun): the same outputs without
        // hashing again; a stat the file no longer has is a change
        let vouched = |bump: u64| {
            let files = on_disk.iter().map(|(n, f)| {
                let mut stamp = FileStamp::of(&std::fs::metadata(&f.path).unwrap());
                stamp.size += bump;
                (n.clone(), InputFile::vouched(f.path.clone(), stamp))
            });
            Artifact::OnDisk(files.collect())
        };
        assert_eq!(run(&vouched(0)).0, from_disk, "{what}");
        let err = run(&vouched(1)).0.unwrap_err();
        assert!(
            err.contains("changed while groove was running"),
            "{what}: {err}"
        );
        // a stale hash: the content changed after the key was made
        for name in on_disk.keys() {
            let mut stale = on_disk.clone();
            let path = stale[name].path.clone();
            stale.insert(name.to_string(), InputFile::checked(path, "0".repeat(64)));
            let err = run(&Artifact::OnDisk(stale)).0.unwrap_err();
            assert!(
                err.contains(name) && err.contains("changed while groove was running"),
                "{what} {name}: {err}"
            );
        }
    }
}

#[test]
fn shuffled_rows_give_byte_identical_outputs() {
    let recs = known_recordings();
    let files = interchange_csv(&recs);
    let reference = stage_outputs(&files, &toml::Table::new());
    for seed in [1, 2, 3] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut lines = trajectory_lines(&recs);
        lines.shuffle(&mut rng);
        let mut runs: Vec<String> = runs_csv(&recs).lines().skip(1).map(String::from).collect();
        runs.shuffle(&mut rng);
        let shuffled = Files::from([
            (
                "runs.csv".to_string(),
                format!(
                    "run,experiment,material,diameter_m,fps,setup\n{}\n",
                    runs.join("\n")
                )
                .into_bytes(),
            ),
            (
                "trajectories.csv".to_string(),
                format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
            ),
        ]);
        assert_eq!(
            stage_outputs(&shuffled, &toml::Table::new()),
            reference,
            "seed {seed}"
        );
    }
}

#[test]
fn stage_outputs_hold_recordings_and_an_empty_skipped_list() {
    let out = stage_outputs(&interchange_csv(&known_recordings()), &toml::Table::new());
    let Artifact::Collection(runs) = &out["runs"] else {
        panic!("runs is not a collection")
    };
    assert_eq!(runs.keys().collect::<Vec<_>>(), ["c01", "s01", "s02"]);
    let c01 = groove::recording::item::decode(&runs["c01"]).unwrap();
    assert_eq!(c01, expected()[0]);
    assert_eq!(out["skipped"], Artifact::File(b"[]\n".to_vec()));
    assert_eq!(
        out.keys().collect::<Vec<_>>(),
        ["runs", "skipped"],
        "no Parquet table of all samples: no stage reads one"
    );
}

#[test]
fn extra_run_columns_are_kept_as_text() {
    let recs = known_recordings();
    let mut files = interchange_csv(&recs);
    let runs = runs_csv(&recs)
        .lines()
        .enumerate()
        .map(|(k, l)| {
            if k == 0 {
                format!("{l},operator")
            } else {
                format!("{l},ana {k}")
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    files.insert("runs.csv".into(), runs.into_bytes());
    let got = run_ok(&files, &params());
    assert_eq!(
        got[0].info.extra,
        BTreeMap::from([("operator".to_string(), "ana 1".to_string())])
    );
}

#[test]
fn item_names_are_file_name_safe_and_distinct() {
    assert_eq!(item_name("run-01_a.b"), "run-01_a.b");
    let odd = ["run/1", "run 1", "run:1", "..", "läuft"];
    let names: Vec<String> = odd.iter().map(|r| item_name(r)).collect();
    for n in &names {
        assert!(
            n.chars()
                .all(|c| c.is_ascii_alphanumeric() || "._-".contains(c)),
            "{n}"
        );
        assert!(n != "." && n != "..");
    }
    let mut unique = names.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), names.len(), "{names:?}");
    // The true id stays in the recording.
    let mut recs = known_recordings();
    recs[1].info.run = "day 2:s01".into();
    let out = stage_outputs(&interchange_csv(&recs), &toml::Table::new());
    let Artifact::Collection(runs) = &out["runs"] else {
        panic!()
    };
    let rec = groove::recording::item::decode(&runs[&item_name("day 2:s01")]).unwrap();
    assert_eq!(rec.info.run, "day 2:s01");
}

#[test]
fn read_dataset_dir_reads_top_level_files_only() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in interchange_csv(&known_recordings()) {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    std::fs::create_dir(dir.path().join("truth")).unwrap();
    std::fs::write(dir.path().join("truth/runs.csv"), "not,a,dataset\n").unwrap();
    assert_eq!(
        ingest::read_dataset_dir(dir.path(), &params()).unwrap(),
        expected()
    );
}

// ---------------------------------------------------------------- bad input

#[test]
fn missing_file_is_named() {
    let mut files = interchange_csv(&known_recordings());
    files.remove("trajectories.csv");
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv: is missing", "add trajectories.csv"],
    );
}

#[test]
fn missing_column_is_named_at_the_header_row() {
    let recs = known_recordings();
    let mut files = interchange_csv(&recs);
    let runs = runs_csv(&recs).replace(",fps,", ",frame_rate,");
    files.insert("runs.csv".into(), runs.into_bytes());
    assert_mentions(
        &run_err(&files),
        &["runs.csv row 1, column fps: missing column", "add fps"],
    );
}

#[test]
fn run_in_one_table_only_is_named_in_both_directions() {
    let recs = known_recordings();
    let mut files = interchange_csv(&recs);
    let runs = format!("{}ghost,single,316,0.004,200,\n", runs_csv(&recs));
    files.insert("runs.csv".into(), runs.into_bytes());
    // header + 3 runs, so ghost is row 5
    assert_mentions(
        &run_err(&files),
        &["runs.csv row 5, column run: run \"ghost\" has no rows in trajectories.csv"],
    );

    // data line 7 (row 8) belongs to a run runs.csv does not list
    let files = edit_trajectory(&recs, 6, |l| set_field(l, 0, "stray"));
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv row 8, column run: run \"stray\" is not in runs.csv"],
    );
}

#[test]
fn non_numeric_and_non_finite_values_are_named() {
    let recs = known_recordings();
    // The known recordings are short; use a longer copy of s02 for the row-1234 example.
    let mut long = known_recordings();
    long[2].tracks = vec![track(0, 0..1500, 200.0, |t| 0.1 - 0.25 * t)];
    let files = edit_trajectory(&long, 1232, |l| set_field(l, 4, "abc"));
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv row 1234, column z_m: \"abc\" is not a number; write a finite number in metres"],
    );
    let files = edit_trajectory(&recs, 3, |l| set_field(l, 3, "inf"));
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv row 5, column t_s: inf is not a finite number"],
    );
    let files = edit_trajectory(&recs, 3, |l| set_field(l, 2, "4.5"));
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv row 5, column frame: \"4.5\" is not a whole number"],
    );
    let mut files = interchange_csv(&recs);
    let runs = runs_csv(&recs).replace("s01,single,316,0.004,200", "s01,single,316,0.004,NaN");
    files.insert("runs.csv".into(), runs.into_bytes());
    assert_mentions(
        &run_err(&files),
        &["runs.csv row 3, column fps: NaN is not a finite number"],
    );
}

#[test]
fn duplicate_sample_is_named_with_both_rows() {
    let recs = known_recordings();
    let mut lines = trajectory_lines(&recs);
    lines.push(lines[9].clone()); // row 11 again, at the end
    let n = lines.len();
    let mut files = interchange_csv(&recs);
    files.insert(
        "trajectories.csv".into(),
        format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
    );
    assert_mentions(
        &run_err(&files),
        &[&format!(
            "trajectories.csv row {}, column run, particle, frame: duplicate of row 11: run \"c01\", particle 0, frame 9 appears twice; delete one",
            n + 1
        )],
    );
}

#[test]
fn too_few_frames_is_named() {
    let mut recs = known_recordings();
    recs[2].tracks = vec![track(0, 0..12, 200.0, |t| 0.1 - 0.25 * t)];
    let files = interchange_csv(&recs);
    // s02's first sample is data line 70 + 56 + 77 + 1 = 204, row 205
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv row 205, column frame: run \"s02\" has 12 frames of particle 0 (the particle), fewer than min_frames = 20"],
    );
    // A collision run whose target was never tracked.
    let mut recs = known_recordings();
    recs[0].tracks.truncate(1);
    assert_mentions(
        &run_err(&interchange_csv(&recs)),
        &["trajectories.csv row 2, column frame: run \"c01\" has 0 frames of particle 1 (the target)"],
    );
}

#[test]
fn unknown_experiment_and_particle_are_named() {
    let recs = known_recordings();
    let mut files = interchange_csv(&recs);
    files.insert(
        "runs.csv".into(),
        runs_csv(&recs)
            .replace("s02,single", "s02,triple")
            .into_bytes(),
    );
    assert_mentions(
        &run_err(&files),
        &["runs.csv row 4, column experiment: \"triple\" is not a known experiment kind; write single"],
    );
    // particle 1 in a single run (s01 starts at 0-based data line 126, row 128)
    let files = edit_trajectory(&recs, 126, |l| set_field(l, 1, "1"));
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv row 128, column particle: particle 1 in run \"s01\", but a single run has only particle 0"],
    );
}

#[test]
fn parquet_problems_name_the_data_row() {
    let recs = known_recordings();
    let mut files = interchange_parquet(&recs);
    let mut df = ParquetReader::new(Cursor::new(files["trajectories.parquet"].clone()))
        .finish()
        .unwrap();
    let mut z: Vec<f64> = df
        .column("z_m")
        .unwrap()
        .f64()
        .unwrap()
        .into_no_null_iter()
        .collect();
    z[41] = f64::NAN;
    df.replace("z_m", Column::new("z_m".into(), z)).unwrap();
    files.insert("trajectories.parquet".into(), parquet_bytes(df));
    assert_mentions(
        &run_err(&files),
        &["trajectories.parquet row 42, column z_m: NaN is not a finite number"],
    );
}

#[test]
fn blank_lines_do_not_shift_row_numbers() {
    let recs = known_recordings();
    let mut lines = trajectory_lines(&recs);
    lines[4] = set_field(&lines[4], 4, "x1");
    lines.insert(2, String::new()); // a blank line: data line 4 is now on row 7
    let mut files = interchange_csv(&recs);
    files.insert(
        "trajectories.csv".into(),
        format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
    );
    assert_mentions(
        &run_err(&files),
        &["trajectories.csv row 7, column z_m: \"x1\" is not a number"],
    );
}

#[test]
fn skip_bad_runs_drops_and_lists_the_bad_runs_only() {
    let recs = known_recordings();
    let files = edit_trajectory(&recs, 130, |l| set_field(l, 4, "abc")); // in s01, row 132
    let mut p = params();
    p.skip_bad_runs = true;
    let got = ingest::ingest(&files, &p).unwrap();
    let want: Vec<Recording> = expected()
        .into_iter()
        .filter(|r| r.info.run != "s01")
        .collect();
    assert_eq!(got.recordings, want);
    assert_eq!(got.skipped.len(), 1);
    assert_eq!(got.skipped[0].run, "s01");
    assert_mentions(
        &got.skipped[0].reason,
        &["trajectories.csv row 132, column z_m"],
    );
    // The same through the stage: the skipped output lists it.
    let params_toml: toml::Table = toml::from_str("skip_bad_runs = true").unwrap();
    let out = stage_outputs(&files, &params_toml);
    let Artifact::File(skipped) = &out["skipped"] else {
        panic!()
    };
    let list: serde_json::Value = serde_json::from_slice(skipped).unwrap();
    assert_eq!(list[0]["run"], "s01");
    // Without the flag the error says how to leave the run out.
    assert_mentions(&run_err(&files), &["skip_bad_runs = true"]);
}

#[test]
fn problems_outside_any_run_are_never_skipped() {
    let recs = known_recordings();
    let files = edit_trajectory(&recs, 5, |l| set_field(l, 0, ""));
    let mut p = params();
    p.skip_bad_runs = true;
    let e = ingest::ingest(&files, &p).unwrap_err().to_string();
    assert_mentions(&e, &["trajectories.csv row 7, column run: is empty"]);
}

#[test]
fn stage_params_are_typed_with_defaults() {
    let kind = Ingest;
    let json = kind.canonical_params(&toml::Table::new()).unwrap();
    assert_eq!(json["format"], "auto");
    assert_eq!(json["min_frames"], 20);
    assert_eq!(json["skip_bad_runs"], false);
    let unknown: toml::Table = toml::from_str("formt = \"auto\"").unwrap();
    assert!(kind
        .canonical_params(&unknown)
        .unwrap_err()
        .to_string()
        .contains("formt"));
    let bad: toml::Table = toml::from_str("calibration = { direction = 2 }").unwrap();
    assert!(kind
        .canonical_params(&bad)
        .unwrap_err()
        .to_string()
        .contains("calibration.direction"));
    let ints: toml::Table = toml::from_str(
        "format = \"trackpy\"\ncalibration = { fps = 200, m_per_px = 1e-5, axis = \"y\" }",
    )
    .unwrap();
    let json = kind.canonical_params(&ints).unwrap();
    assert_eq!(json["calibration"]["fps"], 200.0);
}

// ---------------------------------------------------------------- other trackers

/// Ingests tracker exports of `recs` (all of one experiment kind) and compares with the
/// interchange recordings: same frames and metadata, t and z within 1e-12 (relative to 1 m / 1 s).
fn check_tracker(format: Format, experiment: Experiment, cal: Cal) {
    let recs: Vec<Recording> = known_recordings()
        .into_iter()
        .filter(|r| r.info.experiment == experiment)
        .map(|mut r| {
            r.info.material = "316".into();
            r
        })
        .collect();
    let mut files = Files::new();
    for (k, r) in recs.iter().enumerate() {
        let bytes = match format {
            Format::Trackpy => to_trackpy(r, &cal),
            _ => to_trackmate(r, &cal, 200.0, k as u64),
        };
        files.insert(format!("{}.csv", r.info.run), bytes);
    }
    files.insert("notes.txt".into(), b"not a table".to_vec());
    let mut p = params();
    p.calibration.m_per_px = Some(cal.m_per_px);
    p.calibration.fps = Some(200.0);
    p.calibration.axis = cal.axis;
    p.calibration.direction = cal.direction as i8;
    p.calibration.material = Some("316".into());
    p.calibration.diameter_m = Some(0.004);
    p.calibration.experiment = experiment;
    p.calibration.setup = recs[0].info.setup;
    let from_interchange = run_ok(&interchange_csv(&recs), &params());
    for fmt in [Format::Auto, format] {
        p.format = fmt;
        let got = run_ok(&files, &p);
        assert_eq!(got.len(), from_interchange.len());
        for (g, w) in got.iter().zip(&from_interchange) {
            assert_eq!(g.info, w.info);
            assert_eq!(g.tracks.len(), w.tracks.len());
            for (gt, wt) in g.tracks.iter().zip(&w.tracks) {
                assert_eq!(gt.particle, wt.particle);
                assert_eq!(gt.frame, wt.frame);
                for k in 0..gt.frame.len() {
                    assert!((gt.t_s[k] - wt.t_s[k]).abs() < 1e-12, "{format:?} t");
                    assert!(
                        (gt.z_m[k] - wt.z_m[k]).abs() < 1e-12,
                        "{format:?} z {} vs {}",
                        gt.z_m[k],
                        wt.z_m[k]
                    );
                }
            }
        }
    }
}

#[test]
fn trackpy_gives_the_interchange_recordings() {
    let cal = Cal {
        m_per_px: 2.5e-5,
        axis: Axis::X,
        direction: 1.0,
    };
    check_tracker(Format::Trackpy, Experiment::Single, cal);
    let cal = Cal {
        m_per_px: 4.0e-5,
        axis: Axis::Y,
        direction: -1.0,
    };
    check_tracker(Format::Trackpy, Experiment::Collision, cal);
}

#[test]
fn trackmate_gives_the_interchange_recordings() {
    let cal = Cal {
        m_per_px: 2.5e-5,
        axis: Axis::Y,
        direction: -1.0,
    };
    check_tracker(Format::Trackmate, Experiment::Single, cal);
    let cal = Cal {
        m_per_px: 1.0e-4,
        axis: Axis::X,
        direction: 1.0,
    };
    check_tracker(Format::Trackmate, Experiment::Collision, cal);
}

#[test]
fn tracker_files_need_a_calibration() {
    let rec = &known_recordings()[1];
    let cal = Cal {
        m_per_px: 1e-5,
        axis: Axis::X,
        direction: 1.0,
    };
    let files = Files::from([("s01.csv".to_string(), to_trackpy(rec, &cal))]);
    let e = run_err(&files);
    assert_mentions(
        &e,
        &["calibration.m_per_px", "calibration.fps", "pipeline.toml"],
    );
}

#[test]
fn tracker_collision_with_a_third_track_is_named() {
    let rec = &known_recordings()[0];
    let cal = Cal {
        m_per_px: 1e-4,
        axis: Axis::X,
        direction: 1.0,
    };
    let mut text = String::from_utf8(to_trackpy(rec, &cal)).unwrap();
    text += "999,240.5,100.0,1.0,2.0,0.1,3.0,4.0,0.1,5,12\n";
    let files = Files::from([("c01.csv".to_string(), text.into_bytes())]);
    let mut p = params();
    p.calibration.m_per_px = Some(1e-4);
    p.calibration.fps = Some(200.0);
    p.calibration.material = Some("316".into());
    p.calibration.diameter_m = Some(0.004);
    p.calibration.experiment = Experiment::Collision;
    let e = ingest::ingest(&files, &p).unwrap_err().to_string();
    assert_mentions(
        &e,
        &["c01.csv row 1, column particle: 3 linked tracks (ids 3, 7, 12)"],
    );
}

#[test]
fn trackmate_bad_value_names_the_file_row() {
    let rec = &known_recordings()[1];
    let cal = Cal {
        m_per_px: 1e-5,
        axis: Axis::X,
        direction: 1.0,
    };
    let text = String::from_utf8(to_trackmate(rec, &cal, 200.0, 9)).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    lines[10] = set_field(&lines[10], 4, "1x2");
    let files = Files::from([(
        "s01.csv".to_string(),
        (lines.join("\n") + "\n").into_bytes(),
    )]);
    let mut p = params();
    p.format = Format::Trackmate;
    p.calibration.m_per_px = Some(1e-5);
    p.calibration.fps = Some(200.0);
    p.calibration.material = Some("316".into());
    p.calibration.diameter_m = Some(0.004);
    let e = ingest::ingest(&files, &p).unwrap_err().to_string();
    // line index 10 is row 11 of the file (four header rows count as rows)
    assert_mentions(
        &e,
        &["s01.csv row 11, column POSITION_X: \"1x2\" is not a number"],
    );
}

#[test]
fn duplicate_run_and_unknown_setup_are_named() {
    let recs = known_recordings();
    let mut files = interchange_csv(&recs);
    let runs = format!("{}s02,single,316,0.004,200,\n", runs_csv(&recs));
    files.insert("runs.csv".into(), runs.into_bytes());
    assert_mentions(
        &run_err(&files),
        &["runs.csv row 5, column run: run \"s02\" is listed twice (also row 4)"],
    );
    let mut files = interchange_csv(&recs);
    let runs = runs_csv(&recs).replace(
        "collision,316,0.004,200,rolling",
        "collision,316,0.004,200,thrown",
    );
    files.insert("runs.csv".into(), runs.into_bytes());
    assert_mentions(
        &run_err(&files),
        &["runs.csv row 2, column setup: \"thrown\" is not a known setup; write rolling"],
    );
}

#[test]
fn csv_and_parquet_of_one_table_together_are_ambiguous() {
    let recs = known_recordings();
    let mut files = interchange_csv(&recs);
    files.insert(
        "runs.parquet".into(),
        interchange_parquet(&recs)["runs.parquet"].clone(),
    );
    assert_mentions(
        &run_err(&files),
        &["both runs.csv and runs.parquet", "keep one of them"],
    );
}

#[test]
fn trackmate_with_two_header_rows_reads_the_same() {
    let rec = &known_recordings()[1];
    let cal = Cal {
        m_per_px: 1e-5,
        axis: Axis::X,
        direction: 1.0,
    };
    let full = String::from_utf8(to_trackmate(rec, &cal, 200.0, 4)).unwrap();
    // keep the key line and the names line only
    let short: String = full
        .lines()
        .enumerate()
        .filter(|(k, _)| !(2..=3).contains(k))
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    let mut p = params();
    p.calibration.m_per_px = Some(1e-5);
    p.calibration.fps = Some(200.0);
    p.calibration.material = Some("316".into());
    p.calibration.diameter_m = Some(0.004);
    let four = run_ok(
        &Files::from([("s01.csv".to_string(), full.into_bytes())]),
        &p,
    );
    let two = run_ok(
        &Files::from([("s01.csv".to_string(), short.into_bytes())]),
        &p,
    );
    assert_eq!(four, two);
    assert_eq!(two[0].tracks[0].frame, rec.tracks[0].frame);
}

#[test]
fn shipped_dataset_ingests_every_run() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let listed = std::fs::read_to_string(dir.join("runs.csv"))
        .unwrap()
        .lines()
        .count()
        - 1;
    let recs = ingest::read_dataset_dir(&dir, &params()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(recs.len(), listed);
    for r in &recs {
        let wanted = if r.info.experiment == Experiment::Single {
            1
        } else {
            2
        };
        assert_eq!(r.tracks.len(), wanted, "run {}", r.info.run);
        for t in &r.tracks {
            assert!(
                t.frame.windows(2).all(|w| w[0] < w[1]),
                "run {} frames unsorted",
                r.info.run
            );
            assert!(t.frame.len() >= 20);
        }
    }
}

#[test]
fn many_problems_are_counted_and_listed_in_file_order() {
    let recs = known_recordings();
    let mut lines = trajectory_lines(&recs);
    for line in lines.iter_mut().take(25) {
        *line = set_field(line, 4, "?");
    }
    let mut files = interchange_csv(&recs);
    files.insert(
        "trajectories.csv".into(),
        format!("run,particle,frame,t_s,z_m\n{}\n", lines.join("\n")).into_bytes(),
    );
    let e = run_err(&files);
    assert!(e.starts_with("25 problems in the dataset:"), "{e}");
    assert_mentions(&e, &["... and 5 more"]);
    let first = e.find("row 2,").unwrap();
    let second = e.find("row 3,").unwrap();
    assert!(first < second, "{e}");
}

// ---------------------------------------------------------------- the columnar path

/// The shipped dataset's top-level files.
fn shipped_files() -> Files {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let mut files = Files::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_file() {
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            files.insert(name, std::fs::read(&path).unwrap());
        }
    }
    files
}

/// The row-by-row reference's recordings of `files`.
fn row_by_row(files: &Files) -> Vec<Recording> {
    ingest::ingest_row_by_row(files, &params())
        .unwrap_or_else(|e| panic!("{e}"))
        .recordings
}

/// The columnar path reads `files` (it does not fall back) and gives the row-by-row recordings.
fn assert_columnar_matches(files: &Files, what: &str) -> Vec<Recording> {
    let columnar = ingest::ingest_columnar(files, &params())
        .unwrap_or_else(|| panic!("{what}: the columnar path fell back to row by row"));
    let reference = row_by_row(files);
    assert_eq!(columnar.len(), reference.len(), "{what}");
    assert_eq!(columnar, reference, "{what}");
    columnar
}

/// The shipped trajectories with their data lines in a seeded random order.
fn shuffled_trajectories(files: &Files, seed: u64) -> Files {
    let text = String::from_utf8(files["trajectories.csv"].clone()).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().to_string();
    let mut rows: Vec<&str> = lines.collect();
    rows.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let mut out = files.clone();
    out.insert(
        "trajectories.csv".into(),
        format!("{header}\n{}\n", rows.join("\n")).into_bytes(),
    );
    out
}

#[test]
fn columnar_ingest_gives_the_row_by_row_items_on_the_shipped_data() {
    let files = shipped_files();
    let recs = assert_columnar_matches(&files, "shipped data");
    assert!(recs.len() > 100, "{} runs", recs.len());
    // The stage's items (names and bytes, hence their keys downstream) are those of the
    // row-by-row recordings.
    let out = stage_outputs(&files, &toml::Table::new());
    let Artifact::Collection(items) = &out["runs"] else {
        panic!("runs is not a collection")
    };
    let expected: BTreeMap<String, Vec<u8>> = row_by_row(&files)
        .iter()
        .map(|r| (item_name(&r.info.run), groove::recording::item::encode(r)))
        .collect();
    assert_eq!(items, &expected);
}

#[test]
fn columnar_ingest_of_shuffled_rows_gives_the_same_items() {
    let files = shipped_files();
    let reference = stage_outputs(&files, &toml::Table::new());
    for seed in [7, 8] {
        let shuffled = shuffled_trajectories(&files, seed);
        assert_columnar_matches(&shuffled, &format!("shuffled, seed {seed}"));
        assert_eq!(
            stage_outputs(&shuffled, &toml::Table::new()),
            reference,
            "seed {seed}"
        );
    }
}

#[test]
fn columnar_ingest_reads_parquet_as_csv() {
    let recs = known_recordings();
    let from_csv = assert_columnar_matches(&interchange_csv(&recs), "known, CSV");
    let from_parquet = assert_columnar_matches(&interchange_parquet(&recs), "known, Parquet");
    assert_eq!(from_csv, from_parquet);
    assert_eq!(from_csv, expected());
}

#[test]
fn damaged_files_fall_back_to_row_by_row_with_its_message() {
    let recs = known_recordings();
    let n = trajectory_lines(&recs).len();
    let cases: Vec<(&str, Files)> = vec![
        (
            "extra field",
            edit_trajectory(&recs, 3, |l| format!("{l},9")),
        ),
        (
            "missing field",
            edit_trajectory(&recs, 3, |l| l.rsplit_once(',').unwrap().0.into()),
        ),
        (
            "quoted number",
            edit_trajectory(&recs, 3, |l| set_field(l, 4, "\"0.25\"")),
        ),
        (
            "spaces around a number",
            edit_trajectory(&recs, 3, |l| set_field(l, 3, " 0.001 ")),
        ),
        (
            "frame written 12.0",
            edit_trajectory(&recs, 0, |l| set_field(l, 2, "0.0")),
        ),
        ("nan", edit_trajectory(&recs, 5, |l| set_field(l, 4, "NaN"))),
        (
            "empty cell",
            edit_trajectory(&recs, 5, |l| set_field(l, 3, "")),
        ),
        (
            "far position",
            edit_trajectory(&recs, 5, |l| set_field(l, 4, "1e3")),
        ),
        (
            "unknown particle",
            edit_trajectory(&recs, 5, |l| set_field(l, 1, "7")),
        ),
        (
            "negative particle",
            edit_trajectory(&recs, 5, |l| set_field(l, 1, "-1")),
        ),
        (
            "duplicate frame",
            edit_trajectory(&recs, 6, |l| {
                let prev = trajectory_lines(&recs)[5].clone();
                set_field(l, 2, prev.split(',').nth(2).unwrap())
            }),
        ),
        (
            "clock off",
            edit_trajectory(&recs, n - 1, |l| set_field(l, 3, "0.5")),
        ),
        (
            "unknown run",
            edit_trajectory(&recs, n - 1, |l| set_field(l, 0, "zz9")),
        ),
        (
            "run id with a space",
            edit_trajectory(&recs, 2, |l| {
                let run = l.split(',').next().unwrap().to_string();
                set_field(l, 0, &format!(" {run}"))
            }),
        ),
    ];
    let mut refused = 0;
    for (what, files) in cases {
        let fast = ingest::ingest(&files, &params()).map_err(|e| e.to_string());
        let slow = ingest::ingest_row_by_row(&files, &params()).map_err(|e| e.to_string());
        assert_eq!(fast, slow, "{what}");
        if slow.is_err() {
            refused += 1;
            assert!(
                ingest::ingest_columnar(&files, &params()).is_none(),
                "{what}: the columnar path took a damaged file"
            );
        }
    }
    // All but three: a quoted number, a frame written as `0.0` and spaces around a run id are
    // accepted (row by row, since the columnar path leaves them to it), and read the same.
    assert_eq!(refused, 11);
    let accepted = edit_trajectory(&recs, 0, |l| set_field(l, 2, "0.0"));
    assert_eq!(run_ok(&accepted, &params()), expected());
}

// ---------------------------------------------------------------- a campaign of many runs

/// The process's peak resident memory so far (`VmHWM` of /proc/self/status), bytes.
fn peak_rss_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let line = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap();
    let kib: u64 = line.split_whitespace().nth(1).unwrap().parse().unwrap();
    kib * 1024
}

/// Issue 13's campaign: `GROOVE_CAMPAIGN_RUNS` runs (default 100,000; half 316, half 440c, 600
/// frames each, the shipped physics and camera) written by `groove synth`, read into memory as
/// the engine reads a dataset folder, and ingested by the stage (recordings and their items).
/// Asserts every run became an item and that the process's peak RSS stays within 5 × the
/// CSV's size + 512 MB (measured: 4.8 × at 10,000 runs, 1.27 GB): given in memory, the input's
/// bytes, the typed columns, the recordings and the items are held together. This is the bound
/// of the in-memory entry point; the engine leaves the dataset on disk and streams it, and
/// tests/ingest_campaign.rs holds the whole 100,000-run campaign to 1 GB. Prints the figures. Peak RSS is the process's, so run it alone:
/// `cargo test --locked --features s3 --test ingest -- --ignored --exact campaign_ingests_within_its_memory_bound`
/// (100,000 runs: ≈ 2.6 GB of CSV on disk in a temporary folder, minutes).
#[test]
#[ignore]
fn campaign_ingests_within_its_memory_bound() {
    let n: usize = std::env::var("GROOVE_CAMPAIGN_RUNS")
        .map(|v| v.parse().expect("GROOVE_CAMPAIGN_RUNS is a number of runs"))
        .unwrap_or(100_000);
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = tempfile::tempdir().unwrap();
    let shipped = std::fs::read_to_string(root.join("data/truth/truth.toml")).unwrap();
    let mut truth = shipped.split("[[runs]]").next().unwrap().to_string();
    for (material, count) in [("316", n / 2), ("440c", n - n / 2)] {
        truth += &format!(
            "\n[[runs]]\nexperiment = \"single\"\nmaterial = \"{material}\"\ncount = {count}\n\
             v0_mps = [0.005, 0.1]\ndirections = \"both\"\nduration_s = 0.06\n"
        );
    }
    let truth_path = dir.path().join("truth.toml");
    std::fs::write(&truth_path, truth).unwrap();
    let data = dir.path().join("data");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_groove"))
        .args(["synth", "--truth"])
        .arg(&truth_path)
        .arg("--out")
        .arg(&data)
        .stdout(std::process::Stdio::null())
        .status()
        .unwrap();
    assert!(status.success(), "groove synth failed");
    let mut files = Files::new();
    for name in ["runs.csv", "trajectories.csv"] {
        files.insert(name.into(), std::fs::read(data.join(name)).unwrap());
    }
    let csv_bytes = files["trajectories.csv"].len() as u64;
    let started = std::time::Instant::now();
    let out = stage_outputs(&files, &toml::Table::new());
    let took = started.elapsed();
    let Artifact::Collection(items) = &out["runs"] else {
        panic!("runs is not a collection")
    };
    assert_eq!(items.len(), n);
    let item_bytes: usize = items.values().map(Vec::len).sum();
    drop(out);
    let peak = peak_rss_bytes();
    let bound = 5 * csv_bytes + (512 << 20);
    eprintln!(
        "campaign of {n} runs: {:.0} MB of CSV, ingested in {:.1} s, items {:.0} MB \
         ({} bytes per run), peak RSS {:.0} MB (bound {:.0} MB)",
        csv_bytes as f64 / 1e6,
        took.as_secs_f64(),
        item_bytes as f64 / 1e6,
        item_bytes / n,
        peak as f64 / 1e6,
        bound as f64 / 1e6
    );
    assert!(
        peak <= bound,
        "peak RSS {peak} bytes is above {bound} (5 × the CSV + 512 MB)"
    );
}

/// The items of the whole-file path (`ingest`'s recordings, encoded), by item name.
fn whole_file_items(files: &Files) -> BTreeMap<String, Vec<u8>> {
    ingest::ingest(files, &params())
        .unwrap_or_else(|e| panic!("{e}"))
        .recordings
        .iter()
        .map(|r| (item_name(&r.info.run), groove::recording::item::encode(r)))
        .collect()
}

#[test]
fn streamed_items_are_the_whole_file_items_in_any_chunk_size() {
    let files = shipped_files();
    let whole = whole_file_items(&files);
    assert!(whole.len() > 100, "{} runs", whole.len());
    // 1 KB chunks: most runs span several; 100 KB: a few runs cross each boundary; 8 MB: one chunk.
    for chunk in [1_000, 100_000, 8 << 20] {
        let items = ingest::ingest_items_in_chunks(&files, &params(), chunk).unwrap();
        assert!(items.how.starts_with("read in"), "{chunk}: {}", items.how);
        let want = files["trajectories.csv"].len() / chunk;
        let chunks: usize = items.how["read in ".len()..]
            .split(' ')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        // Each chunk is the whole lines that fit in `chunk` bytes (lines are ~40 bytes).
        assert!(
            (want..=want * 11 / 10 + 1).contains(&chunks),
            "{chunk}: {}",
            items.how
        );
        assert_eq!(items.runs, whole, "chunks of {chunk} bytes");
        assert!(items.skipped.is_empty());
    }
}

#[test]
fn streamed_items_of_shuffled_rows_fall_back_to_the_whole_file_with_the_same_items() {
    let files = shipped_files();
    let whole = whole_file_items(&files);
    let shuffled = shuffled_trajectories(&files, 11);
    let items = ingest::ingest_items_in_chunks(&shuffled, &params(), 100_000).unwrap();
    assert!(
        items.how.starts_with("read whole") && items.how.contains("not together"),
        "{}",
        items.how
    );
    assert_eq!(items.runs, whole);
    // Runs whose blocks are whole but not in runs.csv's order stream.
    let text = String::from_utf8(files["trajectories.csv"].clone()).unwrap();
    let (header, body) = text.split_once('\n').unwrap();
    let mut blocks: Vec<Vec<&str>> = Vec::new();
    for line in body.lines() {
        let run = line.split(',').next().unwrap();
        match blocks.last_mut() {
            Some(b) if b[0].split(',').next() == Some(run) => b.push(line),
            _ => blocks.push(vec![line]),
        }
    }
    blocks.reverse();
    let reversed: Vec<&str> = blocks.concat();
    let mut files_rev = files.clone();
    files_rev.insert(
        "trajectories.csv".into(),
        format!("{header}\n{}\n", reversed.join("\n")).into_bytes(),
    );
    let items = ingest::ingest_items_in_chunks(&files_rev, &params(), 100_000).unwrap();
    assert!(items.how.starts_with("read in"), "{}", items.how);
    assert_eq!(items.runs, whole);
}

#[test]
fn streamed_items_of_parquet_are_the_csv_items() {
    let recs = known_recordings();
    let csv = ingest::ingest_items(&interchange_csv(&recs), &params()).unwrap();
    let parquet = ingest::ingest_items(&interchange_parquet(&recs), &params()).unwrap();
    assert!(
        parquet.how.starts_with(
            "decoded from Parquet in 1 batch of whole row groups (1 row group), each run's item"
        ),
        "{}",
        parquet.how
    );
    assert_eq!(csv.runs, parquet.runs);
    assert_eq!(csv.runs, whole_file_items(&interchange_csv(&recs)));
}

/// trajectories.parquet rewritten with row groups of `rows` rows.
fn with_row_groups(files: &Files, rows: usize) -> Files {
    let mut df = ParquetReader::new(Cursor::new(files["trajectories.parquet"].clone()))
        .finish()
        .unwrap();
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes)
        .with_row_group_size(Some(rows))
        .finish(&mut df)
        .unwrap();
    let mut files = files.clone();
    files.insert("trajectories.parquet".into(), bytes);
    files
}

#[test]
fn parquet_is_decoded_a_batch_of_row_groups_at_a_time_with_the_csv_items() {
    let recs = known_recordings();
    let csv = ingest::ingest_items(&interchange_csv(&recs), &params()).unwrap();
    let parquet = interchange_parquet(&recs);
    // row groups of about 7 rows, batches of at least 20 rows: about 3 row groups a batch, runs
    // cut by both
    let small = with_row_groups(&parquet, 7);
    let groups = ParquetReader::new(Cursor::new(small["trajectories.parquet"].clone()))
        .get_metadata()
        .unwrap()
        .row_groups
        .clone();
    let mut batches = 0;
    let mut open = 20;
    for g in &groups {
        assert!(g.num_rows() < 20, "a row group of {} rows", g.num_rows());
        if open >= 20 {
            (batches, open) = (batches + 1, 0);
        }
        open += g.num_rows();
    }
    assert!(
        groups.len() >= 30 && batches >= 10,
        "{} groups",
        groups.len()
    );
    let items = ingest::ingest_items_in_chunks(&small, &params(), 20 * 32).unwrap();
    assert!(
        items.how.starts_with(&format!(
            "decoded from Parquet in {batches} batches of whole row groups ({} row groups), \
             each batch grouped while the next was decoded",
            groups.len()
        )),
        "{}",
        items.how
    );
    assert_eq!(items.runs, csv.runs);
    // one row group larger than a batch: decoded alone, handed on in slices that cut runs
    let items = ingest::ingest_items_in_chunks(&parquet, &params(), 10 * 32).unwrap();
    assert!(
        items
            .how
            .starts_with("decoded from Parquet in 1 batch of whole row groups (1 row group)"),
        "{}",
        items.how
    );
    assert_eq!(items.runs, csv.runs);
}

/// A Parquet file read in order while its footer was read apart: `footer` stands for what a
/// read at an offset finds, `stream` for what the pass in order finds.
struct TwoViews {
    footer: Vec<u8>,
    stream: Cursor<Vec<u8>>,
}

impl std::io::Read for TwoViews {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.stream.read(buf)
    }
}

impl ingest::Source for TwoViews {
    fn file_len(&self) -> std::io::Result<u64> {
        Ok(self.footer.len() as u64)
    }

    fn read_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        let at = offset as usize;
        buf.copy_from_slice(&self.footer[at..at + buf.len()]);
        Ok(())
    }
}

/// Every byte decoded from a Parquet file on disk is a byte of the checked pass in order: a
/// footer (read first, to plan the batches) that is not the one the pass meets at the end, or a
/// file that ends early or goes on past the length it had, is a file that changed while it was
/// read, an error (not a fallback to the whole read, and never items of a mixed file).
#[test]
fn a_parquet_file_that_changes_while_it_is_read_is_an_error() {
    let recs = known_recordings();
    let files = interchange_parquet(&recs);
    let bytes = files["trajectories.parquet"].clone();
    let mut in_map = files.clone();
    in_map.insert("trajectories.parquet".into(), Vec::new());
    let read = |stream: Vec<u8>| {
        let mut source = TwoViews {
            footer: bytes.clone(),
            stream: Cursor::new(stream),
        };
        let keep = |b: Vec<u8>| b;
        let got = ingest::stream_items(
            &in_map,
            Some(&mut source),
            &params(),
            ingest::CHUNK_BYTES,
            &keep,
            None,
        );
        got.map(|s| match s {
            ingest::Streamed::Done(items) => items.runs,
            ingest::Streamed::ReadWhole(why) => panic!("read whole: {why}"),
        })
    };
    // the same bytes both ways: the items of the file in memory
    let want = ingest::ingest_items(&files, &params()).unwrap().runs;
    assert_eq!(read(bytes.clone()).unwrap(), want);
    // a byte of the footer other in the pass in order
    let mut other_footer = bytes.clone();
    let n = other_footer.len();
    other_footer[n - 9] ^= 1;
    // shorter, longer
    let shorter = bytes[..n - 1].to_vec();
    let mut longer = bytes.clone();
    longer.push(b'\n');
    for (what, stream) in [
        ("footer", other_footer),
        ("shorter", shorter),
        ("longer", longer),
    ] {
        let err = read(stream).expect_err(what);
        assert_eq!(err.kind(), std::io::ErrorKind::InvalidData, "{what}: {err}");
        assert!(
            err.to_string().contains("changed while it was read"),
            "{what}: {err}"
        );
    }
}
