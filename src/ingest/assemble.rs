//! Cross-table checks (runs in both tables, unique runs and samples, enough frames) and the
//! assembly of checked samples into one `Recording` per run, sorted by run, particle and frame.

use super::error::Problem;
use super::samples::{RunRow, Sample, SampleFile};
use super::sanity;
use crate::recording::{Experiment, Recording, Track};
use std::collections::{BTreeMap, BTreeSet};

/// The particles a run of `experiment` must record, with their role for messages.
fn particles(experiment: Experiment) -> &'static [(u32, &'static str)] {
    match experiment {
        Experiment::Single => &[(0, "the particle")],
        Experiment::Collision => &[(0, "the striker"), (1, "the target")],
    }
}

/// Checks `runs` against `files` and builds the recordings of runs without problems. `problems`
/// holds what reading found so far; runs named there are known (not "missing") but not assembled.
pub fn assemble(
    runs: &[RunRow],
    files: &[SampleFile],
    min_frames: usize,
    problems: &mut Vec<Problem>,
) -> Vec<Recording> {
    let mut by_run: BTreeMap<&str, &RunRow> = BTreeMap::new();
    for r in runs {
        if let Some(first) = by_run.get(r.info.run.as_str()) {
            problems.push(
                Problem::at(
                    &r.file,
                    r.row,
                    "run",
                    format!(
                        "run {:?} is listed twice (also row {})",
                        r.info.run, first.row
                    ),
                    "give each run a unique id, or delete the duplicate row",
                )
                .in_run(&r.info.run),
            );
        } else {
            by_run.insert(&r.info.run, r);
        }
    }
    // Runs named by a reading problem exist, even if their row could not be read.
    let known_bad: BTreeSet<String> = problems.iter().filter_map(|p| p.run.clone()).collect();

    // Every run's samples, with the file they came from.
    let mut samples: BTreeMap<&str, Vec<(&SampleFile, &Sample)>> = BTreeMap::new();
    for f in files {
        for s in &f.samples {
            samples.entry(&s.run).or_default().push((f, s));
        }
    }
    for (run, ss) in &samples {
        if !by_run.contains_key(run) && !known_bad.contains(*run) {
            let Some(&(f, first)) = ss.iter().min_by_key(|(f, s)| (&f.file, s.row)) else {
                continue;
            };
            let runs_file = runs.first().map_or("runs.csv", |r| r.file.as_str());
            problems.push(
                Problem::at(
                    &f.file,
                    first.row,
                    "run",
                    format!("run {run:?} is not in {runs_file}"),
                    format!(
                        "add a row for it to {runs_file}, or delete its {} rows",
                        ss.len()
                    ),
                )
                .in_run(run),
            );
        }
    }
    for (run, r) in &by_run {
        if !samples.contains_key(run) && !known_bad.contains(*run) {
            let trajectories = files
                .first()
                .map_or("trajectories.csv", |f| f.file.as_str());
            problems.push(
                Problem::at(
                    &r.file,
                    r.row,
                    "run",
                    format!("run {run:?} has no rows in {trajectories}"),
                    format!("add its trajectory to {trajectories}, or delete this row"),
                )
                .in_run(run),
            );
        }
    }

    let mut recordings = Vec::new();
    for (run, r) in &by_run {
        let Some(ss) = samples.get_mut(run) else {
            continue;
        };
        let before = problems.len();
        let tracks = tracks_of(r, ss, min_frames, problems);
        // A run with a reading problem is not assembled either: its rows are incomplete.
        if problems.len() == before && !known_bad.contains(*run) {
            recordings.push(Recording {
                info: r.info.clone(),
                tracks,
            });
        }
    }
    recordings
}

/// Sorts a run's samples into tracks, reporting unknown particles, duplicate frames and tracks
/// with too few frames.
fn tracks_of(
    r: &RunRow,
    ss: &mut [(&SampleFile, &Sample)],
    min_frames: usize,
    problems: &mut Vec<Problem>,
) -> Vec<Track> {
    let run = r.info.run.as_str();
    ss.sort_by(|(fa, a), (fb, b)| {
        (a.particle, a.frame, &fa.file, a.row).cmp(&(b.particle, b.frame, &fb.file, b.row))
    });
    let wanted = particles(r.info.experiment);
    let before = problems.len();
    let mut tracks: Vec<Track> = Vec::new();
    for pair in ss.iter() {
        let (f, s) = *pair;
        let range = sanity::time(s.t_s)
            .map_err(|c| (f.time_column, c))
            .and_then(|()| sanity::position(s.z_m).map_err(|c| (f.position_column, c)));
        if let Err((column, (message, fix))) = range {
            problems.push(Problem::at(&f.file, s.row, column, message, fix).in_run(run));
            continue;
        }
        if !wanted.iter().any(|(p, _)| *p == s.particle) {
            let kind = match r.info.experiment {
                Experiment::Single => "a single run has only particle 0",
                Experiment::Collision => "a collision run has particles 0 (striker) and 1 (target)",
            };
            problems.push(
                Problem::at(
                    &f.file,
                    s.row,
                    f.particle_column,
                    format!("particle {} in run {run:?}, but {kind}", s.particle),
                    format!(
                        "renumber the particles, or correct the run's experiment in {}",
                        r.file
                    ),
                )
                .in_run(run),
            );
            continue;
        }
        match tracks.last_mut() {
            Some(t) if t.particle == s.particle => {
                if t.frame.last() == Some(&s.frame) {
                    let first = ss
                        .iter()
                        .find(|(_, o)| o.particle == s.particle && o.frame == s.frame)
                        .map_or(0, |(_, o)| o.row);
                    problems.push(
                        Problem::at(
                            &f.file,
                            s.row,
                            f.key_columns,
                            format!(
                                "duplicate of row {first}: run {run:?}, particle {}, frame {} appears twice",
                                s.particle, s.frame
                            ),
                            "delete one of the two rows",
                        )
                        .in_run(run),
                    );
                    continue;
                }
                t.frame.push(s.frame);
                t.t_s.push(s.t_s);
                t.z_m.push(s.z_m);
            }
            _ => tracks.push(Track {
                particle: s.particle,
                frame: vec![s.frame],
                t_s: vec![s.t_s],
                z_m: vec![s.z_m],
            }),
        }
    }
    let Some(&(first_file, first)) = ss.iter().min_by_key(|(f, s)| (&f.file, s.row)) else {
        return tracks;
    };
    for (particle, role) in wanted {
        let n = tracks
            .iter()
            .find(|t| t.particle == *particle)
            .map_or(0, |t| t.frame.len());
        if n < min_frames {
            problems.push(
                Problem::at(
                    &first_file.file,
                    first.row,
                    first_file.frame_column,
                    format!(
                        "run {run:?} has {n} frames of particle {particle} ({role}), fewer than min_frames = {min_frames}"
                    ),
                    "record more frames of it, or lower min_frames in the ingest params",
                )
                .in_run(run),
            );
        }
    }
    if problems.len() == before {
        problems.extend(sanity::clock(r, ss));
    }
    tracks
}
