//! diagnosis.json (output of `discover`): what discovery found, every candidate with its evidence,
//! the residual structure and the per-run drift before and after, as the report reads them.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use super::estimate::Estimate;

/// How well a model does: held-out error and in-sample fit.
#[derive(Clone, Debug, Serialize, Deserialize, Default)]
pub struct ModelScore {
    #[serde(with = "super::nan_null")]
    pub cv_rms_m: f64,
    #[serde(with = "super::nan_null")]
    pub rms_m: f64,
    #[serde(with = "super::nan_null")]
    pub chi2: f64,
    pub n_global_params: usize,
    pub terms: Vec<String>,
}

/// The statistics behind a decision.
#[derive(Clone, Debug, Serialize, Deserialize, Default)]
pub struct Evidence {
    pub round: usize,
    /// χ²(smaller) − χ²(larger), residuals in units of each run's noise.
    #[serde(with = "super::nan_null")]
    pub lr: f64,
    pub extra_params: usize,
    /// Bootstrap null: replicates, mean LR*, p from the fitted gamma law, empirical p.
    pub bootstrap_replicates: usize,
    #[serde(with = "super::nan_null")]
    pub null_mean_lr: f64,
    #[serde(with = "super::nan_null")]
    pub p_value: f64,
    #[serde(with = "super::nan_null")]
    pub p_empirical: f64,
    /// Holm-adjusted over the candidates of the round.
    #[serde(with = "super::nan_null")]
    pub p_holm: f64,
    /// Leave-runs-out CV: paired t of the per-run held-out improvement (None: not cross-validated).
    pub cv_paired_t: Option<f64>,
    pub cv_rms_m: Option<f64>,
    pub decision: String,
    /// The smallest size of the term this dataset would have detected (None: no single size).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detection_limit: Option<DetectionLimit>,
}

/// The smallest size of a term the test would have found (90 % power), from the bootstrap null.
#[derive(Clone, Debug, Serialize, Deserialize, Default)]
pub struct DetectionLimit {
    pub parameter: String,
    #[serde(with = "super::nan_null")]
    pub value: f64,
    /// e.g. "a groove tilt above 0.0213 ° would have been found".
    pub text: String,
}

/// One finding of the contract.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Finding {
    pub effect: String,
    pub accepted: bool,
    pub form: String,
    #[serde(with = "super::estimate::stderr::map")]
    pub parameters: BTreeMap<String, Estimate>,
    pub evidence: Evidence,
    #[serde(rename = "where")]
    pub where_: BTreeMap<String, serde_json::Value>,
    pub baseline: ModelScore,
    pub extended: ModelScore,
}

/// One row of the table of every candidate tested.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CandidateRow {
    pub round: usize,
    pub effect: String,
    pub form: String,
    pub accepted: bool,
    #[serde(with = "super::estimate::stderr::map")]
    pub parameters: BTreeMap<String, Estimate>,
    pub evidence: Evidence,
}

/// Fitted T and μ of one run (its own fit) against its covariates.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct DriftPoint {
    pub run: String,
    pub material: String,
    #[serde(with = "super::nan_null")]
    pub v0_mps: f64,
    #[serde(with = "super::nan_null")]
    pub t_s: f64,
    #[serde(with = "super::nan_null")]
    pub mu: f64,
    #[serde(with = "super::nan_null")]
    pub z0_m: f64,
}

/// Per-run parameter drift with the baseline and with the final model's extra terms held fixed.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Drift {
    pub before: Vec<DriftPoint>,
    pub after: Vec<DriftPoint>,
    /// Lines such as "t_s vs |v0| (316)" before and after.
    pub lines_before: BTreeMap<String, Line>,
    pub lines_after: BTreeMap<String, Line>,
    pub note: String,
}

/// Settings that produced the diagnosis.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Settings {
    pub bootstrap: usize,
    #[serde(with = "super::nan_null")]
    pub alpha: f64,
    pub folds: usize,
    pub seed: u64,
    pub candidates: Vec<String>,
}

