//! The motion modes of one particle (sliding, rolling, rest): their equations, their event
//! functions, and what follows each event.
//!
//! State layout `[z, v, va]`; every function also takes the time since the kick (time-dependent
//! terms) and `ext`, an acceleration from outside the particle's own model (the force of the
//! other particle of a pair; 0 for one particle alone), which enters `a` beside the model's
//! terms. Sliding with slip direction `d`: `v' = −d g μ(u)/s + a`, `va' = d k g μ(u)`. Rolling (constrained, Filippov): `v' = ks²/(1 + ks²)·a`, `va = v/s`, while
//! the friction it needs, `|s a/(1 + ks²)|`, stays within `g μ_static`. Rest while what holds the
//! particle (rolling resistance) exceeds the non-dissipative forces; under a force that depends on
//! time, rest ends where that force outgrows the hold (`Mode::absorbing`). Creep: a slide whose
//! velocity-dependent friction holds the slip at its quasi-static value (below).

use super::{Friction, Model, Phase, G_MPS2};

/// The current mode; `dir` is the sign of v (or of where v is heading when v = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Mode {
    Slide {
        d: f64,
        dir: f64,
    },
    /// A slide whose slip `u` sits on its quasi-static value `d·u_eq` (see `quasi_static`).
    Creep {
        d: f64,
        dir: f64,
    },
    Roll {
        dir: f64,
    },
    Rest,
}

/// Relaxation time of the slip (s) below which a slide with velocity-dependent friction creeps.
///
/// With μ(u) → 0 at zero slip, a force that pushes the slip away from zero (a tilt downhill) is
/// met by a slip `u_eq` where `μ(u_eq) = d·a/K` (`K = g(1 + ks²)/s`), reached in a relaxation
/// time `τ = v_c / (K (μ∞ − μ(u_eq)))`; the slide never ends. For a small v_c (a fit wandering
/// towards Coulomb friction) τ is microseconds and the explicit integrator took steps of that
/// size for the whole run (22 s for one fit of 60 runs). Once the transient is over the slip
/// follows `u_eq(a)` with a lag τ·u̇_eq, and the exact identity `v' = (ks² a + u')/(1 + ks²)`
/// (the slide's two equations combined) with `u' = τ ȧ` gives the motion without the stiff
/// variable; what is left out, the lag's own effect on v, is τ²|ȧ|/(1 + ks²), so z is off by at
/// most τ²|Δa|/(1 + ks²): 2·10⁻¹¹ m per 0.1 m/s² of change in the force at this bound.
const TAU_CREEP_S: f64 = 2e-5;

/// A creep ends (and the slide goes on) once τ exceeds this multiple of `TAU_CREEP_S`, so a τ
/// at the bound does not switch back and forth.
const CREEP_EXIT: f64 = 2.0;

/// A slide starts creeping when what is left of its slip's transient, `|d·u − u_eq|·τ`, is below
/// this distance (m): the integrator's own position tolerance (`simulate::TOL`).
const CREEP_ENTRY_M: f64 = 1e-12;

/// Time step (s) of the forward difference that gives ȧ along the creep.
const CREEP_DT_S: f64 = 1e-7;

/// The quasi-static slip `u_eq` (≥ 0, along `d`) and its relaxation time τ for the extra
/// acceleration `a`, when the friction is velocity-dependent and `a` pushes the slip away from
/// zero less than the kinetic limit can hold.
fn quasi_static(m: &Model, d: f64, a: f64) -> Option<(f64, f64)> {
    let Friction::VelocityDependent { mu_inf, v_c_mps } = m.friction else {
        return None;
    };
    let g = &m.groove;
    let big_k = G_MPS2 * (1.0 + g.ks2()) / g.s;
    let need = d * a / big_k;
    if !(need > 0.0 && need < mu_inf) {
        return None;
    }
    let tau = v_c_mps / (big_k * (mu_inf - need));
    Some((-v_c_mps * (-need / mu_inf).ln_1p(), tau))
}

