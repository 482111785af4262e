//! The collision aggregates of summary.json: μ_pp and the restitution curves over the impacts
//! (`CollisionSummary`), and the whole-run pair fits per material with their μ_pp profile and
//! the restitution law chosen per setup, or taken from discovery under the accepted physics
//! (`WholeRunSummary`). Written by `fit::collision`, read by the report.

use super::collision_fit::{Contact, PreImpactSource};
use super::estimate::Estimate;
use crate::lsq::Termination;
use crate::physics::{Restitution, SlipFriction};
use crate::recording::Setup;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The walk along the grid stops in a direction once a fit beyond the estimate lies this far
/// (raw deviance above the best fit) above the minimum: even divided by the largest serial
/// inflation (39) it is far above the 95 % level, and the fits further out, the slowest of
/// the profile, would only draw the curve.
pub const STOP_DEVIANCE: f64 = 1e4;

/// One grid value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProfilePoint {
    pub mu_pp: f64,
    /// Deviance above the best fit divided by the profile's `inflation` (χ² units; 0 at the
    /// minimum).
    pub deviance: f64,
    pub converged: bool,
}

/// What the profile says about μ_pp.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ProfileVerdict {
    /// A minimum inside the grid; the 95 % interval.
    Interval { estimate: f64, lo: f64, hi: f64 },
    /// Flat above `lo`: the recordings only say μ_pp > lo (95 %).
    LowerBound { lo: f64 },
    /// Flat below `hi`: μ_pp < hi (95 %).
    UpperBound { hi: f64 },
    /// Flat over the whole grid: the recordings do not constrain μ_pp.
    Unconstrained,
}

/// The profile of one material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MuPpProfile {
    pub points: Vec<ProfilePoint>,
    /// Grid values not fitted: beyond a fit whose deviance passed `STOP_DEVIANCE` (raw), on the
    /// same side of the estimate.
    pub not_fitted: Vec<f64>,
    pub verdict: ProfileVerdict,
    /// The deviance rise used for the interval.
    pub threshold: f64,
    /// Run-level dispersion (≥ 1): how much more the runs disagree about μ_pp than their noise
    /// says (a sandwich over runs at the estimate).
    pub dispersion: f64,
    /// Pooled lag-1 autocorrelation of the best fit's residuals (consecutive samples of each
    /// track of each run, Huber-clipped, not centred).
    pub lag1_autocorrelation: f64,
    /// Pooled lag-1 autocorrelation of the residuals' contributions to the μ_pp score
    /// (residual × its derivative in ln μ_pp): the serial correlation where μ_pp is measured.
    pub score_lag1_autocorrelation: f64,
    /// Variance inflation of an AR(1) score, (1 + ρ)/(1 − ρ) with ρ =
    /// `score_lag1_autocorrelation` (1 when ρ ≤ 0): the deviance of correlated residuals
    /// counts each sample as more than the independent information it carries.
    pub serial_factor: f64,
    /// Scale of the Huber deviance, mean ψ² / mean ψ′ of the best fit's whitened residuals
    /// (ψ clipped at the Huber threshold, ψ′ = 1 inside it): 1 when each run's noise estimate
    /// is right; the average rise of the deviance at the true μ_pp otherwise.
    pub scale_factor: f64,
    /// What the deviances were divided by: the larger of `dispersion` and `scale_factor` ×
    /// `serial_factor` (both estimate how much the fit's noise model understates the variance of
    /// the μ_pp score).
    pub inflation: f64,
}

impl ProfileVerdict {
    /// Whether `mu` is inside what the profile allows.
    pub fn contains(&self, mu: f64) -> bool {
        match *self {
            ProfileVerdict::Interval { lo, hi, .. } => lo <= mu && mu <= hi,
            ProfileVerdict::LowerBound { lo } => mu >= lo,
            ProfileVerdict::UpperBound { hi } => mu <= hi,
            ProfileVerdict::Unconstrained => true,
        }
    }
}

/// Form of a restitution law C(v) of the impact speed v.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LawForm {
    /// C = c.
    Constant,
    /// C = c0 − slope·v.
    Linear,
    /// C = c_inf + (1 − c_inf) e^{−v/v_ref} (see `physics`).
    Saturating,
    /// Not chosen among the candidates: the law discovery accepted for these impacts
    /// (`LawChoice::discovered`; the `refit` stage): a named form held as discovery gave it from
    /// the impacts' own C, a map with its nodes' speeds held and its values refitted in the
    /// whole-run fit, started from discovery's.
    FromDiscovery,
}

impl LawForm {
    /// The candidates the whole-run fits choose among.
    pub const ALL: [LawForm; 3] = [LawForm::Constant, LawForm::Linear, LawForm::Saturating];

    /// Names of its parameters (SI units in the names) and how slot b maps to them; none for a
    /// law held from discovery (its parameters are its own, `LawChoice::discovered`).
    pub fn parameter_names(self) -> &'static [&'static str] {
        match self {
            LawForm::Constant => &["c"],
            LawForm::Linear => &["c0", "slope_per_mps"],
            LawForm::Saturating => &["c_inf", "v_ref_mps"],
            LawForm::FromDiscovery => &[],
        }
    }
}

