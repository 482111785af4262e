//! One recorded run, as the analysis stages see it after ingest: run metadata plus one track per particle.
//!
//! Files of this folder:
//!
//! - `item.rs`: The bytes of a recording item
//!
//! This is the per-run item that `ingest` emits (as the binary format of `item`) and that `fit`, `simulate`,
//! `compare` and `discover` read. Units are SI and in the field names. Ingest guarantees every
//! number is finite, |z_m| ≤ `Z_MAX_M`, |t_s| ≤ `T_MAX_S`, and t_s strictly increases along a
//! track and agrees with frame/fps (see `ingest::sanity`).

pub mod item;

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Largest |z_m| of a sample, metres. Ingest refuses a position farther out (a groove on a lab
/// bench is far shorter; such a value is pixels, micrometres or a broken export), so stages may
/// rely on it.
pub const Z_MAX_M: f64 = 10.0;
/// Largest |t_s| of a sample, seconds. A run lasts a fraction of a second and a camera's memory
/// holds seconds; ingest refuses anything beyond a minute, so loops over time stay bounded.
pub const T_MAX_S: f64 = 60.0;

/// The kind of run, column `experiment` of runs.csv.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Experiment {
    /// One particle kicked along the groove.
    Single,
    /// A striker (particle 0) and a target (particle 1).
    Collision,
}

/// How a collision run started, column `setup` of runs.csv.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Setup {
    /// The striker rolled into a resting target.
    Rolling,
    /// The pair started touching; the striker was kicked.
    Contact,
}

/// Metadata of one run (a row of runs.csv).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    pub run: String,
    pub experiment: Experiment,
    pub material: String,
    pub diameter_m: f64,
    pub fps: f64,
    pub setup: Option<Setup>,
    /// Columns of runs.csv that groove does not interpret, kept as text for the report.
    #[serde(default)]
    pub extra: BTreeMap<String, String>,
}

/// One particle's positions, sorted by frame; gaps in `frame` are dropped frames.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Track {
    pub particle: u32,
    pub frame: Vec<i64>,
    pub t_s: Vec<f64>,
    pub z_m: Vec<f64>,
}

/// One run: its metadata and its tracks, sorted by particle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Recording {
    pub info: RunInfo,
    pub tracks: Vec<Track>,
}

impl Recording {
    /// The track of `particle`, if recorded.
    pub fn track(&self, particle: u32) -> Option<&Track> {
        self.tracks.iter().find(|t| t.particle == particle)
    }
}