/// The whole diagnosis.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Diagnosis {
    pub mismatch: bool,
    pub findings: Vec<Finding>,
    pub candidates: Vec<CandidateRow>,
    pub model: ModelScore,
    #[serde(with = "super::estimate::stderr::map")]
    pub model_parameters: BTreeMap<String, Estimate>,
    pub baseline_model: ModelScore,
    pub residuals_before: Option<Structure>,
    pub residuals_after: Option<Structure>,
    pub drift: Option<Drift>,
    /// The missing acceleration against z, v, t and the phase, before and after the accepted physics.
    #[serde(default)]
    pub force_maps: Option<ForceMaps>,
    /// Periodograms of the baseline residuals in z and t (where searched).
    #[serde(default)]
    pub spectra: Vec<Spectrum>,
    pub runs_used: usize,
    pub materials: Vec<String>,
    pub settings: Settings,
    /// A slow drift of the tracking noise that every test's null carried (absent: none found).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracking_drift: Option<TrackingDrift>,
    /// A tracking noise growing with speed that every test's null carried (absent: none found).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tracking_blur: Option<TrackingBlur>,
    pub note: String,
}

/// The tracking noise's growth with speed (motion blur): its σ² is σ₀² + (c·v)², c in metres per
/// m/s (seconds), shared by the runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TrackingBlur {
    pub noise_per_speed_s: f64,
}

/// The slow part of the tracking noise: its variance as a multiple of each run's fast noise
/// variance, and its correlation time.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TrackingDrift {
    pub variance_ratio: f64,
    pub time_constant_s: f64,
    /// Runs it was measured on, and of those left out of its estimate because their wander is
    /// beyond what a drift shared by the runs explains (they still carry it).
    #[serde(default)]
    pub runs: usize,
    #[serde(default)]
    pub runs_left_out: usize,
    /// The band of frequencies (Hz) left out of its estimate for a line, shared by the runs,
    /// that no drift's spectrum has; (0, 0) when none.
    #[serde(default)]
    pub line_hz: (f64, f64),
}

/// Force maps of the baseline and of the final model.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ForceMaps {
    pub before: Vec<ForceMap>,
    pub after: Vec<ForceMap>,
}

/// A fitted force map: the missing acceleration as a smooth function of one variable.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ForceMap {
    /// "z", "v", "t" or "phase".
    pub variable: String,
    /// Unit of `x`: "m", "m/s", "s", or "" for the phase (0 sliding, 1 rolling).
    pub unit: String,
    pub x: Vec<f64>,
    /// Missing acceleration (m/s²) and its standard error at each x.
    pub accel_mps2: Vec<f64>,
    pub se_mps2: Vec<f64>,
    /// Penalty chosen by cross-validation (relative to the mean diagonal) and the effective
    /// number of map parameters it leaves.
    #[serde(with = "super::nan_null")]
    pub lambda: f64,
    #[serde(with = "super::nan_null")]
    pub edf: f64,
    /// In-sample and held-out drop of χ² against no map (shared parameters refitted in both).
    #[serde(with = "super::nan_null")]
    pub chi2_drop: f64,
    #[serde(with = "super::nan_null")]
    pub cv_gain: f64,
    /// Largest |accel| / se over the grid.
    #[serde(with = "super::nan_null")]
    pub max_abs_z: f64,
    /// The spline (lo, knot spacing, segments, coefficients, and the weight of its
    /// second-difference penalty in χ² per (m/s²)²; absent for the phase map): not serialized.
    #[serde(skip)]
    pub spline: Option<(f64, f64, usize, Vec<f64>, f64)>,
}

impl ForceMap {
    /// Largest |accel| over the grid.
    pub fn peak_mps2(&self) -> f64 {
        self.accel_mps2.iter().fold(0.0, |m, a| m.max(a.abs()))
    }
}

