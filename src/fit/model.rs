//! The closed-form baseline as a fit model: positions and their analytic partial derivatives.
//!
//! The model of one particle (the physics module's closed form of the baseline, generalised to a nonzero
//! initial spin as in the contract's addendum): Coulomb friction μ and linear drag v/T while
//! sliding with direction d = sign(v0 − s·va0), a switch at t1 where v = s·va, then constrained
//! rolling decaying with Te = T(1 + ks²)/ks². The observation model adds an offset and a time shift:
//!
//! ```text
//! z(t) = z0 + Δz(t − t_ref + t0; v0, va0, μ, T)
//! ```
//!
//! where t_ref is a fixed origin (the first frame, or a segment start) and t0 the time elapsed
//! between the kick and t_ref. Before the kick (τ < 0) the particle rests at z0.
//!
//! `physics::Baseline` is the reference implementation of the same motion; this copy exists because a
//! fit needs the derivatives with respect to every parameter at every frame, sharing one
//! exponential per frame (the test `model_matches_physics_baseline` checks the two agree).

use crate::physics::{Groove, G_MPS2};

/// Index of each parameter in a parameter vector.
pub const Z0: usize = 0;
pub const T0: usize = 1;
pub const V0: usize = 2;
pub const VA0: usize = 3;
pub const MU: usize = 4;
pub const TD: usize = 5;
/// Number of parameters of the model.
pub const NP: usize = 6;

/// Parameter names, in index order, for messages and tables.
pub const NAMES: [&str; NP] = ["z0_m", "t0_s", "v0_mps", "va0_mps", "mu", "t_drag_s"];

/// The quantities that depend on the parameters but not on the time of a frame.
#[derive(Clone, Copy, Debug)]
pub struct Prepared {
    /// z0, t0, v0, va0, μ, T as given.
    pub p: [f64; NP],
    /// Sliding direction d ∈ {−1, 0, 1}; 0 means rolling from the start.
    pub dir: f64,
    /// d·A with A = g μ T / s.
    pub da: f64,
    /// Switch time after the kick, s (0 when rolling from the start).
    pub t1_s: f64,
    /// Displacement and velocity at the switch.
    pub z1_m: f64,
    pub v1_mps: f64,
    /// Rolling time constant Te = T (1 + ks²)/ks².
    pub te_s: f64,
    /// d z1/dp, d v1/dp, d t1/dp for p = v0, va0, μ, T (indices V0..=TD; others zero).
    pub dz1: [f64; NP],
    pub dv1: [f64; NP],
    pub dt1: [f64; NP],
    groove: Groove,
}

/// Where a time after the kick falls.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Before,
    Sliding,
    Rolling,
}

/// (e^{−x}, 1 − e^{−x}) from one `exp_m1`: the second stays accurate for small x.
#[inline]
fn decay(x: f64) -> (f64, f64) {
    let em1 = (-x).exp_m1();
    (1.0 + em1, -em1)
}

/// Sliding velocity (without the d·A shift folded in) at time τ after the kick.
#[inline]
fn slide_v(v0: f64, da: f64, e: f64) -> f64 {
    (v0 + da) * e - da
}

