//! The motion modes of one particle (sliding, rolling, rest): their equations, their event
//! functions, and what follows each event.
//!
//! State layout `[z, v, va]`; every function also takes the time since the kick (time-dependent
//! terms). Sliding with slip direction `d`: `v' = −d g μ(u)/s + a`,
//! `va' = d k g μ(u)`. Rolling (constrained, Filippov): `v' = ks²/(1 + ks²)·a`, `va = v/s`, while
//! the friction it needs, `|s a/(1 + ks²)|`, stays within `g μ_static`. Rest while what holds the
//! particle (rolling resistance) exceeds the non-dissipative forces.

use super::{Model, Phase, G_MPS2};

/// The current mode; `dir` is the sign of v (or of where v is heading when v = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Mode {
    Slide { d: f64, dir: f64 },
    Roll { dir: f64 },
    Rest,
}

/// Extra acceleration at time since the kick `t`, with sign terms taken in direction `dir` when
/// v = 0, and also when v is past 0 in a model with a sign jump (a rolling resistance), whose
/// modes end where v crosses 0 (an event): evaluated at the sign of v itself the right-hand side
/// jumps there, the integrator cannot step across, and a slide the resistance stops ground on at
/// v = ±1e-11 in ever smaller steps (2 s for one 0.1 s track) instead of reaching its event.
fn accel(m: &Model, z: f64, v: f64, t: f64, dir: f64) -> f64 {
    let v_eff = if v == 0.0 || (v * dir < 0.0 && m.has_sign_jump()) {
        dir * f64::MIN_POSITIVE
    } else {
        v
    };
    m.accel(z, v_eff, t)
}

fn sign_or(x: f64, fallback: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        fallback
    }
}

/// Friction can hold the rolling constraint against the extra acceleration `a`.
fn can_roll(m: &Model, a: f64) -> bool {
    let g = &m.groove;
    (g.s * a / (1.0 + g.ks2())).abs() <= G_MPS2 * m.friction.static_limit() * (1.0 + 1e-12)
}

impl Mode {
    pub fn phase(&self) -> Phase {
        match self {
            Mode::Slide { .. } => Phase::Sliding,
            Mode::Roll { .. } => Phase::Rolling,
            Mode::Rest => Phase::Rest,
        }
    }

    /// Time derivative of `[z, v, va]` at time since the kick `t`.
    pub fn rhs(&self, m: &Model, y: &[f64; 3], t: f64) -> [f64; 3] {
        let g = &m.groove;
        match *self {
            Mode::Slide { d, dir } => {
                let mu = m.friction.kinetic(y[1] - g.s * y[2]);
                let a = accel(m, y[0], y[1], t, dir);
                [y[1], -d * G_MPS2 * mu / g.s + a, d * g.k * G_MPS2 * mu]
            }
            Mode::Roll { dir } => {
                let dv = g.rolling_factor() * accel(m, y[0], y[1], t, dir);
                [y[1], dv, dv / g.s]
            }
            Mode::Rest => [0.0; 3],
        }
    }

    /// Event functions (an event fires when one goes negative): [slip or friction limit, v = 0].
    pub fn events(&self, m: &Model, y: &[f64; 3], t: f64) -> [f64; 2] {
        let g = &m.groove;
        match *self {
            Mode::Slide { d, dir } => {
                let v_zero = if m.has_sign_jump() { y[1] * dir } else { 1.0 };
                // rounding slack so a slide that starts at zero slip is armed
                let slack = 1e-15 * (y[1].abs() + (g.s * y[2]).abs());
                [d * (y[1] - g.s * y[2]) + slack, v_zero]
            }
            Mode::Roll { dir } => {
                let a = accel(m, y[0], y[1], t, dir);
                let need = (g.s * a / (1.0 + g.ks2())).abs();
                // the same slack as `can_roll`
                let limit = G_MPS2 * m.friction.static_limit() * (1.0 + 1e-12);
                [limit - need, y[1] * dir]
            }
            Mode::Rest => [1.0, 1.0],
        }
    }

    /// The mode and (projected) state after event `k` of this mode at state `y`.
    pub fn after_event(&self, m: &Model, k: usize, y: &[f64; 3], t: f64) -> (Mode, [f64; 3]) {
        match (*self, k) {
            (Mode::Slide { .. }, 0) => settle(m, y[0], y[1], t),
            (Mode::Slide { d, dir }, _) => {
                // v passed zero while sliding: continue sliding, heading where v' points
                let mut y0 = *y;
                y0[1] = 0.0;
                let probe = Mode::Slide { d, dir: -dir };
                let back = probe.rhs(m, &y0, t)[1];
                if back * dir >= 0.0 {
                    // the way back is barred too: what holds a particle at rest (a rolling
                    // resistance) outweighs the friction of its spin, so v stays 0 (Filippov)
                    // and z with it; carried on, v chattered about 0 to the cap on switches
                    return (Mode::Rest, [y[0], 0.0, 0.0]);
                }
                (Mode::Slide { d, dir: -dir }, y0)
            }
            (Mode::Roll { dir }, 0) => {
                let a = accel(m, y[0], y[1], t, dir);
                (
                    Mode::Slide {
                        d: sign_or(a, dir),
                        dir,
                    },
                    *y,
                )
            }
            (Mode::Roll { .. }, _) => settle(m, y[0], 0.0, t),
            (Mode::Rest, _) => (Mode::Rest, *y),
        }
    }
}

/// The mode of a particle with zero slip at position `z` and velocity `v` (`va = v/s`).
pub(crate) fn settle(m: &Model, z: f64, v: f64, t: f64) -> (Mode, [f64; 3]) {
    let s = m.groove.s;
    if v == 0.0 {
        let a_static = m.accel(z, 0.0, t);
        if a_static.abs() <= m.static_hold_mps2() {
            return (Mode::Rest, [z, 0.0, 0.0]);
        }
        let dir = a_static.signum();
        let a = accel(m, z, 0.0, t, dir);
        let mode = if can_roll(m, a) {
            Mode::Roll { dir }
        } else {
            Mode::Slide { d: a.signum(), dir }
        };
        return (mode, [z, 0.0, 0.0]);
    }
    let dir = v.signum();
    let a = m.accel(z, v, t);
    let mode = if can_roll(m, a) {
        Mode::Roll { dir }
    } else {
        Mode::Slide {
            d: sign_or(a, dir),
            dir,
        }
    };
    (mode, [z, v, v / s])
}

/// The mode at the start from a given state.
pub(crate) fn start(m: &Model, z: f64, v: f64, va: f64, t: f64) -> (Mode, [f64; 3]) {
    let s = m.groove.s;
    let u = v - s * va;
    if u.abs() <= 1e-15 * (v.abs() + (s * va).abs()) {
        return settle(m, z, if v.abs() <= 1e-300 { 0.0 } else { v }, t);
    }
    let d = u.signum();
    let y = [z, v, va];
    let dir = if v != 0.0 {
        v.signum()
    } else {
        let probe = Mode::Slide { d, dir: 1.0 };
        sign_or(probe.rhs(m, &y, t)[1], 1.0)
    };
    (Mode::Slide { d, dir }, y)
}