/// A periodogram of the residuals.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Spectrum {
    /// "z" (coherent over runs) or "t" (a phase per run).
    pub variable: String,
    /// Wavelength (m) for z, frequency (Hz) for t.
    pub x: Vec<f64>,
    /// χ² drop at each x.
    pub power: Vec<f64>,
    /// Expected power of pure noise (2 for z, 2 per run for t).
    #[serde(with = "super::nan_null")]
    pub noise_power: f64,
    pub peaks: Vec<Peak>,
}

/// A local maximum of a periodogram with the fitted force there.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Peak {
    /// Wavenumber (rad/m) or angular frequency (rad/s).
    #[serde(with = "super::nan_null")]
    pub omega: f64,
    #[serde(with = "super::nan_null")]
    pub power: f64,
    /// z: the sin and cos amplitudes (m/s²); t: the amplitude (m/s², bias-corrected) and 0.
    pub coef: [f64; 2],
}

/// Pooled residual statistics of one bin.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Bin {
    pub n: usize,
    #[serde(with = "super::nan_null")]
    pub rms_m: f64,
    #[serde(with = "super::nan_null")]
    pub mean_m: f64,
    /// Mean residual over its standard error (runs as independent units).
    #[serde(with = "super::nan_null")]
    pub mean_z: f64,
    /// RMS of residual/σ_run: 1 where the model fits within noise.
    #[serde(with = "super::nan_null")]
    pub rms_over_noise: f64,
}

/// Residual structure of a fitted model.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Structure {
    pub by_phase: BTreeMap<String, Bin>,
    pub by_speed: BTreeMap<String, Bin>,
    pub by_position: BTreeMap<String, Bin>,
    pub by_direction: BTreeMap<String, Bin>,
    pub by_material: BTreeMap<String, Bin>,
    /// Stouffer combination of per-run Wald–Wolfowitz runs tests (negative: too few sign changes).
    #[serde(with = "super::nan_null")]
    pub runs_test_z: f64,
    #[serde(with = "super::nan_null")]
    pub runs_test_p: f64,
    /// Mean lag-1 autocorrelation of residuals, and its combined z (√n-weighted).
    #[serde(with = "super::nan_null")]
    pub lag1_autocorrelation: f64,
    #[serde(with = "super::nan_null")]
    pub lag1_z: f64,
}

/// A straight-line fit y = intercept + slope·x with ordinary least-squares standard errors.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Line {
    pub n: usize,
    #[serde(with = "super::nan_null")]
    pub intercept: f64,
    #[serde(with = "super::nan_null")]
    pub slope: f64,
    #[serde(with = "super::nan_null")]
    pub slope_se: f64,
    /// slope / slope_se.
    #[serde(with = "super::nan_null")]
    pub t: f64,
}

/// How a pair physics test's decision opens when the pairs' contact distance, not friction or
/// drag, fits them best (`where.contact_over_diameter`): a length calibration error or a wrong
/// diameter. The summary of the report looks for it.
pub const CONTACT_NOT_PHYSICS: &str = "not friction or drag";

/// An effect id of diagnosis.json: the physics a finding names. Variants are in the order of their
/// ids, so sorting effects sorts their names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Effect {
    /// μ differs by the direction of motion.
    DirectionDependentFriction,
    /// Collision runs only: a force between the two particles before they touch.
    ForceBetweenParticles,
    GrooveTilt,
    /// Collision runs only: the impacts do something the impulse rule misses.
    ImpactSpecificMismatch,
    /// Collision runs only: μ_pp depends on the slip speed at the contact.
    PairFrictionSlipSpeed,
    /// Collision runs only: the pairs' friction or drag differ from the single runs'.
    PairPhysicsMismatch,
    /// μ or T differ from particle to particle beyond the runs' noise, nothing else missing.
    ParticleDifferences,
    /// The camera's positions are distorted across the image (a measurement, no dynamics).
    PositionDistortion,
    PositionDependentForce,
    /// μ varies along the groove (fixed in the lab).
    PositionDependentFriction,
    /// Collision runs only: the coefficient of restitution follows a law outside the candidates.
    RestitutionLaw,
    RollingResistance,
    /// A force that depends on the time since the kick (e.g. a vibration), not on z or v.
    TimeDependentForce,
    Unexplained,
    VelocityDependentDrag,
    VelocityDependentFriction,
}