/// The state at the start of a creep: the slip put on its quasi-static value, and v moved by
/// what the rest of the transient would change it (`v' − s va' = u'` shared as the slide's
/// equations share it: v by `Δu/(1 + ks²)`); left on v, the offset of at most 2·10⁻⁷ m/s at entry
/// put z off by 5·10⁻⁹ m in 50 ms.
fn onto_creep(m: &Model, d: f64, dir: f64, y: &[f64; 3], t: f64, ext: f64) -> [f64; 3] {
    let g = &m.groove;
    let a = accel(m, y[0], y[1], t, dir, ext);
    let Some((u_eq, _)) = quasi_static(m, d, a) else {
        return *y;
    };
    let u = y[1] - g.s * y[2];
    let v = y[1] - (u - d * u_eq) / (1.0 + g.ks2());
    [y[0], v, (v - d * u_eq) / g.s]
}

/// The creep's entry function at state `y` (negative: the slide may creep), or None when the
/// friction is not velocity-dependent.
fn creep_entry(m: &Model, d: f64, dir: f64, y: &[f64; 3], t: f64, ext: f64) -> Option<f64> {
    // the quasi-static slip is that of the law alone: with a variation of μ on top the slide is
    // integrated as it is (stiff, so in small steps, but exact)
    if !matches!(m.friction, Friction::VelocityDependent { .. }) || !m.variation.is_none() {
        return None;
    }
    let u = y[1] - m.groove.s * y[2];
    let a = accel(m, y[0], y[1], t, dir, ext);
    Some(match quasi_static(m, d, a) {
        Some((u_eq, tau)) if tau <= TAU_CREEP_S => (d * u - u_eq).abs() * tau - CREEP_ENTRY_M,
        _ => 1.0,
    })
}

