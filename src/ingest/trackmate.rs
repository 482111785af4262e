//! Reads Fiji TrackMate spot tables: a key header line plus up to three more header rows (names,
//! short names, units), numbers like `1.0E-4`, rows in any order, empty `TRACK_ID` for unlinked spots.

use super::error::Problem;
use super::params::Axis;
use super::spots::{axis_column, run_id, Spot, SpotFile};
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
    let run = run_id(&table.file);
    let p_column = axis_column(axis, ("POSITION_X", "POSITION_Y"));
    let mut spots = Vec::with_capacity(table.height());
    let mut problems = Vec::new();
    for i in 0..table.height() {
        let spot = (|| {
            let frame = table.int("FRAME", i, "write the frame index, a whole number")?;
            let track = match table.text("TRACK_ID", i) {
                None => None,
                Some(s) if s.eq_ignore_ascii_case("none") => None,
                Some(_) => Some(table.int(
                    "TRACK_ID",
                    i,
                    "write the track id, a whole number, or leave it empty for an unlinked spot",
                )?),
            };
            let p_px = table.float(p_column, i, "write a finite number in pixels")?;
            Ok::<Spot, Problem>(Spot {
                track,
                frame,
                p_px,
                row: table.row(i),
            })
        })();
        match spot {
            Ok(s) => spots.push(s),
            Err(p) => problems.push(p.in_run(&run)),
        }
    }
    Ok((
        SpotFile {
            file: table.file.clone(),
            run,
            key_columns: "TRACK_ID, FRAME",
            frame_column: "FRAME",
            track_column: "TRACK_ID",
            spots,
        },
        problems,
    ))
}
