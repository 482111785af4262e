//! Composable extra physics along the groove: accelerations a(z, v, t) other than groove friction
//! (t is the time since the kick of the particle's run).

use super::spline::SplineForce;
use super::G_MPS2;
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// One extra acceleration term; a model sums any number of them.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(tag = "term", rename_all = "snake_case")]
pub enum Term {
    /// Linear drag `−v/T`.
    LinearDrag { t_s: f64 },
    /// Quadratic drag `−c v|v|` (either sign of c).
    QuadraticDrag { c_per_m: f64 },
    /// Saturating drag `−v/(T0 + T'|v|)`: linear at low speed, a constant force at high speed.
    SaturatingDrag { t0_s: f64, tp_s_per_mps: f64 },
    /// Rolling resistance `−c g sign(v)` (dimensionless c); at rest it holds up to `c g`.
    RollingResistance { c: f64 },
    /// Groove tilt: `−g sin α`, the same lab-frame sign for both directions of motion.
    GrooveTilt { alpha_deg: f64 },
    /// Position-dependent force (waviness, a defect): `amp sin(2π z/λ + φ)`.
    PositionForce {
        amp_mps2: f64,
        wavelength_m: f64,
        phase_rad: f64,
    },
    /// Localized force fixed in the lab (a bump, a defect): `amp exp(−(z − z_c)²/(2 w²))`.
    LocalizedForce {
        amp_mps2: f64,
        centre_m: f64,
        width_m: f64,
    },
    /// A step fixed in the lab (the joint of two pieces of groove at different slopes):
    /// `amp (1 + tanh((z − z_s)/(2w)))/2`, nothing below the step and `amp` above it.
    StepForce {
        amp_mps2: f64,
        z_step_m: f64,
        width_m: f64,
    },
    /// Force periodic in the time since the kick (a vibration): `amp sin(2π f t + φ)`.
    /// A truth file may give each run its own φ (`[physics] time_phase_per_run = true`).
    TimePeriodicForce {
        amp_mps2: f64,
        freq_hz: f64,
        phase_rad: f64,
    },
    /// A smooth force of z, v or t given by a cubic B-spline (the nonparametric model).
    Spline(SplineForce),
}

impl Term {
    /// Acceleration (m/s²) at position `z_m`, velocity `v_mps` and time since the kick `t_s`;
    /// sign terms give 0 at v = 0.
    pub fn accel(&self, z_m: f64, v_mps: f64, t_s: f64) -> f64 {
        match *self {
            Term::LinearDrag { t_s } => -v_mps / t_s,
            Term::QuadraticDrag { c_per_m } => -c_per_m * v_mps * v_mps.abs(),
            Term::SaturatingDrag { t0_s, tp_s_per_mps } => {
                -v_mps / (t0_s + tp_s_per_mps * v_mps.abs())
            }
            Term::RollingResistance { c } => {
                if v_mps == 0.0 {
                    0.0
                } else {
                    -c * G_MPS2 * v_mps.signum()
                }
            }
            Term::GrooveTilt { alpha_deg } => -G_MPS2 * alpha_deg.to_radians().sin(),
            Term::PositionForce {
                amp_mps2,
                wavelength_m,
                phase_rad,
            } => amp_mps2 * (TAU * z_m / wavelength_m + phase_rad).sin(),
            Term::LocalizedForce {
                amp_mps2,
                centre_m,
                width_m,
            } => {
                let u = (z_m - centre_m) / width_m;
                amp_mps2 * (-0.5 * u * u).exp()
            }
            Term::StepForce {
                amp_mps2,
                z_step_m,
                width_m,
            } => amp_mps2 * step_shape((z_m - z_step_m) / width_m),
            Term::TimePeriodicForce {
                amp_mps2,
                freq_hz,
                phase_rad,
            } => amp_mps2 * (TAU * freq_hz * t_s + phase_rad).sin(),
            Term::Spline(ref sp) => sp.accel(z_m, v_mps, t_s),
        }
    }

    /// The term depends on the time since the kick.
    pub fn time_dependent(&self) -> bool {
        match self {
            Term::TimePeriodicForce { .. } => true,
            Term::Spline(sp) => sp.variable == super::spline::Variable::T,
            _ => false,
        }
    }

    /// The time over which the term changes (s): a vibration's period, a spline's knot spacing
    /// in t; `None` for a term that does not depend on time.
    pub fn time_scale_s(&self) -> Option<f64> {
        match self {
            Term::TimePeriodicForce { freq_hz, .. } => Some(1.0 / freq_hz.abs()),
            Term::Spline(sp) if sp.variable == super::spline::Variable::T => Some(sp.dx.abs()),
            _ => None,
        }
    }

    /// The term jumps where v changes sign (so the integrator stops there).
    pub fn has_sign_jump(&self) -> bool {
        matches!(self, Term::RollingResistance { c } if *c != 0.0)
    }

    /// Resistance (m/s², ≥ 0) this term can offer to a particle at rest.
    pub fn static_hold_mps2(&self) -> f64 {
        match *self {
            Term::RollingResistance { c } => (c * G_MPS2).max(0.0),
            _ => 0.0,
        }
    }

    /// A short physical name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Term::LinearDrag { .. } => "linear drag",
            Term::QuadraticDrag { .. } => "quadratic drag",
            Term::SaturatingDrag { .. } => "saturating drag",
            Term::RollingResistance { .. } => "rolling resistance",
            Term::GrooveTilt { .. } => "groove tilt",
            Term::PositionForce { .. } => "position-dependent force",
            Term::LocalizedForce { .. } => "localized force",
            Term::StepForce { .. } => "step force",
            Term::TimePeriodicForce { .. } => "time-periodic force",
            Term::Spline(_) => "spline force",
        }
    }
}

/// The shape of a step of unit height and width: 0 far below, 1 far above, ½ at u = 0.
pub fn step_shape(u: f64) -> f64 {
    0.5 * (1.0 + (0.5 * u).tanh())
}
