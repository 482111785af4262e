//! Everything the figures and pages show, read from the upstream artifacts (absent parts stay empty).

use super::collisions::{self, CollisionRun};
use super::singles::{self, SingleRow};
use crate::artifacts::summary::WholeRunSummary;
use crate::artifacts::under_accepted::UnderAccepted;
use crate::artifacts::{
    self, Comparison, Diagnosis, Provenance, RunFit, RunResiduals, Skipped, Summary, Validation,
};
use crate::physics::Groove;
use crate::recording::Recording;
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
    pub residuals: BTreeMap<String, RunResiduals>,
    pub summary: Option<Summary>,
    /// The compare stage's pooled residuals (`compare:comparison`).
    pub comparison: Option<Comparison>,
    pub diagnosis: Option<Diagnosis>,
    /// The chapter's numbers under the accepted physics (`refit:physics`).
    pub under_accepted: Option<UnderAccepted>,
    /// Absent when the dataset has no truth file (`{"truth": false}`).
    pub validation: Option<Validation>,
    pub provenance: Option<Provenance>,
    /// Runs ingest left out, with the reason.
    pub skipped: Vec<(String, String)>,
    /// The groove of the analysis (the stage's params `groove_angle_deg` and `k`, which
    /// `[project] params` sets for every stage at once); the chapter's by default.
    pub groove: Groove,
    /// This run's summary.json and diagnosis.json against a baseline's (the report stage's
    /// optional input `baseline`: an earlier reports folder or published bundle).
    pub baseline: Option<super::diff::Diff>,
    /// The user's notes file and own figures and tables (the report stage's optional inputs
    /// `notes` and `additional`).
    pub own: super::own::Own,
}

/// One input of a `figures` or `report` stage, unpacked by the stage adapter: a single file, or
/// the items of a collection by item name.
#[derive(Debug, Clone)]
pub enum Input<'a> {
    File(&'a [u8]),
    Items(Vec<(&'a str, &'a [u8])>),
}

/// The inputs by name.
pub type Inputs<'a> = BTreeMap<&'a str, Input<'a>>;

fn file<'a>(inputs: &Inputs<'a>, name: &str) -> Result<Option<&'a [u8]>, String> {
    match inputs.get(name) {
        None => Ok(None),
        Some(Input::File(b)) => Ok(Some(*b)),
        Some(Input::Items(_)) => Err(format!(
            "input `{name}` is a collection but a single file is expected; bind it to a file output"
        )),
    }
}

fn items<'a>(inputs: &Inputs<'a>, name: &str) -> Result<Vec<(&'a str, &'a [u8])>, String> {
    match inputs.get(name) {
        None => Ok(Vec::new()),
        Some(Input::Items(m)) => Ok(m.clone()),
        Some(Input::File(_)) => Err(format!(
            "input `{name}` is a single file but a collection is expected; bind it to a per-run output"
        )),
    }
}

/// The user's `notes` file and `additional` folder, each checked to be bound to the right thing.
fn own(inputs: &Inputs) -> Result<super::own::Own, String> {
    let notes = match inputs.get("notes") {
        Some(Input::Items(_)) => return Err(format!(
            "{} is a folder; bind it to one Markdown file: notes = {{ path = \"notes.md\", optional = true }}",
            super::own::NOTES
        )),
        Some(Input::File(b)) => Some(*b),
        None => None,
    };
    let additional = match inputs.get("additional") {
        Some(Input::File(_)) => return Err(
            "input `additional` of the report stage is one file; bind it to a folder of figures and tables: a `command` stage's folder output (additional = \"<stage>:<output>\") or a folder path".into(),
        ),
        Some(Input::Items(m)) => m.clone(),
        None => Vec::new(),
    };
    super::own::read(notes, &additional)
}

impl ReportData {
    /// The whole-run collision fits of summary.json (`collisions.whole_run`), if any.
    pub fn whole_run(&self) -> Option<&WholeRunSummary> {
        self.summary
            .as_ref()?
            .collisions
            .as_ref()?
            .whole_run
            .as_ref()
    }

    /// Read the artifacts a `figures` or `report` stage receives. Known input names: `runs`, `fits`,
    /// `fits_csv`, `residuals`, `summary`, `comparison`, `diagnosis`, `under_accepted`, `validation`, `provenance`, `skipped`,
    /// `notes` (a Markdown file of the user's), `additional` (a folder of the user's figures and tables).
    pub fn from_inputs(inputs: &Inputs) -> Result<ReportData, String> {
        let mut d = ReportData::default();
        for (name, bytes) in items(inputs, "runs")? {
            let rec = crate::recording::item::decode(bytes).map_err(|e| {
                format!("runs item `{name}` is not a recording: {e}; rerun the ingest stage")
            })?;
            d.recordings.insert(rec.info.run.clone(), rec);
        }
        let mut single_json = BTreeMap::new();
        for (name, bytes) in items(inputs, "fits")? {
            match artifacts::from_json::<RunFit>(&format!("fits item `{name}`"), bytes)? {
                RunFit::Collision(fit) => {
                    let setup = d.recordings.get(&fit.run).and_then(|r| r.info.setup);
                    d.collisions.push(collisions::from_fit(&fit, setup));
                }
                RunFit::Single(fit) => {
                    if let Some(row) = singles::from_fit(&fit) {
                        single_json.insert(row.run.clone(), row);
                    }
                }
            }
        }
        // the typed per-run items (by run id); fits.csv holds the same fits as text
        d.singles = single_json.into_values().collect();
        d.collisions.sort_by(|a, b| a.run.cmp(&b.run));
        for (name, bytes) in items(inputs, "residuals")? {
            let r: RunResiduals = artifacts::from_json(&format!("residuals item `{name}`"), bytes)?;
            d.residuals.insert(r.run.clone(), r);
        }
        d.summary = file(inputs, "summary")?
            .map(|b| artifacts::from_json::<Summary>("summary", b))
            .transpose()?;
        d.comparison = file(inputs, "comparison")?
            .map(|b| artifacts::from_json::<Comparison>("comparison", b))
            .transpose()?;
        d.diagnosis = file(inputs, "diagnosis")?
            .map(|b| artifacts::from_json::<Diagnosis>("diagnosis", b))
            .transpose()?;
        d.under_accepted = file(inputs, "under_accepted")?
            .map(|b| artifacts::from_json::<UnderAccepted>("under_accepted", b))
            .transpose()?;
        d.validation = file(inputs, "validation")?
            .map(|b| artifacts::from_json::<Validation>("validation", b))
            .transpose()?
            .filter(|v| v.truth);
        d.provenance = file(inputs, "provenance")?
            .map(|b| artifacts::from_json::<Provenance>("provenance", b))
            .transpose()?;
        if let Some(b) = file(inputs, "skipped")? {
            let list: Vec<Skipped> = artifacts::from_json("skipped", b)?;
            d.skipped = list.into_iter().map(|s| (s.run, s.reason)).collect();
        }
        d.own = own(inputs)?;
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
