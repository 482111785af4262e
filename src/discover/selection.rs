//! The state a discovery carries between its steps: the data and settings every step reads
//! (`Ctx`), the term selection under way (`Selection`) and each accepted term (`Accepted`); the
//! steps themselves are in `run`, what a finished selection reports in `findings`.

use super::candidate::Extra;
use super::cv::CvResult;
use super::data::RunData;
use super::forcemap::ForceMap;
use super::model::Model;
use super::null_distribution::NullFit;
use super::ranges::Ranges;
use super::spectral::Spectrum;
use super::Options;
use crate::artifacts::diagnosis::{CandidateRow, ModelScore};

/// An accepted term with what the report shows about it.
pub(super) struct Accepted {
    pub(super) row: CandidateRow,
    pub(super) before: ModelScore,
    pub(super) after: ModelScore,
    pub(super) probes_after: Vec<CandidateRow>,
    pub(super) null: NullFit,
    pub(super) extra: Extra,
}

/// A form that held-out runs could not tell from an accepted term in its round, decided again
/// once the later terms are in the model (`ties`).
pub(super) struct Tied {
    /// The accepted term it tied with.
    pub(super) with: Extra,
    /// It, as it would have been accepted in that round.
    pub(super) alt: Accepted,
    /// Its parameters, fitted in full in that round.
    pub(super) start: Vec<f64>,
}

/// The data and settings every step of a discovery reads.
pub(super) struct Ctx<'a> {
    pub(super) runs: &'a [RunData],
    pub(super) materials: &'a [String],
    pub(super) fold: &'a [usize],
    pub(super) rg: &'a Ranges,
    pub(super) opts: &'a Options,
    pub(super) t0: std::time::Instant,
    /// Where the step under way is said (the stage's progress line).
    pub(super) say: &'a (dyn Fn(&str) + Sync),
}

/// The state of the term selection: the current model and what the diagnosis reports of it.
pub(super) struct Selection {
    pub(super) current: Model,
    pub(super) current_cv: CvResult,
    pub(super) accepted: Vec<Accepted>,
    pub(super) removed: Vec<Accepted>,
    /// Named terms still in the model that are reported as parts of one field in z with the
    /// map accepted beside them (`consolidate.rs`).
    pub(super) parts: Vec<Accepted>,
    /// The forms tied with an accepted term in its round.
    pub(super) ties: Vec<Tied>,
    /// Every candidate and probe row of every round.
    pub(super) table: Vec<CandidateRow>,
    /// The candidates of the last round (none accepted) and its probes.
    pub(super) last_rows: Vec<CandidateRow>,
    pub(super) last_probes: Vec<CandidateRow>,
    /// Probes still flagging a mismatch when no candidate passed.
    pub(super) unexplained: Vec<CandidateRow>,
    pub(super) maps_before: Vec<ForceMap>,
    pub(super) spectra: Vec<Spectrum>,
    pub(super) round: usize,
}