impl Prepared {
    /// Prepare the model for parameters `p` on `groove`. Returns `None` if the parameters are
    /// not finite or T, μ are not positive (a fit keeps them inside its bounds).
    pub fn new(p: &[f64; NP], groove: Groove) -> Option<Prepared> {
        if p.iter().any(|x| !x.is_finite()) || p[MU] < 0.0 || p[TD] <= 0.0 {
            return None;
        }
        let (s, k) = (groove.s, groove.k);
        let ks2 = k * s * s;
        let (v0, va0, mu, t) = (p[V0], p[VA0], p[MU], p[TD]);
        let slip = v0 - s * va0;
        let dir = if slip > 0.0 {
            1.0
        } else if slip < 0.0 {
            -1.0
        } else {
            0.0
        };
        let c = G_MPS2 * mu / s; // A / T
        let da = dir * c * t;
        let te = t * (1.0 + ks2) / ks2;
        let mut out = Prepared {
            p: *p,
            dir,
            da,
            t1_s: 0.0,
            z1_m: 0.0,
            v1_mps: v0,
            te_s: te,
            dz1: [0.0; NP],
            dv1: [0.0; NP],
            dt1: [0.0; NP],
            groove,
        };
        if dir == 0.0 || mu == 0.0 {
            // Rolls from the start (or slides forever without friction: treat μ = 0 as rolling
            // with no spin-up, which only happens at the lower bound of a fit).
            out.dv1[V0] = 1.0;
            return Some(out);
        }
        // g(t) = v_s(t) − s (va0 + d k g μ t) is strictly monotone in the sliding direction.
        let spin_rate = dir * k * G_MPS2 * mu; // dva/dt
        let g = |tt: f64| {
            let e = (-tt / t).exp();
            slide_v(v0, da, e) - s * (va0 + spin_rate * tt)
        };
        let t1 = switch_root(
            g,
            slip,
            v0.abs() + s * va0.abs() + c * t,
            c + s * spin_rate.abs(),
        )?;
        let (e1, om1) = decay(t1 / t);
        let v1 = slide_v(v0, da, e1);
        let z1 = t * (v0 + da) * om1 - da * t1;
        let a1 = -(v0 + da) * e1 / t;
        // partial derivatives of the sliding solution at fixed time t1
        let mut dzs = [0.0; NP];
        let mut dvs = [0.0; NP];
        dzs[V0] = t * om1;
        dvs[V0] = e1;
        dzs[MU] = dir * (G_MPS2 * t / s) * (t * om1 - t1);
        dvs[MU] = dir * (G_MPS2 * t / s) * (e1 - 1.0);
        dzs[TD] = v0 * (om1 - e1 * t1 / t) + dir * c * (2.0 * t * om1 - e1 * t1 - t1);
        dvs[TD] = (v0 + da) * e1 * t1 / (t * t) + dir * c * (e1 - 1.0);
        // implicit switch time: dt1/dp = −(∂g/∂p)/(∂g/∂t)
        let dg_dt = a1 - s * spin_rate;
        let mut dg = [0.0; NP];
        dg[V0] = dvs[V0];
        dg[VA0] = -s;
        dg[MU] = dvs[MU] - s * dir * k * G_MPS2 * t1;
        dg[TD] = dvs[TD];
        for i in V0..=TD {
            let dt1 = -dg[i] / dg_dt;
            out.dt1[i] = dt1;
            out.dz1[i] = dzs[i] + v1 * dt1;
            out.dv1[i] = dvs[i] + a1 * dt1;
        }
        out.t1_s = t1;
        out.z1_m = z1;
        out.v1_mps = v1;
        Some(out)
    }

    /// Displacement Δz(τ), velocity and whether the particle is still sliding, at τ after the kick.
    #[inline]
    pub fn state(&self, tau_s: f64) -> (f64, f64, bool) {
        if tau_s < 0.0 {
            return (0.0, 0.0, false);
        }
        let (v0, t) = (self.p[V0], self.p[TD]);
        if tau_s < self.t1_s {
            let (e, om) = decay(tau_s / t);
            let z = t * (v0 + self.da) * om - self.da * tau_s;
            (z, slide_v(v0, self.da, e), true)
        } else {
            let x = (tau_s - self.t1_s) / self.te_s;
            let (f, om) = decay(x);
            (
                self.z1_m + self.v1_mps * self.te_s * om,
                self.v1_mps * f,
                false,
            )
        }
    }

    /// Model position at data time `t_s` and its gradient with respect to the six parameters.
    #[inline]
    pub fn eval_grad(&self, t_s: f64, t_ref_s: f64, grad: &mut [f64; NP]) -> f64 {
        let tau = t_s - t_ref_s + self.p[T0];
        match self.phase(tau) {
            Phase::Before => self.before(grad),
            Phase::Sliding => {
                let (e, om) = decay(tau / self.p[TD]);
                self.sliding(tau, e, om, grad)
            }
            Phase::Rolling => {
                let x = (tau - self.t1_s) / self.te_s;
                let (f, om) = decay(x);
                self.rolling(x, f, om, grad)
            }
        }
    }

