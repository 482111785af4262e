//! Tracker spots (trackpy, TrackMate) in pixels and frames, and their conversion with a calibration
//! into one run of the interchange form.

use super::error::Problem;
use super::params::{Axis, CheckedCalibration};
use super::samples::{RunRow, Sample, SampleFile};
use super::table::Table;
use crate::recording::{Experiment, RunInfo};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

/// One detected spot: its track id (`None` if unlinked), frame, pixel position along the groove
/// axis, and its row in the file.
#[derive(Debug, Clone)]
pub struct Spot {
    pub track: Option<i64>,
    pub frame: i64,
    pub p_px: f64,
    pub row: usize,
}

/// The spots of one tracker file, which holds one run.
#[derive(Debug, Clone)]
pub struct SpotFile {
    pub file: String,
    pub run: String,
    pub key_columns: &'static str,
    pub frame_column: &'static str,
    pub track_column: &'static str,
    /// The position column read (by the calibration's axis).
    pub position_column: &'static str,
    pub spots: Vec<Spot>,
}

/// The names of a tracker table's columns.
pub struct SpotColumns {
    pub track: &'static str,
    pub frame: &'static str,
    pub x: &'static str,
    pub y: &'static str,
    /// The columns that identify a spot, for messages about duplicates.
    pub key: &'static str,
}

/// Reads the spots of a tracker table holding one run (named after the file). Rows with problems
/// are left out and returned as problems of the run. An empty track id (or `None`, `NaN`) marks an
/// unlinked spot.
pub fn read_spots(table: &Table, names: &SpotColumns, axis: Axis) -> (SpotFile, Vec<Problem>) {
    let run = run_id(&table.file);
    let track = table.col(names.track);
    let frame = table.col(names.frame);
    let position_column = match axis {
        Axis::X => names.x,
        Axis::Y => names.y,
    };
    let position = table.col(position_column);
    let mut spots = Vec::with_capacity(table.height());
    let mut problems = Vec::new();
    for i in 0..table.height() {
        let spot = (|| {
            let unlinked = track
                .text(i)
                .is_none_or(|s| s.eq_ignore_ascii_case("none") || s.eq_ignore_ascii_case("nan"));
            Ok::<Spot, Problem>(Spot {
                track: match unlinked {
                    true => None,
                    false => Some(track.int(
                        i,
                        "write the track id, a whole number, or leave it empty for an unlinked spot",
                    )?),
                },
                frame: frame.int(i, "write the frame index, a whole number")?,
                p_px: position.float(i, "write a finite number in pixels")?,
                row: table.row(i),
            })
        })();
        match spot {
            Ok(s) => spots.push(s),
            Err(p) => problems.push(p.in_run(&run)),
        }
    }
    let file = SpotFile {
        file: table.file.clone(),
        run,
        key_columns: names.key,
        frame_column: names.frame,
        track_column: names.track,
        position_column,
        spots,
    };
    (file, problems)
}

/// The run id of a tracker file: its name without the `.csv` extension.
pub fn run_id(file: &str) -> String {
    file.strip_suffix(".csv")
        .or_else(|| file.strip_suffix(".CSV"))
        .unwrap_or(file)
        .to_string()
}

/// Converts a tracker file into its run row and samples. Unlinked spots are left out. In a single
/// run the tracks are merged into particle 0 (see `merge_fragments`); in a collision run there must
/// be exactly two tracks, and the one starting at smaller z is the striker (particle 0), so
/// `direction` must point from striker to target.
pub fn calibrate(
    spots: &SpotFile,
    cal: &CheckedCalibration,
) -> Result<(RunRow, SampleFile), Problem> {
    let run: Arc<str> = Arc::from(spots.run.as_str());
    let linked: Vec<&Spot> = spots.spots.iter().filter(|s| s.track.is_some()).collect();
    let z_m = |s: &Spot| cal.direction * s.p_px * cal.m_per_px;
    let mut tracks: BTreeMap<i64, Vec<&Spot>> = BTreeMap::new();
    for s in &linked {
        tracks
            .entry(s.track.unwrap_or_default())
            .or_default()
            .push(s);
    }
    let particle_of: BTreeMap<i64, u32> = match cal.experiment {
        Experiment::Single => tracks.keys().map(|&id| (id, 0)).collect(),
        Experiment::Collision => {
            if tracks.len() != 2 {
                let ids: Vec<String> = tracks.keys().map(|id| id.to_string()).collect();
                return Err(Problem::at(
                    &spots.file,
                    1,
                    spots.track_column,
                    format!(
                        "{} linked tracks (ids {}) but a collision run needs two, striker and target",
                        tracks.len(),
                        if ids.is_empty() { "none".to_string() } else { ids.join(", ") }
                    ),
                    "link each sphere's spots into one track in the tracker and delete spurious tracks, or set calibration.experiment = \"single\"",
                )
                .in_run(&spots.run));
            }
            // The striker starts behind the target (smaller z at its first frame).
            let mut starts: Vec<(f64, i64)> = tracks
                .iter()
                .map(|(&id, ss)| {
                    let first = ss
                        .iter()
                        .min_by_key(|s| (s.frame, s.row))
                        .map_or(0.0, |s| z_m(s));
                    (first, id)
                })
                .collect();
            starts.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            starts
                .iter()
                .enumerate()
                .map(|(k, &(_, id))| (id, k as u32))
                .collect()
        }
    };
    let used = match cal.experiment {
        Experiment::Single => merge_fragments(&tracks),
        Experiment::Collision => linked,
    };
    let frame0 = used.iter().map(|s| s.frame).min().unwrap_or(0);
    let samples = used
        .iter()
        .map(|s| Sample {
            run: run.clone(),
            particle: particle_of[&s.track.unwrap_or_default()],
            frame: s.frame,
            t_s: (s.frame - frame0) as f64 / cal.fps,
            z_m: z_m(s),
            row: s.row,
        })
        .collect();
    let info = RunInfo {
        run: spots.run.clone(),
        experiment: cal.experiment,
        material: cal.material.clone(),
        diameter_m: cal.diameter_m,
        fps: cal.fps,
        setup: cal.setup,
        extra: BTreeMap::new(),
    };
    Ok((
        RunRow {
            info,
            file: spots.file.clone(),
            row: 1,
        },
        SampleFile {
            file: spots.file.clone(),
            key_columns: spots.key_columns,
            frame_column: spots.frame_column,
            particle_column: spots.track_column,
            time_column: spots.frame_column,
            position_column: spots.position_column,
            samples,
        },
    ))
}

/// The spots of a single run's one sphere from its tracks: trackers split one sphere's track into
/// fragments when it is briefly lost, and link the odd spurious detection into a short track. The
/// longest track is taken whole; each shorter one (longest first, then lower id) adds its spots in
/// frames not yet covered by an earlier track, and its other spots are left out as spurious.
fn merge_fragments<'a>(tracks: &BTreeMap<i64, Vec<&'a Spot>>) -> Vec<&'a Spot> {
    let mut order: Vec<(i64, &Vec<&'a Spot>)> = tracks.iter().map(|(&id, ss)| (id, ss)).collect();
    order.sort_by_key(|&(id, ss)| (std::cmp::Reverse(ss.len()), id));
    let mut covered: BTreeSet<i64> = BTreeSet::new();
    let mut kept = Vec::new();
    for (_, ss) in order {
        let fresh: Vec<&Spot> = ss
            .iter()
            .filter(|s| !covered.contains(&s.frame))
            .copied()
            .collect();
        covered.extend(fresh.iter().map(|s| s.frame));
        kept.extend(fresh);
    }
    kept
}
