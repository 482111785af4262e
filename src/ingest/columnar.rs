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
//!
//! `stream` reads a CSV in pieces of a few megabytes cut at line ends (a Parquet file a batch of
//! row groups at a time, `parquet_groups`) and hands each run on as its last row is read, so
//! memory is bounded by a piece, not the file; it needs each run's rows to be one block and
//! otherwise says why, and the caller reads the file whole as above.

use super::csv_fast;
use super::csv_pieces::{for_each_piece, Stop};
use super::interchange;
use super::parquet_groups::{self, Batches, InMemory, Source, COLUMNS};
use super::run_memo::{self, RunMemo, Step};
use super::sanity;
use super::table::Table;
use crate::recording::{Experiment, Recording, RunInfo, Track};
use polars::prelude::*;
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::io::Cursor;
use std::ops::Range;

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
        parquet_groups::read_whole(traj_bytes)?
    } else {
        read_csv(traj_bytes)?
    };
    let cols = Columns::of(df)?;
    let mut recordings = Vec::with_capacity(infos.len());
    for (run, rows) in &cols.runs {
        let info = infos.remove(run.as_str())?;
        recordings.push(recording(info, &cols.block(), rows.clone(), min_frames)?);
    }
    // Sorted by run as the row-by-row path's map sorts them; every run of runs.csv has rows.
    recordings.sort_by(|a, b| a.info.run.cmp(&b.info.run));
    infos.is_empty().then_some(recordings)
}

/// Reads trajectories.csv with the typed schema. `None` if the bytes hold anything the typed
/// read might take differently from the row-by-row path: text that is not UTF-8, a double quote,
/// a row with another number of fields than the header, a header that is not exactly the names.
pub(crate) fn read_csv(bytes: &[u8]) -> Option<DataFrame> {
    let (bytes, data_lines) = check_csv(bytes)?;
    let df = parse_csv(bytes)?;
    (df.height() == data_lines).then_some(df)
}

/// The CSV without a byte-order mark and its number of data lines, if the typed read takes every
/// line as the row-by-row path does (see `read_csv`).
fn check_csv(bytes: &[u8]) -> Option<(&[u8], usize)> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).ok()?;
    let header_len = bytes
        .iter()
        .position(|&b| b == b'\n')
        .unwrap_or(bytes.len());
    let header = std::str::from_utf8(&bytes[..header_len])
        .ok()?
        .trim_end_matches('\r');
    if header.contains('"') {
        return None;
    }
    let names: Vec<&str> = header.split(',').collect();
    let mut unique: Vec<&str> = names.iter().map(|n| n.trim()).collect();
    unique.sort_unstable();
    unique.dedup();
    if unique.len() != names.len() || COLUMNS.iter().any(|(c, _)| !names.contains(c)) {
        return None;
    }
    // Every line is blank or has the header's number of fields, so the projection hides no
    // ragged row (the row-by-row path refuses one with too many fields); no quoted cell. One
    // pass over the bytes.
    let fields_less_one = names.len() - 1;
    let (mut data_lines, mut commas, mut blank) = (0, 0, true);
    let mut line_ends = |commas: usize, blank: bool| {
        if commas == fields_less_one {
            data_lines += 1;
            true
        } else {
            commas == 0 && blank
        }
    };
    if header_len < bytes.len() {
        for &b in &bytes[header_len + 1..] {
            match b {
                b',' => commas += 1,
                b'\n' => {
                    if !line_ends(commas, blank) {
                        return None;
                    }
                    (commas, blank) = (0, true);
                }
                b'"' => return None,
                _ => blank &= b.is_ascii_whitespace(),
            }
        }
        if !line_ends(commas, blank) {
            return None;
        }
    }
    Some((bytes, data_lines))
}

