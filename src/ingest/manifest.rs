//! The per-run metadata of tracker exports: a `runs.csv` manifest beside the exports, or
//! `runs = [...]` in the ingest params. Each row names a run (and, optionally, the file holding
//! it) and gives what trackers do not record: material, diameter, frame rate, experiment, setup.
//! A value a row leaves empty is taken from the calibration in the ingest params.

use super::error::Problem;
use super::interchange::{experiment_of, extra_of, rows_by_run, setup_of};
use super::params::{Calibration, IngestParams, RunEntry};
use super::spots::{RunMeta, Units};
use super::table::Table;
use crate::recording::RunInfo;
use std::collections::BTreeMap;

/// The manifest's file name beside tracker exports.
pub const FILE: &str = "runs.csv";

/// The columns of runs.csv that groove interprets; any other column is kept as text.
const KNOWN: [&str; 7] = [
    "run",
    "file",
    "material",
    "diameter_m",
    "fps",
    "experiment",
    "setup",
];

/// One row of the manifest: its values, the columns groove does not interpret, and where it is.
#[derive(Debug, Clone)]
pub struct Entry {
    pub values: RunEntry,
    pub extra: BTreeMap<String, String>,
    /// Row in runs.csv (1 for params entries).
    pub row: usize,
}

/// The manifest: where it was written (`runs.csv` or `pipeline.toml`) and its rows.
#[derive(Debug, Clone)]
pub struct Manifest {
    pub source: String,
    pub entries: Vec<Entry>,
}

impl Manifest {
    /// The run a file of one run holds: the row naming the file in its `file` column, else the file's own name.
    pub fn run_of_file(&self, file: &str, default: &str) -> String {
        self.entries
            .iter()
            .find(|e| e.values.file.as_deref() == Some(file))
            .map_or_else(|| default.to_string(), |e| e.values.run.clone())
    }

    /// The row of `run`.
    pub fn entry(&self, run: &str) -> Option<&Entry> {
        self.entries.iter().find(|e| e.values.run == run)
    }
}

/// The manifest of a tracker dataset, if any: `runs.csv` in the folder or `runs` in the params
/// (not both), with the problems of its rows.
pub fn load(
    files: &BTreeMap<String, Vec<u8>>,
    params: &IngestParams,
) -> Result<(Option<Manifest>, Vec<Problem>), Problem> {
    let csv = files.get(FILE);
    match (csv, params.runs.is_empty()) {
        (Some(_), false) => Err(Problem::file(
            FILE,
            "the runs of the tracker exports are given twice, in runs.csv and in the ingest params (runs = [...])",
            "keep one of the two",
        )),
        (None, true) => Ok((None, Vec::new())),
        (None, false) => Ok((
            Some(Manifest {
                source: "pipeline.toml".into(),
                entries: params
                    .runs
                    .iter()
                    .map(|r| Entry {
                        values: r.clone(),
                        extra: BTreeMap::new(),
                        row: 1,
                    })
                    .collect(),
            }),
            Vec::new(),
        )),
        (Some(bytes), true) => {
            let table = Table::from_csv(FILE, bytes)?;
            table.require(&[("run", "the id of each run")])?;
            let (entries, problems) = read_rows(&table);
            Ok((
                Some(Manifest {
                    source: FILE.into(),
                    entries,
                }),
                problems,
            ))
        }
    }
}

fn read_rows(table: &Table) -> (Vec<Entry>, Vec<Problem>) {
    let extra_columns: Vec<&String> = table
        .names
        .iter()
        .filter(|n| !KNOWN.contains(&n.as_str()))
        .collect();
    // the row each run was first listed in
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    let (entries, problems) = rows_by_run(table, |i, run| {
        if let Some(first) = seen.get(run) {
            return Err(table.problem(
                "run",
                i,
                format!("run {run:?} is listed twice (also row {first})"),
                "give each run one row",
            ));
        }
        let values = row(table, i, run)?;
        seen.insert(run.to_string(), table.row(i));
        Ok(Entry {
            values,
            extra: extra_of(table, i, &extra_columns),
            row: table.row(i),
        })
    });
    (entries, problems)
}

