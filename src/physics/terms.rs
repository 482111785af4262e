//! Composable extra physics along the groove: accelerations a(z, v) other than groove friction.

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
}

impl Term {
    /// Acceleration (m/s²) at position `z_m` and velocity `v_mps`; sign terms give 0 at v = 0.
    pub fn accel(&self, z_m: f64, v_mps: f64) -> f64 {
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
        }
    }
}