/// One candidate form.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LawCandidate {
    pub form: LawForm,
    /// Each parameter by name (`LawForm::parameter_names`) with its standard error and 95 %
    /// interval (written `{value, lo, hi}`).
    #[serde(with = "crate::artifacts::estimate::bounds::map")]
    pub parameters: BTreeMap<String, Estimate>,
    /// RMS of the held-out runs' residuals, in units of their position noise.
    pub heldout_rms_noise: f64,
    /// Held-out Huber deviance summed over the folds.
    pub heldout_deviance: f64,
}

/// The law chosen for one material and setup.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LawChoice {
    pub setup: Setup,
    pub n_runs: usize,
    pub folds: usize,
    pub chosen: LawForm,
    /// Empty when the law is discovery's (`chosen` is then `from_discovery`).
    pub candidates: Vec<LawCandidate>,
    /// The law used, when `chosen` is `from_discovery`: the named form discovery accepted, or
    /// its map at the values the whole-run fit gave its nodes (`physics::Restitution`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub discovered: Option<Restitution>,
}

impl LawCandidate {
    /// The parameters in the order of `LawForm::parameter_names` (slot a, then b).
    pub fn ordered(&self) -> Vec<(&'static str, &Estimate)> {
        self.form
            .parameter_names()
            .iter()
            .filter_map(|n| self.parameters.get(*n).map(|e| (*n, e)))
            .collect()
    }

    /// The values of the law's two fit slots (`LawForm::law`'s a and b): a saturating law's
    /// v_ref through its logarithm, the fitted slot; b is 0 for a one-parameter law, a is None
    /// when the first parameter is missing.
    pub fn slots(&self) -> Option<[f64; 2]> {
        let p = self.ordered();
        let a = p.first()?.1.value;
        let b = match (self.form, p.get(1)) {
            (LawForm::Saturating, Some((_, e))) => e.value.ln(),
            (_, Some((_, e))) => e.value,
            (_, None) => 0.0,
        };
        Some([a, b])
    }
}

impl LawChoice {
    pub fn chosen_candidate(&self) -> Option<&LawCandidate> {
        self.candidates.iter().find(|c| c.form == self.chosen)
    }

    /// The law the fit used: the chosen candidate's at its all-runs values, or discovery's.
    pub fn law(&self) -> Option<Restitution> {
        if let Some(h) = self.discovered {
            return Some(h);
        }
        let cand = self.chosen_candidate()?;
        let [a, b] = cand.slots()?;
        Some(cand.form.law(a, b))
    }
}

/// μ_pp estimates.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MuPp {
    /// The headline value: the impulse-model fit when there are slip impacts, else None.
    #[serde(with = "crate::artifacts::estimate::bounds::option")]
    pub value: Option<Estimate>,
    /// Slope of −sign(S)·Δv_a against Δv_z of the target over slip impacts, divided by k.
    #[serde(with = "crate::artifacts::estimate::bounds::option")]
    pub from_slip_slope: Option<Estimate>,
    /// μ_pp minimizing the misfit of the measured spin changes of both particles to the
    /// impulse model, stick and slip impacts together.
    #[serde(with = "crate::artifacts::estimate::bounds::option")]
    pub from_impulse_fit: Option<Estimate>,
    /// Stick impacts need μ_pp > |S| / (2 k J); the largest such bound.
    pub stick_lower_bound: Option<f64>,
    pub n_slip: usize,
    pub n_stick: usize,
    pub n_undetermined: usize,
}

/// C against impact speed for one material and setup, over the first impact of each run
/// (secondary impacts are slow and short-lived; they are listed in `restitution_points`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RestitutionCurve {
    pub material: String,
    pub setup: Option<Setup>,
    pub n_impacts: usize,
    pub n_runs: usize,
    /// C = c0 − slope · v (weighted least squares).
    #[serde(with = "crate::artifacts::estimate::bounds")]
    pub c0: Estimate,
    #[serde(with = "crate::artifacts::estimate::bounds")]
    pub slope_per_mps: Estimate,
    /// C = 1 − a · v, the chapter's "C → 1 at low speed" form.
    #[serde(with = "crate::artifacts::estimate::bounds")]
    pub a_per_mps: Estimate,
    /// C = c_inf + (1 − c_inf) e^{−v/v_ref}: 1 for a gentle touch, falling to c_inf
    /// (the form `physics::Restitution::SpeedDependent` simulates).
    #[serde(with = "crate::artifacts::estimate::bounds")]
    pub c_inf: Estimate,
    #[serde(with = "crate::artifacts::estimate::bounds")]
    pub v_ref_mps: Estimate,
    #[serde(with = "crate::artifacts::nan_null")]
    pub mean_c: f64,
    #[serde(with = "crate::artifacts::nan_null")]
    pub min_speed_mps: f64,
    #[serde(with = "crate::artifacts::nan_null")]
    pub max_speed_mps: f64,
}

