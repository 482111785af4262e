//! The `report` stage kind: report.html (self-contained) and report.md from the figures and artifacts.
//!
//! Your own sections: two optional inputs add the user's material to the report.
//!
//! ```toml
//! [stages.growth]                       # any `command` stage writing a folder of figures and tables
//! kind = "command"
//! cmd = "python3 scripts/growth.py {in.fits} {out.plots}"
//! inputs = { fits = "aggregate:fits_csv", script = "scripts/growth.py" }
//! outputs = { plots = "${reports}/additional" }  # report.md shows its figures from additional/
//!
//! [stages.report]
//! inputs = { figures = "figures:figures", notes = { path = "notes.md", optional = true }, additional = "growth:plots", … }
//! ```
//!
//! - `notes`: a Markdown file. Its highest headings cut it into parts; a part whose heading is
//!   the title of a section or subsection (its number optional, case ignored: `## Discovery`,
//!   `## Fig. 4.2c: drag time T against v0`) is printed at the end of that section, the others and
//!   the text before the first heading in "Additional analyses". Raw HTML shows as text and
//!   images as links, so report.html stays one file that loads nothing.
//! - `additional`: a folder (a `command` stage's folder output, or a path): `NAME.svg` and
//!   `NAME.png` are figures, `NAME.csv` a table (at most 200 rows shown), `NAME.md` or `NAME.txt`
//!   the caption of what is called NAME; shown in "Additional analyses" in file-name order, the
//!   figures inside report.html as `data:` addresses and beside report.md under `additional/`.
//!
//! Both are hashed like every input: editing the notes reruns the report alone. A file the page
//! cannot show (not UTF-8, another format, a ragged CSV, a caption of nothing) fails the stage
//! with a message naming it and the fix (exit 2); the last good report stays.

use super::fit_io::param_error;
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::options::check_groove;
use crate::physics::Groove;
use crate::report::diff::{compare, Diff, Side, FILES};
use crate::report::inputs::{Input, Inputs};
use crate::report::{render_pages, ReportData};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Params of the `report` stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReportParams {
    /// The page title.
    pub title: String,
    /// Seconds since the Unix epoch of the date printed under the title (pass `SOURCE_DATE_EPOCH`);
    /// no date is printed without it, so the report never depends on the clock.
    pub source_date_epoch: Option<i64>,
    /// Opening angle of the groove, degrees (the chapter's 70.6 by default).
    pub groove_angle_deg: f64,
    /// k = m R² / I of the particles (5/2, a solid sphere, by default).
    pub k: f64,
}

impl Default for ReportParams {
    fn default() -> Self {
        ReportParams {
            title: "groove: micro-particles in a v-groove — the chapter reproduced".into(),
            source_date_epoch: None,
            groove_angle_deg: 70.6,
            k: 2.5,
        }
    }
}

/// Renders the pages; the engine writes them to `${reports}/report.html` and `report.md`.
pub struct Report;

impl StageKind for Report {
    fn kind(&self) -> &'static str {
        "report"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["figures"]
    }
    fn optional_inputs(&self) -> &'static [&'static str] {
        &[
            "runs",
            "fits",
            "fits_csv",
            "summary",
            "residuals",
            "comparison",
            "diagnosis",
            "under_accepted",
            "validation",
            "provenance",
            "skipped",
            "baseline",
            "notes",
            "additional",
        ]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["html", "md"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        let (p, json) = typed_params::<ReportParams>(params)?;
        check_groove(p.groove_angle_deg, p.k).map_err(param_error)?;
        Ok(json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (p, _) =
            typed_params::<ReportParams>(input.params).map_err(|e| StageError(e.to_string()))?;
        let mut data = ReportData::from_inputs(&unpack(&input.inputs)).map_err(StageError)?;
        data.groove = Groove::of_params(p.groove_angle_deg, p.k);
        data.baseline = baseline(&input.inputs)?;
        let figures: BTreeMap<String, String> = match input.inputs.get("figures") {
            Some(Artifact::Collection(m)) => m
                .iter()
                .map(|(k, v)| (k.clone(), String::from_utf8_lossy(v).into_owned()))
                .collect(),
            _ => return Err(StageError("input `figures` must be the figures stage's collection (figures = \"figures:figures\")".into())),
        };
        let pages =
            render_pages(&data, &figures, &p.title, p.source_date_epoch).map_err(StageError)?;
        Ok(StageOutputs::from([
            ("html".to_string(), Artifact::File(pages.html.into_bytes())),
            ("md".to_string(), Artifact::File(pages.md.into_bytes())),
        ]))
    }
}

/// This run's summary.json and diagnosis.json (the inputs `summary`, `diagnosis`) against those
/// of the input `baseline`, a folder of an earlier result (a reports folder or a published
/// bundle: its top-level files), when it is bound.
fn baseline(inputs: &BTreeMap<&str, &Artifact>) -> Result<Option<Diff>, StageError> {
    let Some(given) = inputs.get("baseline") else {
        return Ok(None);
    };
    let Artifact::Collection(items) = given else {
        return Err(StageError(
            "input `baseline` must be a folder holding an earlier summary.json and diagnosis.json (a reports folder or a published bundle): bind it as baseline = { path = \"...\", optional = true }".into(),
        ));
    };
    let json = |what: &str, bytes: &[u8]| {
        serde_json::from_slice::<serde_json::Value>(bytes).map_err(|e| {
            StageError(format!(
                "{what} is not JSON ({e}); point `baseline` at a reports folder or a published bundle"
            ))
        })
    };
    let mut before = Side {
        label: "the baseline".into(),
        files: BTreeMap::new(),
        lock: None,
    };
    let mut now = Side {
        label: "this run".into(),
        files: BTreeMap::new(),
        lock: None,
    };
    for (file, input) in FILES.into_iter().zip(["summary", "diagnosis"]) {
        if let Some(bytes) = items.get(file) {
            before
                .files
                .insert(file, json(&format!("the baseline's {file}"), bytes)?);
        }
        if let Some(Artifact::File(bytes)) = inputs.get(input) {
            now.files
                .insert(file, json(&format!("this run's {file}"), bytes)?);
        }
    }
    if before.files.is_empty() {
        return Err(StageError(format!(
            "the baseline folder holds neither summary.json nor diagnosis.json (it holds {}); point `baseline` at a reports folder or a published bundle",
            items.keys().cloned().collect::<Vec<_>>().join(", ")
        )));
    }
    if let Some(lock) = items.get("pipeline.lock") {
        before.lock = Some(json("the baseline's pipeline.lock", lock)?);
    }
    Ok(Some(compare(&before, &now)))
}

/// The engine's artifacts as the report reads them: files as bytes, collections as their items.
pub fn unpack<'a>(inputs: &BTreeMap<&'a str, &'a Artifact>) -> Inputs<'a> {
    inputs
        .iter()
        .map(|(name, artifact)| {
            let input = match artifact {
                Artifact::File(b) => Input::File(b),
                Artifact::Collection(m) => {
                    Input::Items(m.iter().map(|(k, v)| (k.as_str(), v.as_slice())).collect())
                }
                Artifact::InStore(_) | Artifact::OnDisk(_) => {
                    unreachable!("{}", crate::engine::stage::IN_STORE_INPUT)
                }
            };
            (*name, input)
        })
        .collect()
}