/// The five columns of CSV text with its header line, typed; `None` if polars refuses it.
fn parse_csv(bytes: &[u8]) -> Option<DataFrame> {
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
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(read))
        .ok()?
        .ok()
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
    /// The rows sorted by (particle, frame) (of a one-run `Columns`; `runs` is left empty).
    fn sorted(&self) -> Columns {
        let mut order: Vec<usize> = (0..self.particle.len()).collect();
        order.sort_by_key(|&k| (self.particle[k], self.frame[k]));
        Columns {
            runs: Vec::new(),
            particle: order.iter().map(|&k| self.particle[k]).collect(),
            frame: order.iter().map(|&k| self.frame[k]).collect(),
            t_s: order.iter().map(|&k| self.t_s[k]).collect(),
            z_m: order.iter().map(|&k| self.z_m[k]).collect(),
        }
    }

    /// The columns as a `Block`.
    fn block(&self) -> Block<'_> {
        Block {
            particle: &self.particle,
            frame: &self.frame,
            t_s: &self.t_s,
            z_m: &self.z_m,
        }
    }

    fn empty() -> Columns {
        Columns {
            runs: Vec::new(),
            particle: Vec::new(),
            frame: Vec::new(),
            t_s: Vec::new(),
            z_m: Vec::new(),
        }
    }

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
    cols: &Block,
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
fn track(particle: u32, cols: &Block, rows: Range<usize>) -> Option<Track> {
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

/// Bytes of trajectories.csv read at a time by `stream` (plus the header line, and up to the end
/// of the line the chunk ends in).
pub const CHUNK_BYTES: usize = 8 << 20;

/// Why `stream` gave up on a run's rows not coming together: the dataset is read whole and sorted
/// instead.
pub const NOT_GROUPED: &str = "the rows of a run are not together";

/// The recordings of a clean interchange dataset handed to `each` in file order, a piece's worth
/// at a time (the runs whose last row was in the piece just read): trajectories.csv is read
/// `chunk_bytes` at a time, so neither the whole table nor all recordings are held (a Parquet
/// file is read once and decoded a batch of whole row groups at a time,
/// `parquet_groups::for_each_batch`). The trajectories come from `traj` if given (the file
/// named trajectories.csv or .parquet in `files`, whose bytes there are not read), else from
/// `files`. Says how it read (`Pieces`). It needs each run's rows to be
/// one block (in any order within it), as `groove synth` and most trackers write them. At anything
/// else, or anything `recordings` would give `None` for, it stops with the reason: the caller then
/// forgets what `each` received and reads the dataset whole (`ingest::ingest`), which sorts the
/// rows or names the problems. On clean grouped data it gives the runs `recordings` gives.
pub fn stream(
    files: &BTreeMap<String, Vec<u8>>,
    traj: Option<&mut dyn Source>,
    min_frames: usize,
    chunk_bytes: usize,
    memo: Option<RunMemo>,
    each: &mut dyn FnMut(Ready),
) -> Result<Pieces, Stop> {
    const PROBLEM: &str = "a problem to name, or a cell the typed read might take differently";
    let (runs_name, runs_bytes) = interchange::pick(files, "runs", "").map_err(|_| PROBLEM)?;
    let (traj_name, traj_bytes) =
        interchange::pick(files, "trajectories", "").map_err(|_| PROBLEM)?;
    let runs_table = Table::from_bytes(runs_name, runs_bytes).map_err(|_| PROBLEM)?;
    let (runs, problems) = interchange::read_runs(&runs_table).map_err(|_| PROBLEM)?;
    if !problems.is_empty() {
        return Err(PROBLEM.into());
    }
    let mut infos: BTreeMap<&str, &RunInfo> = BTreeMap::new();
    for r in &runs {
        if infos.insert(&r.info.run, &r.info).is_some() {
            return Err(PROBLEM.into());
        }
    }
    let mut stream = Stream {
        infos,
        done: std::collections::HashSet::new(),
        pending: None,
        failed: false,
        min_frames,
        ready: Ready::default(),
        piece_keys: HashMap::new(),
        each,
    };
    let parquet = traj_name.to_ascii_lowercase().ends_with(".parquet");
    let mut in_memory = InMemory::new(traj_bytes);
    let traj: &mut dyn Source = match traj {
        Some(traj) => traj,
        None => &mut in_memory,
    };
    let chunks = if parquet {
        // a batch of row groups read and decoded on a thread of its own while the one before
        // is grouped, and the runs of a slice encoded and kept while the next is grouped
        let mut each = |df: &DataFrame| {
            stream.chunk(df)?;
            stream.hand_over();
            Ok(())
        };
        let rows = chunk_bytes / parquet_groups::ROW_BYTES;
        Pieces::Parquet(parquet_groups::for_each_batch(traj, rows, &mut each)?)
    } else {
        Pieces::CsvChunks(csv_chunks(traj, chunk_bytes, memo, &mut stream)?)
    };
    stream.finish()?;
    Ok(chunks)
}

/// How `stream` read the trajectories: CSV chunks as they were read, or a Parquet file decoded
/// whole and handed on in slices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pieces {
    CsvChunks(usize),
    Parquet(Batches),
}