fn row(table: &Table, i: usize, run: &str) -> Result<RunEntry, Problem> {
    let positive = |column: &str, what: &str| -> Result<Option<f64>, Problem> {
        if table.text(column, i).is_none() {
            return Ok(None);
        }
        let fix =
            format!("write {what}, a positive number, or leave it empty to use the calibration");
        let x = table.float(column, i, &fix)?;
        if x <= 0.0 {
            return Err(table.problem(column, i, format!("{x} is not positive"), fix));
        }
        Ok(Some(x))
    };
    let experiment = table
        .text("experiment", i)
        .map(|s| experiment_of(table, i, &s))
        .transpose()?;
    let setup = setup_of(table, i)?;
    Ok(RunEntry {
        run: run.to_string(),
        file: table.text("file", i).map(|s| s.into_owned()),
        material: table.text("material", i).map(|s| s.into_owned()),
        diameter_m: positive("diameter_m", "the particle diameter in metres")?,
        fps: positive("fps", "the camera frame rate in frames per second")?,
        experiment,
        setup,
    })
}

/// A run's metadata and calibration: the manifest row's values first, then what the file says of
/// its own units (positions in a length unit; the frame interval only where neither the manifest
/// nor the params give fps), then the calibration in the params.
pub fn resolve(
    run: &str,
    file: &str,
    manifest: Option<&Manifest>,
    cal: &Calibration,
    units: &Units,
) -> Result<RunMeta, Problem> {
    let entry = manifest.and_then(|m| m.entry(run));
    if let (Some(m), None) = (manifest, entry) {
        return Err(Problem::file(
            &m.source,
            format!("run {run:?} (in {file}) has no row"),
            format!(
                "add a row for it to {} (run, material, diameter_m, fps, experiment), or move {file} out of the dataset folder",
                m.source
            ),
        )
        .in_run(run));
    }
    let e = entry.map(|e| &e.values);
    let material = e
        .and_then(|e| e.material.clone())
        .or_else(|| cal.material.clone())
        .filter(|m| !m.trim().is_empty());
    let diameter_m = e.and_then(|e| e.diameter_m).or(cal.diameter_m);
    let fps = e.and_then(|e| e.fps).or(cal.fps).or(units.fps);
    let m_per_px = units.m_per_unit.or(cal.m_per_px);
    let mut missing = Vec::new();
    if m_per_px.is_none() {
        missing.push(match units.spatial.is_empty() {
            true => "calibration.m_per_px (metres per pixel)".to_string(),
            false => format!(
                "calibration.m_per_px (metres per pixel; the file's positions are in {:?})",
                units.spatial
            ),
        });
    }
    if fps.is_none() {
        missing.push("calibration.fps (camera frame rate)".into());
    }
    if material.is_none() {
        missing.push("calibration.material (e.g. \"316\")".into());
    }
    if diameter_m.is_none() {
        missing.push("calibration.diameter_m (particle diameter in metres)".into());
    }
    if !missing.is_empty() {
        return Err(match (manifest, entry) {
            (Some(m), Some(en)) => Problem {
                file: m.source.clone(),
                row: (m.source == FILE).then_some(en.row),
                column: None,
                run: Some(run.to_string()),
                message: format!(
                    "run {run:?} needs {}, and neither its row nor the ingest params give it",
                    missing.join(", ")
                ),
                fix: "fill the column (material, diameter_m, fps) in its row, or set the value in the ingest params' calibration of pipeline.toml".into(),
            },
            _ => Problem::file(
                "pipeline.toml",
                format!("tracker files need a calibration, and {} is missing", missing.join(", ")),
                "set it in the ingest params of pipeline.toml, or give the runs' material, diameter_m and fps in a runs.csv beside the exports (see README, Tracker exports)",
            ),
        });
    }
    Ok(RunMeta {
        info: RunInfo {
            run: run.to_string(),
            experiment: e.and_then(|e| e.experiment).unwrap_or(cal.experiment),
            material: material.unwrap_or_default(),
            diameter_m: diameter_m.unwrap_or_default(),
            fps: fps.unwrap_or_default(),
            setup: e.and_then(|e| e.setup).or(cal.setup),
            extra: entry.map(|e| e.extra.clone()).unwrap_or_default(),
        },
        m_per_px: m_per_px.unwrap_or_default(),
        direction: f64::from(cal.direction),
    })
}
