//! under_accepted_physics.json (output of `refit`): the chapter's numbers again, with every
//! single-run term that discovery accepted carried (and into the pair fits a force between the
//! particles and the impact laws it accepted), in the shape of summary.json's sections.

use super::estimate::Estimate;
use super::summary::WholeRunSummary;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One accepted term carried by the refit: its effect and form as diagnosis.json names them,
/// with the values it is carried at (a restitution map: its value at each node,
/// `restitution_map_at_<mm/s>_mmps`; μ_pp against the slip speed: also the reference slip speed
/// `mu_pp_reference_slip_speed_mps` at which the fitted μ_pp applies).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CarriedTerm {
    pub effect: String,
    pub form: String,
    pub parameters: BTreeMap<String, f64>,
}

/// The drag time as a line in the speed, T(|v|) = intercept + slope·|v|, where the accepted drag
/// still has one (a linear drag: slope 0; a saturating drag: T0 + T'|v|).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DragTimeLine {
    pub intercept_s: Estimate,
    pub slope_s_per_mps: Estimate,
}

/// The single runs of one material under the accepted physics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SingleMaterial {
    /// μ_pg of the material, with its standard error.
    pub mu: Estimate,
    /// The drag time's line in |v|; None when the accepted drag has none (a quadratic drag).
    pub t_line: Option<DragTimeLine>,
}

/// Everything about the single runs under the accepted physics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SingleUnder {
    /// Where the numbers come from, in words.
    pub source: String,
    pub materials: BTreeMap<String, SingleMaterial>,
}

/// The collision runs under the accepted physics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CollisionsUnder {
    /// The whole-run pair fits, in the shape of summary.json's `collisions.whole_run`; a material
    /// whose accepted physics the pair model cannot carry is left out (see `notes`).
    pub whole_run: WholeRunSummary,
    /// Materials whose whole-run fits already carried every accepted term, so the baseline's
    /// numbers are theirs unchanged (a saturating drag only, the whole-run model's own, and no
    /// force or impact law for their pairs).
    pub unchanged: Vec<String>,
}

/// under_accepted_physics.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct UnderAccepted {
    /// Whether discovery accepted any physics the refit carries (a single-run term, a force
    /// between the particles, an impact law); when false, nothing is refitted and `single` and
    /// `collisions` are null.
    pub accepted: bool,
    /// The accepted terms carried, in diagnosis.json's order.
    pub terms: Vec<CarriedTerm>,
    pub single: Option<SingleUnder>,
    pub collisions: Option<CollisionsUnder>,
    /// Plain-language notes: what was not refitted and why.
    pub notes: Vec<String>,
}