impl Pieces {
    pub fn count(self) -> usize {
        match self {
            Pieces::CsvChunks(n) => n,
            Pieces::Parquet(b) => b.batches,
        }
    }
}

impl std::fmt::Display for Pieces {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        let s = |n: usize| if n == 1 { "" } else { "s" };
        match *self {
            Pieces::CsvChunks(n) => write!(f, "read in {n} chunk{} of trajectories", s(n)),
            Pieces::Parquet(b) => write!(
                f,
                "decoded from Parquet in {} batch{} of whole row groups ({} row group{}){}",
                b.batches,
                if b.batches == 1 { "" } else { "es" },
                b.row_groups,
                s(b.row_groups),
                // with one batch there is no next one to decode meanwhile
                match b.batches > 1 {
                    true => ", each batch grouped while the next was decoded",
                    false => "",
                }
            ),
        }
    }
}

/// What `stream` hands on after each piece: the recordings made, each with the memo key of its
/// lines when it was a whole run of a strict-layout piece (`run_memo::run_key`; the caller may
/// remember the key with the item once the stream has ended well, not before: a stream that
/// stops may have paired a key with rows it never saw whole), and the runs whose item the memo
/// gave (run id, item sha256).
#[derive(Default)]
pub struct Ready {
    pub made: Vec<(Recording, Option<[u8; 32]>)>,
    pub found: Vec<(String, String)>,
}

impl Ready {
    fn is_empty(&self) -> bool {
        self.made.is_empty() && self.found.is_empty()
    }
}

/// Reads CSV text in pieces into `stream`, each checked as `read_csv` checks a whole file;
/// with a memo, a strict-layout piece's whole runs found in it are not parsed (`run_memo`).
fn csv_chunks(
    read: &mut (dyn std::io::Read + Send),
    chunk_bytes: usize,
    memo: Option<RunMemo>,
    stream: &mut Stream,
) -> Result<usize, Stop> {
    const PROBLEM: &str = "a problem to name, or a cell the typed read might take differently";
    for_each_piece(read, chunk_bytes, &mut |text| {
        if let Some(memo) = memo {
            if stream.piece_with_memo(text, memo)? {
                return Ok(());
            }
        }
        if let Some(parts) = csv_fast::parse_parts(text) {
            stream.parsed(parts)?;
            stream.hand_over();
            return Ok(());
        }
        let (text, data_lines) = check_csv(text).ok_or(PROBLEM)?;
        let df = parse_csv(text).ok_or(PROBLEM)?;
        if df.height() != data_lines {
            return Err(PROBLEM.into());
        }
        stream.chunk(&df)?;
        stream.hand_over();
        Ok(())
    })
}

/// A chunk's typed columns, borrowed from its data frame (or from `Columns`).
struct Block<'c> {
    particle: &'c [i64],
    frame: &'c [i64],
    t_s: &'c [f64],
    z_m: &'c [f64],
}

