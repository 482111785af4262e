//! The `simulate` stage's item per run: re-simulation residuals, column-wise, with phase and outlier flag.

use crate::recording::Experiment;
use serde::{Deserialize, Serialize};

/// The motion regime of the fitted model at a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    Sliding,
    Rolling,
    Rest,
}

/// Residuals of one run, column-wise (one entry per frame of the fitted track).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunResiduals {
    pub run: String,
    pub material: String,
    pub experiment: Experiment,
    /// +1 for motion towards +z, −1 towards −z, 0 if not fitted.
    pub direction: i8,
    /// `ok`, or why there are no residuals (`skipped: …`).
    pub status: String,
    /// The particle of each frame (0 for single runs; 0 striker, 1 target in collision runs).
    pub particle: Vec<u32>,
    pub t_s: Vec<f64>,
    pub z_obs_m: Vec<f64>,
    pub z_fit_m: Vec<f64>,
    /// z_obs − z_fit.
    pub residual_m: Vec<f64>,
    /// Model velocity at the frame.
    pub v_fit_mps: Vec<f64>,
    pub phase: Vec<Phase>,
    /// |residual| above the fit's outlier cut (the fit left these frames out).
    pub outlier: Vec<bool>,
    /// Times of the fitted impacts (s, first impact first); empty for single runs.
    pub impacts_s: Vec<f64>,
}
