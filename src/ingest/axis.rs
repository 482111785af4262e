//! Catches a wrong calibration axis of tracker exports: a particle that moves more across the
//! chosen image axis than along it, or not beyond its noise along it, was filmed along the other.
//! The other axis is advised only when the runs move clearly more along it (both axes' spans
//! decide, so the advice cannot flip with the axis chosen); tracks that wander about as much
//! along both (cells, colloids) get no axis advice but the doubt that they are groove recordings.

use super::error::Problem;
use super::params::Axis;
use super::spots::{motion, Motion, SpotFile};

/// Motion along the axis up to this many times its frame-to-frame noise is "at the noise level".
const NOISE_FACTOR: f64 = 10.0;

/// How many runs a message names before summarising the rest.
const NAMED: usize = 8;

/// The median run must span this many times more along one axis than the other for that axis to
/// be the groove's.
const DOMINANT: f64 = 2.0;

/// Which image axis the runs' motion points to, from the median ratio of their spans.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Verdict {
    /// The chosen axis: the runs move along it.
    Chosen,
    /// The other axis: the runs move clearly more along it.
    Other,
    /// Neither: the runs move about as much along both (median across/along ratio).
    Neither(f64),
}

fn verdict(ratios: &mut [f64]) -> Verdict {
    if ratios.is_empty() {
        return Verdict::Chosen;
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    if median >= DOMINANT {
        Verdict::Other
    } else if median <= 1.0 / DOMINANT {
        Verdict::Chosen
    } else {
        Verdict::Neither(median)
    }
}

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
    let mut ratios = Vec::new();
    let mut flagged: Vec<(String, String, String)> = Vec::new();
    for f in files {
        for rs in &f.runs {
            let Some(m) = motion(rs) else { continue };
            measured += 1;
            ratios.push(m.across / m.along);
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
    let verdict = verdict(&mut ratios);
    let fix = match verdict {
        Verdict::Other => format!(
            "the groove probably runs along image {o}: set calibration.axis = \"{o}\" in the ingest params of pipeline.toml (and check calibration.direction)"
        ),
        Verdict::Chosen => format!(
            "most runs move along image {a}, so the axis is right; check this run's tracking"
        ),
        Verdict::Neither(r) => format!(
            "the runs move about as much along image {o} as along {a} (median span ratio {r:.2}), as cells or colloids do, not a sphere rolling along a groove: check that the export holds this experiment's runs (the axis cannot be told from them)"
        ),
    };
    if 2 * flagged.len() >= measured && verdict != Verdict::Chosen {
        let mut names: Vec<String> = flagged
            .iter()
            .take(NAMED)
            .map(|(run, _, why)| format!("{run:?} {why}"))
            .collect();
        if flagged.len() > NAMED {
            names.push(format!("and {} more", flagged.len() - NAMED));
        }
        let doubt = match verdict {
            Verdict::Other => "looks wrong",
            _ => "cannot be confirmed",
        };
        return Some(vec![Problem::file(
            "pipeline.toml",
            format!(
                "calibration.axis = \"{a}\" {doubt}: in {} of {measured} runs the particle does not move along image {a}: {}",
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
