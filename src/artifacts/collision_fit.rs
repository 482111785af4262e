//! The per-run result of a collision fit (`RunFit::Collision`, item of the `fit` stage): phase fits of both particles
//! and every impact with velocities and spins before and after. SI units in the field names;
//! velocities and spins in the lab frame (sign = direction along z).

use crate::recording::Setup;
use serde::{Deserialize, Serialize};

pub use super::estimate::Estimate;
pub use crate::lsq::Termination;

/// The `status` word of a rolling-setup run whose target never left rest: no impact to measure
/// (the approach was fitted; `termination` says how that fit ended).
pub const NO_IMPACT: &str = "no_impact";

/// Phase of one particle's motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PhaseKind {
    Rest,
    Sliding,
    Rolling,
}

/// A time span of one phase.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhaseSpan {
    pub phase: PhaseKind,
    pub t_start_s: f64,
    pub t_end_s: f64,
}

/// One piece of a particle's track between impacts (or track start/end), fitted with the
/// closed-form motion from (v, v_a) at its start: a sliding phase, then rolling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SegmentFit {
    /// 0 striker, 1 target.
    pub particle: u32,
    pub t_start_s: f64,
    pub t_end_s: f64,
    pub z_start_m: f64,
    pub v_start_mps: Estimate,
    pub va_start_mps: Estimate,
    /// Drag time of this segment (the run's T unless fitted per segment).
    pub t_drag_s: Estimate,
    /// When sliding ends (absolute time); None if not within the segment.
    pub t_switch_s: Option<f64>,
    /// False when the segment ends before the switch to rolling, so v_a is only bounded.
    pub spin_identified: bool,
    pub phases: Vec<PhaseSpan>,
    pub n_points: usize,
}

/// Velocity and spin (v_a = R ω) of a particle at an instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Kin {
    pub v_mps: Estimate,
    pub va_mps: Estimate,
}

/// Stick or slip at the contact, judged from the measured spins (see `physics`): stick leaves the
/// surfaces moving together (v_a1' + v_a2' = 0); slip changes both spins by the same amount.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Contact {
    Stick,
    Slip,
    /// The spins after the impact are not resolved (e.g. the next impact came before rolling).
    Undetermined,
}

/// Where the striker's pre-impact velocity comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PreImpactSource {
    /// The fit of its track before the impact.
    Fitted,
    /// Contact setup, no track before the impact: v1 = v1' + v2' (equal masses, target at rest,
    /// momentum conserved), spins zero.
    MomentumConservation,
}

/// One impact between striker and target.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ImpactFit {
    /// 0 for the first impact; later ones are secondary collisions.
    pub index: usize,
    pub t_s: Estimate,
    pub striker_before: Kin,
    pub striker_after: Kin,
    pub target_before: Kin,
    pub target_after: Kin,
    pub striker_before_source: PreImpactSource,
    /// Approach speed v1 − v2 just before (m/s, positive).
    pub impact_speed_mps: Estimate,
    /// C = (v2' − v1') / (v1 − v2) (Eq. 4.20).
    pub restitution: Estimate,
    /// Δv_z and Δv_a of the target, in the striker-forward frame (Δv_z > 0).
    pub target_dvz_mps: Estimate,
    pub target_dva_mps: Estimate,
    /// Δv_a of the striker, same frame.
    pub striker_dva_mps: Estimate,
    /// v_a1 + v_a2 before and after (striker-forward frame).
    #[serde(with = "super::nan_null")]
    pub spin_sum_before_mps: f64,
    pub spin_sum_after_mps: Estimate,
    /// (v1 + v2) − (v1' + v2'): zero by construction when the impulse ties the states (m/s).
    #[serde(with = "super::nan_null")]
    pub momentum_mismatch_mps: f64,
    pub contact: Contact,
}

/// The fit of one collision run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CollisionFit {
    pub run: String,
    pub material: String,
    pub setup: Option<Setup>,
    /// +1 when the striker moves toward +z, −1 toward −z.
    pub direction: i32,
    /// How the joint fit ended (a missing or short track is `too_few_points`).
    pub termination: Termination,
    /// One word: `converged`, `max_iterations` or `failed` (from `termination`), or
    /// `no_impact` (see [`NO_IMPACT`]); anything but `converged` is shown, not hidden.
    pub status: String,
    pub message: String,
    /// Particle–groove friction, shared by both particles and all segments.
    pub mu_pg: Estimate,
    /// Drag time of the run: shared by all segments, or the centre their own T (see
    /// `segments`) are drawn toward when fitted per segment.
    pub t_drag_s: Estimate,
    pub segments: Vec<SegmentFit>,
    pub impacts: Vec<ImpactFit>,
    #[serde(with = "super::nan_null")]
    pub rms_m: f64,
    /// Robust residual scale (1.4826·MAD) of the joint fit.
    #[serde(with = "super::nan_null")]
    pub noise_m: f64,
    pub n_points: usize,
    /// Samples with |residual| > 5 noise scales (down-weighted by the robust loss).
    pub n_outliers: usize,
    pub iterations: usize,
    /// The fit stops here (s) when the pair touches again without a resolvable impact; later
    /// samples are left out (see `message`). None: the whole tracks were fitted.
    pub fit_end_s: Option<f64>,
}

impl CollisionFit {
    /// Whether its impacts can be used: it has impacts and its fit converged or stopped at the
    /// iteration limit with a result.
    pub fn usable(&self) -> bool {
        self.status != NO_IMPACT
            && (self.termination.is_converged() || self.termination == Termination::MaxIterations)
    }
}
