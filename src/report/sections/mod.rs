//! The report's content as plain data (blocks of paragraphs, tables and figures), built once and
//! rendered by both the Markdown and the HTML template.
//!
//! Files of this folder:
//!
//! - `additional.rs`: The user's own sections: notes placed by their headings, "Additional analyses"
//! - `baseline.rs`: Section 7, when a baseline is given: this result against an earlier one
//! - `chapter.rs`: Section 3, single runs: the chapter's figures and tables
//! - `collisions.rs`: Section 3, collisions: the chapter's figures and tables
//! - `compare.rs`: Section 3.4.1: the compare stage's residuals of the collision fits
//! - `data.rs`: Section 2: the data
//! - `discovery.rs`: Section 4: discovery
//! - `leads.rs`: The opening sentences of sections 3.1, 3.4–3.7, 5 and 6
//! - `params.rs`: A fitted term's parameters as text
//! - `provenance.rs`: Section 6: provenance
//! - `stage_params.rs`: Section 6's table of every stage's params as run
//! - `summary.rs`: Section 1: what was analysed
//! - `toc.rs`: The table of contents: every section and subsection with its anchor
//! - `under_accepted.rs`: Section 3.8: the chapter's numbers under the physics discovery accepted
//! - `verdict.rs`: Discovery's verdict in one sentence per finding
//! - `whole_run.rs`: The whole-run collision fits in the report

pub mod additional;
pub mod baseline;
pub mod chapter;
pub mod collisions;
pub mod compare;
pub mod data;
pub mod discovery;
pub mod leads;
pub mod params;
pub mod provenance;
pub mod stage_params;
pub mod summary;
pub mod toc;
pub mod under_accepted;
pub mod verdict;
pub mod whole_run;

use super::audit::{audit, AuditItem};
use super::inputs::ReportData;
use serde::Serialize;
use std::collections::BTreeMap;

/// A table with a caption; every cell is already formatted text.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Table {
    pub caption: String,
    pub headers: Vec<String>,
    pub rows: Vec<Vec<String>>,
    /// A table of statistics behind a finding: folded under its caption in HTML (`<details>`),
    /// in full in the Markdown.
    pub folded: bool,
}

impl Table {
    pub fn new(caption: &str, headers: &[&str]) -> Table {
        Table {
            caption: caption.into(),
            headers: headers.iter().map(|h| h.to_string()).collect(),
            rows: Vec::new(),
            folded: false,
        }
    }
    pub fn push(&mut self, cells: Vec<String>) {
        self.rows.push(cells);
    }
}

/// A figure the page shows: its file name (`figures/<name>` in Markdown), caption and SVG text.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FigureRef {
    pub name: String,
    pub caption: String,
    pub svg: String,
    /// The file of its data points beside it (`fig_4_2c.csv`), when it has any.
    pub data: Option<String>,
    /// The file of its residual strip's points (`fig_4_2b_residuals.csv`), when it has one.
    pub residuals: Option<String>,
}

/// One piece of a block, in reading order.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Item {
    Para {
        text: String,
    },
    Table(Table),
    Figure(FigureRef),
    /// A figure of the user's (`additional` input): `name` beside report.md under `additional/`,
    /// `data` its bytes in base64 for the HTML page's `data:` address.
    Image {
        name: String,
        caption: String,
        mime: String,
        data: String,
    },
    /// Markdown of the user's (`notes` input), blocks and all, shown as written.
    Markdown {
        text: String,
    },
}

/// A part of the user's notes placed under a section: its heading, anchor, level and Markdown
/// (its own headings already moved below `level`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Note {
    pub id: String,
    pub heading: String,
    /// The heading level it is printed at (3: under a section, 4: under a subsection).
    pub level: usize,
    pub body: String,
}

