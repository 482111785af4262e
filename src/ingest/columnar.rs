//! The fast path of the interchange format: trajectories read with a typed schema by polars,
//! grouped by run (sorted by (run, particle, frame) in polars when the rows do not come grouped),
//! and each run's rows sliced straight into `Recording` tracks, with no per-row structs and no
//! maps of rows.
//!
//! It gives a dataset's recordings only when the dataset is clean: every check of the row-by-row
//! path (`interchange`, `assemble`, `sanity`) holds. At the first thing it would have to complain
//! about, or anything it may not read exactly as the row-by-row path does (quoted fields, a
//! ragged row, text polars refuses as a number, a null), it gives `None`, and the caller reads
//! the dataset row by row, which names the file, row and column of every problem. So messages on
//! bad input are the row-by-row path's, and a clean dataset gives the same recordings either way
//! (tests/ingest.rs checks both on the shipped data, on shuffled rows and on damaged files).

use super::interchange;
use super::sanity;
use super::table::Table;
use crate::recording::{Experiment, Recording, RunInfo, Track};
use polars::prelude::*;
use std::collections::BTreeMap;
use std::io::Cursor;
use std::ops::Range;

/// The trajectory columns and their types.
const COLUMNS: [(&str, DataType); 5] = [
    ("run", DataType::String),
    ("particle", DataType::Int64),
    ("frame", DataType::Int64),
    ("t_s", DataType::Float64),
    ("z_m", DataType::Float64),
];

/// The recordings of a clean interchange dataset, sorted by run; `None` if anything would need
/// a message (or might not read exactly as the row-by-row path reads it).
pub fn recordings(files: &BTreeMap<String, Vec<u8>>, min_frames: usize) -> Option<Vec<Recording>> {
    let (runs_name, runs_bytes) = interchange::pick(files, "runs", "").ok()?;
    let (traj_name, traj_bytes) = interchange::pick(files, "trajectories", "").ok()?;
    let runs_table = Table::from_bytes(runs_name, runs_bytes).ok()?;
    let (runs, problems) = interchange::read_runs(&runs_table).ok()?;
    if !problems.is_empty() {
        return None;
    }
    let mut infos: BTreeMap<&str, &RunInfo> = BTreeMap::new();
    for r in &runs {
        if infos.insert(&r.info.run, &r.info).is_some() {
            return None;
        }
    }
    let df = if traj_name.to_ascii_lowercase().ends_with(".parquet") {
        read_parquet(traj_bytes)?
    } else {
        read_csv(traj_bytes)?
    };
    let cols = Columns::of(df)?;
    let mut recordings = Vec::with_capacity(infos.len());
    for (run, rows) in &cols.runs {
        let info = infos.remove(run.as_str())?;
        recordings.push(recording(info, &cols, rows.clone(), min_frames)?);
    }
    // Sorted by run as the row-by-row path's map sorts them; every run of runs.csv has rows.
    recordings.sort_by(|a, b| a.info.run.cmp(&b.info.run));
    infos.is_empty().then_some(recordings)
}

/// Reads trajectories.csv with the typed schema. `None` if the bytes hold anything the typed
/// read might take differently from the row-by-row path: text that is not UTF-8, a double quote,
/// a row with another number of fields than the header, a header that is not exactly the names.
fn read_csv(bytes: &[u8]) -> Option<DataFrame> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).ok()?;
    if bytes.contains(&b'"') {
        return None;
    }
    // Every line is blank or has the header's number of fields, so the projection hides no
    // ragged row (the row-by-row path refuses one with too many fields).
    let mut lines = bytes.split(|&b| b == b'\n');
    let header = std::str::from_utf8(lines.next()?)
        .ok()?
        .trim_end_matches('\r');
    let names: Vec<&str> = header.split(',').collect();
    let mut unique: Vec<&str> = names.iter().map(|n| n.trim()).collect();
    unique.sort_unstable();
    unique.dedup();
    if unique.len() != names.len() || COLUMNS.iter().any(|(c, _)| !names.contains(c)) {
        return None;
    }
    let mut data_lines = 0;
    for line in lines {
        let commas = line.iter().filter(|&&b| b == b',').count();
        if commas == names.len() - 1 {
            data_lines += 1;
        } else if commas != 0 || !line.iter().all(u8::is_ascii_whitespace) {
            return None;
        }
    }
    let schema: Schema = COLUMNS
        .iter()
        .map(|(n, t)| Field::new((*n).into(), t.clone()))
        .collect();
    let projection: Arc<[PlSmallStr]> = COLUMNS.iter().map(|(n, _)| (*n).into()).collect();
    let read = || {
        CsvReadOptions::default()
            .with_has_header(true)
            .with_infer_schema_length(Some(0))
            .with_schema_overwrite(Some(Arc::new(schema)))
            .with_columns(Some(projection))
            .into_reader_with_file_handle(Cursor::new(bytes))
            .finish()
    };
    let df = std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
        .ok()?
        .ok()?;
    (df.height() == data_lines).then_some(df)
}

