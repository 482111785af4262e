//! Reads trackpy CSV exports (`,y,x,mass,size,ecc,signal,raw_mass,ep,frame,particle`, pixels, y
//! down): one file per run (the run named by the file), or one file of many runs with a `run`
//! column naming each row's run.

use super::error::Problem;
use super::params::Axis;
use super::spots::{read_spots, SpotColumns, SpotFile};
use super::table::Table;

const COLUMNS: [(&str, &str); 4] = [
    ("frame", "frame index"),
    ("particle", "track id from trackpy.link"),
    ("x", "column position in pixels"),
    ("y", "row position in pixels, y down"),
];

/// True if the header names look like a trackpy export.
pub fn looks_like(names: &[String]) -> bool {
    COLUMNS.iter().all(|(c, _)| names.iter().any(|n| n == c))
}

/// Reads one trackpy table. Rows with problems are left out and returned as problems of their run.
/// An empty `particle` cell is an unlinked spot.
pub fn read(table: &Table, axis: Axis) -> Result<(SpotFile, Vec<Problem>), Problem> {
    table.require(&COLUMNS)?;
    let names = SpotColumns {
        track: "particle",
        frame: "frame",
        x: "x",
        y: "y",
        key: "particle, frame",
        run: Some("run"),
    };
    Ok(read_spots(table, &names, axis))
}
