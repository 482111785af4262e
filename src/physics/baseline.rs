//! The closed-form baseline: Coulomb friction μ plus linear drag v/T, exact in every phase.
//!
//! Sliding with slip direction `d = sign(v − s·va)` and `A = g μ T / s`:
//! `v(τ) = (v_s + dA) e^{−τ/T} − dA`, `z(τ) = T (v_s + dA)(1 − e^{−τ/T}) − dA τ`,
//! `va(τ) = va_s + d k g μ τ`; the switch is the unique root of the slip `v − s·va` (found by a
//! bracketed, safeguarded Newton iteration). Rolling then decays with `Te = T (1 + ks²)/ks²`.
//! If at the switch the drag is too strong for friction to hold the rolling constraint
//! (`|v| s / (T (1 + ks²)) > g μ`) the particle slips the other way first, as the integrator does.
//! Both directions of motion and any initial spin are handled; `t_drag_s = ∞` means no drag and
//! `mu ≤ 0` means no friction (the particle then slides forever).

use super::{Groove, Phase, G_MPS2};

/// Closed-form baseline (Coulomb μ + linear drag v/T) for one particle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Baseline {
    pub mu: f64,
    /// Linear drag time constant T (s), > 0; `f64::INFINITY` for no drag.
    pub t_drag_s: f64,
    pub groove: Groove,
}

/// One analytic piece of the motion, valid from `t_s` on.
#[derive(Clone, Copy, Debug)]
struct Segment {
    t_s: f64,
    dz_m: f64,
    v_mps: f64,
    va_mps: f64,
    kind: Kind,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// Sliding with slip direction d = ±1 (0 for frictionless sliding).
    Slide(f64),
    Roll,
    Rest,
}

/// At most four pieces: slide, slide back, roll (the fourth is never needed but caps the loop).
struct Plan {
    seg: [Segment; 4],
    n: usize,
}

/// `T (1 − e^{−τ/T})`, → τ for T = ∞.
fn em1(tau: f64, t: f64) -> f64 {
    if t.is_infinite() {
        tau
    } else {
        -t * (-tau / t).exp_m1()
    }
}

/// `T² (τ/T − 1 + e^{−τ/T})`, → τ²/2 for T = ∞; stable for τ ≪ T.
fn phi2(tau: f64, t: f64) -> f64 {
    if t.is_infinite() {
        return 0.5 * tau * tau;
    }
    let x = tau / t;
    if x.abs() < 1e-3 {
        t * t * x * x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x / 120.0)))
    } else {
        t * t * (x + (-x).exp_m1())
    }
}

/// `e^{−τ/T}`, 1 for T = ∞.
fn decay(tau: f64, t: f64) -> f64 {
    (-tau / t).exp()
}

impl Baseline {
    /// The chapter's groove with friction `mu` and drag time `t_drag_s`.
    pub fn new(mu: f64, t_drag_s: f64) -> Baseline {
        Baseline {
            mu,
            t_drag_s,
            groove: Groove::CHAPTER,
        }
    }

    /// Rolling decay time `Te = T (1 + ks²)/ks²` (s).
    pub fn rolling_time_s(&self) -> f64 {
        self.t_drag_s / self.groove.rolling_factor()
    }

    /// Switch time t1 (s) from sliding to rolling for a kick `v0_mps` (sign = direction), no spin.
    pub fn switch_time_s(&self, v0_mps: f64) -> f64 {
        self.switch_time_from_s(v0_mps, 0.0)
    }

    /// Switch time (s) into the final rolling motion from `v0`, `va0`; ∞ when it never rolls.
    pub fn switch_time_from_s(&self, v0_mps: f64, va0_mps: f64) -> f64 {
        let plan = self.plan(v0_mps, va0_mps);
        let last = &plan.seg[plan.n - 1];
        match last.kind {
            Kind::Slide(_) => f64::INFINITY,
            Kind::Roll | Kind::Rest => last.t_s,
        }
    }

    /// `z(t) − z(0)`, `v(t)` and the phase for a kick `v0_mps` without spin, `t_s ≥ 0`.
    pub fn state(&self, v0_mps: f64, t_s: f64) -> (f64, f64, Phase) {
        let (dz, v, _, phase) = self.state_from(v0_mps, 0.0, t_s);
        (dz, v, phase)
    }

    /// `z(t) − z(0)`, `v(t)`, `va(t)` and the phase from `v0`, `va0` at t = 0. For `t_s < 0`
    /// the initial motion is extrapolated backward (smooth, for fitters with a free start time).
    pub fn state_from(&self, v0_mps: f64, va0_mps: f64, t_s: f64) -> (f64, f64, f64, Phase) {
        let plan = self.plan(v0_mps, va0_mps);
        self.eval(&plan, t_s)
    }

    /// `z(t) − z(0)` for many times at once (no spin at t = 0); the fast path for fitting.
    pub fn positions(&self, v0_mps: f64, t_s: &[f64], out_dz_m: &mut [f64]) {
        self.positions_from(v0_mps, 0.0, t_s, out_dz_m);
    }

    /// `z(t) − z(0)` for many times at once from `v0`, `va0`. Panics if the slices differ in length.
    pub fn positions_from(&self, v0_mps: f64, va0_mps: f64, t_s: &[f64], out_dz_m: &mut [f64]) {
        assert_eq!(
            t_s.len(),
            out_dz_m.len(),
            "positions: times and output must have the same length"
        );
        let plan = self.plan(v0_mps, va0_mps);
        for (t, out) in t_s.iter().zip(out_dz_m.iter_mut()) {
            *out = self.eval(&plan, *t).0;
        }
    }

