//! Everything the figures and pages show, read from the upstream artifacts (absent parts stay empty).

use super::collisions::{self, CollisionRun};
use super::singles::{self, SingleRow};
use crate::engine::stage::Artifact;
use crate::recording::{Experiment, Recording, Setup};
use serde_json::Value;
use std::collections::BTreeMap;

/// The report's view of one pipeline run.
#[derive(Debug, Default)]
pub struct ReportData {
    /// Recordings by run id (from `ingest:runs`).
    pub recordings: BTreeMap<String, Recording>,
    /// Single-run baseline fits, sorted by run.
    pub singles: Vec<SingleRow>,
    /// Collision-run fits, sorted by run.
    pub collisions: Vec<CollisionRun>,
    /// Per-run simulate residuals (`simulate:residuals`), by run id.
    pub residuals: BTreeMap<String, Value>,
    pub summary: Option<Value>,
    pub diagnosis: Option<Value>,
    pub validation: Option<Value>,
    pub provenance: Option<Value>,
    /// Runs ingest left out, with the reason.
    pub skipped: Vec<(String, String)>,
}

fn file<'a>(inputs: &BTreeMap<&str, &'a Artifact>, name: &str) -> Result<Option<&'a [u8]>, String> {
    match inputs.get(name).copied() {
        None => Ok(None),
        Some(Artifact::File(b)) => Ok(Some(b)),
        Some(Artifact::Collection(_)) => Err(format!(
            "input `{name}` is a collection but a single file is expected; bind it to a file output"
        )),
    }
}

fn items<'a>(
    inputs: &BTreeMap<&str, &'a Artifact>,
    name: &str,
) -> Result<Vec<(&'a str, &'a [u8])>, String> {
    match inputs.get(name).copied() {
        None => Ok(Vec::new()),
        Some(Artifact::Collection(m)) => Ok(m.iter().map(|(k, v)| (k.as_str(), v.as_slice())).collect()),
        Some(Artifact::File(_)) => Err(format!(
            "input `{name}` is a single file but a collection is expected; bind it to a per-run output"
        )),
    }
}

fn json(name: &str, bytes: &[u8]) -> Result<Value, String> {
    serde_json::from_slice(bytes)
        .map_err(|e| format!("{name} is not valid JSON ({e}); rerun the stage that makes it"))
}

impl ReportData {
    /// Read the artifacts a `figures` or `report` stage receives. Known input names: `runs`, `fits`,
    /// `fits_csv`, `residuals`, `summary`, `diagnosis`, `validation`, `provenance`, `skipped`.
    pub fn from_artifacts(inputs: &BTreeMap<&str, &Artifact>) -> Result<ReportData, String> {
        let mut d = ReportData::default();
        for (name, bytes) in items(inputs, "runs")? {
            let rec: Recording = serde_json::from_slice(bytes).map_err(|e| {
                format!("runs item `{name}` is not a recording ({e}); rerun the ingest stage")
            })?;
            d.recordings.insert(rec.info.run.clone(), rec);
        }
        let mut single_json = BTreeMap::new();
        for (name, bytes) in items(inputs, "fits")? {
            let fit = json(&format!("fits item `{name}`"), bytes)?;
            let run = super::value::text(&fit, &["run"]).unwrap_or(name.trim_end_matches(".json"));
            let info = d.recordings.get(run).map(|r| &r.info);
            let material = info.map(|i| i.material.as_str()).unwrap_or("");
            let experiment = super::value::text(&fit, &["experiment"])
                .map(str::to_string)
                .or_else(|| {
                    info.map(|i| match i.experiment {
                        Experiment::Single => "single".to_string(),
                        Experiment::Collision => "collision".to_string(),
                    })
                });
            if experiment.as_deref() == Some("collision") {
                let setup = info.and_then(|i| i.setup).map(|s| match s {
                    Setup::Rolling => "rolling",
                    Setup::Contact => "contact",
                });
                d.collisions
                    .push(collisions::from_fit_json(run, material, setup, &fit));
            } else if let Some(row) = singles::from_fit_json(run, material, &fit) {
                single_json.insert(row.run.clone(), row);
            }
        }
        d.singles = match file(inputs, "fits_csv")? {
            Some(b) => {
                let mut rows = singles::parse_fits_csv(&String::from_utf8_lossy(b))?;
                singles::add_nuisance(&mut rows, &single_json);
                rows
            }
            None => single_json.into_values().collect(),
        };
        d.collisions.sort_by(|a, b| a.run.cmp(&b.run));
        for (name, bytes) in items(inputs, "residuals")? {
            let v = json(&format!("residuals item `{name}`"), bytes)?;
            let run = super::value::text(&v, &["run"])
                .unwrap_or(name.trim_end_matches(".json"))
                .to_string();
            d.residuals.insert(run, v);
        }
        let opt = |n: &str| -> Result<Option<Value>, String> {
            file(inputs, n)?.map(|b| json(n, b)).transpose()
        };
        d.summary = opt("summary")?;
        d.diagnosis = opt("diagnosis")?;
        d.validation = opt("validation")?.filter(|v| v.get("truth") != Some(&Value::Bool(false)));
        d.provenance = opt("provenance")?;
        if let Some(Value::Array(list)) = opt("skipped")? {
            for s in list {
                let run = super::value::text(&s, &["run"]).unwrap_or("?").to_string();
                let why = super::value::text(&s, &["reason", "why"])
                    .unwrap_or("")
                    .to_string();
                d.skipped.push((run, why));
            }
        }
        Ok(d)
    }

    /// Materials of the single runs in first-seen sorted order (316, 440c, ...).
    pub fn materials(&self) -> Vec<String> {
        let mut m: Vec<String> = self.singles.iter().map(|r| r.material.clone()).collect();
        m.extend(self.collisions.iter().map(|c| c.material.clone()));
        m.sort();
        m.dedup();
        m
    }

    /// Converged single fits of one material.
    pub fn singles_of<'a>(&'a self, material: &'a str) -> impl Iterator<Item = &'a SingleRow> + 'a {
        self.singles
            .iter()
            .filter(move |r| r.material == material && r.converged())
    }
}
