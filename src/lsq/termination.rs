//! Why a minimisation stopped, as data, for every back-end: a converged fit, an exhausted budget,
//! a model that could not be evaluated, or a singular system. The report shows it; nothing here
//! is an error. The snake_case names are part of the artifacts' bytes.

use serde::{Deserialize, Serialize};

/// The reason a minimisation ended (in the spirit of argmin's `TerminationReason`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// An accepted step changed every parameter by less than the step tolerance.
    SmallStep,
    /// An accepted step lowered the cost by less than the relative tolerance.
    SmallCostChange,
    /// No step lowers the cost at any damping: a minimum to working precision.
    NoFurtherDecrease,
    /// Every free parameter is pressed against a bound.
    AtBounds,
    /// The iteration budget ran out before a stopping rule held.
    MaxIterations,
    /// The model gave non-finite values at the start, or in the gradient of a step.
    NonFinite,
    /// Too few frames for the number of free parameters.
    TooFewPoints,
    /// The normal equations at the solution are singular: no standard errors.
    Singular,
}

impl Termination {
    /// True for the reasons that mean "at a minimum".
    pub fn is_converged(self) -> bool {
        matches!(
            self,
            Termination::SmallStep
                | Termination::SmallCostChange
                | Termination::NoFurtherDecrease
                | Termination::AtBounds
        )
    }

    /// The one-word status of fits.csv: `converged`, `max_iterations` or `failed`.
    pub fn status_word(self) -> &'static str {
        if self.is_converged() {
            "converged"
        } else if self == Termination::MaxIterations {
            "max_iterations"
        } else {
            "failed"
        }
    }
}
