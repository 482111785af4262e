//! The closed-form motion of one sphere in the groove (Coulomb μ, linear drag v/T) from any
//! initial velocity and spin — `physics::Baseline::state_from` — as each phase of a collision
//! track is fitted with it.
//!
//! Sliding while v ≠ s·v_a with d = sign(v0 − s·v_a0) (either sign; friction may accelerate),
//! then constrained rolling decaying with Te = T(1 + ks²)/ks² (see `physics`).

pub use crate::physics::G_MPS2;
use crate::physics::{Baseline, Groove, Phase};

/// Friction, drag and groove geometry of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    pub mu: f64,
    pub t_drag_s: f64,
    /// sin(θ/2)
    pub s: f64,
    /// m R² / I
    pub k: f64,
}

/// Position change, velocity and spin at one time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kinematics {
    pub dz_m: f64,
    pub v_mps: f64,
    pub va_mps: f64,
    pub sliding: bool,
}

impl Motion {
    fn baseline(&self) -> Baseline {
        Baseline {
            mu: self.mu,
            t_drag_s: self.t_drag_s,
            groove: Groove {
                s: self.s,
                k: self.k,
            },
        }
    }

    /// Decay time of constrained rolling, Te = T (1 + ks²) / ks².
    pub fn te_s(&self) -> f64 {
        let ks2 = self.k * self.s * self.s;
        self.t_drag_s * (1.0 + ks2) / ks2
    }

    /// Time (s, from the state's instant) at which sliding ends; 0 when already rolling,
    /// ∞ when it never rolls.
    pub fn switch_time_s(&self, v0_mps: f64, va0_mps: f64) -> f64 {
        self.baseline().switch_time_from_s(v0_mps, va0_mps)
    }

    /// State at `t_s` ≥ 0 after the state (v0, va0) at 0.
    pub fn state(&self, v0_mps: f64, va0_mps: f64, t_s: f64) -> Kinematics {
        let (dz_m, v_mps, va_mps, phase) = self.baseline().state_from(v0_mps, va0_mps, t_s);
        Kinematics {
            dz_m,
            v_mps,
            va_mps,
            sliding: phase == Phase::Sliding,
        }
    }

    /// Position changes at many times ≥ 0 (the fit's fast path).
    pub fn positions(&self, v0_mps: f64, va0_mps: f64, t_s: &[f64], out_dz_m: &mut [f64]) {
        self.baseline()
            .positions_from(v0_mps, va0_mps, t_s, out_dz_m);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const M: Motion = Motion {
        mu: 0.3,
        t_drag_s: 0.06,
        s: 0.5779,
        k: 2.5,
    };

    /// Independent check: integrate the sliding/rolling equations with small RK4 steps.
    fn integrate(v0: f64, va0: f64, t_end: f64) -> (f64, f64, f64) {
        let (mut z, mut v, mut va) = (0.0, v0, va0);
        let n = 200_000;
        let h = t_end / n as f64;
        let gm = G_MPS2 * M.mu;
        let mut rolling = false;
        for _ in 0..n {
            if !rolling {
                let d = (v - M.s * va).signum();
                let acc = |v: f64| -d * gm / M.s - v / M.t_drag_s;
                let k1 = acc(v);
                let k2 = acc(v + 0.5 * h * k1);
                let k3 = acc(v + 0.5 * h * k2);
                let k4 = acc(v + h * k3);
                z += h * (v + h * (k1 + k2 + k3) / 6.0);
                let vn = v + h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0;
                let van = va + d * M.k * gm * h;
                if (vn - M.s * van).signum() != d {
                    rolling = true;
                    // project onto the rolling manifold conserving the angular momentum about the contact
                    let ks2 = M.k * M.s * M.s;
                    v = (ks2 * vn + M.s * van) / (1.0 + ks2);
                    va = v / M.s;
                } else {
                    v = vn;
                    va = van;
                }
            } else {
                let dv = -v / M.te_s() * h;
                z += h * (v + 0.5 * dv);
                v += dv;
                va = v / M.s;
            }
        }
        (z, v, va)
    }

    #[test]
    fn matches_integration_for_forward_and_back_spin_both_directions() {
        for &(v0, va0) in &[
            (0.1, 0.0),
            (0.02, 0.2),
            (-0.08, 0.05),
            (0.05, -0.1),
            (-0.03, -0.3),
        ] {
            let k = M.state(v0, va0, 0.04);
            let (z, v, va) = integrate(v0, va0, 0.04);
            assert!((k.dz_m - z).abs() < 2e-8, "{v0} {va0}: {} vs {z}", k.dz_m);
            assert!((k.v_mps - v).abs() < 1e-5, "{v0} {va0}: {} vs {v}", k.v_mps);
            assert!(
                (k.va_mps - va).abs() < 2e-5,
                "{v0} {va0}: {} vs {va}",
                k.va_mps
            );
        }
    }

    #[test]
    fn rolling_start_has_no_sliding_phase_and_decays_with_te() {
        let v0 = 0.05;
        assert_eq!(M.switch_time_s(v0, v0 / M.s), 0.0);
        let k = M.state(v0, v0 / M.s, 0.01);
        assert!((k.v_mps - v0 * (-0.01 / M.te_s()).exp()).abs() < 1e-12);
        assert!(!k.sliding);
    }
}
