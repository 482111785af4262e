//! Ingest: reads a dataset folder (interchange CSV/Parquet, trackpy or TrackMate exports), checks
//! every bad-input class of data-format.md, and returns one `Recording` per run.
//!
//! Everything here works on bytes in memory (file name → bytes), so the stage never touches the
//! file system; `read_dataset_dir` is the one helper that reads a folder, for tests and tools.

// A `Problem` carries file, row, column, run, message and fix; it is returned only for bad
// input, so its size on the error path is not worth boxing.
#![allow(clippy::result_large_err)]

mod assemble;
mod csv_check;
pub mod error;
mod interchange;
pub mod output;
pub mod params;
mod samples;
pub mod sanity;
mod spots;
mod table;
mod trackmate;
mod trackpy;

pub use error::{IngestError, Problem};
pub use output::{item_name, skipped_json, table_parquet, Skipped};
pub use params::{Axis, Calibration, Format, IngestParams};

use crate::recording::Recording;
use samples::{RunRow, SampleFile};
use std::collections::BTreeMap;
use std::path::Path;
use table::Table;

/// The result of ingesting a dataset: the usable runs sorted by id, and the runs left out.
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

/// Reads and checks a dataset given as its top-level files (name → bytes).
pub fn ingest(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Result<Ingested, IngestError> {
    params.check().map_err(|p| {
        Problem::file(
            "pipeline.toml",
            format!("ingest param {}: {}", p.key, p.message),
            p.fix,
        )
    })?;
    let (runs, sample_files, mut problems) = read_sources(files, params)?;
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
        return Ok(Ingested {
            recordings,
            skipped: Vec::new(),
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
    let skipped = by_run
        .into_iter()
        .map(|(run, mut ps)| {
            ps.sort();
            let more = match ps.len() {
                1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            Skipped {
                run,
                reason: format!("{}{more}", ps[0]),
            }
        })
        .collect();
    Ok(Ingested {
        recordings,
        skipped,
    })
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

/// The run rows and sample files of a dataset, and the row-level problems found reading them.
type Sources = (Vec<RunRow>, Vec<SampleFile>, Vec<Problem>);

/// The run rows and sample files of the dataset in its format, and the row-level problems found.
fn read_sources(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Result<Sources, IngestError> {
    let interchange_present = INTERCHANGE_FILES.iter().any(|f| files.contains_key(*f));
    match params.format {
        Format::Interchange => read_interchange(files),
        Format::Auto if interchange_present => read_interchange(files),
        format => read_trackers(files, format, params),
    }
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
            Ok((runs, vec![samples], problems))
        }
        (r, t) => Err(IngestError::new(
            [r.err(), t.err()].into_iter().flatten().collect(),
        )),
    }
}

/// Tracker exports, one run per CSV file. In `auto` mode each CSV file is recognised by its header
/// and others are ignored; with an explicit format every CSV file must be of that kind.
fn read_trackers(
    files: &BTreeMap<String, Vec<u8>>,
    format: Format,
    params: &IngestParams,
) -> Result<Sources, IngestError> {
    let mut problems = Vec::new();
    let mut spot_files = Vec::new();
    for (name, bytes) in files {
        if !name.to_ascii_lowercase().ends_with(".csv") {
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
        let axis = params.calibration.axis;
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
        let names: Vec<&str> = files.keys().map(String::as_str).collect();
        return Err(Problem::file(
            "the dataset folder",
            format!(
                "holds no dataset files (it has: {})",
                if names.is_empty() { "nothing".to_string() } else { names.join(", ") }
            ),
            "add runs.csv and trajectories.csv (see data-format.md), or trackpy or TrackMate CSV exports with a calibration in the ingest params",
        )
        .into());
    }
    let cal = params.checked_calibration().map_err(|message| {
        Problem::file(
            "pipeline.toml",
            message,
            "set it in the ingest params of pipeline.toml",
        )
    })?;
    let mut runs = Vec::new();
    let mut sample_files = Vec::new();
    for spots in &spot_files {
        match spots::calibrate(spots, &cal) {
            Ok((run, samples)) => {
                runs.push(run);
                sample_files.push(samples);
            }
            Err(p) => problems.push(p),
        }
    }
    Ok((runs, sample_files, problems))
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
