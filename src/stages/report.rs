//! The `report` stage kind: report.html (self-contained) and report.md from the figures and artifacts.

use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
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
}

impl Default for ReportParams {
    fn default() -> Self {
        ReportParams {
            title: "groove: micro-particles in a v-groove — the chapter reproduced".into(),
            source_date_epoch: None,
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
        ]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["html", "md"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        typed_params::<ReportParams>(params).map(|(_, json)| json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (p, _) =
            typed_params::<ReportParams>(input.params).map_err(|e| StageError(e.to_string()))?;
        let data = ReportData::from_inputs(&unpack(&input.inputs)).map_err(StageError)?;
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
