//! Catches a wrong calibration axis of tracker exports: a particle that moves more across the
//! chosen image axis than along it, or not beyond its noise along it, was filmed along the other.

use super::error::Problem;
use super::params::Axis;
use super::spots::{motion, Motion, SpotFile};

/// Motion along the axis up to this many times its frame-to-frame noise is "at the noise level".
const NOISE_FACTOR: f64 = 10.0;

/// How many runs a message names before summarising the rest.
const NAMED: usize = 8;

/// Why a run's motion says the axis is wrong, or `None` if it looks right.
fn wrong(m: &Motion) -> Option<&'static str> {
    if m.across > m.along {
        Some("moves more across")
    } else if m.along <= NOISE_FACTOR * m.noise_along {
        Some("moves no more than its noise along")
    } else {
        None
    }
}

fn name(axis: Axis) -> &'static str {
    match axis {
        Axis::X => "x",
        Axis::Y => "y",
    }
}

/// Problems for runs whose motion says the calibration axis is wrong. When half the runs or more
/// say so, it is one problem of the calibration (never skipped); otherwise one per run.
pub fn check(files: &[SpotFile], axis: Axis) -> Option<Vec<Problem>> {
    let other = match axis {
        Axis::X => Axis::Y,
        Axis::Y => Axis::X,
    };
    let (a, o) = (name(axis), name(other));
    let mut measured = 0;
    let mut flagged: Vec<(String, String, String)> = Vec::new();
    for f in files {
        for rs in &f.runs {
            let Some(m) = motion(rs) else { continue };
            measured += 1;
            if let Some(why) = wrong(&m) {
                flagged.push((
                    rs.run.clone(),
                    f.file.clone(),
                    format!(
                        "{why} the image {a} axis: it spans {:.3} units along {a} (noise {:.3}) and {:.3} along {o}",
                        m.along, m.noise_along, m.across
                    ),
                ));
            }
        }
    }
    if flagged.is_empty() {
        return None;
    }
    let fix = format!(
        "the groove probably runs along image {o}: set calibration.axis = \"{o}\" in the ingest params of pipeline.toml (and check calibration.direction)"
    );
    if 2 * flagged.len() >= measured {
        let mut names: Vec<String> = flagged
            .iter()
            .take(NAMED)
            .map(|(run, _, why)| format!("{run:?} {why}"))
            .collect();
        if flagged.len() > NAMED {
            names.push(format!("and {} more", flagged.len() - NAMED));
        }
        return Some(vec![Problem::file(
            "pipeline.toml",
            format!(
                "calibration.axis = \"{a}\" looks wrong: in {} of {measured} runs the particle does not move along image {a}: {}",
                flagged.len(),
                names.join("; ")
            ),
            fix,
        )]);
    }
    Some(
        flagged
            .into_iter()
            .map(|(run, file, why)| {
                Problem::file(
                    &file,
                    format!("in run {run:?} the particle {why}"),
                    format!("{fix}, or leave the run out (skip_bad_runs = true) if it recorded no kicked sphere"),
                )
                .in_run(&run)
            })
            .collect(),
    )
}