impl Effect {
    /// Every effect, in id order.
    pub const ALL: [Effect; 16] = [
        Effect::DirectionDependentFriction,
        Effect::ForceBetweenParticles,
        Effect::GrooveTilt,
        Effect::ImpactSpecificMismatch,
        Effect::PairFrictionSlipSpeed,
        Effect::PairPhysicsMismatch,
        Effect::ParticleDifferences,
        Effect::PositionDependentForce,
        Effect::PositionDependentFriction,
        Effect::PositionDistortion,
        Effect::RestitutionLaw,
        Effect::RollingResistance,
        Effect::TimeDependentForce,
        Effect::Unexplained,
        Effect::VelocityDependentDrag,
        Effect::VelocityDependentFriction,
    ];

    /// The id as written in diagnosis.json.
    pub fn id(self) -> &'static str {
        match self {
            Effect::DirectionDependentFriction => "direction_dependent_friction",
            Effect::ForceBetweenParticles => "force_between_particles",
            Effect::GrooveTilt => "groove_tilt",
            Effect::ImpactSpecificMismatch => "impact_specific_mismatch",
            Effect::PairFrictionSlipSpeed => "pair_friction_slip_speed",
            Effect::PairPhysicsMismatch => "pair_physics_mismatch",
            Effect::ParticleDifferences => "particle_differences",
            Effect::PositionDependentForce => "position_dependent_force",
            Effect::PositionDependentFriction => "position_dependent_friction",
            Effect::PositionDistortion => "position_distortion",
            Effect::RestitutionLaw => "restitution_law",
            Effect::RollingResistance => "rolling_resistance",
            Effect::TimeDependentForce => "time_dependent_force",
            Effect::Unexplained => "unexplained",
            Effect::VelocityDependentDrag => "velocity_dependent_drag",
            Effect::VelocityDependentFriction => "velocity_dependent_friction",
        }
    }

    /// The effect of an id, if it is one.
    pub fn from_id(id: &str) -> Option<Effect> {
        Effect::ALL.into_iter().find(|e| e.id() == id)
    }

    /// Where the effect enters the equations (`where.place` of a finding): a force on the
    /// particle, the particle–groove friction, the measurement, or the pair's contact.
    pub fn place(self) -> &'static str {
        match self {
            Effect::DirectionDependentFriction
            | Effect::PositionDependentFriction
            | Effect::VelocityDependentFriction => "friction",
            Effect::PositionDistortion => "measurement",
            Effect::ParticleDifferences => "particles",
            Effect::ForceBetweenParticles
            | Effect::ImpactSpecificMismatch
            | Effect::PairFrictionSlipSpeed
            | Effect::PairPhysicsMismatch
            | Effect::RestitutionLaw => "pair",
            Effect::GrooveTilt
            | Effect::PositionDependentForce
            | Effect::RollingResistance
            | Effect::TimeDependentForce
            | Effect::Unexplained
            | Effect::VelocityDependentDrag => "force",
        }
    }
}

/// The shipped diagnosis (`reports/diagnosis.json`), for tests that change a finding of it.
#[cfg(test)]
pub(crate) fn shipped() -> Diagnosis {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/reports/diagnosis.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn effect_ids_are_the_serialized_names_in_sorted_order() {
        for e in Effect::ALL {
            assert_eq!(
                serde_json::to_string(&e).unwrap(),
                format!("\"{}\"", e.id())
            );
            assert_eq!(Effect::from_id(e.id()), Some(e));
        }
        assert!(Effect::ALL.windows(2).all(|w| w[0].id() < w[1].id()));
        for id in crate::discover::EFFECTS {
            assert!(Effect::from_id(id).is_some(), "{id} has no Effect");
        }
        assert_eq!(Effect::from_id("probe"), None);
    }
}
