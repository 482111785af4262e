//! Particle–groove friction: constant Coulomb μ, or a kinetic μ that vanishes at low slip speed.

use serde::{Deserialize, Serialize};

/// Particle–groove friction law.
///
/// `VelocityDependent` is velocity-strengthening kinetic friction with a finite static limit:
/// while sliding at slip speed `u = |v − s·va|` the kinetic coefficient is
/// `μ(u) = μ∞ (1 − e^{−u/v_c})` (→ 0 as u → 0, → μ∞ for u ≫ v_c, smooth and monotone, so the
/// dissipation `μ(u)·u` is never negative); holding the rolling constraint or rest (zero slip) may
/// use up to the static limit `μ∞`. This is how lubricated or very smooth contacts behave (the
/// chapter's 440c particles show μ → 0 at low speed): slow runs slide longer and a constant-μ fit
/// of them finds a lower μ. Because the drag keeps pushing the slip through zero the switch to
/// rolling is still reached in finite time.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum Friction {
    Constant { mu: f64 },
    VelocityDependent { mu_inf: f64, v_c_mps: f64 },
}

impl Friction {
    /// Kinetic coefficient at slip speed `slip_mps` (either sign).
    pub fn kinetic(&self, slip_mps: f64) -> f64 {
        match *self {
            Friction::Constant { mu } => mu,
            Friction::VelocityDependent { mu_inf, v_c_mps } => {
                -mu_inf * (-slip_mps.abs() / v_c_mps).exp_m1()
            }
        }
    }

    /// Largest coefficient available at zero slip (holding rolling or rest).
    pub fn static_limit(&self) -> f64 {
        match *self {
            Friction::Constant { mu } => mu,
            Friction::VelocityDependent { mu_inf, .. } => mu_inf,
        }
    }
}
