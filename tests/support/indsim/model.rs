//! Constants of the groove and the physics one particle obeys (friction, drag, extra forces).

use super::effects::{Drag, Force, FrictionLaw};

/// Gravity, m/s².
pub const G: f64 = 9.81;

/// The groove's geometry and the particle's inertia.
#[derive(Clone, Copy, Debug)]
pub struct Groove {
    /// sin(θ/2), θ the opening angle.
    pub s: f64,
    /// m R² / I (5/2 for a solid sphere).
    pub k: f64,
}

impl Groove {
    /// A groove of opening angle `theta_deg` holding solid spheres.
    pub fn from_angle_deg(theta_deg: f64) -> Groove {
        Groove {
            s: (0.5 * theta_deg.to_radians()).sin(),
            k: 2.5,
        }
    }

    /// k s².
    pub fn ks2(&self) -> f64 {
        self.k * self.s * self.s
    }
}

/// Everything that moves one particle.
#[derive(Clone, Debug)]
pub struct Physics {
    pub groove: Groove,
    /// Particle–groove Coulomb friction (the base value the law modifies).
    pub mu: f64,
    pub drag: Drag,
    pub friction: FrictionLaw,
    pub forces: Vec<Force>,
}

impl Physics {
    /// The baseline: constant μ and linear drag with time constant `t_s`.
    pub fn baseline(mu: f64, t_s: f64) -> Physics {
        Physics {
            groove: Groove::from_angle_deg(70.6),
            mu,
            drag: Drag::Linear { t_s },
            friction: FrictionLaw::Constant,
            forces: Vec::new(),
        }
    }

    /// Every acceleration but groove friction; `dir` is the direction of motion (±1), kept through
    /// a step (a change of direction is an event), so the stages of a step agree on it.
    pub fn accel(&self, z: f64, v: f64, t: f64, dir: f64) -> f64 {
        self.drag.accel(v)
            + self
                .forces
                .iter()
                .map(|f| f.accel(z, v, t, dir))
                .sum::<f64>()
    }

    /// Kinetic friction coefficient at lab position `z`, slip speed `slip` (≥ 0), direction `dir`.
    pub fn mu_kinetic(&self, z: f64, slip: f64, dir: f64) -> f64 {
        self.friction.mu(self.mu, z, Some(slip), dir)
    }

    /// The coefficient that bounds the rolling hold.
    pub fn mu_static(&self, z: f64, dir: f64) -> f64 {
        self.friction.mu(self.mu, z, None, dir)
    }
}
