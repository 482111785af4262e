//! Running one drawn case through the whole pipeline (`groove run` in a scratch folder) and
//! turning its diagnosis.json into a result record.

use super::cli::{command, said, RUN_IN_PROJECT};
use super::draw::Case;
use super::score::{accepted, score};
use super::table::Record;
use crate::indsim::writer::write_dataset;
use std::path::Path;
use std::time::Instant;

/// The discover stage's time from `groove run`'s log ("discover: ran in 12.34 s").
pub fn discover_seconds(log: &str) -> Option<f64> {
    log.lines()
        .filter_map(|l| l.split("discover: ran in ").nth(1))
        .filter_map(|rest| rest.split_whitespace().next()?.parse().ok())
        .next_back()
}

/// Writes the case's dataset under `dir/data` and its truth to `dir/truth.json` (beside, not
/// inside, the dataset), runs `groove` with `pipeline` and scores the diagnosis.
pub fn run_case(
    case: &Case,
    quick: bool,
    groove: &Path,
    pipeline: &Path,
    dir: &Path,
) -> Result<Record, String> {
    let data = dir.join("data");
    let reports = dir.join("reports");
    let io = |e: std::io::Error| format!("{}: {e}", dir.display());
    std::fs::create_dir_all(dir).map_err(io)?;
    write_dataset(&data, &case.spec.render(false)).map_err(io)?;
    let truth = serde_json::to_string_pretty(&case.truths).map_err(|e| e.to_string())?;
    std::fs::write(dir.join("truth.json"), truth).map_err(io)?;
    std::fs::copy(pipeline, dir.join("pipeline.toml")).map_err(io)?;
    let started = Instant::now();
    let out = command(groove, dir, &RUN_IN_PROJECT)
        .output()
        .map_err(|e| format!("cannot start {}: {e}", groove.display()))?;
    let run_s = started.elapsed().as_secs_f64();
    let log = said(&out);
    std::fs::write(dir.join("run.log"), &log).map_err(io)?;
    let mut record = Record {
        index: case.index,
        quick,
        noise: case.noise.clone(),
        places: case.truths.iter().map(|t| t.place.clone()).collect(),
        shapes: case.truths.iter().map(|t| t.shape.clone()).collect(),
        multiples: case
            .truths
            .iter()
            .map(|t| (t.multiple * 100.0).round() / 100.0)
            .collect(),
        sizes: case.truths.iter().map(|t| t.sizes.clone()).collect(),
        status: "ok".to_string(),
        named: false,
        sized: false,
        false_accept: false,
        accepted: Vec::new(),
        estimates: Vec::new(),
        discover_s: discover_seconds(&log),
        run_s: (run_s * 10.0).round() / 10.0,
    };
    if !out.status.success() {
        let tail: Vec<&str> = log.lines().rev().take(3).collect();
        record.status = format!("groove run failed ({}): {}", out.status, tail.join(" / "));
        return Ok(record);
    }
    let text = std::fs::read_to_string(reports.join("diagnosis.json")).map_err(io)?;
    let found = accepted(&text)?;
    let s = score(&found, &case.truths);
    record.named = s.named;
    record.sized = s.sized;
    record.false_accept = s.false_accept;
    record.accepted = found
        .iter()
        .map(|a| format!("{}/{}: {}", a.place, a.effect, a.form))
        .collect();
    record.estimates = found.iter().map(|a| a.parameters.clone()).collect();
    Ok(record)
}
