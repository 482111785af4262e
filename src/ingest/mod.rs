//! Ingest: reads a dataset folder (interchange CSV/Parquet, trackpy or TrackMate exports), checks
//! every class of bad input (below), and returns one `Recording` per run.
//!
//! Files of this folder:
//!
//! - `assemble.rs`: Cross-table checks
//! - `axis.rs`: Catches a wrong calibration axis of tracker exports
//! - `bounds.rs`: Limits checked before a dataset file is read
//! - `columnar.rs`: The fast path of the interchange format
//! - `csv_check.rs`: Checks of a CSV file's bytes before the parser sees them
//! - `csv_fast.rs`: Trajectory rows in the layout `groove synth` writes
//! - `csv_pieces.rs`: A CSV read from any reader in pieces of whole lines
//! - `error.rs`: What can be wrong with a dataset
//! - `interchange.rs`: Reads the interchange format: runs.csv and trajectories.csv (or `.parquet`)
//! - `manifest.rs`: The per-run metadata of tracker exports
//! - `output.rs`: The ingest stage's artifacts as bytes
//! - `params.rs`: The ingest stage's params as written in `pipeline.toml`
//! - `parquet_groups.rs`: trajectories.parquet read once, in order, a batch of row groups at a time
//! - `parquet_pages.rs`: A Parquet file's page headers checked before polars decodes the pages
//! - `run_memo.rs`: Runs whose item an earlier ingest already made from the same bytes
//! - `samples.rs`: The common form every source format is read into before checking
//! - `sanity.rs`: Physical sanity of a recording
//! - `scale.rs`: The positions' scale: tracks faster or slowing harder than steel spheres can
//! - `spots.rs`: Tracker spots (trackpy, TrackMate) into tracks of one run
//! - `table.rs`: A table read from CSV or Parquet bytes with polars
//! - `trackmate.rs`: Reads Fiji TrackMate spot tables
//! - `trackmate_xml.rs`: Reads the XML file Fiji TrackMate saves
//! - `trackpy.rs`: Reads trackpy CSV exports
//!
//! Everything here works on bytes in memory (file name → bytes), or, for trajectories.csv, on a
//! reader the stage is given, so the stage never opens a file itself; `read_dataset_dir` is the
//! one helper that reads a folder, for tests and tools.
//!
//! # The interchange format
//!
//! A dataset is a folder holding two tables, as CSV (`runs.csv`, `trajectories.csv`) or as
//! Parquet with the same columns (`runs.parquet`, `trajectories.parquet`).
//!
//! `runs.csv` has one row per recorded run:
//!
//! | column | type | meaning |
//! | --- | --- | --- |
//! | `run` | text | the run's id, unique in the table |
//! | `experiment` | text | `single` (one sphere) or `collision` (a striker and a target) |
//! | `material` | text | e.g. `316`, `440c`; runs are grouped by it exactly as written |
//! | `diameter_m` | number | the sphere's diameter, metres |
//! | `fps` | number | the camera's frame rate, frames per second |
//!
//! Optional: `setup` for collision runs (`rolling`: the striker rolled in; `contact`: the pair
//! started touching), and any other column, kept and shown but not interpreted.
//!
//! `trajectories.csv` has one row per particle per frame:
//!
//! | column | type | meaning |
//! | --- | --- | --- |
//! | `run` | text | a run of runs.csv |
//! | `particle` | integer | 0 in a single run; in a collision run 0 is the striker, 1 the target |
//! | `frame` | integer | the frame index; a gap is a dropped frame |
//! | `t_s` | number | seconds since the run's first frame |
//! | `z_m` | number | position along the groove, metres; either direction |
//!
//! Rows may come in any order. Noise, dropped frames, a few tracking outliers and particles leaving
//! the view are normal and handled, not rejected.
//!
//! Bad input is: a missing file or column; a run in one table and not the other; a value that is not
//! a number or not finite; a repeated (run, particle, frame); a run with too few frames to fit; an
//! unknown experiment; values outside the physical limits (`sanity.rs`: fps 50 … 1e8, diameter 1 µm … 10 cm, |z_m| ≤ 10 m, |t_s| ≤ 60 s, and t_s within
//! half a frame plus 1 % of the elapsed time of (frame − first frame)/fps). Each is reported with the
//! file, the row and the column and what would fix it. The run stops before any output is replaced,
//! unless the ingest params say `skip_bad_runs = true`, which leaves the bad runs out and names them
//! in the `skipped` output.
//!
//! The ingest params, with a calibration for tracker exports:
//!
//! ```toml
//! [stages.ingest]
//! kind = "ingest"
//! inputs = { dataset = "${data}" }
//! params = { format = "auto", skip_bad_runs = false, min_frames = 20,
//!   calibration = { m_per_px = 2.5e-5, fps = 200, axis = "x", direction = 1,
//!                   material = "316", diameter_m = 3e-4, experiment = "single" } }
//! ```
//!
//! # The recording items
//!
//! The items of `ingest:runs` (one per run, named by the run id made file-name safe; a `command`
//! stage receives them as files) are binary, not JSON (`src/recording/item.rs`), all numbers
//! little-endian with no padding:
//!
//! | bytes | field |
//! | --- | --- |
//! | 8 | magic `GROOVREC` |
//! | 4 | format version, u32 = 1 |
//! | 4 | length M of the metadata, u32 |
//! | M | metadata: compact UTF-8 JSON of the run's row of runs.csv: `run`, `experiment` (`single`/`collision`), `material`, `diameter_m`, `fps`, `setup` (`rolling`/`contact`/null), `extra` (other columns, as text) |
//! | 4 | number of tracks, u32; then per track, sorted by particle: |
//! | 4 + 4 + 4 | particle u32, number of samples N u32, number of frame segments S u32 |
//! | 8·S + 8·S | each segment's first frame (i64), then each segment's length (i64, ≥ 1, summing to N): a segment is a stretch of consecutive frames, so a track without dropped frames has one |
//! | 8·N + 8·N | `t_s` (f64, s), then `z_m` (f64, m), in frame order |
//!
//! Units and checks are those of the trajectories table above (SI; ingest has checked every
//! value). A 600-frame single run is 9.7 KB (JSON text was 12.7 KB) and decodes without parsing
//! a number. In Python: `numpy.frombuffer(b, '<f8', count=N, offset=o)` reads a column.
//!
//! # Reading fast and in bounded memory
//!
//! the interchange format (polars), trackpy and TrackMate exports, checks with
//!   errors at file, row and column; `columnar.rs` the fast path of a clean interchange dataset
//!   (typed columns sorted and sliced into recordings by polars; at any problem the row-by-row
//!   path reads the dataset again and names it). The stage streams: trajectories.csv is read from
//!   disk and parsed 8 MB of whole lines at a time (`csv_pieces.rs`; rows in the exact layout
//!   `groove synth` writes are split and parsed without polars by `csv_fast.rs`, any other piece by
//!   polars) and each run's item is made as its last row is read, so the typed table and
//!   the recordings are never held whole (`ingest::ingest_items`); when the rows of a run are not
//!   one block (shuffled rows) it reads the file whole and sorts it, and the progress
//!   line says which (`read in N chunks …`, `decoded from Parquet in N batches of whole row groups
//!   …` or `read whole (why)`); a Parquet file is read once in order and decoded a batch of its row
//!   groups at a time on a thread of its own, never held whole (`parquet_groups.rs`), and the page
//!   headers of every row group are checked before polars decodes them (`parquet_pages.rs`: a
//!   negative count in a damaged header made polars' decoder abort the process). Same items either way; and the same items from Parquet as pyarrow and pandas write it (snappy, zstd, gzip, v1 and v2 pages, dictionary, plain, byte-stream-split and delta encodings, shuffled rows with pandas' index, int32 particles, a typed runs.parquet with null setups: `tests/parquet_writers.rs`, files made by `tests/fixtures/parquet_writers/make_fixtures.py`). With the stage's memo
//!   (`run_memo.rs`) a strict-layout piece is first cut into its runs' blocks of lines, each whole
//!   run keyed by a BLAKE3 digest of its lines and its runs.csv row; a run whose key the memo holds
//!   (and whose item the store still holds) is not parsed, so an edit of one recording parses
//!   that run and the runs at the pieces' edges only.
//!
//! # Tracker exports
//!
//! groove reads positions exported by trackpy and Fiji TrackMate directly; the `ingest` stage turns
//! them into the interchange tables with a calibration. With `format = "auto"` a folder holding
//! `trajectories.csv` (or `.parquet`) is the interchange format; otherwise every tracker file in it
//! is recognised by its header (trackpy: `frame, particle, x, y`; TrackMate: `TRACK_ID, FRAME,
//! POSITION_X, POSITION_Y`) or root element (`<TrackMate>`), and other files are ignored.
//!
//! **Layouts.** Any mix of:
//!
//! - one trackpy CSV per run (`tp.link(...).to_csv("s01.csv")`): the run is named by the file (`s01`);
//! - one trackpy CSV holding many runs, with a column `run` naming each row's run (the particle ids
//!   may repeat between runs). A file of several runs without it stops with "add a column `run`";
//! - one TrackMate XML per movie (`File > Save`): spots from `Model/AllSpots/SpotsInFrame/Spot`
//!   (`ID`, `FRAME`, `POSITION_X`, `POSITION_Y`, `VISIBILITY`), tracks from
//!   `Model/AllTracks/Track/Edge`, the tracks kept by TrackMate's filters from `FilteredTracks`;
//! - one TrackMate spot table per movie (`Spots in tracks statistics.csv`, or any name; spaces in
//!   file names are fine), with its extra header rows.
//!
//! **Naming.** A run's id is the `run` column's value, or the file name without `.csv` / `.xml`, or
//! what the manifest's `file` column maps the file to (a TrackMate default name says nothing about the
//! run). Ids that are not file-name safe are kept as they are in the report and get a safe item name.
//!
//! **Calibration and metadata.** Trackers record pixels and frames, not the run. Each run's material,
//! diameter, frame rate, experiment and setup come from a manifest `runs.csv` beside the exports
//! (columns `run` and any of `file, material, diameter_m, fps, experiment, setup`; other columns are
//! kept and shown), or from the same rows as `runs = [{ run = "s01", material = "316" }, ...]` in the
//! ingest params; what a row leaves empty comes from `calibration` in the ingest params. With a
//! manifest, every run must have a row and every row a run. Positions become
//! `z_m = direction · position · m_per_px` along `axis` (image x right or y down) and frames
//! `t_s = (frame − first frame) / fps`. TrackMate files that state a length unit (XML
//! `spatialunits="micron"`, CSV units row `(micron)`) are converted with it and need no `m_per_px`;
//! the XML's frame interval (`ImageData timeinterval` in `timeunits`) is used only when neither the
//! manifest nor the params give `fps`.
//!
//! **What is left out, and said.** In a single run the longest track is the sphere; shorter tracks
//! fill frames it misses, and spots in frames it already covers are spurious. Every track or spot left
//! out (spurious tracks, unlinked spots, tracks TrackMate's filters removed, hidden spots) is listed
//! in the ingest stage's `skipped` output and in the report's "Left out" table, with the run kept;
//! "Nothing was left out" appears only when nothing was.
//!
//! **Wrong axis.** If in half the runs or more the sphere moves more across `axis` than along it, or
//! not beyond its frame-to-frame noise along it, the run stops with exit code 2 naming the runs and
//! the axis to try (`set calibration.axis = "y"`); in fewer runs those runs are named as bad runs.
//!
//! **Worked example** (the fixtures in `tests/fixtures/trackers/`, made by `make_fixtures.py` with
//! trackpy 0.7 from rendered videos of six synthesized runs, 20 µm per pixel, 10,000 fps):
//!
//! ```
//! my-runs/
//!   runs.csv      run,material,diameter_m,fps,experiment
//!                 single-316-001,316,0.0003,10000,single
//!                 single-440c-001,440c,0.0003,10000,single
//!                 ...
//!   tracks.csv    ,run,y,x,mass,size,ecc,signal,raw_mass,ep,frame,particle
//!                 0,single-316-001,10.32,96.4872,6891.52,3.46574,0.025013,131.833,15800,,0,0
//!                 ...
//! ```
//!
//! ```toml
//! [stages.ingest]
//! kind = "ingest"
//! inputs = { dataset = "${data}" }
//! params = { calibration = { m_per_px = 2e-5, axis = "x", direction = 1 } }
//! ```
//!
//! `groove run --data my-runs` then fits every run with its own material and frame rate. A TrackMate
//! XML in microns needs only the manifest (or `calibration.material` and `diameter_m`); a TrackMate
//! table under its default name needs a manifest row naming it:
//! `single-440c-002,Spots in tracks statistics.csv,440c,0.0003,10000,single` under
//! `run,file,material,diameter_m,fps,experiment`.
//!
//! # Hostile input
//!
//! Fuzzing: `cargo test --locked --test fuzz` runs 1,000 cases per property (CSV, generated cells,
//! Parquet, trackpy/TrackMate, `pipeline.toml`); `PROPTEST_CASES=100000 cargo test --locked --test
//! fuzz` runs 100,000. The cases come from a fixed seed, the same in every run (another with
//! `PROPTEST_RNG_SEED=<u64>`). A mutated Parquet file once made polars' page decoder ask for 2^61 bytes (a damaged page
//! header's negative count, cast to an unsigned size) and the failed allocation aborted the process
//! (about one case in 30,000: seeds 112, 118, 125, 127 and 128 of 5,000 cases). Every page header
//! is now checked before polars decodes the page (`ingest/parquet_pages.rs`: no negative size or
//! count, each page inside its column chunk, the pages' values adding up to the chunk's, one a
//! row), and such a file exits 2 ("a page's header is damaged"); 40 seeds × 5,000 cases
//! (`PROPTEST_RNG_SEED=100…139`, 200,000 mutated files) passed with none aborting. The
//! hostile-input reproducers are `tests/hostile_input.rs` (library) and
//! `tests/hostile_project.rs` (binary: exit 2 within 10 s, every project file unchanged). The kill -9
//! soak is `bash tests/soak.sh [KILLS_PER_VERB]` (needs `cargo build`; prints counts of corrupt entries,
//! partial outputs and failed recoveries, which must all be 0).

