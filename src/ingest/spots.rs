//! Tracker spots (trackpy, TrackMate) in pixels and frames, grouped into runs, and their conversion
//! with each run's calibration into the interchange form; tracks and spots left out are noted.

use super::error::Problem;
use super::params::Axis;
use super::samples::{RunRow, Sample, SampleFile};
use super::table::Table;
use crate::recording::{Experiment, RunInfo};
use crate::stats::{quantile_nearest, upper_median, MAD_TO_SIGMA};
use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

/// One detected spot: its track id (`None` if unlinked), frame, position along the groove axis
/// (`p_px`) and across it (`q_px`) in the file's units, and its row (line) in the file.
#[derive(Debug, Clone)]
pub struct Spot {
    pub track: Option<i64>,
    pub frame: i64,
    pub p_px: f64,
    pub q_px: f64,
    pub row: usize,
}

/// The spots of one run in a tracker file, and what reading left out of it.
#[derive(Debug, Clone)]
pub struct RunSpots {
    pub run: String,
    /// True if the run id is the file's name (one run per file), false if it came from a run column.
    pub named_by_file: bool,
    pub spots: Vec<Spot>,
    /// Tracks or spots left out while reading, said in words.
    pub notes: Vec<String>,
}

/// What a tracker file says about its own units: metres per position unit (TrackMate XML in a
/// length unit) and frames per second; `None` where the file does not say.
#[derive(Debug, Clone, Default)]
pub struct Units {
    pub m_per_unit: Option<f64>,
    pub fps: Option<f64>,
    /// The spatial unit as written in the file, for messages.
    pub spatial: String,
}

/// The runs of one tracker file.
#[derive(Debug, Clone)]
pub struct SpotFile {
    pub file: String,
    pub key_columns: &'static str,
    pub frame_column: &'static str,
    pub track_column: &'static str,
    /// The position column read (by the calibration's axis), named in errors.
    pub position_column: &'static str,
    pub runs: Vec<RunSpots>,
    pub units: Units,
}

/// The names of a tracker table's columns.
pub struct SpotColumns {
    pub track: &'static str,
    pub frame: &'static str,
    pub x: &'static str,
    pub y: &'static str,
    /// The columns that identify a spot, for messages about duplicates.
    pub key: &'static str,
    /// The column naming each row's run when one file holds several runs, if the table has it.
    pub run: Option<&'static str>,
}

/// Reads the spots of a tracker table. With a run column the rows are grouped by its value;
/// otherwise the file holds one run named after the file. Rows with problems are left out and
/// returned as problems of their run. An empty track id (or `None`, `NaN`) marks an unlinked spot.
pub fn read_spots(table: &Table, names: &SpotColumns, axis: Axis) -> (SpotFile, Vec<Problem>) {
    let file_run = run_id(&table.file);
    let run_col = names.run.filter(|c| table.has(c)).map(|c| table.col(c));
    let track = table.col(names.track);
    let frame = table.col(names.frame);
    let (along, across) = match axis {
        Axis::X => (table.col(names.x), table.col(names.y)),
        Axis::Y => (table.col(names.y), table.col(names.x)),
    };
    let mut runs: BTreeMap<String, Vec<Spot>> = BTreeMap::new();
    let mut problems = Vec::new();
    for i in 0..table.height() {
        let run = match &run_col {
            None => file_run.clone(),
            Some(c) => match c.text(i) {
                Some(r) => r.into_owned(),
                None => {
                    problems.push(c.problem(
                        i,
                        "is empty",
                        "write the id of the run (video) this row was tracked in",
                    ));
                    continue;
                }
            },
        };
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
                p_px: along.float(i, "write a finite number in pixels")?,
                q_px: across.float(i, "write a finite number in pixels")?,
                row: table.row(i),
            })
        })();
        match spot {
            Ok(s) => runs.entry(run).or_default().push(s),
            Err(p) => problems.push(p.in_run(&run)),
        }
    }
    let named_by_file = run_col.is_none();
    if named_by_file {
        runs.entry(file_run).or_default();
    }
    let file = SpotFile {
        file: table.file.clone(),
        key_columns: names.key,
        frame_column: names.frame,
        track_column: names.track,
        position_column: match axis {
            Axis::X => names.x,
            Axis::Y => names.y,
        },
        runs: runs
            .into_iter()
            .map(|(run, spots)| RunSpots {
                run,
                named_by_file,
                spots,
                notes: Vec::new(),
            })
            .collect(),
        units: Units::default(),
    };
    (file, problems)
}

/// The run id of a tracker file: its name without the extension (`.csv`, `.xml`).
pub fn run_id(file: &str) -> String {
    let lower = file.to_ascii_lowercase();
    for ext in [".csv", ".xml"] {
        if lower.ends_with(ext) {
            return file[..file.len() - ext.len()].to_string();
        }
    }
    file.to_string()
}

