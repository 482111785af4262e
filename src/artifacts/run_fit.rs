//! The `fit` stage's item per run (per-run fit): a single run's baseline fit or a collision fit,
//! tagged by `experiment`.

pub use super::collision_fit::CollisionFit;
pub use crate::lsq::Termination;
use crate::physics::Groove;
use serde::{Deserialize, Serialize};

/// How a single-run fit ended, written as fits.csv's `status` word.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitStatus {
    /// At a minimum, and every check of its quality passed.
    Converged,
    /// At a minimum, but a check failed (the reasons are in `SingleFit::suspect`).
    Suspect,
    /// The iteration budget ran out first.
    MaxIterations,
    /// Any other stop: too few frames, non-finite values, a singular system.
    Failed,
}

impl FitStatus {
    /// The status of a fit that stopped for `why`, suspect when a converged fit failed a check.
    pub fn of(why: Termination, suspect: bool) -> FitStatus {
        match (why.is_converged(), suspect, why) {
            (true, true, _) => FitStatus::Suspect,
            (true, false, _) => FitStatus::Converged,
            (false, _, Termination::MaxIterations) => FitStatus::MaxIterations,
            (false, _, _) => FitStatus::Failed,
        }
    }

    /// The word fits.csv and the report print.
    pub fn word(self) -> &'static str {
        match self {
            FitStatus::Converged => "converged",
            FitStatus::Suspect => "suspect",
            FitStatus::MaxIterations => "max_iterations",
            FitStatus::Failed => "failed",
        }
    }

    /// The status a fits.csv word names.
    pub fn from_word(word: &str) -> Option<FitStatus> {
        [
            FitStatus::Converged,
            FitStatus::Suspect,
            FitStatus::MaxIterations,
            FitStatus::Failed,
        ]
        .into_iter()
        .find(|s| s.word() == word)
    }
}

impl std::fmt::Display for FitStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.word())
    }
}

/// The fit of one run: the JSON item the `fit` stage emits per run.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "experiment", rename_all = "lowercase")]
pub enum RunFit {
    Single(SingleFit),
    Collision(CollisionFit),
}

/// The fit of one single run (JSON item of the `fit` stage, and a row of fits.csv).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SingleFit {
    pub run: String,
    pub material: String,
    /// The groove the fit assumed (re-simulation uses the same).
    pub groove: Groove,
    /// Velocity at the kick, m/s; negative for motion towards −z.
    pub v0_mps: f64,
    pub v0_se: Option<f64>,
    pub mu: f64,
    pub mu_se: Option<f64>,
    /// Linear-drag time constant T.
    pub t_drag_s: f64,
    pub t_drag_se: Option<f64>,
    /// Position at the kick.
    pub z0_m: f64,
    pub z0_se: Option<f64>,
    /// Time from the kick to the first frame (t_s = 0), within one frame.
    pub t0_s: f64,
    pub t0_se: Option<f64>,
    /// Switch from sliding to rolling, seconds after the kick (computed from v0, μ, T).
    #[serde(with = "super::nan_null")]
    pub t1_s: f64,
    /// RMS of the residuals of the frames used, and the robust scale (1.4826·MAD).
    #[serde(with = "super::nan_null")]
    pub rms_m: f64,
    #[serde(with = "super::nan_null")]
    pub scale_m: f64,
    /// Frames with |residual| above this were flagged as outliers and left out.
    #[serde(with = "super::nan_null")]
    pub outlier_cut_m: f64,
    pub n_frames: usize,
    pub n_used: usize,
    pub n_outliers: usize,
    pub iterations: u32,
    pub termination: Termination,
    /// How the fit ended (the status column of fits.csv). Only `converged` fits enter the
    /// aggregates.
    pub status: FitStatus,
    /// Why a converged fit is suspect (a parameter at a bound, the switch to rolling outside the
    /// recording, v0 far from the first frames' speed, structured residuals); empty if it is not.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub suspect: Vec<String>,
    /// True if the fit from the data's start values was suspect and a restart from other start
    /// values gave a fit that is not.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub restarted: bool,
}
