//! The robust fit of the per-run fits: the shared loop [`crate::lsq::robust`] at [`NP`] parameters.

use super::model::NP;

pub use crate::lsq::robust::fit_robust;

/// How the robust fit treats residuals.
pub type RobustOptions = crate::lsq::robust::RobustOptions<NP>;
/// The result of a robust fit.
pub type RobustFit = crate::lsq::robust::RobustFit<NP>;