// A `Problem` carries file, row, column, run, message and fix; it is returned only for bad
// input, so its size on the error path is not worth boxing.
#![allow(clippy::result_large_err)]

mod assemble;
mod axis;
pub mod bounds;
mod columnar;
pub use columnar::CHUNK_BYTES;
mod csv_check;
mod csv_fast;
mod csv_pieces;
pub mod error;
mod interchange;
mod manifest;
pub mod output;
pub mod params;
mod parquet_groups;
mod parquet_pages;
mod run_memo;
mod samples;
pub mod sanity;
pub mod scale;
mod spots;
mod table;
mod trackmate;
mod trackmate_xml;
mod trackpy;

/// trajectories.csv read with the typed schema the fast path reads it with (`None` where the
/// row-by-row path might read it otherwise); `groove synth --format parquet` writes it as is.
pub(crate) use columnar::read_csv as typed_trajectories;
pub use error::{IngestError, Problem};
pub use output::{item_name, skipped_json, Skipped};
pub use params::{Axis, Calibration, Format, IngestParams, RunEntry};
pub use parquet_groups::Source;

use crate::recording::{item, Recording};
use csv_pieces::Stop;
use rayon::prelude::*;
use samples::{RunRow, SampleFile};
use std::collections::BTreeMap;
use std::path::Path;
use table::Table;

