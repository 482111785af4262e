//! The switches between sliding, rolling and rest, found by bisection inside a fixed step.

use super::integrator::{rk4, Mode, State};
use super::model::{Physics, G};

/// Slip speed below which sliding has ended (m/s).
const SLIP_END_MPS: f64 = 1e-9;
/// Bisection halvings of a step (10 µs / 2⁴⁰ ≈ 1e-17 s).
const HALVINGS: usize = 40;
/// Switches allowed inside one step (beyond: the step is taken as it is).
const MAX_SWITCHES: usize = 8;

/// One particle: its state, its mode and its direction of motion (kept through v = 0).
#[derive(Clone, Copy, Debug)]
pub struct Particle {
    pub x: State,
    pub mode: Mode,
    pub dir: f64,
    /// When the current mode began (s since the kick).
    pub switched_at: f64,
}

/// The friction the rolling constraint needs, as g μ would be: s a / (1 + ks²).
fn hold_needed(p: &Physics, x: &State, t: f64, ext: f64, dir: f64) -> f64 {
    let g = p.groove;
    g.s * (p.accel(x.z, x.v, t, dir) + ext) / (1.0 + g.ks2())
}

/// The direction a force would move the particle from rest at `x`, if any.
fn release(p: &Physics, x: &State, t: f64, ext: f64) -> Option<f64> {
    [1.0, -1.0]
        .into_iter()
        .find(|&d| d * (p.accel(x.z, 0.0, t, d) + ext) > 0.0)
}

impl Particle {
    /// A particle kicked to `v0` with no spin at `z0`.
    pub fn kicked(z0: f64, v0: f64) -> Particle {
        let mode = if v0 == 0.0 {
            Mode::Rest
        } else {
            Mode::Slide(v0.signum())
        };
        Particle {
            x: State {
                z: z0,
                v: v0,
                va: 0.0,
            },
            mode,
            dir: if v0 < 0.0 { -1.0 } else { 1.0 },
            switched_at: 0.0,
        }
    }

    /// Puts the particle in the mode its state calls for (after an impulse or a switch).
    pub fn settle(&mut self, p: &Physics, t: f64, ext: f64) {
        let g = p.groove;
        if self.x.v != 0.0 {
            self.dir = self.x.v.signum();
        }
        let u = self.x.v - g.s * self.x.va;
        if u.abs() > SLIP_END_MPS {
            self.mode = Mode::Slide(u.signum());
            return;
        }
        self.x.va = self.x.v / g.s;
        if self.x.v == 0.0 {
            match release(p, &self.x, t, ext) {
                Some(d) => self.dir = d,
                None => {
                    self.mode = Mode::Rest;
                    return;
                }
            }
        } else {
            self.dir = self.x.v.signum();
        }
        let f = hold_needed(p, &self.x, t, ext, self.dir);
        self.mode = if f.abs() > G * p.mu_static(self.x.z, self.dir) {
            Mode::Slide(f.signum())
        } else {
            Mode::Roll
        };
    }

    /// True when a switch has happened between `self` (at `t`) and `y` (at `t1`).
    fn switched(&self, p: &Physics, y: &State, t1: f64, ext: f64) -> bool {
        match self.mode {
            Mode::Slide(d) => d * (y.v - p.groove.s * y.va) <= SLIP_END_MPS || y.v * self.dir < 0.0,
            Mode::Roll => {
                y.v * self.dir <= 0.0
                    || hold_needed(p, y, t1, ext, self.dir).abs() > G * p.mu_static(y.z, self.dir)
            }
            Mode::Rest => false,
        }
    }

    /// Advances by `h` from `t`, switching modes where the motion calls for it.
    pub fn advance(&mut self, p: &Physics, t: f64, h: f64, ext: f64) {
        let (mut t, mut rem) = (t, h);
        for n in 0..=MAX_SWITCHES {
            if self.mode == Mode::Rest {
                if release(p, &self.x, t, ext).is_none() {
                    return;
                }
                self.settle(p, t, ext);
                self.switched_at = t;
            }
            let y = rk4(p, self.mode, &self.x, t, rem, ext, self.dir);
            if n == MAX_SWITCHES || !self.switched(p, &y, t + rem, ext) {
                self.x = y;
                return;
            }
            let (mut lo, mut hi) = (0.0, rem);
            for _ in 0..HALVINGS {
                let mid = 0.5 * (lo + hi);
                let ym = rk4(p, self.mode, &self.x, t, mid, ext, self.dir);
                if self.switched(p, &ym, t + mid, ext) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let y = rk4(p, self.mode, &self.x, t, hi, ext, self.dir);
            let was = self.mode;
            self.x = y;
            t += hi;
            rem -= hi;
            match was {
                Mode::Slide(d) if d * (y.v - p.groove.s * y.va) <= SLIP_END_MPS => {
                    // the slip ends: roll (or stop, or slip the other way if the hold fails)
                    self.x.va = self.x.v / p.groove.s;
                    self.settle(p, t, ext);
                }
                // the motion reverses while sliding: the same slip, the other direction
                Mode::Slide(_) => self.dir = -self.dir,
                Mode::Roll if y.v * self.dir <= 0.0 => {
                    self.x.v = 0.0;
                    self.x.va = 0.0;
                    self.settle(p, t, ext);
                }
                // a hold that breaks leaves u = 0: start the slip in the direction the force drives
                _ => {
                    let f = hold_needed(p, &self.x, t, ext, self.dir);
                    self.mode = Mode::Slide(f.signum());
                    self.x.va -= f.signum() * 2.0 * SLIP_END_MPS / p.groove.s;
                }
            }
            if self.mode != was {
                self.switched_at = t;
            }
            if rem <= 0.0 {
                return;
            }
        }
    }
}
