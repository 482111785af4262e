//! The common form every source format is read into before checking: run rows and position samples,
//! each remembering where in which file it was written.

use crate::recording::RunInfo;
use std::sync::Arc;

/// One run's metadata and the file and row it came from.
#[derive(Debug, Clone)]
pub struct RunRow {
    pub info: RunInfo,
    pub file: String,
    pub row: usize,
}

/// One particle's position in one frame, and its row in the file.
#[derive(Debug, Clone)]
pub struct Sample {
    pub run: Arc<str>,
    pub particle: u32,
    pub frame: i64,
    pub t_s: f64,
    pub z_m: f64,
    pub row: usize,
}

/// The samples of one file, with the names of its columns used in messages.
#[derive(Debug, Clone)]
pub struct SampleFile {
    pub file: String,
    /// The columns that identify a sample, e.g. `run, particle, frame`.
    pub key_columns: &'static str,
    /// The frame column, e.g. `frame` or `FRAME`.
    pub frame_column: &'static str,
    /// The particle column, e.g. `particle` or `TRACK_ID`.
    pub particle_column: &'static str,
    /// The column the time comes from, e.g. `t_s` (or `FRAME` for tracker files).
    pub time_column: &'static str,
    /// The column the position comes from, e.g. `z_m` or `POSITION_X`.
    pub position_column: &'static str,
    pub samples: Vec<Sample>,
}