/// Everything a run's positions need to become metres and seconds, and its metadata.
#[derive(Debug, Clone, PartialEq)]
pub struct RunMeta {
    pub info: RunInfo,
    /// Metres per unit of the file's positions.
    pub m_per_px: f64,
    /// +1 or -1: the sign of z against the position along the axis.
    pub direction: f64,
}

/// A run converted to the interchange form, and the notes on what was left out.
pub type Calibrated = (RunRow, SampleFile, Vec<String>);

/// Converts one run of a tracker file into its run row and samples. Unlinked spots are left out.
/// In a single run the tracks are merged into particle 0 (see `merge_fragments`); in a collision
/// run there must be exactly two tracks, and the one starting at smaller z is the striker
/// (particle 0), so `direction` must point from striker to target. Every track or spot left out
/// is said in the notes.
pub fn calibrate(file: &SpotFile, rs: &RunSpots, meta: &RunMeta) -> Result<Calibrated, Problem> {
    let run: Arc<str> = Arc::from(meta.info.run.as_str());
    let mut notes = rs.notes.clone();
    let unlinked = rs.spots.iter().filter(|s| s.track.is_none()).count();
    if unlinked > 0 {
        notes.push(format!(
            "{unlinked} unlinked spots left out (no {}): the tracker did not link them into a track",
            file.track_column
        ));
    }
    let z_m = |s: &Spot| meta.direction * s.p_px * meta.m_per_px;
    let mut tracks: BTreeMap<i64, Vec<&Spot>> = BTreeMap::new();
    for s in &rs.spots {
        if let Some(id) = s.track {
            tracks.entry(id).or_default().push(s);
        }
    }
    for (id, ss) in &tracks {
        let mut frames = BTreeSet::new();
        if let Some(twice) = ss.iter().find(|s| !frames.insert(s.frame)) {
            let first = ss
                .iter()
                .find(|s| s.frame == twice.frame)
                .map_or(0, |s| s.row);
            let fix = match rs.named_by_file {
                true => "if the file holds several runs (videos), add a column `run` naming each row's run, or write one file per run (see README, Tracker exports); otherwise delete one of the two rows",
                false => "check that each run's rows carry the right run id; otherwise delete one of the two rows",
            };
            return Err(Problem::at(
                &file.file,
                twice.row,
                file.key_columns,
                format!(
                    "track {id} has two spots in frame {} (rows {first} and {}) in run {:?}",
                    twice.frame, twice.row, meta.info.run
                ),
                fix,
            )
            .in_run(&meta.info.run));
        }
    }
    let particle_of: BTreeMap<i64, u32> = match meta.info.experiment {
        Experiment::Single => tracks.keys().map(|&id| (id, 0)).collect(),
        Experiment::Collision => {
            if tracks.len() != 2 {
                let ids: Vec<String> = tracks.keys().map(|id| id.to_string()).collect();
                return Err(Problem::at(
                    &file.file,
                    1,
                    file.track_column,
                    format!(
                        "{} linked tracks (ids {}) in run {:?} but a collision run needs two, striker and target",
                        tracks.len(),
                        if ids.is_empty() { "none".to_string() } else { ids.join(", ") },
                        meta.info.run
                    ),
                    "link each sphere's spots into one track in the tracker and delete spurious tracks, or set the run's experiment to single",
                )
                .in_run(&meta.info.run));
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
    let used = match meta.info.experiment {
        Experiment::Single => merge_fragments(&tracks, &mut notes),
        Experiment::Collision => tracks.values().flatten().copied().collect(),
    };
    let frame0 = used.iter().map(|s| s.frame).min().unwrap_or(0);
    let samples = used
        .iter()
        .map(|s| Sample {
            run: run.clone(),
            particle: particle_of[&s.track.unwrap_or_default()],
            frame: s.frame,
            t_s: (s.frame - frame0) as f64 / meta.info.fps,
            z_m: z_m(s),
            row: s.row,
        })
        .collect();
    Ok((
        RunRow {
            info: meta.info.clone(),
            file: file.file.clone(),
            row: 1,
        },
        SampleFile {
            file: file.file.clone(),
            key_columns: file.key_columns,
            frame_column: file.frame_column,
            particle_column: file.track_column,
            time_column: file.frame_column,
            position_column: file.position_column,
            samples,
        },
        notes,
    ))
}

/// The spots of a single run's one sphere from its tracks: trackers split one sphere's track into
/// fragments when it is briefly lost, and link the odd spurious detection (dust, a reflection)
/// into a track of its own, sometimes longer than the sphere's. The track that moves most along
/// the axis is taken whole; each other one (moving most first, then longest, then lower id) adds
/// its spots in frames not yet covered by an earlier track, and its other spots are left out as
/// spurious. A track that moves no more than its own noise along the axis (a still object) is
/// left out whole while another track moves. Each track left out, in part or whole, is said in
/// `notes`, one line per track.
fn merge_fragments<'a>(
    tracks: &BTreeMap<i64, Vec<&'a Spot>>,
    notes: &mut Vec<String>,
) -> Vec<&'a Spot> {
    // (id, spots, span along the axis, still)
    let mut order: Vec<(i64, &Vec<&'a Spot>, f64, bool)> = tracks
        .iter()
        .map(|(&id, ss)| {
            let mut by_frame = ss.clone();
            by_frame.sort_by_key(|s| s.frame);
            let p: Vec<f64> = by_frame.iter().map(|s| s.p_px).collect();
            let span = spread(&p);
            let still = p.len() >= 5 && span <= STILL_FACTOR * noise(&p);
            (id, ss, span, still)
        })
        .collect();
    order.sort_by(|a, b| {
        b.2.total_cmp(&a.2)
            .then(b.1.len().cmp(&a.1.len()))
            .then(a.0.cmp(&b.0))
    });
    let Some(&(first, _, first_span, _)) = order.first() else {
        return Vec::new();
    };
    let mut covered: BTreeSet<i64> = BTreeSet::new();
    let mut kept = Vec::new();
    for (id, ss, span, still) in order {
        let lo = ss.iter().map(|s| s.frame).min().unwrap_or(0);
        let hi = ss.iter().map(|s| s.frame).max().unwrap_or(0);
        if still && id != first {
            notes.push(format!(
                "track {id} ({} spots, frames {lo}–{hi}) left out: it moves {span:.3} units along the axis, no more than its noise (a still object, not the kicked sphere); track {first}, which moves {first_span:.3}, is taken",
                ss.len()
            ));
            continue;
        }
        let fresh: Vec<&Spot> = ss
            .iter()
            .filter(|s| !covered.contains(&s.frame))
            .copied()
            .collect();
        let dropped = ss.len() - fresh.len();
        if dropped > 0 {
            let what = match fresh.len() {
                0 => format!("track {id} ({} spots, frames {lo}–{hi}) left out", ss.len()),
                n => format!(
                    "{dropped} of the {} spots of track {id} (frames {lo}–{hi}) left out, {n} kept",
                    ss.len()
                ),
            };
            notes.push(format!(
                "{what}: a track that moves more (track {first}) already has a spot in those frames, so they are taken as spurious detections"
            ));
        }
        covered.extend(fresh.iter().map(|s| s.frame));
        kept.extend(fresh);
    }
    kept
}

/// A track that spans no more than this many times its frame-to-frame noise along the axis is
/// still.
const STILL_FACTOR: f64 = 10.0;

/// How much a run's longest track moves along and across the chosen axis, against its noise.
#[derive(Debug, Clone, Copy)]
pub struct Motion {
    /// Range of the position along the chosen axis (robust: 2nd to 98th percentile), file units.
    pub along: f64,
    /// The same across it.
    pub across: f64,
    /// Frame-to-frame noise along the axis (from second differences), file units.
    pub noise_along: f64,
}

/// The motion of a run's track that moves most (among tracks of 5 spots or more), or `None` if
/// no track has 5 spots.
pub fn motion(rs: &RunSpots) -> Option<Motion> {
    let mut tracks: BTreeMap<i64, Vec<&Spot>> = BTreeMap::new();
    for s in &rs.spots {
        if let Some(id) = s.track {
            tracks.entry(id).or_default().push(s);
        }
    }
    tracks
        .into_values()
        .filter(|ss| ss.len() >= 5)
        .map(|mut ss| {
            ss.sort_by_key(|s| s.frame);
            let p: Vec<f64> = ss.iter().map(|s| s.p_px).collect();
            let q: Vec<f64> = ss.iter().map(|s| s.q_px).collect();
            Motion {
                along: spread(&p),
                across: spread(&q),
                noise_along: noise(&p),
            }
        })
        .max_by(|a, b| a.along.max(a.across).total_cmp(&b.along.max(b.across)))
}

/// The 2nd-to-98th percentile range.
fn spread(x: &[f64]) -> f64 {
    let mut s = x.to_vec();
    s.sort_by(f64::total_cmp);
    quantile_nearest(&s, 0.98) - quantile_nearest(&s, 0.02)
}

/// The noise of a smooth series from its second differences: 1.4826 · MAD / √6, both medians
/// the upper median (the convention this detector was calibrated with).
fn noise(x: &[f64]) -> f64 {
    let mut d: Vec<f64> = x.windows(3).map(|w| w[0] - 2.0 * w[1] + w[2]).collect();
    if d.is_empty() {
        return 0.0;
    }
    let med = upper_median(&mut d);
    let mut dev: Vec<f64> = d.iter().map(|v| (v - med).abs()).collect();
    MAD_TO_SIGMA * upper_median(&mut dev) / 6f64.sqrt()
}