    /// `eval_grad` at every time of `t_s` into `z` and `grad`. Between frames one interval
    /// apart in the same phase, the exponential is carried forward by one multiplication
    /// (e' = e·q, 1 − e' = (1 − e) + e·(1 − q), both terms positive, so 1 − e keeps its relative
    /// accuracy); it is computed afresh every `REFRESH` frames, after a gap or any other
    /// interval, and at the switch. The values agree with `eval_grad` within 1e-12 relative
    /// (unit test).
    pub fn eval_grad_many(&self, t_s: &[f64], t_ref_s: f64, z: &mut [f64], grad: &mut [[f64; NP]]) {
        const REFRESH: u32 = 32;
        // the series: phase, τ of the last frame, its (e, 1 − e), the interval h of the step
        // factor q = e^{−h/scale} with 1 − q, and the frames since the last fresh value
        let mut last: Option<(Phase, f64, f64, f64)> = None;
        let (mut h_q, mut q_phase, mut q, mut omq) = (f64::NAN, Phase::Before, 0.0, 0.0);
        let mut since = 0u32;
        let (t, te) = (self.p[TD], self.te_s);
        for ((&ti, zi), gi) in t_s.iter().zip(z.iter_mut()).zip(grad.iter_mut()) {
            let tau = ti - t_ref_s + self.p[T0];
            let phase = self.phase(tau);
            let (x, scale) = match phase {
                Phase::Before => {
                    *zi = self.before(gi);
                    last = None;
                    continue;
                }
                Phase::Sliding => (tau / t, t),
                Phase::Rolling => ((tau - self.t1_s) / te, te),
            };
            let (e, om) = match last {
                Some((p, tau0, e0, om0)) if p == phase && since < REFRESH => {
                    let h = tau - tau0;
                    // the same interval up to the rounding of decimal times, or a new factor
                    if q_phase != phase || !((h - h_q).abs() <= 1e-12 * h_q) {
                        (h_q, q_phase, (q, omq)) = (h, phase, decay(h / scale));
                    }
                    since += 1;
                    (e0 * q, om0 + e0 * omq)
                }
                _ => {
                    since = 0;
                    decay(x)
                }
            };
            *zi = match phase {
                Phase::Rolling => self.rolling(x, e, om, gi),
                _ => self.sliding(tau, e, om, gi),
            };
            last = Some((phase, tau, e, om));
        }
    }

    #[inline]
    fn phase(&self, tau: f64) -> Phase {
        if tau < 0.0 {
            Phase::Before
        } else if tau < self.t1_s {
            Phase::Sliding
        } else {
            Phase::Rolling
        }
    }

    /// Before the kick: at rest at z0.
    #[inline]
    fn before(&self, grad: &mut [f64; NP]) -> f64 {
        *grad = [0.0; NP];
        grad[Z0] = 1.0;
        self.p[Z0]
    }

    /// Sliding, at τ after the kick with (e, om) = (e^{−τ/T}, 1 − e^{−τ/T}).
    #[inline]
    fn sliding(&self, tau: f64, e: f64, om: f64, grad: &mut [f64; NP]) -> f64 {
        let (v0, t) = (self.p[V0], self.p[TD]);
        let (s, dir, da) = (self.groove.s, self.dir, self.da);
        let c = G_MPS2 * self.p[MU] / s;
        grad[Z0] = 1.0;
        grad[T0] = slide_v(v0, da, e);
        grad[V0] = t * om;
        grad[VA0] = 0.0;
        grad[MU] = dir * (G_MPS2 * t / s) * (t * om - tau);
        grad[TD] = v0 * (om - e * tau / t) + dir * c * (2.0 * t * om - e * tau - tau);
        self.p[Z0] + t * (v0 + da) * om - da * tau
    }