impl<'c> Block<'c> {
    /// Some of the rows.
    fn slice(&self, rows: Range<usize>) -> Block<'c> {
        Block {
            particle: &self.particle[rows.clone()],
            frame: &self.frame[rows.clone()],
            t_s: &self.t_s[rows.clone()],
            z_m: &self.z_m[rows],
        }
    }

    /// A copy of some rows (of one run), as a one-run `Columns`.
    fn one_run(&self, rows: Range<usize>) -> Columns {
        Columns {
            runs: Vec::new(),
            particle: self.particle[rows.clone()].to_vec(),
            frame: self.frame[rows.clone()].to_vec(),
            t_s: self.t_s[rows.clone()].to_vec(),
            z_m: self.z_m[rows].to_vec(),
        }
    }
}

fn ints(c: &Column) -> Option<&[i64]> {
    c.i64().ok()?.cont_slice().ok()
}

fn floats(c: &Column) -> Option<&[f64]> {
    c.f64().ok()?.cont_slice().ok()
}

/// The state of `stream` between chunks: the runs not yet read, the runs done, and the rows so
/// far of the run being read (as one-run `Columns`).
struct Stream<'a, 'e> {
    infos: BTreeMap<&'a str, &'a RunInfo>,
    done: std::collections::HashSet<String>,
    pending: Option<(String, Columns)>,
    /// A run whose recording `recordings` would not give: the dataset is read whole at the end.
    failed: bool,
    min_frames: usize,
    /// The runs completed in the piece being read, handed over together after it.
    ready: Ready,
    /// The memo keys of the whole runs among the piece's lines being parsed (run id → key).
    piece_keys: HashMap<String, [u8; 32]>,
    each: &'e mut dyn FnMut(Ready),
}