    fn b(&self) -> f64 {
        G_MPS2 * self.mu / self.groove.s
    }

    /// Friction can hold the rolling constraint against the drag at speed `v`.
    fn can_roll(&self, v: f64) -> bool {
        let need = v.abs() * self.groove.s / (self.t_drag_s * (1.0 + self.groove.ks2()));
        need <= G_MPS2 * self.mu * (1.0 + 1e-12)
    }

    fn plan(&self, v0: f64, va0: f64) -> Plan {
        let rest = Segment {
            t_s: 0.0,
            dz_m: 0.0,
            v_mps: v0,
            va_mps: va0,
            kind: Kind::Rest,
        };
        let mut plan = Plan {
            seg: [rest; 4],
            n: 0,
        };
        let s = self.groove.s;
        if self.mu <= 0.0 {
            plan.seg[0].kind = Kind::Slide(0.0);
            plan.n = 1;
            return plan;
        }
        let mut cur = rest;
        let u0 = v0 - s * va0;
        let tol = 1e-14 * (v0.abs() + (s * va0).abs());
        cur.kind = if u0.abs() > tol {
            Kind::Slide(u0.signum())
        } else if v0 == 0.0 {
            Kind::Rest
        } else if self.can_roll(v0) {
            Kind::Roll
        } else {
            Kind::Slide(-v0.signum())
        };
        loop {
            plan.seg[plan.n] = cur;
            plan.n += 1;
            let Kind::Slide(d) = cur.kind else { break };
            if plan.n == plan.seg.len() {
                break;
            }
            let tau = self.slip_root(cur.v_mps, cur.va_mps, d);
            let (dz, v, va) = self.slide(&cur, d, tau);
            let next_kind = if v == 0.0 {
                Kind::Rest
            } else if self.can_roll(v) {
                Kind::Roll
            } else {
                Kind::Slide(-v.signum())
            };
            cur = Segment {
                t_s: cur.t_s + tau,
                dz_m: dz,
                v_mps: v,
                va_mps: if next_kind == Kind::Roll { v / s } else { va },
                kind: next_kind,
            };
        }
        plan
    }

    /// Sliding from `seg` for a time `tau`: (dz, v, va).
    fn slide(&self, seg: &Segment, d: f64, tau: f64) -> (f64, f64, f64) {
        let t = self.t_drag_s;
        let b = self.b();
        let v = seg.v_mps * decay(tau, t) - d * b * em1(tau, t);
        let dz = seg.dz_m + seg.v_mps * em1(tau, t) - d * b * phi2(tau, t);
        let va = seg.va_mps + d * self.groove.k * G_MPS2 * self.mu * tau;
        (dz, v, va)
    }

    /// The time τ > 0 at which the slip `d (v − s va)` of a sliding piece reaches zero.
    fn slip_root(&self, v_s: f64, va_s: f64, d: f64) -> f64 {
        let t = self.t_drag_s;
        let b = self.b();
        let s = self.groove.s;
        let r = s * self.groove.k * G_MPS2 * self.mu; // slip rate from the spin-up
        let w0 = d * (v_s - s * va_s);
        if t.is_infinite() {
            return (w0 / (b + r)).max(0.0);
        }
        // w(τ) = c e^{−τ/T} − bT − d s va_s − r τ, concave if c < 0, convex decreasing otherwise.
        let c = d * v_s + b * t;
        let base = b * t + d * s * va_s;
        let w = |tau: f64| c * decay(tau, t) - base - r * tau;
        let dw = |tau: f64| -c / t * decay(tau, t) - r;
        let mut lo = 0.0;
        if c < 0.0 {
            let tau_max = t * (-c / (t * r)).ln();
            if tau_max > 0.0 {
                lo = tau_max;
            }
        }
        let mut hi = ((c.max(0.0) - base) / r).max(lo);
        // make sure the bracket holds the sign change despite rounding
        let mut grow = 0;
        while w(hi) > 0.0 && grow < 60 {
            hi = hi * 1.5 + 1e-12;
            grow += 1;
        }
        if w(lo) <= 0.0 {
            return lo;
        }
        let mut x = hi;
        for _ in 0..100 {
            let fx = w(x);
            if fx > 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            if fx == 0.0 || hi - lo <= 1e-15 * hi.max(1e-300) {
                break;
            }
            let newton = x - fx / dw(x);
            if (newton - x).abs() <= 1e-15 * x.abs() {
                x = newton;
                break;
            }
            x = if newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
        }
        // return the side where the slip has just vanished
        if w(x).abs() <= w(hi).abs() {
            x
        } else {
            hi
        }
    }

    fn eval(&self, plan: &Plan, t_s: f64) -> (f64, f64, f64, Phase) {
        let mut i = 0;
        while i + 1 < plan.n && plan.seg[i + 1].t_s <= t_s {
            i += 1;
        }
        let seg = &plan.seg[i];
        let tau = t_s - seg.t_s;
        match seg.kind {
            Kind::Slide(d) => {
                let (dz, v, va) = self.slide(seg, d, tau);
                (dz, v, va, Phase::Sliding)
            }
            Kind::Roll => {
                let te = self.rolling_time_s();
                let v = seg.v_mps * decay(tau, te);
                let dz = seg.dz_m + seg.v_mps * em1(tau, te);
                (dz, v, v / self.groove.s, Phase::Rolling)
            }
            Kind::Rest => (seg.dz_m, 0.0, 0.0, Phase::Rest),
        }
    }
}