/// One section or subsection: paragraphs, tables and figures in the order they were added.
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct Block {
    pub id: String,
    pub heading: String,
    /// What the part found, in one or two sentences: printed first, under the heading.
    pub lead: Option<String>,
    pub items: Vec<Item>,
    /// Why this part has no figure or numbers (e.g. "no collision runs in this dataset").
    pub missing: Option<String>,
    /// The user's notes whose headings name this part, printed after it.
    pub notes: Vec<Note>,
}

impl Block {
    pub fn new(id: &str, heading: &str) -> Block {
        Block {
            id: id.into(),
            heading: heading.into(),
            ..Block::default()
        }
    }
    pub fn para(&mut self, text: impl Into<String>) {
        self.items.push(Item::Para { text: text.into() });
    }
    pub fn table(&mut self, t: Table) {
        self.items.push(Item::Table(t));
    }
    /// Fold every table of this block (statistics behind its lead) in the HTML page.
    pub fn fold_tables(&mut self) {
        for i in &mut self.items {
            if let Item::Table(t) = i {
                t.folded = true;
            }
        }
    }
    /// The figures of this block.
    pub fn figures_mut(&mut self) -> impl Iterator<Item = &mut FigureRef> {
        self.items.iter_mut().filter_map(|i| match i {
            Item::Figure(f) => Some(f),
            _ => None,
        })
    }
    /// Add figure `name` from the rendered set, or note that it is absent.
    pub fn figure(&mut self, figs: &BTreeMap<String, String>, name: &str, caption: &str) -> bool {
        match figs.get(name) {
            Some(svg) => {
                let csv = name.replace(".svg", ".csv");
                let strip = name.replace(".svg", "_residuals.csv");
                self.items.push(Item::Figure(FigureRef {
                    name: name.into(),
                    caption: caption.into(),
                    svg: svg.clone(),
                    data: figs.contains_key(&csv).then_some(csv),
                    residuals: figs.contains_key(&strip).then_some(strip),
                }));
                true
            }
            None => false,
        }
    }
}

/// The whole page.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Page {
    pub title: String,
    pub date: Option<String>,
    /// Whether the comparison tables carry a truth column (a truth file was validated).
    pub has_truth: bool,
    pub summary: Block,
    pub data: Block,
    pub chapter: Vec<Block>,
    /// The user's notes whose headings name section 3 itself.
    pub chapter_notes: Vec<Note>,
    pub discovery: Block,
    pub audit: Vec<AuditItem>,
    /// What the audit found, in one sentence.
    pub audit_lead: Option<String>,
    /// The user's notes whose headings name section 5 itself.
    pub audit_notes: Vec<Note>,
    pub provenance: Block,
    /// Only when the report stage is given a baseline.
    pub baseline: Option<Block>,
    /// The user's own figures, tables and notes no section's heading names (inputs `notes`,
    /// `additional`); only when there are any.
    pub additional: Option<Block>,
    /// Every section and subsection with its anchor, in reading order.
    pub toc: Vec<toc::Entry>,
}

/// Build the page from the data and the rendered figures (by file name).
pub fn build(
    d: &ReportData,
    figs: &BTreeMap<String, String>,
    title: &str,
    date: Option<String>,
) -> Page {
    let mut chapter = chapter::blocks(d, figs);
    chapter.extend(collisions::blocks(d, figs));
    chapter.extend(under_accepted::block(d, figs));
    let audit_items = audit(d);
    let mut page = Page {
        title: title.into(),
        date,
        has_truth: d.validation.is_some(),
        summary: summary::block(d),
        data: data::block(d),
        chapter,
        chapter_notes: Vec::new(),
        discovery: discovery::block(d, figs),
        audit_lead: leads::audit(&audit_items),
        audit: audit_items,
        audit_notes: Vec::new(),
        provenance: provenance::block(d),
        baseline: baseline::block(d),
        additional: None,
        toc: Vec::new(),
    };
    additional::place(&mut page, &d.own);
    page.toc = toc::of(&page);
    page
}