/// Reads trajectories.parquet: `run` text, `particle` and `frame` integers, `t_s` and `z_m`
/// floats (or integers, read as floats, as the row-by-row path does).
fn read_parquet(bytes: &[u8]) -> Option<DataFrame> {
    let projection: Vec<String> = COLUMNS.iter().map(|(n, _)| n.to_string()).collect();
    let read = || {
        ParquetReader::new(Cursor::new(bytes))
            .with_columns(Some(projection))
            .finish()
    };
    let df = std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
        .ok()?
        .ok()?;
    let mut columns = Vec::with_capacity(COLUMNS.len());
    for (name, dtype) in &COLUMNS {
        let c = df.column(name).ok()?;
        let fits = match dtype {
            DataType::String => c.dtype() == &DataType::String,
            DataType::Int64 => c.dtype().is_integer(),
            _ => {
                c.dtype().is_integer() || matches!(c.dtype(), DataType::Float32 | DataType::Float64)
            }
        };
        if !fits {
            return None;
        }
        columns.push(c.cast(dtype).ok()?);
    }
    DataFrame::new(df.height(), columns).ok()
}

/// The five columns, each run's rows in one block sorted by (particle, frame), without nulls.
struct Columns {
    /// Each run's id and its rows.
    runs: Vec<(String, Range<usize>)>,
    particle: Vec<i64>,
    frame: Vec<i64>,
    t_s: Vec<f64>,
    z_m: Vec<f64>,
}

impl Columns {
    /// The columns as they come when each run's rows are one block sorted by (particle, frame),
    /// as `groove synth` and most trackers write them; otherwise after polars sorted the rows by
    /// (run, particle, frame).
    fn of(df: DataFrame) -> Option<Columns> {
        if df.columns().iter().any(|c| c.null_count() > 0) {
            return None;
        }
        if let Some(grouped) = Columns::grouped(&df)? {
            return Some(grouped);
        }
        let by = COLUMNS[..3].iter().map(|(n, _)| *n);
        let sorted = df
            .sort(by, SortMultipleOptions::default().with_multithreaded(true))
            .ok()?;
        Columns::grouped(&sorted)?
    }

    /// `Some(None)` if the rows are not grouped by run and sorted within each run; `None` on a
    /// column of another type or a run id the row-by-row path reads differently (it trims
    /// cells; an empty one is a problem).
    fn grouped(df: &DataFrame) -> Option<Option<Columns>> {
        let column = |name: &str| -> Option<Column> { Some(df.column(name).ok()?.rechunk()) };
        let ints = |name: &str| -> Option<Vec<i64>> {
            Some(column(name)?.i64().ok()?.cont_slice().ok()?.to_vec())
        };
        let floats = |name: &str| -> Option<Vec<f64>> {
            Some(column(name)?.f64().ok()?.cont_slice().ok()?.to_vec())
        };
        let particle = ints("particle")?;
        let frame = ints("frame")?;
        let run_column = column("run")?;
        let run = run_column.str().ok()?;
        let mut runs: Vec<(String, Range<usize>)> = Vec::new();
        for arr in run.downcast_iter() {
            for id in arr.values_iter() {
                let i = runs.last().map_or(0, |(_, rows)| rows.end);
                match runs.last_mut() {
                    Some((last, rows)) if last == id => {
                        if (particle[i], frame[i]) < (particle[i - 1], frame[i - 1]) {
                            return Some(None);
                        }
                        rows.end = i + 1;
                    }
                    _ => {
                        if id.is_empty() || id.trim() != id {
                            return None;
                        }
                        runs.push((id.to_string(), i..i + 1));
                    }
                }
            }
        }
        let mut ids: Vec<&str> = runs.iter().map(|(r, _)| r.as_str()).collect();
        ids.sort_unstable();
        if ids.windows(2).any(|w| w[0] == w[1]) {
            return Some(None);
        }
        Some(Some(Columns {
            runs,
            particle,
            frame,
            t_s: floats("t_s")?,
            z_m: floats("z_m")?,
        }))
    }
}

