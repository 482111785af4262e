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
    /// Per-run metadata of tracker exports, as the rows of a `runs.csv` manifest would give it
    /// (`runs = [{ run = "a", material = "316" }, ...]`); empty: none, or `runs.csv` beside them.
    pub runs: Vec<RunEntry>,
}

/// One run of tracker exports: which run (and file) it is, and the metadata trackers do not record.
/// An absent value is taken from the calibration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunEntry {
    /// The run id (the value of a trackpy `run` column, or the name a one-run file gets).
    pub run: String,
    /// The tracker file holding the run, when its name is not the run id (e.g. TrackMate's
    /// `Spots in tracks statistics.csv`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diameter_m: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fps: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub experiment: Option<Experiment>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub setup: Option<Setup>,
}

impl Default for IngestParams {
    fn default() -> Self {
        IngestParams {
            format: Format::Auto,
            skip_bad_runs: false,
            min_frames: 20,
            calibration: Calibration::default(),
            runs: Vec::new(),
        }
    }
}

/// The dataset's file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// `runs.*` present: interchange; otherwise each CSV file is recognised by its header.
    Auto,
    /// runs.csv + trajectories.csv (or .parquet), see the module docs.
    Interchange,
    /// trackpy CSV exports: one file per run (run id = file name without `.csv`), or files with a
    /// `run` column naming each row's run.
    Trackpy,
    /// Fiji TrackMate XML files or spot tables, one file per run (run id = file name without
    /// `.xml` / `.csv`, or as the manifest maps it).
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
    /// Metres per pixel. Not needed for TrackMate files that state their spatial unit (XML
    /// `spatialunits`, CSV units row such as `(micron)`): their own unit is used.
    pub m_per_px: Option<f64>,
    /// Camera frame rate, frames per second.
    pub fps: Option<f64>,
    /// Which image axis runs along the groove.
    pub axis: Axis,
    /// +1 if z grows with the pixel coordinate along `axis`, -1 if it shrinks.
    pub direction: i8,
    /// Material label of every run from tracker files (a manifest's value wins).
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
            (
                "calibration.diameter_m",
                c.diameter_m.map(super::sanity::diameter),
            ),
        ];
        for (key, verdict) in plausible {
            if let Some(Err((message, fix))) = verdict {
                return Err(problem(key, message, &fix));
            }
        }
        for (k, r) in self.runs.iter().enumerate() {
            if r.run.trim().is_empty() {
                return Err(problem(
                    &format!("runs[{k}].run"),
                    "is empty".into(),
                    "give the run's id",
                ));
            }
            for (key, value) in [("diameter_m", r.diameter_m), ("fps", r.fps)] {
                if let Some(v) = value {
                    if !(v.is_finite() && v > 0.0) {
                        return Err(problem(
                            &format!("runs[{k}].{key}"),
                            format!("{v} is not positive"),
                            "use a positive number",
                        ));
                    }
                    let verdict = if key == "fps" {
                        super::sanity::fps(v)
                    } else {
                        super::sanity::diameter(v)
                    };
                    if let Err((message, fix)) = verdict {
                        return Err(problem(&format!("runs[{k}].{key}"), message, &fix));
                    }
                }
            }
        }
        Ok(())
    }
}
