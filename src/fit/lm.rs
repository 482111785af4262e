//! The per-run fits' view of the fixed-size back-end [`crate::lsq::fixed`] at [`NP`] parameters.

use super::model::NP;
use crate::lsq::fixed;

pub use fixed::{cost_and_weights, minimize, normal_equations, solve_spd, Problem};

/// Box bounds; a parameter with `free[i] == false` stays at its start value.
pub type Bounds = fixed::Bounds<NP>;
/// Stopping rules.
pub type Settings = fixed::Settings<NP>;
/// Buffers reused across fits (the iterations allocate nothing).
pub type Workspace = fixed::Workspace<NP>;
/// The result of one minimisation at a fixed scale.
pub type Outcome = fixed::Outcome<NP>;
