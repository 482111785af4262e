//! Ingest: reads a dataset folder (interchange CSV/Parquet, trackpy or TrackMate exports), checks
//! every bad-input class of data-format.md, and returns one `Recording` per run.
//!
//! Everything here works on bytes in memory (file name → bytes), or, for trajectories.csv, on a
//! reader the stage is given, so the stage never opens a file itself; `read_dataset_dir` is the
//! one helper that reads a folder, for tests and tools.

// A `Problem` carries file, row, column, run, message and fix; it is returned only for bad
// input, so its size on the error path is not worth boxing.
#![allow(clippy::result_large_err)]

mod assemble;
mod axis;
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
        "add runs.csv and trajectories.csv (see data-format.md), or trackpy or TrackMate exports (CSV or TrackMate XML) with a calibration in the ingest params (see README, Tracker exports)",
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