impl<'a> Stream<'a, '_> {
    /// A strict-layout piece with the memo (`run_memo::plan`): its lines parsed but for the
    /// whole runs found, every run taken in file order. False (nothing taken) when the piece is
    /// not for that path.
    fn piece_with_memo(&mut self, text: &[u8], memo: RunMemo) -> Result<bool, &'static str> {
        let Some(body) = csv_fast::body(text) else {
            return Ok(false);
        };
        let Some(plan) = run_memo::plan(body, &self.infos, self.min_frames, memo) else {
            return Ok(false);
        };
        self.piece_keys = plan.keys;
        for step in plan.steps {
            match step {
                Step::Parsed(parts) => self.parsed(parts)?,
                Step::Found { id, sha256 } => self.found(id, sha256)?,
            }
        }
        self.piece_keys.clear();
        self.hand_over();
        Ok(true)
    }

    /// Consecutive lines parsed by the strict-layout parser, in parts, into their runs.
    fn parsed(&mut self, parts: Vec<csv_fast::Rows>) -> Result<(), &'static str> {
        for rows in parts {
            let block = Block {
                particle: &rows.particle,
                frame: &rows.frame,
                t_s: &rows.t_s,
                z_m: &rows.z_m,
            };
            self.blocks(&rows.ids, &block)?;
        }
        Ok(())
    }

    /// A whole run whose item the memo gave: the run before it is complete.
    fn found(&mut self, id: &str, sha256: String) -> Result<(), &'static str> {
        self.hand_on()?;
        if !self.done.insert(id.to_string()) {
            return Err(NOT_GROUPED);
        }
        match self.infos.remove(id) {
            Some(_) => self.ready.found.push((id.to_string(), sha256)),
            None => self.failed = true,
        }
        Ok(())
    }

    /// Adds a chunk's rows to their runs, handing on each run whose rows end inside it.
    fn chunk(&mut self, df: &DataFrame) -> Result<(), &'static str> {
        const PROBLEM: &str = "a null, a column of another type or an untrimmed run id";
        if df.columns().iter().any(|c| c.null_count() > 0) {
            return Err(PROBLEM);
        }
        let column = |name: &str| -> Result<Column, &'static str> {
            Ok(df.column(name).map_err(|_| PROBLEM)?.rechunk())
        };
        let (particle, frame) = (column("particle")?, column("frame")?);
        let (t_s, z_m, run) = (column("t_s")?, column("z_m")?, column("run")?);
        let block = Block {
            particle: ints(&particle).ok_or(PROBLEM)?,
            frame: ints(&frame).ok_or(PROBLEM)?,
            t_s: floats(&t_s).ok_or(PROBLEM)?,
            z_m: floats(&z_m).ok_or(PROBLEM)?,
        };
        let ids = run.str().map_err(|_| PROBLEM)?;
        let ids: Vec<&str> = ids.downcast_iter().flat_map(|a| a.values_iter()).collect();
        self.blocks(&ids, &block)
    }

    /// Adds rows (their run ids, and their other columns in `block`) to their runs, handing on
    /// each run whose rows end among them.
    fn rows<'i>(
        &mut self,
        ids: impl Iterator<Item = &'i str>,
        block: &Block,
    ) -> Result<(), &'static str> {
        let mut start = 0;
        let mut i = 0;
        for id in ids {
            if self.pending.as_ref().map(|(r, _)| r.as_str()) != Some(id) {
                self.extend(block, start..i);
                self.hand_on()?;
                if id.is_empty() || id.trim() != id {
                    return Err("an untrimmed run id");
                }
                if self.done.contains(id) {
                    return Err(NOT_GROUPED);
                }
                self.pending = Some((id.to_string(), Columns::empty()));
                start = i;
            }
            i += 1;
        }
        self.extend(block, start..i);
        Ok(())
    }

    /// `rows`, with the run ids at hand: the runs that both start and end among the rows are
    /// made into recordings on every core, straight from `block`, with no copy per run; the run
    /// open at the start (pending) and the one open at the end go through `rows`'s copy, so the
    /// outcome is `rows`'s.
    fn blocks(&mut self, ids: &[&str], block: &Block) -> Result<(), &'static str> {
        // blocks of consecutive rows of one run id
        let mut runs: Vec<(&str, Range<usize>)> = Vec::new();
        for (i, &id) in ids.iter().enumerate() {
            match runs.last_mut() {
                Some((last, rows)) if *last == id => rows.end = i + 1,
                _ => runs.push((id, i..i + 1)),
            }
        }
        let n_runs = runs.len();
        if n_runs < 3 {
            return self.rows(ids.iter().copied(), block);
        }
        // the first block ends the pending run (or starts one), the last stays open: both as
        // `rows` takes them; those between are whole runs, checked here in file order
        let (first, middle, last) = (&runs[0], &runs[1..n_runs - 1], &runs[n_runs - 1]);
        self.rows(ids[first.1.clone()].iter().copied(), block)?;
        self.hand_on()?;
        let mut whole: Vec<(Option<&'a RunInfo>, Range<usize>, Option<[u8; 32]>)> =
            Vec::with_capacity(middle.len());
        for (id, rows) in middle {
            if id.is_empty() || id.trim() != *id {
                return Err("an untrimmed run id");
            }
            if !self.done.insert(id.to_string()) {
                return Err(NOT_GROUPED);
            }
            let key = self.piece_keys.get(*id).copied();
            whole.push((self.infos.remove::<str>(id), rows.clone(), key));
        }
        let min_frames = self.min_frames;
        let made: Vec<Option<(Recording, Option<[u8; 32]>)>> = whole
            .par_iter()
            .map(|(info, rows, key)| {
                let info = (*info)?;
                let sorted = (rows.start + 1..rows.end).all(|k| {
                    (block.particle[k - 1], block.frame[k - 1])
                        <= (block.particle[k], block.frame[k])
                });
                let rec = match sorted {
                    true => recording(info, block, rows.clone(), min_frames),
                    false => {
                        let one = block.one_run(rows.clone()).sorted();
                        recording(info, &one.block(), 0..rows.len(), min_frames)
                    }
                };
                rec.map(|r| (r, *key))
            })
            .collect();
        for rec in made {
            match rec {
                Some(rec) => self.ready.made.push(rec),
                None => self.failed = true,
            }
        }
        self.rows(
            ids[last.1.clone()].iter().copied(),
            &block.slice(last.1.clone()),
        )
    }

    /// The recordings ready go to `each`, all at once (it may work on them in parallel).
    fn hand_over(&mut self) {
        if !self.ready.is_empty() {
            (self.each)(std::mem::take(&mut self.ready));
        }
    }

    fn extend(&mut self, block: &Block, rows: Range<usize>) {
        if let Some((_, c)) = &mut self.pending {
            c.particle.extend_from_slice(&block.particle[rows.clone()]);
            c.frame.extend_from_slice(&block.frame[rows.clone()]);
            c.t_s.extend_from_slice(&block.t_s[rows.clone()]);
            c.z_m.extend_from_slice(&block.z_m[rows]);
        }
    }

    /// The run being read is complete: its recording is ready.
    fn hand_on(&mut self) -> Result<(), &'static str> {
        let Some((id, cols)) = self.pending.take() else {
            return Ok(());
        };
        let n = cols.particle.len();
        let sorted = (1..n).all(|k| {
            (cols.particle[k - 1], cols.frame[k - 1]) <= (cols.particle[k], cols.frame[k])
        });
        // A collision run's rows often come frame by frame (both particles at each frame): its
        // rows are sorted here, as the whole-file path sorts them.
        let cols = if sorted { cols } else { cols.sorted() };
        let rec = match self.infos.remove(id.as_str()) {
            Some(info) => recording(info, &cols.block(), 0..n, self.min_frames),
            None => None,
        };
        let key = self.piece_keys.get(&id).copied();
        self.done.insert(id);
        match rec {
            Some(rec) => self.ready.made.push((rec, key)),
            // Read on: the reason may yet turn out to be rows of runs interleaved.
            None => self.failed = true,
        }
        Ok(())
    }

    /// The last run is complete; every run of runs.csv had rows.
    fn finish(mut self) -> Result<(), &'static str> {
        self.hand_on()?;
        self.hand_over();
        if self.failed {
            Err("a run with a problem to name, or one runs.csv does not list")
        } else if self.infos.is_empty() {
            Ok(())
        } else {
            Err("a run of runs.csv without rows")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::check_csv;

    #[test]
    fn the_csv_check_counts_data_lines_and_refuses_ragged_or_quoted_ones() {
        let head = "run,particle,frame,t_s,z_m,note\n";
        let ok = format!("{head}a,0,0,0.0,1e-3,x\r\n\n  \na,0,1,1e-4,2e-3,\n");
        assert_eq!(check_csv(ok.as_bytes()).map(|c| c.1), Some(2));
        // no newline at the end, and a byte-order mark
        let bom = format!("\u{feff}{head}a,0,0,0.0,1e-3,x");
        assert_eq!(check_csv(bom.as_bytes()).map(|c| c.1), Some(1));
        assert_eq!(check_csv(head.trim_end().as_bytes()).map(|c| c.1), Some(0));
        for bad in [
            format!("{head}a,0,0,0.0,1e-3\n"),
            format!("{head}a,0,0,0.0,1e-3,x,y\n"),
            format!("{head}a,0,0,0.0,1e-3,x\nstray\n"),
            format!("{head}\"a\",0,0,0.0,1e-3,x\n"),
            "run,particle,frame,t_s\na,0,0,0.0\n".to_string(),
            "run,run,particle,frame,t_s,z_m\n".to_string(),
        ] {
            assert_eq!(check_csv(bad.as_bytes()), None, "{bad:?}");
        }
    }
}