/// Extra acceleration at time since the kick `t`, with sign terms taken in direction `dir` when
/// v = 0, and also when v is past 0 in a model with a sign jump (a rolling resistance), whose
/// modes end where v crosses 0 (an event): evaluated at the sign of v itself the right-hand side
/// jumps there, the integrator cannot step across, and a slide the resistance stops ground on at
/// v = ±1e-11 in ever smaller steps (2 s for one 0.1 s track) instead of reaching its event.
fn accel(m: &Model, z: f64, v: f64, t: f64, dir: f64, ext: f64) -> f64 {
    let v_eff = if v == 0.0 || (v * dir < 0.0 && m.has_sign_jump()) {
        dir * f64::MIN_POSITIVE
    } else {
        v
    };
    m.accel(z, v_eff, t) + ext
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

/// Largest friction coefficient available at zero slip at `z`, moving in direction `dir`.
fn hold_mu(m: &Model, z: f64, dir: f64) -> f64 {
    m.friction.static_limit() * m.variation.factor(z, dir, 0.0)
}

/// Friction can hold the rolling constraint at `z` (direction `dir`) against the extra
/// acceleration `a`.
fn can_roll(m: &Model, z: f64, dir: f64, a: f64) -> bool {
    let g = &m.groove;
    (g.s * a / (1.0 + g.ks2())).abs() <= G_MPS2 * hold_mu(m, z, dir) * (1.0 + 1e-12)
}

impl Mode {
    /// The mode lasts to the end: rest under forces that do not depend on time (z is fixed, so
    /// nothing that holds it can change).
    pub fn absorbing(&self, m: &Model) -> bool {
        *self == Mode::Rest && !m.time_dependent()
    }

    /// The longest step this mode may take (s): at rest under forces in time, a 32nd of their
    /// shortest time scale, so that no step spans a window where they outgrow the hold (nothing
    /// moves at rest, so the error control would let steps grow to the largest); otherwise
    /// unbounded (the error control sees the forces through the motion).
    pub fn step_cap(&self, m: &Model) -> f64 {
        match self {
            // a floor, so that a term with no time scale left (f = ∞) cannot stall the integrator
            Mode::Rest => (m.shortest_time_scale_s() / 32.0).max(1e-7),
            _ => f64::INFINITY,
        }
    }

    pub fn phase(&self) -> Phase {
        match self {
            Mode::Slide { .. } | Mode::Creep { .. } => Phase::Sliding,
            Mode::Roll { .. } => Phase::Rolling,
            Mode::Rest => Phase::Rest,
        }
    }

    /// How much `v'` moves per unit of `ext` in this mode: 1 while sliding, the rolling factor
    /// while rolling or creeping (the groove's friction takes its share), 0 at rest. A pair held
    /// together shares its contact's normal force between the two by it (`pair`).
    pub fn ext_gain(&self, m: &Model) -> f64 {
        match self {
            Mode::Slide { .. } => 1.0,
            Mode::Creep { .. } | Mode::Roll { .. } => m.groove.rolling_factor(),
            Mode::Rest => 0.0,
        }
    }

    /// Time derivative of `[z, v, va]` at time since the kick `t`.
    pub fn rhs(&self, m: &Model, y: &[f64; 3], t: f64, ext: f64) -> [f64; 3] {
        let g = &m.groove;
        match *self {
            Mode::Slide { d, dir } => {
                let slip = y[1] - g.s * y[2];
                let mu = m.friction.kinetic(slip) * m.variation.factor(y[0], dir, slip);
                let a = accel(m, y[0], y[1], t, dir, ext);
                [y[1], -d * G_MPS2 * mu / g.s + a, d * g.k * G_MPS2 * mu]
            }
            Mode::Creep { d, dir } => {
                let a = accel(m, y[0], y[1], t, dir, ext);
                let ks2 = g.ks2();
                // ȧ along the motion (v' to first order: the rolling one)
                let dt = CREEP_DT_S;
                let ahead = accel(
                    m,
                    y[0] + y[1] * dt,
                    y[1] + g.rolling_factor() * a * dt,
                    t + dt,
                    dir,
                    // a force from another particle taken as constant over dt: its own change
                    // moves the slip's lag by τ·ȧ, below the creep's own approximation
                    ext,
                );
                let tau = quasi_static(m, d, a).map_or(0.0, |(_, tau)| tau);
                // u' = d·u̇_eq = τ ȧ
                let du = tau * (ahead - a) / dt;
                [
                    y[1],
                    (ks2 * a + du) / (1.0 + ks2),
                    g.k * g.s * (a - du) / (1.0 + ks2),
                ]
            }
            Mode::Roll { dir } => {
                let dv = g.rolling_factor() * accel(m, y[0], y[1], t, dir, ext);
                [y[1], dv, dv / g.s]
            }
            Mode::Rest => [0.0; 3],
        }
    }

    /// Event functions (an event fires when one goes negative): [slip or friction limit, v = 0].
    pub fn events(&self, m: &Model, y: &[f64; 3], t: f64, ext: f64) -> [f64; 2] {
        let g = &m.groove;
        match *self {
            Mode::Slide { d, dir } => {
                let v_zero = if m.has_sign_jump() { y[1] * dir } else { 1.0 };
                // rounding slack so a slide that starts at zero slip is armed
                let slack = 1e-15 * (y[1].abs() + (g.s * y[2]).abs());
                let slip = d * (y[1] - g.s * y[2]) + slack;
                let creep = creep_entry(m, d, dir, y, t, ext).unwrap_or(1.0);
                [slip.min(creep), v_zero]
            }
            Mode::Creep { d, dir } => {
                let v_zero = if m.has_sign_jump() { y[1] * dir } else { 1.0 };
                let a = accel(m, y[0], y[1], t, dir, ext);
                // ends where the force stops pushing the slip (it reaches zero: rolling), or
                // where the slip's relaxation is no longer fast (the slide goes on); with no
                // quasi-static slip left (the force no longer pushes it, or pushes more than
                // the kinetic limit holds: τ passes the exit on the way there unless the force
                // jumps) it ends at once
                let end = match quasi_static(m, d, a) {
                    Some((_, tau)) => (d * a).min(CREEP_EXIT * TAU_CREEP_S - tau),
                    None => -1.0,
                };
                [end, v_zero]
            }
            Mode::Roll { dir } => {
                let a = accel(m, y[0], y[1], t, dir, ext);
                let need = (g.s * a / (1.0 + g.ks2())).abs();
                // the same slack as `can_roll`
                let limit = G_MPS2 * hold_mu(m, y[0], dir) * (1.0 + 1e-12);
                [limit - need, y[1] * dir]
            }
            // z is fixed at rest, so only a force in time can outgrow what holds the particle
            Mode::Rest if m.time_dependent() || ext != 0.0 => [
                m.static_hold_mps2() - (m.accel(y[0], 0.0, t) + ext).abs(),
                1.0,
            ],
            Mode::Rest => [1.0, 1.0],
        }
    }

    /// The mode and (projected) state after event `k` of this mode at state `y`.
    pub fn after_event(
        &self,
        m: &Model,
        k: usize,
        y: &[f64; 3],
        t: f64,
        ext: f64,
    ) -> (Mode, [f64; 3]) {
        match (*self, k) {
            (Mode::Slide { d, dir }, 0) => {
                let slip = d * (y[1] - m.groove.s * y[2]);
                match creep_entry(m, d, dir, y, t, ext) {
                    Some(creep) if creep < slip => {
                        (Mode::Creep { d, dir }, onto_creep(m, d, dir, y, t, ext))
                    }
                    _ => settle(m, y[0], y[1], t, ext),
                }
            }
            (Mode::Creep { d, dir }, 0) => {
                if d * accel(m, y[0], y[1], t, dir, ext) <= 0.0 {
                    // the quasi-static slip has reached zero with the force: rolling (or rest)
                    settle(m, y[0], y[1], t, ext)
                } else {
                    (Mode::Slide { d, dir }, *y)
                }
            }
            (Mode::Creep { d, dir }, _) => Mode::Slide { d, dir }.after_event(m, 1, y, t, ext),
            (Mode::Slide { d, dir }, _) => {
                // v passed zero while sliding: continue sliding, heading where v' points
                let mut y0 = *y;
                y0[1] = 0.0;
                let probe = Mode::Slide { d, dir: -dir };
                let back = probe.rhs(m, &y0, t, ext)[1];
                if back * dir >= 0.0 {
                    // the way back is barred too: what holds a particle at rest (a rolling
                    // resistance) outweighs the friction of its spin, so v stays 0 (Filippov)
                    // and z with it; carried on, v chattered about 0 to the cap on switches
                    return (Mode::Rest, [y[0], 0.0, 0.0]);
                }
                (Mode::Slide { d, dir: -dir }, y0)
            }
            (Mode::Roll { dir }, 0) => {
                let a = accel(m, y[0], y[1], t, dir, ext);
                (
                    Mode::Slide {
                        d: sign_or(a, dir),
                        dir,
                    },
                    *y,
                )
            }
            (Mode::Roll { .. }, _) => settle(m, y[0], 0.0, t, ext),
            // a force in time outgrew the hold: the particle starts from rest as `settle` says
            (Mode::Rest, 0) => settle(m, y[0], 0.0, t, ext),
            (Mode::Rest, _) => (Mode::Rest, *y),
        }
    }
}

/// The mode of a particle with zero slip at position `z` and velocity `v` (`va = v/s`).
pub(crate) fn settle(m: &Model, z: f64, v: f64, t: f64, ext: f64) -> (Mode, [f64; 3]) {
    let s = m.groove.s;
    if v == 0.0 {
        let a_static = m.accel(z, 0.0, t) + ext;
        if a_static.abs() <= m.static_hold_mps2() {
            return (Mode::Rest, [z, 0.0, 0.0]);
        }
        let dir = a_static.signum();
        let a = accel(m, z, 0.0, t, dir, ext);
        let mode = if can_roll(m, z, dir, a) {
            Mode::Roll { dir }
        } else {
            Mode::Slide { d: a.signum(), dir }
        };
        return (mode, [z, 0.0, 0.0]);
    }
    let dir = v.signum();
    let a = m.accel(z, v, t) + ext;
    let mode = if can_roll(m, z, dir, a) {
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
pub(crate) fn start(m: &Model, z: f64, v: f64, va: f64, t: f64, ext: f64) -> (Mode, [f64; 3]) {
    let s = m.groove.s;
    let u = v - s * va;
    if u.abs() <= 1e-15 * (v.abs() + (s * va).abs()) {
        return settle(m, z, if v.abs() <= 1e-300 { 0.0 } else { v }, t, ext);
    }
    let d = u.signum();
    let y = [z, v, va];
    let dir = if v != 0.0 {
        v.signum()
    } else {
        let probe = Mode::Slide { d, dir: 1.0 };
        sign_or(probe.rhs(m, &y, t, ext)[1], 1.0)
    };
    (Mode::Slide { d, dir }, y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{Groove, Term};

    fn held(v_c_mps: f64) -> Model {
        Model {
            groove: Groove::CHAPTER,
            friction: Friction::VelocityDependent {
                mu_inf: 0.3,
                v_c_mps,
            },
            variation: Default::default(),
            terms: vec![Term::GrooveTilt { alpha_deg: -1.0 }],
        }
    }

    /// The state with velocity `v` and slip `u` (`va = (v − u)/s`).
    fn with_slip(m: &Model, v: f64, u: f64) -> [f64; 3] {
        [0.0, v, (v - u) / m.groove.s]
    }

    #[test]
    fn a_fast_slip_on_its_quasi_static_value_creeps_and_only_then() {
        let (d, dir, v) = (1.0, 1.0, 0.01);
        let slide = Mode::Slide { d, dir };
        let m = held(5e-5);
        let (u_eq, tau) = quasi_static(&m, d, m.accel(0.0, v, 0.0)).expect("the tilt pushes");
        assert!(tau < TAU_CREEP_S && u_eq > 0.0, "τ {tau}, u_eq {u_eq}");
        // armed at the kick (slip far above u_eq), firing on the quasi-static slip
        assert!(slide.events(&m, &with_slip(&m, 0.02, 0.02), 0.0, 0.0)[0] > 0.0);
        let on = with_slip(&m, v, u_eq);
        assert!(slide.events(&m, &on, 0.0, 0.0)[0] < 0.0);
        let (mode, y) = slide.after_event(&m, 0, &on, 0.0, 0.0);
        assert_eq!(mode, Mode::Creep { d, dir });
        assert!((y[1] - on[1]).abs() < 1e-15, "v moved on the value itself");
        // the creep is armed where it starts, and ends where the force stops pushing the slip
        assert!(mode.events(&m, &y, 0.0, 0.0)[0] > 0.0);
        let flat = Model {
            terms: vec![Term::LinearDrag { t_s: 0.05 }],
            ..held(5e-5)
        };
        assert!(mode.events(&flat, &y, 0.0, 0.0)[0] < 0.0);
        // a slow slip (v_c = 4 mm/s: τ ≈ 0.4 ms) is integrated as it is
        let soft = held(4e-3);
        let (u_soft, tau_soft) = quasi_static(&soft, d, soft.accel(0.0, v, 0.0)).unwrap();
        assert!(tau_soft > CREEP_EXIT * TAU_CREEP_S);
        assert!(slide.events(&soft, &with_slip(&soft, v, u_soft), 0.0, 0.0)[0] > 0.0);
        // a force that does not push the slip (a drag) leaves the zero-slip event alone
        assert!(slide.events(&flat, &with_slip(&flat, v, 1e-3), 0.0, 0.0)[0] > 0.0);
        assert_eq!(quasi_static(&flat, d, flat.accel(0.0, v, 0.0)), None);
    }
}
