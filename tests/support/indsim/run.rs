//! A fine trajectory on the fixed step grid and the simulation of one kicked particle.

use super::events::Particle;
use super::integrator::Mode;
use super::model::Physics;

/// Default integration step (s).
pub const DT_S: f64 = 1e-5;

/// Positions and velocities at t = i·dt since the kick, and the modes the particle went through.
#[derive(Clone, Debug, Default)]
pub struct Fine {
    pub dt: f64,
    pub z: Vec<f64>,
    pub v: Vec<f64>,
    pub va: Vec<f64>,
    /// (time, mode entered) at every change of mode seen at a grid point.
    pub switches: Vec<(f64, Mode)>,
}

impl Fine {
    pub fn push(&mut self, p: &Particle, t: f64) {
        if self.switches.last().map(|s| s.1) != Some(p.mode) {
            self.switches
                .push((if self.z.is_empty() { t } else { p.switched_at }, p.mode));
        }
        self.z.push(p.x.z);
        self.v.push(p.x.v);
        self.va.push(p.x.va);
    }

    /// Time of the last grid point.
    pub fn end_s(&self) -> f64 {
        (self.z.len().saturating_sub(1)) as f64 * self.dt
    }

    /// Position and velocity at time `t` (cubic Hermite between grid points; clamped at the ends).
    pub fn at(&self, t: f64) -> (f64, f64) {
        let n = self.z.len();
        let x = (t / self.dt).clamp(0.0, (n - 1) as f64);
        let i = (x.floor() as usize).min(n - 2);
        let s = x - i as f64;
        let (z0, z1, v0, v1) = (
            self.z[i],
            self.z[i + 1],
            self.v[i] * self.dt,
            self.v[i + 1] * self.dt,
        );
        let (s2, s3) = (s * s, s * s * s);
        let z = (2.0 * s3 - 3.0 * s2 + 1.0) * z0
            + (s3 - 2.0 * s2 + s) * v0
            + (-2.0 * s3 + 3.0 * s2) * z1
            + (s3 - s2) * v1;
        let v = self.v[i] + s * (self.v[i + 1] - self.v[i]);
        (z, v)
    }
}

/// One particle kicked at t = 0 from `z0` with velocity `v0` and no spin, for `duration_s`.
pub fn simulate(p: &Physics, z0: f64, v0: f64, duration_s: f64, dt: f64) -> Fine {
    let mut part = Particle::kicked(z0, v0);
    part.settle(p, 0.0, 0.0);
    let steps = (duration_s / dt).ceil() as usize + 1;
    let mut fine = Fine {
        dt,
        ..Fine::default()
    };
    fine.push(&part, 0.0);
    for i in 0..steps {
        let t = i as f64 * dt;
        part.advance(p, t, dt, 0.0);
        fine.push(&part, t + dt);
    }
    fine
}