/// The result of ingesting a dataset: the usable runs sorted by id, and what was left out: runs
/// (with `skip_bad_runs`), and tracks or spots of tracker exports (the run itself is kept; its
/// reason starts with `track` or a count of spots).
#[derive(Debug, Clone, PartialEq)]
pub struct Ingested {
    pub recordings: Vec<Recording>,
    pub skipped: Vec<Skipped>,
}

/// File names that mark a folder as the interchange format.
const INTERCHANGE_FILES: [&str; 4] = [
    "runs.csv",
    "runs.parquet",
    "trajectories.csv",
    "trajectories.parquet",
];

/// Reads and checks a dataset given as its top-level files (name → bytes). A clean dataset in
/// the interchange format is read column by column (`columnar`); anything else, and any dataset
/// with a problem, row by row (`ingest_row_by_row`), which names every problem's file, row and
/// column. Both give the same recordings for a clean dataset.
pub fn ingest(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Result<Ingested, IngestError> {
    check_params(params)?;
    if let Some(recordings) = ingest_columnar(files, params) {
        {
            let mut problems = Vec::new();
            check_item_names(&recordings, &mut problems);
            problems.extend(scale::check(&recordings, "trajectories", "z_m"));
            if problems.is_empty() && !recordings.is_empty() {
                return Ok(Ingested {
                    recordings,
                    skipped: Vec::new(),
                });
            }
        }
    }
    ingest_row_by_row(files, params)
}

/// The recordings of a clean interchange dataset read column by column, as `ingest` returns
/// them; `None` where `ingest` reads the dataset row by row instead (other formats, a problem,
/// anything the typed read might take differently).
pub fn ingest_columnar(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Option<Vec<Recording>> {
    let read = reads_interchange(files, params.format) && params.check().is_ok();
    read.then(|| columnar::recordings(files, params.min_frames))
        .flatten()
}

fn check_params(params: &IngestParams) -> Result<(), IngestError> {
    params.check().map_err(|p| {
        Problem::file(
            "pipeline.toml",
            format!("ingest param {}: {}", p.key, p.message),
            p.fix,
        )
        .into()
    })
}

/// Whether `read_sources` reads the folder as the interchange format without looking for
/// tracker files first.
fn reads_interchange(files: &BTreeMap<String, Vec<u8>>, format: Format) -> bool {
    let trajectories = ["trajectories.csv", "trajectories.parquet"]
        .iter()
        .any(|f| files.contains_key(*f));
    format == Format::Interchange || (format == Format::Auto && trajectories)
}

/// `ingest` reading every row into a sample first: the path that names every problem, and the
/// reference the columnar path is tested against.
pub fn ingest_row_by_row(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Result<Ingested, IngestError> {
    check_params(params)?;
    let (runs, sample_files, mut problems, notes) = read_sources(files, params)?;
    let mut recordings = assemble::assemble(&runs, &sample_files, params.min_frames, &mut problems);
    if recordings.is_empty() && problems.is_empty() {
        problems.push(Problem::file(
            runs.first().map_or("runs.csv", |r| r.file.as_str()),
            "the dataset has no runs",
            "add one row per recorded run",
        ));
    }
    check_item_names(&recordings, &mut problems);
    if problems.is_empty() {
        let (file, column) = sample_files
            .first()
            .map_or(("trajectories.csv", "z_m"), |f| {
                (f.file.as_str(), f.position_column)
            });
        problems.extend(scale::check(&recordings, file, column));
    }
    if problems.is_empty() {
        return Ok(Ingested {
            recordings,
            skipped: notes,
        });
    }
    if !params.skip_bad_runs || problems.iter().any(|p| p.run.is_none()) {
        return Err(IngestError::new(problems));
    }
    let mut by_run: BTreeMap<String, Vec<Problem>> = BTreeMap::new();
    for p in problems {
        by_run
            .entry(p.run.clone().unwrap_or_default())
            .or_default()
            .push(p);
    }
    recordings.retain(|r| !by_run.contains_key(&r.info.run));
    if recordings.is_empty() {
        let bad_runs = by_run.len();
        let mut all: Vec<Problem> = by_run.into_values().flatten().collect();
        all.push(Problem::file(
            "the dataset",
            format!("no usable run is left after leaving out {bad_runs} bad runs"),
            "fix the problems listed",
        ));
        return Err(IngestError::new(all));
    }
    let mut skipped: Vec<Skipped> = notes
        .into_iter()
        .filter(|n| !by_run.contains_key(&n.run))
        .collect();
    skipped.extend(by_run.into_iter().map(|(run, mut ps)| {
        ps.sort();
        let more = match ps.len() {
            1 => String::new(),
            n => format!(" (and {} more problems)", n - 1),
        };
        Skipped {
            run,
            reason: format!("{}{more}", ps[0]),
        }
    }));
    skipped.sort();
    Ok(Ingested {
        recordings,
        skipped,
    })
}

/// A dataset ingested into the `ingest:runs` items (item name → `recording::item` bytes, or what
/// `keep` made of them), the runs and parts left out, and how the dataset was read (for the
/// stage's progress line).
pub struct Items<T = Vec<u8>> {
    pub runs: BTreeMap<String, T>,
    pub skipped: Vec<Skipped>,
    pub how: String,
    /// The memo keys of the runs made from their lines (key, item name), for the caller to
    /// remember with the items (`RunMemo`); empty unless streamed with a memo.
    pub memo_made: Vec<([u8; 32], String)>,
}

/// The items an earlier ingest made of whole runs' lines (by `run_memo::run_key`), and how an
/// item found there is kept (as `keep` would keep it).
pub struct ItemMemo<'m, T> {
    pub get: run_memo::RunMemo<'m>,
    pub kept: &'m (dyn Fn(String) -> T + Sync),
}

/// `ingest`, as the stage's items. A clean interchange dataset whose runs' rows come grouped is
/// streamed (`columnar::stream`): each run's item is made as its last row is read, so the whole
/// table and all recordings are never held at once. Otherwise (rows of runs interleaved, another
/// format, a problem to name) the items of `ingest`'s recordings, and `how` says why. Same items
/// either way.
pub fn ingest_items(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Result<Items, IngestError> {
    ingest_items_in_chunks(files, params, columnar::CHUNK_BYTES)
}

/// `ingest_items` reading trajectories.csv `chunk_bytes` at a time (tests try small chunks, so
/// that runs span chunks).
pub fn ingest_items_in_chunks(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
    chunk_bytes: usize,
) -> Result<Items, IngestError> {
    ingest_items_kept(files, params, chunk_bytes, &|bytes| bytes)
}

/// `ingest_items_in_chunks` handing each item's bytes to `keep` as soon as it is made and keeping
/// what `keep` returns instead (the stage puts each item in the store and keeps its hash, so
/// that no more than a chunk's items are held). If the stream stops and the dataset is read
/// whole, `keep` sees the streamed runs again.
pub fn ingest_items_kept<T: Send>(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
    chunk_bytes: usize,
    keep: &(dyn Fn(Vec<u8>) -> T + Sync),
) -> Result<Items<T>, IngestError> {
    match stream_items(files, None, params, chunk_bytes, keep, None) {
        Ok(Streamed::Done(items)) => Ok(items),
        Ok(Streamed::ReadWhole(why)) => ingest_items_whole(files, params, why, keep),
        Err(_) => unreachable!("bytes in memory are always readable"),
    }
}

/// What `stream_items` did: the items, or why the dataset must be read whole
/// (`ingest_items_whole`).
pub enum Streamed<T> {
    Done(Items<T>),
    ReadWhole(&'static str),
}

/// The items of a clean interchange dataset whose runs' rows come grouped, streamed
/// (`columnar::stream`): each run's item is made as its last row is read and handed to `keep`.
/// The trajectories come from `traj` if given (then the file stands in `files` with no bytes,
/// for its name), a piece or a batch of row groups at a time, so a file larger than memory is
/// never held. The error is a failure to read `traj` (or its content changing, as `InputFile`
/// checks).
pub fn stream_items<T: Send>(
    files: &BTreeMap<String, Vec<u8>>,
    traj: Option<&mut dyn Source>,
    params: &IngestParams,
    chunk_bytes: usize,
    keep: &(dyn Fn(Vec<u8>) -> T + Sync),
    memo: Option<ItemMemo<T>>,
) -> Result<Streamed<T>, std::io::Error> {
    if check_params(params).is_err() || !reads_interchange(files, params.format) {
        return Ok(Streamed::ReadWhole(
            "the dataset is not in the interchange format",
        ));
    }
    // the runs of a piece are encoded and kept (stored) in parallel on a thread of their own,
    // while the next piece is parsed; at most one piece waits for it
    let kept_found = memo.as_ref().map(|m| m.kept);
    let (streamed, (runs, clash, memo_made, found, moves)) = std::thread::scope(|scope| {
        let (tx, rx) = std::sync::mpsc::sync_channel::<columnar::Ready>(1);
        let writer = scope.spawn(move || {
            let (mut runs, mut clash) = (BTreeMap::new(), false);
            let (mut memo_made, mut found) = (Vec::new(), 0);
            let mut moves = Vec::new();
            for ready in rx {
                moves.extend(ready.made.iter().flat_map(|(r, _)| scale::measure(r)));
                let kept: Vec<(String, T, Option<[u8; 32]>)> = ready
                    .made
                    .par_iter()
                    .map(|(r, key)| (item_name(&r.info.run), keep(item::encode(r)), *key))
                    .collect();
                for (name, k, key) in kept {
                    if let Some(key) = key {
                        memo_made.push((key, name.clone()));
                    }
                    clash |= runs.insert(name, k).is_some();
                }
                for (run, sha256) in ready.found {
                    let kept = kept_found.expect("runs are found only with a memo");
                    clash |= runs.insert(item_name(&run), kept(sha256)).is_some();
                    found += 1;
                }
            }
            (runs, clash, memo_made, found, moves)
        });
        let streamed = columnar::stream(
            files,
            traj,
            params.min_frames,
            chunk_bytes,
            memo.as_ref().map(|m| m.get),
            &mut |ready: columnar::Ready| {
                // the writer ends only when this sender is dropped, so the send succeeds
                let _ = tx.send(ready);
            },
        );
        drop(tx);
        let written = writer
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (streamed, written)
    });
    let why = match streamed {
        Ok(_) if scale::impossible(&moves).is_some() => {
            "the positions are not in metres (the whole read names the problem)"
        }
        Ok(pieces) if !clash && !runs.is_empty() => {
            let how = match found {
                0 => format!("{pieces}, each run's item made as its last row was read"),
                n => format!(
                    "{pieces}; {n} of {} runs' items found by their lines' digest, the rest made as their last row was read",
                    runs.len()
                ),
            };
            return Ok(Streamed::Done(Items {
                runs,
                skipped: Vec::new(),
                how,
                memo_made,
            }));
        }
        Ok(_) if clash => "two runs share an item name",
        Ok(_) => "the dataset has no runs",
        Err(Stop::Reason(why)) => why,
        Err(Stop::Read(e)) => return Err(e),
    };
    Ok(Streamed::ReadWhole(why))
}

/// `ingest`'s recordings as items (each through `keep`), with `why` the dataset was read whole.
pub fn ingest_items_whole<T: Send>(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
    why: &str,
    keep: &(dyn Fn(Vec<u8>) -> T + Sync),
) -> Result<Items<T>, IngestError> {
    let ingested = ingest(files, params)?;
    let runs = ingested
        .recordings
        .into_iter()
        .map(|r| (item_name(&r.info.run), keep(item::encode(&r))))
        .collect();
    Ok(Items {
        runs,
        skipped: ingested.skipped,
        how: format!("read whole ({why})"),
        memo_made: Vec::new(),
    })
}

/// The recordings of a clean interchange dataset whose runs' rows come grouped, handed to `each`
/// one run at a time as `columnar::stream` reads them (`chunk_bytes` of CSV at a time); the
/// number of pieces (CSV chunks or Parquet batches of row groups), or why it stopped (then
/// `each` has seen only some runs: forget them and use `ingest`). For callers that keep no item
/// in memory (the 100,000-run memory test).
pub fn stream_recordings(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
    chunk_bytes: usize,
    each: &mut dyn FnMut(Recording),
) -> Result<usize, &'static str> {
    if check_params(params).is_err() || !reads_interchange(files, params.format) {
        return Err("not a clean interchange dataset");
    }
    let mut each_of = |ready: columnar::Ready| ready.made.into_iter().for_each(|(r, _)| each(r));
    match columnar::stream(
        files,
        None,
        params.min_frames,
        chunk_bytes,
        None,
        &mut each_of,
    ) {
        Ok(pieces) => Ok(pieces.count()),
        Err(Stop::Reason(why)) => Err(why),
        Err(Stop::Read(_)) => unreachable!("bytes in memory are always readable"),
    }
}

/// Reads the folder's top-level regular files and ingests them; the recordings sorted by run.
pub fn read_dataset_dir(dir: &Path, params: &IngestParams) -> Result<Vec<Recording>, IngestError> {
    let shown = dir.display().to_string();
    let unreadable = |e: std::io::Error| {
        Problem::file(
            &shown,
            format!("cannot be read ({e})"),
            "check that the dataset folder exists and is readable",
        )
    };
    let mut files = BTreeMap::new();
    for entry in std::fs::read_dir(dir).map_err(unreadable)? {
        let entry = entry.map_err(unreadable)?;
        let path = entry.path();
        if path.is_file() {
            let bytes = std::fs::read(&path).map_err(unreadable)?;
            files.insert(entry.file_name().to_string_lossy().into_owned(), bytes);
        }
    }
    Ok(ingest(&files, params)?.recordings)
}

/// The run rows and sample files of a dataset, the row-level problems found reading them, and the
/// tracks or spots left out of runs that are kept.
type Sources = (Vec<RunRow>, Vec<SampleFile>, Vec<Problem>, Vec<Skipped>);

/// The run rows and sample files of the dataset in its format, and the row-level problems found.
/// In `auto` mode a folder with `trajectories.*` is the interchange format; otherwise tracker
/// exports (with `runs.csv` as their manifest) if there are any, else the interchange format.
fn read_sources(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Result<Sources, IngestError> {
    let trajectories = ["trajectories.csv", "trajectories.parquet"]
        .iter()
        .any(|f| files.contains_key(*f));
    let interchange_present = INTERCHANGE_FILES.iter().any(|f| files.contains_key(*f));
    match params.format {
        Format::Interchange => read_interchange(files),
        Format::Auto if trajectories => read_interchange(files),
        format => match read_trackers(files, format, params)? {
            Some(sources) => Ok(sources),
            None if interchange_present => read_interchange(files),
            None => Err(no_dataset_files(files).into()),
        },
    }
}

fn no_dataset_files(files: &BTreeMap<String, Vec<u8>>) -> Problem {
    let names: Vec<&str> = files.keys().map(String::as_str).collect();
    Problem::file(
        "the dataset folder",
        format!(
            "holds no dataset files (it has: {})",
            if names.is_empty() { "nothing".to_string() } else { names.join(", ") }
        ),
        "add runs.csv and trajectories.csv (see README, Using it on your data), or trackpy or TrackMate exports (CSV or TrackMate XML) with a calibration in the ingest params (see README, Tracker exports)",
    )
}

fn read_interchange(files: &BTreeMap<String, Vec<u8>>) -> Result<Sources, IngestError> {
    let runs_file = interchange::pick(files, "runs", "one row per run");
    let traj_file = interchange::pick(files, "trajectories", "one row per particle per frame");
    let (runs_file, traj_file) = match (runs_file, traj_file) {
        (Ok(r), Ok(t)) => (r, t),
        (r, t) => {
            return Err(IngestError::new(
                [r.err(), t.err()].into_iter().flatten().collect(),
            ))
        }
    };
    let runs_table = Table::from_bytes(runs_file.0, runs_file.1);
    let traj_table = Table::from_bytes(traj_file.0, traj_file.1);
    let read_runs = runs_table.and_then(|t| interchange::read_runs(&t));
    let read_traj = traj_table.and_then(|t| interchange::read_trajectories(&t));
    match (read_runs, read_traj) {
        (Ok((runs, mut problems)), Ok((samples, more))) => {
            problems.extend(more);
            Ok((runs, vec![samples], problems, Vec::new()))
        }
        (r, t) => Err(IngestError::new(
            [r.err(), t.err()].into_iter().flatten().collect(),
        )),
    }
}

/// Reads the tracker files of the folder: trackpy CSV (one run per file, or a `run` column),
/// TrackMate CSV spot tables and TrackMate XML (one run per file). In `auto` mode each file is
/// recognised by its header (or root element) and others are ignored; with an explicit format
/// every CSV file but the manifest must be of that kind. `None` if `auto` found no tracker file.
fn read_trackers(
    files: &BTreeMap<String, Vec<u8>>,
    format: Format,
    params: &IngestParams,
) -> Result<Option<Sources>, IngestError> {
    let axis = params.calibration.axis;
    let mut problems = Vec::new();
    let mut spot_files = Vec::new();
    for (name, bytes) in files {
        let lower = name.to_ascii_lowercase();
        if lower.ends_with(".xml") && format != Format::Trackpy {
            if format == Format::Auto && !trackmate_xml::looks_like(bytes) {
                continue;
            }
            match trackmate_xml::read(name, bytes, axis, &spots::run_id(name)) {
                Ok((spots, more)) => {
                    problems.extend(more);
                    spot_files.push(spots);
                }
                Err(p) => problems.push(p),
            }
            continue;
        }
        if !lower.ends_with(".csv") || name == manifest::FILE {
            continue;
        }
        let table = match Table::from_csv(name, bytes) {
            Ok(t) => t,
            Err(_) if format == Format::Auto => continue,
            Err(p) => {
                problems.push(p);
                continue;
            }
        };
        let kind = match format {
            Format::Auto if trackmate::looks_like(&table.names) => Format::Trackmate,
            Format::Auto if trackpy::looks_like(&table.names) => Format::Trackpy,
            Format::Auto => continue,
            f => f,
        };
        let read = match kind {
            Format::Trackmate => trackmate::read(table, axis),
            _ => trackpy::read(&table, axis),
        };
        match read {
            Ok((spots, more)) => {
                problems.extend(more);
                spot_files.push(spots);
            }
            Err(p) => problems.push(p),
        }
    }
    if spot_files.is_empty() && problems.is_empty() {
        return match format {
            Format::Auto => Ok(None),
            _ => Err(no_dataset_files(files).into()),
        };
    }
    let (manifest, more) = manifest::load(files, params)?;
    problems.extend(more);
    // A file of one run may be renamed by the manifest's `file` column.
    if let Some(m) = &manifest {
        for f in &mut spot_files {
            for rs in &mut f.runs {
                if rs.named_by_file {
                    rs.run = m.run_of_file(&f.file, &rs.run);
                }
            }
        }
        check_manifest_files(m, &spot_files, &mut problems);
    }
    if let Some(p) = axis::check(&spot_files, axis) {
        problems.extend(p);
    }
    let mut runs = Vec::new();
    let mut sample_files = Vec::new();
    let mut notes = Vec::new();
    for f in &spot_files {
        for rs in &f.runs {
            let calibrated = manifest::resolve(
                &rs.run,
                &f.file,
                manifest.as_ref(),
                &params.calibration,
                &f.units,
            )
            .and_then(|meta| spots::calibrate(f, rs, &meta));
            match calibrated {
                Ok((run, samples, said)) => {
                    runs.push(run);
                    sample_files.push(samples);
                    notes.extend(said.into_iter().map(|reason| Skipped {
                        run: rs.run.clone(),
                        reason: format!("{reason} ({})", f.file),
                    }));
                }
                Err(p) => problems.push(p),
            }
        }
    }
    Ok(Some((runs, sample_files, problems, notes)))
}

/// Every manifest row names a run some file holds, and every file it names is in the folder.
fn check_manifest_files(
    m: &manifest::Manifest,
    spot_files: &[spots::SpotFile],
    problems: &mut Vec<Problem>,
) {
    let held: BTreeMap<&str, &str> = spot_files
        .iter()
        .flat_map(|f| {
            f.runs
                .iter()
                .map(move |r| (r.run.as_str(), f.file.as_str()))
        })
        .collect();
    for e in &m.entries {
        if held.contains_key(e.values.run.as_str()) {
            continue;
        }
        let at = |message: String, fix: String| Problem {
            file: m.source.clone(),
            row: (m.source == manifest::FILE).then_some(e.row),
            column: Some("run".into()),
            run: Some(e.values.run.clone()),
            message,
            fix,
        };
        problems.push(match &e.values.file {
            Some(file) if !spot_files.iter().any(|f| &f.file == file) => at(
                format!("run {:?} is in {file}, which is not a tracker export in the dataset folder", e.values.run),
                format!("add {file} to the folder, correct the file name, or delete the row"),
            ),
            _ => at(
                format!("run {:?} is in no tracker file of the dataset folder", e.values.run),
                "add its export (a file named after the run, rows with this run id in a `run` column, or name the file in the row's `file` column), or delete the row".into(),
            ),
        });
    }
}

/// Two runs whose item names coincide would overwrite each other in the `runs` collection.
fn check_item_names(recordings: &[Recording], problems: &mut Vec<Problem>) {
    let mut names: BTreeMap<String, &str> = BTreeMap::new();
    for r in recordings {
        let name = item_name(&r.info.run);
        if let Some(other) = names.insert(name.clone(), &r.info.run) {
            problems.push(Problem::file(
                "the dataset",
                format!(
                    "runs {other:?} and {:?} both get the item name {name:?}",
                    r.info.run
                ),
                "rename one of the two runs",
            ));
        }
    }
}
