//! Reads trackpy CSV exports (`,y,x,mass,size,ecc,signal,raw_mass,ep,frame,particle`, pixels, y down).

use super::error::Problem;
use super::params::Axis;
use super::spots::{axis_column, run_id, Spot, SpotFile};
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

/// Reads one trackpy table (one run). Rows with problems are left out and returned as problems of
/// the run. An empty `particle` cell is an unlinked spot.
pub fn read(table: &Table, axis: Axis) -> Result<(SpotFile, Vec<Problem>), Problem> {
    table.require(&COLUMNS)?;
    let run = run_id(&table.file);
    let p_column = axis_column(axis, ("x", "y"));
    let mut spots = Vec::with_capacity(table.height());
    let mut problems = Vec::new();
    for i in 0..table.height() {
        let spot = (|| {
            let frame = table.int("frame", i, "write the frame index, a whole number")?;
            let track = match table.text("particle", i) {
                None => None,
                Some(_) => Some(table.int(
                    "particle",
                    i,
                    "write the trackpy particle id, a whole number, or leave it empty",
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
            key_columns: "particle, frame",
            frame_column: "frame",
            track_column: "particle",
            spots,
        },
        problems,
    ))
}