/// One impact in Fig. 4.4a (target, striker-forward frame).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpinPoint {
    pub run: String,
    pub material: String,
    pub impact: usize,
    #[serde(with = "crate::artifacts::nan_null")]
    pub dvz_mps: f64,
    pub dvz_se_mps: Option<f64>,
    #[serde(with = "crate::artifacts::nan_null")]
    pub dva_mps: f64,
    pub dva_se_mps: Option<f64>,
    pub contact: Contact,
}

/// One impact in Figs. 4.4b–c.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RestitutionPoint {
    pub run: String,
    pub material: String,
    pub setup: Option<Setup>,
    pub impact: usize,
    #[serde(with = "crate::artifacts::nan_null")]
    pub impact_speed_mps: f64,
    #[serde(with = "crate::artifacts::nan_null")]
    pub restitution: f64,
    pub restitution_se: Option<f64>,
    pub striker_before_source: PreImpactSource,
}

/// `summary.json` → "collisions".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CollisionSummary {
    pub n_runs: usize,
    pub n_runs_fitted: usize,
    pub n_impacts: usize,
    #[serde(with = "crate::artifacts::nan_null")]
    pub k: f64,
    pub mu_pp: MuPp,
    pub restitution: Vec<RestitutionCurve>,
    pub spin_points: Vec<SpinPoint>,
    pub restitution_points: Vec<RestitutionPoint>,
    pub bootstrap_seed: u64,
    pub bootstrap_resamples: usize,
    pub notes: Vec<String>,
    /// The whole-run pair fits per material (μ_pp profile, restitution laws); absent when the
    /// stage did not compute them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub whole_run: Option<WholeRunSummary>,
}

/// One run in the whole-run fit of its material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WholeRun {
    pub run: String,
    pub setup: Setup,
    /// Kick speed of the striker (lab frame, m/s).
    pub v0_mps: Estimate,
    pub t_kick_s: f64,
    /// RMS of the residuals (m) and the position noise (m).
    pub rms_m: f64,
    pub noise_m: f64,
    pub n_points: usize,
    /// Impacts the fitted model makes in the recorded time, and how many slip.
    pub n_impacts: usize,
    pub n_slip: usize,
    /// The first impact: approach speed (m/s) and C of the fitted law there.
    pub first_impact_speed_mps: Option<f64>,
    pub first_impact_restitution: Option<f64>,
    /// RMS of the residuals (in units of the noise) by phase of the particle and by time since
    /// the last impact (`0-1ms`, `1-5ms`, `5-20ms`, `>20ms`, `before`).
    pub residual_by_phase: BTreeMap<String, f64>,
    pub residual_by_time_since_impact: BTreeMap<String, f64>,
}

/// The whole-run analysis of one material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MaterialWholeRun {
    pub material: String,
    pub n_runs: usize,
    pub status: Termination,
    pub iterations: usize,
    pub max_iter: usize,
    /// The drag form of the shared physics.
    pub drag: String,
    pub mu_pg: Estimate,
    pub t0_s: Estimate,
    pub tp_s_per_mps: Estimate,
    /// μ_pp of the best fit (its standard error is meaningful only with an interval).
    pub mu_pp: Estimate,
    /// μ_pp's dependence on the slip speed carried from discovery (`refit`): `mu_pp` and the
    /// profile are then μ_pp at its `u_ref_mps`. Absent: one μ_pp.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu_pp_slip: Option<SlipFriction>,
    pub profile: MuPpProfile,
    pub restitution: Vec<LawChoice>,
    /// Deviance (χ² units) and residual RMS in noise units over all runs.
    pub deviance: f64,
    pub rms_noise: f64,
    pub runs: Vec<WholeRun>,
    pub notes: Vec<String>,
}

/// summary.json → collisions → whole_run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WholeRunSummary {
    pub materials: Vec<MaterialWholeRun>,
    pub notes: Vec<String>,
}

impl MaterialWholeRun {
    /// The sentence the report prints about μ_pp.
    pub fn mu_pp_words(&self) -> String {
        match self.profile.verdict {
            ProfileVerdict::Interval { estimate, lo, hi } => format!(
                "μ_pp = {estimate:.2} (95 % profile interval {lo:.2}–{hi:.2}); the chapter's 1.4 is {}",
                if (lo..=hi).contains(&1.4) { "inside it" } else { "outside it" }
            ),
            ProfileVerdict::LowerBound { lo } => format!(
                "the recordings bound μ_pp from below at {lo:.2} (95 %): the profile is flat above, so the chapter's 1.4 is {}",
                if 1.4 >= lo { "allowed but not measured" } else { "excluded" }
            ),
            ProfileVerdict::UpperBound { hi } => {
                format!("the recordings bound μ_pp from above at {hi:.2} (95 %)")
            }
            ProfileVerdict::Unconstrained => {
                "the recordings do not constrain μ_pp over the profiled range".to_string()
            }
        }
    }
}
