//! Tracker spots (trackpy, TrackMate) in pixels and frames, and their conversion with a calibration
//! into one run of the interchange form.

use super::error::Problem;
use super::params::{Axis, CheckedCalibration};
use super::samples::{RunRow, Sample, SampleFile};
use crate::recording::{Experiment, RunInfo};
use std::collections::BTreeMap;
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
    pub spots: Vec<Spot>,
}

/// The run id of a tracker file: its name without the `.csv` extension.
pub fn run_id(file: &str) -> String {
    file.strip_suffix(".csv")
        .or_else(|| file.strip_suffix(".CSV"))
        .unwrap_or(file)
        .to_string()
}

/// The pixel coordinate column for `axis` among `(x column, y column)`.
pub fn axis_column(axis: Axis, columns: (&'static str, &'static str)) -> &'static str {
    match axis {
        Axis::X => columns.0,
        Axis::Y => columns.1,
    }
}

/// Converts a tracker file into its run row and samples. Unlinked spots are left out. In a single
/// run every linked track is the one particle 0 (trackers often split one sphere's track); in a
/// collision run there must be exactly two tracks, and the one starting at smaller z is the striker
/// (particle 0), so `direction` must point from striker to target.
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
    let frame0 = linked.iter().map(|s| s.frame).min().unwrap_or(0);
    let samples = linked
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
            samples,
        },
    ))
}
