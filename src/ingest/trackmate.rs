//! Reads Fiji TrackMate spot tables (e.g. `Spots in tracks statistics.csv`, one movie, one run):
//! a key header line plus up to three more header rows (names, short names, units), numbers like
//! `1.0E-4`, rows in any order, empty `TRACK_ID` for unlinked spots. The units row, when present,
//! gives the spatial unit (`(micron)`); `(pixel)` leaves it to the calibration.

use super::error::Problem;
use super::params::Axis;
use super::spots::{read_spots, SpotColumns, SpotFile};
use super::table::Table;
use super::trackmate_xml::metres_per;

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
    let unit = (0..header_rows)
        .filter_map(|i| table.text("POSITION_X", i))
        .find_map(|s| {
            s.trim()
                .strip_prefix('(')
                .and_then(|u| u.strip_suffix(')'))
                .map(str::to_string)
        });
    table.drop_leading_rows(header_rows);
    let names = SpotColumns {
        track: "TRACK_ID",
        frame: "FRAME",
        x: "POSITION_X",
        y: "POSITION_Y",
        key: "TRACK_ID, FRAME",
        run: None,
    };
    let (mut file, problems) = read_spots(&table, &names, axis);
    if let Some(unit) = unit {
        file.units.m_per_unit = metres_per(&unit);
        file.units.spatial = unit;
    }
    Ok((file, problems))
}
