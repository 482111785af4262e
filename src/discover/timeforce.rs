//! Each run's own phase of a force periodic in time: a vibration is not synchronised with the
//! kick, so the phase is a parameter of every run, fitted (profiled) inside each prediction.
//!
//! For amplitude A and frequency f the run is simulated three times: without the force, with
//! `A sin(2π f t)` and with `A cos(2π f t)`. For small forces the motion responds linearly, so the
//! phase that best fits the recorded positions minimises
//! `|e − cos φ·δs − sin φ·δc|²` (e the residual without the force, δs and δc the two responses),
//! a one-dimensional problem solved on a grid and refined; the run's model then carries that phase.

use super::candidate::N_LOCAL;
use super::data::RunData;
use super::sim::SimModel;
use crate::physics::Term;
use std::f64::consts::{FRAC_PI_2, TAU};

fn simulate(m: &SimModel, l: &[f64; N_LOCAL], tt: &[f64]) -> Vec<f64> {
    let mut z = vec![0.0; tt.len()];
    m.simulate(l[0], l[2], tt, &mut z, None, None);
    z
}

/// Sum of squares of `e − cos φ·s − sin φ·c` from the sums (ss, sc, cc, es, ec).
fn objective(phi: f64, k: &[f64; 5]) -> f64 {
    let (sn, cs) = phi.sin_cos();
    cs * cs * k[0] + 2.0 * sn * cs * k[1] + sn * sn * k[2] - 2.0 * (cs * k[3] + sn * k[4])
}

/// The phase minimising the objective: the best of 32 grid points, refined by golden section.
pub fn best_phase(k: &[f64; 5]) -> f64 {
    let n = 32;
    let step = TAU / n as f64;
    let mut best = (0.0, f64::INFINITY);
    for i in 0..n {
        let phi = i as f64 * step;
        let v = objective(phi, k);
        if v < best.1 {
            best = (phi, v);
        }
    }
    let (mut a, mut b) = (best.0 - step, best.0 + step);
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let mut x1 = b - r * (b - a);
    let mut x2 = a + r * (b - a);
    let (mut f1, mut f2) = (objective(x1, k), objective(x2, k));
    for _ in 0..40 {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - r * (b - a);
            f1 = objective(x1, k);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + r * (b - a);
            f2 = objective(x2, k);
        }
    }
    (0.5 * (a + b)).rem_euclid(TAU)
}

/// Set the phase of the time-periodic force in `m` to the one that fits `run` best.
pub fn profile_phase(m: &mut SimModel, l: &[f64; N_LOCAL], run: &RunData) {
    let Some(idx) = m
        .terms
        .iter()
        .position(|t| matches!(t, Term::TimePeriodicForce { .. }))
    else {
        return;
    };
    let Term::TimePeriodicForce {
        amp_mps2, freq_hz, ..
    } = m.terms[idx]
    else {
        return;
    };
    if amp_mps2 == 0.0 {
        return;
    }
    let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
    let mut without = m.clone();
    without.terms.remove(idx);
    let z0 = simulate(&without, l, &tt);
    let with_phase = |phase_rad: f64| {
        let mut w = m.clone();
        w.terms[idx] = Term::TimePeriodicForce {
            amp_mps2,
            freq_hz,
            phase_rad,
        };
        simulate(&w, l, &tt)
    };
    let zs = with_phase(0.0);
    let zc = with_phase(FRAC_PI_2);
    let mut k = [0.0; 5];
    for i in 0..tt.len() {
        if !run.keep[i] {
            continue;
        }
        let e = run.z_m[i] - z0[i];
        let s = zs[i] - z0[i];
        let c = zc[i] - z0[i];
        k[0] += s * s;
        k[1] += s * c;
        k[2] += c * c;
        k[3] += e * s;
        k[4] += e * c;
    }
    let phase_rad = best_phase(&k);
    m.terms[idx] = Term::TimePeriodicForce {
        amp_mps2,
        freq_hz,
        phase_rad,
    };
}

#[cfg(test)]
mod tests {
    #[test]
    fn best_phase_recovers_a_known_phase() {
        // e = cos φ0·s + sin φ0·c with s, c orthonormal-ish
        let phi0: f64 = 2.2;
        let k = [
            1.0,
            0.1,
            1.0,
            phi0.cos() + 0.1 * phi0.sin(),
            0.1 * phi0.cos() + phi0.sin(),
        ];
        let phi = super::best_phase(&k);
        assert!((phi - phi0).abs() < 1e-6, "{phi}");
    }
}
