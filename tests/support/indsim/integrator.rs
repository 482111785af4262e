//! The state of one particle, its three modes of motion and one fixed RK4 step in a mode.

use super::model::{Physics, G};

/// Position, velocity and spin surface speed v_a = R ω.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct State {
    pub z: f64,
    pub v: f64,
    pub va: f64,
}

/// How the particle moves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    /// Sliding with slip direction d = sign(v − s v_a).
    Slide(f64),
    /// Rolling without slip (v = s v_a).
    Roll,
    /// At rest.
    Rest,
}

/// Time derivatives (dz, dv, dv_a) in `mode`; `ext` is an extra acceleration held over the step
/// (the force between two particles) and `dir` the direction of motion, fixed over the step.
pub fn rhs(p: &Physics, mode: Mode, x: &State, t: f64, ext: f64, dir: f64) -> (f64, f64, f64) {
    let g = p.groove;
    match mode {
        Mode::Slide(d) => {
            let u = x.v - g.s * x.va;
            let mu = p.mu_kinetic(x.z, u.abs(), dir);
            let a = p.accel(x.z, x.v, t, dir) + ext;
            (x.v, -d * G * mu / g.s + a, d * g.k * G * mu)
        }
        Mode::Roll => {
            let a = p.accel(x.z, x.v, t, dir) + ext;
            let dv = g.ks2() / (1.0 + g.ks2()) * a;
            (x.v, dv, dv / g.s)
        }
        Mode::Rest => (0.0, 0.0, 0.0),
    }
}

/// One classical RK4 step of length `h` from time `t`.
pub fn rk4(p: &Physics, mode: Mode, x: &State, t: f64, h: f64, ext: f64, dir: f64) -> State {
    let add = |x: &State, k: (f64, f64, f64), f: f64| State {
        z: x.z + f * k.0,
        v: x.v + f * k.1,
        va: x.va + f * k.2,
    };
    let k1 = rhs(p, mode, x, t, ext, dir);
    let k2 = rhs(p, mode, &add(x, k1, 0.5 * h), t + 0.5 * h, ext, dir);
    let k3 = rhs(p, mode, &add(x, k2, 0.5 * h), t + 0.5 * h, ext, dir);
    let k4 = rhs(p, mode, &add(x, k3, h), t + h, ext, dir);
    State {
        z: x.z + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
        v: x.v + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
        va: x.va + h / 6.0 * (k1.2 + 2.0 * k2.2 + 2.0 * k3.2 + k4.2),
    }
}