    /// Rolling, x = (τ − t1)/Te after the switch with (f, om) = (e^{−x}, 1 − e^{−x}).
    #[inline]
    fn rolling(&self, x: f64, f: f64, om: f64, grad: &mut [f64; NP]) -> f64 {
        let te = self.te_s;
        let v1 = self.v1_mps;
        grad[Z0] = 1.0;
        grad[T0] = v1 * f;
        // ∂R/∂Te · ∂Te/∂T with R = v1 Te (1 − F)
        let dr_dte = v1 * (om - f * x);
        for (i, g) in grad.iter_mut().enumerate().take(TD + 1).skip(V0) {
            *g = self.dz1[i] + te * om * self.dv1[i] - v1 * f * self.dt1[i];
        }
        grad[TD] += dr_dte * te / self.p[TD];
        self.p[Z0] + self.z1_m + v1 * te * om
    }

    /// Model position at data time `t_s` (no derivatives).
    #[inline]
    pub fn eval(&self, t_s: f64, t_ref_s: f64) -> f64 {
        self.p[Z0] + self.state(t_s - t_ref_s + self.p[T0]).0
    }
}

/// Root of the monotone switch function `g` on t > 0, with g(0) = `g0` ≠ 0. `speed_scale` bounds
/// the size of g, `rate` its decrease per second from friction alone; together they bracket t1.
fn switch_root(g: impl Fn(f64) -> f64, g0: f64, speed_scale: f64, rate: f64) -> Option<f64> {
    if rate.is_nan() || rate <= 0.0 || !speed_scale.is_finite() {
        return None;
    }
    let sign = g0.signum();
    let (mut lo, mut hi) = (0.0_f64, 2.0 * speed_scale / rate);
    let mut tries = 0;
    while sign * g(hi) > 0.0 {
        lo = hi;
        hi *= 2.0;
        tries += 1;
        if tries > 60 {
            return None;
        }
    }
    // Illinois-modified regula falsi: superlinear, never leaves the bracket.
    let (mut glo, mut ghi) = (g0, g(hi));
    let mut side = 0;
    for _ in 0..100 {
        let m = (lo * ghi - hi * glo) / (ghi - glo);
        let gm = g(m);
        if gm == 0.0 || (hi - lo) <= 1e-15 * hi.max(1e-300) {
            return Some(m);
        }
        if gm.signum() == glo.signum() {
            lo = m;
            glo = gm;
            if side == -1 {
                ghi *= 0.5;
            }
            side = -1;
        } else {
            hi = m;
            ghi = gm;
            if side == 1 {
                glo *= 0.5;
            }
            side = 1;
        }
        if (hi - lo).abs() <= 1e-14 * hi {
            break;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn groove() -> Groove {
        Groove::CHAPTER
    }

    #[test]
    fn gradient_matches_central_differences() {
        let cases = [
            [1e-3, 4e-5, 0.05, 0.0, 0.33, 0.06],
            [-2e-3, 1e-5, -0.03, 0.0, 0.29, 0.09],
            [0.0, 0.0, 0.02, 0.05, 0.3, 0.05],
            [0.0, 0.0, 0.01, -0.04, 0.5, 0.2],
            [0.0, 0.0, -0.01, 0.01, 0.4, 0.07],
        ];
        let steps = [1e-7, 1e-8, 1e-6, 1e-6, 1e-6, 1e-6];
        for p in cases {
            let m = Prepared::new(&p, groove()).unwrap();
            for &t in &[0.0005, 0.002, 0.004, 0.01, 0.03, 0.06] {
                let mut g = [0.0; NP];
                m.eval_grad(t, 0.0, &mut g);
                for i in 0..NP {
                    let (mut hi, mut lo) = (p, p);
                    hi[i] += steps[i];
                    lo[i] -= steps[i];
                    let zh = Prepared::new(&hi, groove()).unwrap().eval(t, 0.0);
                    let zl = Prepared::new(&lo, groove()).unwrap().eval(t, 0.0);
                    let fd = (zh - zl) / (2.0 * steps[i]);
                    let tol = 1e-5 * (fd.abs() + g[i].abs()) + 1e-9;
                    assert!(
                        (fd - g[i]).abs() < tol,
                        "param {} at t={t}, p={p:?}: analytic {} vs numeric {fd}",
                        NAMES[i],
                        g[i]
                    );
                }
            }
        }
    }

    #[test]
    fn the_series_agrees_with_each_frame_computed_alone() {
        // 10 kHz frames with decimal times, a dropped frame, a jittered one, frames before the
        // kick and after the switch; three parameter sets (sliding then rolling, rolling from
        // the start, backwards)
        let mut t: Vec<f64> = (0..700)
            .map(|k| format!("{:.7}", k as f64 * 1e-4).parse().unwrap())
            .collect();
        t.remove(300);
        t[400] += 3.3e-6;
        let cases = [
            [1e-3, -2e-4, 0.05, 0.0, 0.33, 0.06],
            [0.0, 3e-5, 0.02, 0.02 / Groove::CHAPTER.s, 0.3, 0.05],
            [-2e-3, 1e-5, -0.03, 0.0, 0.29, 0.09],
        ];
        for p in cases {
            let m = Prepared::new(&p, groove()).unwrap();
            let (mut z, mut g) = (vec![0.0; t.len()], vec![[0.0; NP]; t.len()]);
            m.eval_grad_many(&t, 0.0, &mut z, &mut g);
            let rolled = t.iter().filter(|&&ti| ti + p[T0] > m.t1_s).count();
            assert!(rolled > 100, "{p:?}: {rolled} frames after the switch");
            for (i, &ti) in t.iter().enumerate() {
                let mut want = [0.0; NP];
                let zw = m.eval_grad(ti, 0.0, &mut want);
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * (a.abs() + b.abs()) + 1e-18;
                assert!(close(z[i], zw), "{p:?} frame {i}: z {} vs {zw}", z[i]);
                for k in 0..NP {
                    assert!(
                        close(g[i][k], want[k]),
                        "{p:?} frame {i}, {}: {} vs {}",
                        NAMES[k],
                        g[i][k],
                        want[k]
                    );
                }
            }
        }
    }

    #[test]
    fn switch_is_continuous_and_rolls_at_s_va() {
        let p = [0.0, 0.0, 0.08, 0.0, 0.337, 0.06];
        let m = Prepared::new(&p, groove()).unwrap();
        let (s, k) = (groove().s, groove().k);
        // at the switch v equals s·va with va = k g μ t1
        let va1 = k * G_MPS2 * 0.337 * m.t1_s;
        assert!(
            (m.v1_mps - s * va1).abs() < 1e-12,
            "{} vs {}",
            m.v1_mps,
            s * va1
        );
        let (za, va, _) = m.state(m.t1_s * (1.0 - 1e-12));
        let (zb, vb, _) = m.state(m.t1_s * (1.0 + 1e-12));
        assert!((za - zb).abs() < 1e-12 && (va - vb).abs() < 1e-9);
    }

    #[test]
    fn drag_free_limit_gives_the_textbook_switch() {
        // without drag: t1 = v0 s / (g μ (1 + ks²)), v1 = v0 ks² / (1 + ks²)
        let g = groove();
        let ks2 = g.k * g.s * g.s;
        let p = [0.0, 0.0, 0.05, 0.0, 0.3, 1e4];
        let m = Prepared::new(&p, g).unwrap();
        let t1 = 0.05 * g.s / (G_MPS2 * 0.3 * (1.0 + ks2));
        assert!((m.t1_s / t1 - 1.0).abs() < 1e-5);
        assert!((m.v1_mps / (0.05 * ks2 / (1.0 + ks2)) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn mirror_symmetry_of_directions() {
        let p = [0.0, 3e-5, 0.04, 0.01, 0.3, 0.07];
        let q = [0.0, 3e-5, -0.04, -0.01, 0.3, 0.07];
        let (mp, mq) = (
            Prepared::new(&p, groove()).unwrap(),
            Prepared::new(&q, groove()).unwrap(),
        );
        for &t in &[0.0, 0.001, 0.01, 0.05] {
            assert!((mp.eval(t, 0.0) + mq.eval(t, 0.0)).abs() < 1e-15);
        }
    }
}
