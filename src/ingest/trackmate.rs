//! Reads Fiji TrackMate spot tables: a key header line plus up to three more header rows (names,
//! short names, units), numbers like `1.0E-4`, rows in any order, empty `TRACK_ID` for unlinked spots.

use super::error::Problem;
use super::params::Axis;
use super::spots::{read_spots, SpotColumns, SpotFile};
use super::table::Table;

const COLUMNS: [(&str, &str); 4] = [
    ("TRACK_ID", "track id, empty for unlinked spots"),
    ("FRAME", "frame index"),
    ("POSITION_X", "x position"),
    ("POSITION_Y", "y position, y down"),
];

/// The most header rows after the key line (names, short names, units).
const EXTRA_HEADER_ROWS: usize = 3;

/// True if the header names look like a TrackMate spot table.
pub fn looks_like(names: &[String]) -> bool {
    COLUMNS.iter().all(|(c, _)| names.iter().any(|n| n == c))
}

/// Reads one TrackMate spot table (one run), dropping its extra header rows. Rows with problems are
/// left out and returned as problems of the run.
pub fn read(mut table: Table, axis: Axis) -> Result<(SpotFile, Vec<Problem>), Problem> {
    table.require(&COLUMNS)?;
    let header_rows = (0..table.height().min(EXTRA_HEADER_ROWS))
        .take_while(|&i| {
            table
                .text("FRAME", i)
                .is_none_or(|s| s.parse::<f64>().is_err())
        })
        .count();
    table.drop_leading_rows(header_rows);
    let names = SpotColumns {
        track: "TRACK_ID",
        frame: "FRAME",
        x: "POSITION_X",
        y: "POSITION_Y",
        key: "TRACK_ID, FRAME",
    };
    Ok(read_spots(&table, &names, axis))
}
