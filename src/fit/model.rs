//! The closed-form baseline as a fit model: positions and their analytic partial derivatives.
//!
//! The model of one particle (physics.md, "Closed form of the baseline", generalised to a nonzero
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
        *grad = [0.0; NP];
        grad[Z0] = 1.0;
        if tau < 0.0 {
            return self.p[Z0];
        }
        let (v0, t) = (self.p[V0], self.p[TD]);
        let (s, dir, da) = (self.groove.s, self.dir, self.da);
        if tau < self.t1_s {
            let (e, om) = decay(tau / t);
            let c = G_MPS2 * self.p[MU] / s;
            grad[T0] = slide_v(v0, da, e);
            grad[V0] = t * om;
            grad[MU] = dir * (G_MPS2 * t / s) * (t * om - tau);
            grad[TD] = v0 * (om - e * tau / t) + dir * c * (2.0 * t * om - e * tau - tau);
            self.p[Z0] + t * (v0 + da) * om - da * tau
        } else {
            let te = self.te_s;
            let v1 = self.v1_mps;
            let x = (tau - self.t1_s) / te;
            let (f, om) = decay(x);
            grad[T0] = v1 * f;
            // ∂R/∂Te · ∂Te/∂T with R = v1 Te (1 − F)
            let dr_dte = v1 * (om - f * x);
            for (i, g) in grad.iter_mut().enumerate().take(TD + 1).skip(V0) {
                *g = self.dz1[i] + te * om * self.dv1[i] - v1 * f * self.dt1[i];
            }
            grad[TD] += dr_dte * te / t;
            self.p[Z0] + self.z1_m + v1 * te * om
        }
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