/// One run's recording from its rows (sorted by particle and frame), or `None` if the row-by-row
/// path would name a problem in them.
fn recording(
    info: &RunInfo,
    cols: &Columns,
    rows: Range<usize>,
    min_frames: usize,
) -> Option<Recording> {
    let wanted: &[u32] = match info.experiment {
        Experiment::Single => &[0],
        Experiment::Collision => &[0, 1],
    };
    let mut tracks = Vec::with_capacity(wanted.len());
    let mut start = rows.start;
    while start < rows.end {
        let particle = cols.particle[start];
        let end = start
            + cols.particle[start..rows.end]
                .iter()
                .take_while(|p| **p == particle)
                .count();
        let particle = u32::try_from(particle).ok()?;
        if !wanted.contains(&particle) {
            return None;
        }
        tracks.push(track(particle, cols, start..end)?);
        start = end;
    }
    for p in wanted {
        if tracks.iter().find(|t| t.particle == *p)?.frame.len() < min_frames {
            return None;
        }
    }
    clock_holds(info.fps, &tracks).then(|| Recording {
        info: info.clone(),
        tracks,
    })
}

/// One particle's track, or `None` on a duplicate frame, a time or position not finite or out of
/// range, or
/// time not growing with the frame.
fn track(particle: u32, cols: &Columns, rows: Range<usize>) -> Option<Track> {
    let frame = &cols.frame[rows.clone()];
    let t_s = &cols.t_s[rows.clone()];
    let z_m = &cols.z_m[rows];
    let increasing = |w: &[f64]| w[0] < w[1];
    let ok = frame.windows(2).all(|w| w[0] < w[1])
        && t_s
            .iter()
            .all(|t| t.is_finite() && sanity::time(*t).is_ok())
        && z_m
            .iter()
            .all(|z| z.is_finite() && sanity::position(*z).is_ok())
        && t_s.windows(2).all(increasing);
    ok.then(|| Track {
        particle,
        frame: frame.to_vec(),
        t_s: t_s.to_vec(),
        z_m: z_m.to_vec(),
    })
}

/// `sanity::clock` on typed tracks: every t_s agrees with frame/fps counted from the run's first
/// frame. If two particles share that first frame with different times, which is "first"
/// depends on row order: left to the row-by-row path (`false`).
fn clock_holds(fps: f64, tracks: &[Track]) -> bool {
    let Some(first_frame) = tracks.iter().filter_map(|t| t.frame.first()).min().copied() else {
        return true;
    };
    let mut firsts = tracks
        .iter()
        .filter(|t| t.frame.first() == Some(&first_frame))
        .map(|t| t.t_s[0]);
    let Some(first_t) = firsts.next() else {
        return false;
    };
    if firsts.any(|t| t.to_bits() != first_t.to_bits()) {
        return false;
    }
    tracks.iter().all(|t| {
        t.frame.iter().zip(&t.t_s).all(|(&frame, &t_s)| {
            let expected = (frame as f64 - first_frame as f64) / fps;
            let elapsed = t_s - first_t;
            (elapsed - expected).abs() <= 0.5 / fps + sanity::CLOCK_TOLERANCE * expected.abs()
        })
    })
}
