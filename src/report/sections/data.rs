//! Section 2: the data — runs per material and setup, frame rates, noise, what was left out and why.

use super::{Block, Table};
use crate::artifacts::FitStatus;
use crate::artifacts::Summary;
use crate::recording::{Experiment, Setup};
use crate::report::inputs::ReportData;
use crate::report::value::sig;
use std::collections::BTreeMap;

fn median(mut xs: Vec<f64>) -> Option<f64> {
    xs.retain(|x| x.is_finite());
    if xs.is_empty() {
        return None;
    }
    Some(crate::stats::median_in_place(&mut xs))
}

/// The plain-language notes of summary.json (top level and collisions), in order.
fn summary_notes(s: &Summary) -> Vec<String> {
    let mut out = s.notes.clone();
    if let Some(c) = &s.collisions {
        out.extend(c.notes.iter().cloned());
    }
    out
}

/// Per (experiment, material, setup): runs, frame rates, samples per run, duration per run.
type Group = (usize, Vec<f64>, Vec<f64>, Vec<f64>);

/// The recordings grouped by experiment, material and setup.
fn run_groups(d: &ReportData) -> BTreeMap<(String, String, String), Group> {
    let mut groups: BTreeMap<(String, String, String), Group> = BTreeMap::new();
    for r in d.recordings.values() {
        let exp = match r.info.experiment {
            Experiment::Single => "single",
            Experiment::Collision => "collision",
        };
        let setup = match r.info.setup {
            Some(Setup::Rolling) => "rolling",
            Some(Setup::Contact) => "contact",
            None => "—",
        };
        let g = groups
            .entry((exp.into(), r.info.material.clone(), setup.into()))
            .or_default();
        g.0 += 1;
        g.1.push(r.info.fps);
        let frames: usize = r.tracks.iter().map(|t| t.frame.len()).sum();
        g.2.push(frames as f64);
        let dur = r
            .tracks
            .iter()
            .filter_map(|t| Some(t.t_s.last()? - t.t_s.first()?))
            .fold(0.0, f64::max);
        g.3.push(dur);
    }
    groups
}

/// The table of runs per experiment, material and setup.
fn runs_table(groups: &BTreeMap<(String, String, String), Group>) -> Table {
    let mut t = Table::new(
        "Runs per experiment, material and setup",
        &[
            "experiment",
            "material",
            "setup",
            "runs",
            "frame rate (fps)",
            "samples per run (median)",
            "duration (ms, median)",
        ],
    );
    for ((exp, mat, setup), (n, fps, frames, dur)) in groups {
        let (lo, hi) = fps
            .iter()
            .fold((f64::INFINITY, 0.0_f64), |(a, b), &x| (a.min(x), b.max(x)));
        let fps_txt = if (hi - lo).abs() < 1e-9 {
            sig(lo, 5)
        } else {
            format!("{}–{}", sig(lo, 5), sig(hi, 5))
        };
        t.push(vec![
            exp.clone(),
            mat.clone(),
            setup.clone(),
            n.to_string(),
            fps_txt,
            median(frames.clone()).map_or("—".into(), |x| format!("{x:.0}")),
            median(dur.clone()).map_or("—".into(), |x| format!("{:.1}", x * 1e3)),
        ]);
    }
    t
}

/// The single runs whose fit is not converged, each with why it is left out of the aggregates
/// (the aggregate stage lists the runs it left out with the reason, `left_out` per material).
fn failed_singles(d: &ReportData) -> Vec<(String, String)> {
    let left_out_why = |run: &str| -> Option<String> {
        let single = d.summary.as_ref()?.single.as_ref()?;
        single
            .materials
            .values()
            .flat_map(|m| &m.left_out)
            .find(|l| l.run == run)
            .map(|l| l.why.clone())
    };
    d.singles
        .iter()
        .filter(|r| !r.converged())
        .map(|r| {
            let why = match (r.status, left_out_why(&r.run)) {
                (FitStatus::Suspect, Some(w)) => {
                    format!("fit suspect: {w}; excluded from the aggregates")
                }
                (FitStatus::Suspect, None) => "fit suspect; excluded from the aggregates".into(),
                _ => "fit did not converge; excluded from the aggregates".into(),
            };
            (format!("{} ({})", r.run, r.status), why)
        })
        .collect()
}

pub fn block(d: &ReportData) -> Block {
    let mut b = Block::new("data", "2. The data");
    let groups = run_groups(d);
    if groups.is_empty() {
        b.missing =
            Some("no recordings reached the report (the ingest stage's runs are empty)".into());
        return b;
    }
    let n_coll = d.collisions.len();
    let noise = median(d.singles.iter().filter_map(|r| r.rms_m).collect());
    b.lead = Some(format!(
        "{} with a baseline fit and {}, materials {}{}.",
        crate::report::value::count(d.singles.len(), "single-particle run"),
        crate::report::value::count(n_coll, "collision run"),
        d.materials().join(", "),
        noise.map_or(String::new(), |rms| format!(
            "; the single runs' positions scatter {:.2} µm about their fits (the median residual RMS of the robust baseline fits, where a few tracking outliers per run are down-weighted, not removed)",
            rms * 1e6
        ))
    ));
    b.table(runs_table(&groups));
    let n_neg = d.singles.iter().filter(|r| r.v0_mps.value < 0.0).count();
    if !d.singles.is_empty() {
        b.para(format!(
            "Single runs moving in −z: {n_neg} of {}; the fits handle both directions.",
            d.singles.len()
        ));
    }
    let failed = failed_singles(d);
    let coll_failed: Vec<String> = d
        .collisions
        .iter()
        .filter(|c| !c.usable())
        .map(|c| format!("{} ({})", c.run, c.status))
        .collect();
    if let Some(notes) = d
        .summary
        .as_ref()
        .map(summary_notes)
        .filter(|n| !n.is_empty())
    {
        let notes: Vec<String> = notes
            .iter()
            .map(|n| {
                if n.ends_with('.') {
                    n.clone()
                } else {
                    format!("{n}.")
                }
            })
            .collect();
        b.para(format!("Notes of the aggregate stage: {}", notes.join(" ")));
    }
    if d.skipped.is_empty() && failed.is_empty() && coll_failed.is_empty() {
        b.para("Nothing was left out: every run was ingested and every single-run fit converged.");
    } else {
        let mut s = Table::new("Left out", &["run", "why"]);
        for (run, why) in &d.skipped {
            let at = if why.starts_with("track ") || why.contains(" spots ") {
                "left out at ingest (the run is kept)"
            } else {
                "skipped at ingest"
            };
            s.push(vec![run.clone(), format!("{at}: {why}")]);
        }
        for (f, why) in failed {
            s.push(vec![f, why]);
        }
        b.table(s);
    }
    b
}
