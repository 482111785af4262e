//! Options of every fit (the `params` of the `fit` stage): groove geometry, loss, outlier cut.

use super::collision::CollisionOptions;
use crate::lsq::loss::Loss;
use crate::physics::Groove;
use serde::{Deserialize, Serialize};

/// A fit-side param out of range: its key, and what is wrong with a valid value to use
/// (lowercase; the engine says it at the param's line of pipeline.toml).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("param `{key}`: {message}")]
pub struct OptionError {
    pub key: &'static str,
    pub message: &'static str,
}

/// Check the groove params every stage that needs the geometry takes (`groove_angle_deg`, `k`;
/// `[project] params` sets them for all at once).
pub fn check_groove(groove_angle_deg: f64, k: f64) -> Result<(), OptionError> {
    if !(groove_angle_deg > 0.0 && groove_angle_deg < 180.0) {
        return Err(OptionError {
            key: "groove_angle_deg",
            message: "must be between 0 and 180 degrees, e.g. 70.6",
        });
    }
    if !(k > 0.0 && k.is_finite()) {
        return Err(OptionError {
            key: "k",
            message: "must be positive (2.5 for a solid sphere)",
        });
    }
    Ok(())
}

/// How runs are fitted. Defaults are the chapter's groove and a Huber loss.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FitOptions {
    /// Opening angle θ of the v-groove, degrees.
    pub groove_angle_deg: f64,
    /// k = m R² / I (5/2 for a solid sphere).
    pub k: f64,
    pub loss: Loss,
    /// Frames with |residual| above this many robust scales are flagged and left out.
    pub outlier_sigma: f64,
    pub max_iterations: u32,
    /// A track with fewer frames is not fitted (status `failed`, reason `too_few_points`).
    pub min_frames: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            groove_angle_deg: 70.6,
            k: 2.5,
            loss: Loss::Huber,
            outlier_sigma: 5.0,
            max_iterations: 200,
            min_frames: 10,
        }
    }
}

impl FitOptions {
    /// The groove these options describe.
    pub fn groove(&self) -> Groove {
        Groove::of_params(self.groove_angle_deg, self.k)
    }

    /// The collision fit's options on the same groove (its other settings at their defaults).
    pub fn collision_options(&self) -> CollisionOptions {
        CollisionOptions {
            s: self.groove().s,
            k: self.k,
            ..CollisionOptions::default()
        }
    }

    /// Check ranges; the error names the key and a valid range.
    pub fn validate(&self) -> Result<(), OptionError> {
        let bad = |key, message| Err(OptionError { key, message });
        check_groove(self.groove_angle_deg, self.k)?;
        if !(self.outlier_sigma >= 2.0 && self.outlier_sigma.is_finite()) {
            return bad(
                "outlier_sigma",
                "must be at least 2 (robust scales), e.g. 5",
            );
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1, e.g. 200");
        }
        if self.min_frames < 8 {
            return bad(
                "min_frames",
                "must be at least 8 (the model has 5 free parameters)",
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_option_out_of_range_is_a_typed_error_naming_its_key_and_a_valid_value() {
        assert_eq!(FitOptions::default().validate(), Ok(()));
        let wide = FitOptions {
            groove_angle_deg: 190.0,
            ..FitOptions::default()
        };
        let e = wide.validate().unwrap_err();
        assert_eq!(e.key, "groove_angle_deg");
        assert_eq!(
            e.to_string(),
            "param `groove_angle_deg`: must be between 0 and 180 degrees, e.g. 70.6"
        );
        let few = FitOptions {
            min_frames: 3,
            ..FitOptions::default()
        };
        assert_eq!(few.validate().unwrap_err().key, "min_frames");
    }
}
