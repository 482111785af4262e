//! The report: figures (plotters SVG) and pages (Markdown, self-contained HTML) rendered to strings
//! from the upstream artifacts; the engine writes them.
//!
//! Files of this folder:
//!
//! - `accepted_curve.rs`: One single run's fitted curve under the physics discovery accepted
//! - `audit.rs`: The equation audit
//! - `chapter.rs`: The chapter's printed values and the constants used to check them
//! - `collisions.rs`: Collision-run fits read from the per-run fit JSON
//! - `date.rs`: A calendar date
//! - `diff.rs`: Two results compared number by number
//! - `html.rs`: The HTML page (report.html)
//! - `impact_laws.rs`: The impact laws the whole-run fits carried from discovery, in words
//! - `formula.rs`: Discovery's forms written as formulas
//! - `inputs.rs`: Everything the figures and pages show
//! - `markdown.rs`: The Markdown page
//! - `mathml.rs`: Formulas as MathML
//! - `md_html.rs`: The page's Markdown text rendered to HTML
//! - `singles.rs`: Per-run fits of single runs
//! - `style.rs`: Colours, marker shapes and font sizes shared by every figure
//! - `summary.rs`: Aggregates per material from summary.json
//! - `trajectory.rs`: One single run's observed positions beside its fitted baseline
//! - `truth.rs`: Truth values from the validate stage's `validation`
//! - `value.rs`: Numbers as the report prints them
//! - `figures/`: every figure of the report
//! - `own/`: The user's own notes, figures and tables for the report
//! - `sections/`: The report's content as plain data
//!
//! Upstream artifacts are read as their contract types (`crate::artifacts`): per-run fits, fits.csv,
//! summary.json, residuals, diagnosis.json, validation, provenance; an absent part stays empty and
//! the report says so. The report imports nothing from the engine: the stage adapters
//! (`stages::report`, `stages::figures`) unpack the engine's artifacts into `inputs::Input`.

pub mod accepted_curve;
pub mod audit;
pub mod chapter;
pub mod collisions;
pub mod date;
pub mod diff;
pub mod figures;
pub mod formula;
pub mod html;
pub mod impact_laws;
pub mod inputs;
pub mod markdown;
pub mod mathml;
pub mod md_html;
pub mod own;
pub mod sections;
pub mod singles;
pub mod style;
pub mod summary;
pub mod trajectory;
pub mod truth;
pub mod value;

pub use figures::{render_all as render_figures, FigureOptions};
pub use inputs::ReportData;

use std::collections::BTreeMap;

/// The two pages of a report.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pages {
    pub html: String,
    pub md: String,
}

/// Render report.html and report.md from the data and the figures (file name → SVG).
/// `date_epoch_s`, when given (from `SOURCE_DATE_EPOCH`), prints that UTC date under the title.
pub fn render_pages(
    d: &ReportData,
    figures: &BTreeMap<String, String>,
    title: &str,
    date_epoch_s: Option<i64>,
) -> Result<Pages, String> {
    let page = sections::build(d, figures, title, date_epoch_s.map(date::utc_date));
    Ok(Pages {
        html: html::render(&page)?,
        md: markdown::render(&page)?,
    })
}
