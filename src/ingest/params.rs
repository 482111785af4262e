//! The ingest stage's params as written in `pipeline.toml`: source format, run filtering, calibration.

use crate::recording::{Experiment, Setup};
use serde::{Deserialize, Serialize};

/// `[stages.ingest] params = { ... }`. Every key has a default; unknown keys are rejected.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IngestParams {
    /// Which kind of files the dataset folder holds.
    pub format: Format,
    /// Leave out runs with run-level problems (and list them in `skipped`) instead of stopping.
    pub skip_bad_runs: bool,
    /// Fewest frames a particle's track needs for its run to be fitted.
    pub min_frames: usize,
    /// How to turn tracker pixels and frames into metres and seconds (trackpy and TrackMate only).
    pub calibration: Calibration,
}

impl Default for IngestParams {
    fn default() -> Self {
        IngestParams {
            format: Format::Auto,
            skip_bad_runs: false,
            min_frames: 20,
            calibration: Calibration::default(),
        }
    }
}

/// The dataset's file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// `runs.*` present: interchange; otherwise each CSV file is recognised by its header.
    Auto,
    /// runs.csv + trajectories.csv (or .parquet), see data-format.md.
    Interchange,
    /// trackpy CSV exports, one file per run (run id = file name without `.csv`).
    Trackpy,
    /// Fiji TrackMate spot tables, one file per run (run id = file name without `.csv`).
    Trackmate,
}

/// The image axis along the groove.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    X,
    Y,
}

/// Calibration of tracker exports. A tracker position `p` (pixels, image x right, image y down)
/// along `axis` becomes `z_m = direction * p * m_per_px`; frame `f` becomes `t_s = (f - f0) / fps`
/// with `f0` the run's first frame. Run metadata that trackers do not record comes from here.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Calibration {
    /// Metres per pixel (for a TrackMate image calibrated in microns: metres per micron, 1e-6).
    pub m_per_px: Option<f64>,
    /// Camera frame rate, frames per second.
    pub fps: Option<f64>,
    /// Which image axis runs along the groove.
    pub axis: Axis,
    /// +1 if z grows with the pixel coordinate along `axis`, -1 if it shrinks.
    pub direction: i8,
    /// Material label of every run from tracker files.
    pub material: Option<String>,
    /// Particle diameter in metres.
    pub diameter_m: Option<f64>,
    /// `single` or `collision`.
    pub experiment: Experiment,
    /// For collision runs: `rolling` or `contact`.
    pub setup: Option<Setup>,
}

impl Default for Calibration {
    fn default() -> Self {
        Calibration {
            m_per_px: None,
            fps: None,
            axis: Axis::X,
            direction: 1,
            material: None,
            diameter_m: None,
            experiment: Experiment::Single,
            setup: None,
        }
    }
}

/// A params key with a value out of range.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParamProblem {
    pub key: String,
    pub message: String,
    pub fix: String,
}

/// A calibration with every value needed to convert tracker files present and in range.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckedCalibration {
    pub m_per_px: f64,
    pub fps: f64,
    pub axis: Axis,
    pub direction: f64,
    pub material: String,
    pub diameter_m: f64,
    pub experiment: Experiment,
    pub setup: Option<Setup>,
}

impl IngestParams {
    /// Range checks that do not depend on the data: which key is wrong, and how to fix it.
    pub fn check(&self) -> Result<(), ParamProblem> {
        let problem = |key: &str, message: String, fix: &str| ParamProblem {
            key: key.to_string(),
            message,
            fix: fix.to_string(),
        };
        if self.min_frames < 2 {
            return Err(problem(
                "min_frames",
                format!("{} is too few frames to fit a run", self.min_frames),
                "use 2 or more",
            ));
        }
        let c = &self.calibration;
        if c.direction != 1 && c.direction != -1 {
            return Err(problem(
                "calibration.direction",
                format!("{} is not a direction", c.direction),
                "use 1 (z grows with the pixel coordinate) or -1",
            ));
        }
        for (key, value) in [
            ("calibration.m_per_px", c.m_per_px),
            ("calibration.fps", c.fps),
            ("calibration.diameter_m", c.diameter_m),
        ] {
            if let Some(v) = value {
                if !(v.is_finite() && v > 0.0) {
                    return Err(problem(
                        key,
                        format!("{v} is not positive"),
                        "use a positive number",
                    ));
                }
            }
        }
        let plausible = [
            ("calibration.fps", c.fps.map(super::sanity::fps)),
            ("calibration.diameter_m", c.diameter_m.map(super::sanity::diameter)),
        ];
        for (key, verdict) in plausible {
            if let Some(Err((message, fix))) = verdict {
                return Err(problem(key, message, &fix));
            }
        }
        Ok(())
    }

    /// The calibration for converting tracker files, or which keys are missing and what they mean.
    pub fn checked_calibration(&self) -> Result<CheckedCalibration, String> {
        let c = &self.calibration;
        let mut missing = Vec::new();
        if c.m_per_px.is_none() {
            missing.push("calibration.m_per_px (metres per pixel)");
        }
        if c.fps.is_none() {
            missing.push("calibration.fps (camera frame rate)");
        }
        if c.material.as_deref().is_none_or(|m| m.trim().is_empty()) {
            missing.push("calibration.material (e.g. \"316\")");
        }
        if c.diameter_m.is_none() {
            missing.push("calibration.diameter_m (particle diameter in metres)");
        }
        if !missing.is_empty() {
            return Err(format!(
                "tracker files need a calibration, and {} is missing",
                missing.join(", ")
            ));
        }
        Ok(CheckedCalibration {
            m_per_px: c.m_per_px.unwrap_or_default(),
            fps: c.fps.unwrap_or_default(),
            axis: c.axis,
            direction: f64::from(c.direction),
            material: c.material.clone().unwrap_or_default(),
            diameter_m: c.diameter_m.unwrap_or_default(),
            experiment: c.experiment,
            setup: c.setup,
        })
    }
}
