//! Each run's own phase of a force periodic in time: a vibration is not synchronised with the
//! kick, so the phase is a parameter of every run, fitted (profiled) inside each prediction.
//!
//! For amplitude A and frequency f the run is simulated without the force, with `A sin(2π f t)`,
//! with `A cos(2π f t)` and, for the run's own parameters, with v0 stepped. For small forces the
//! motion responds linearly, so the phase that best fits the recorded positions minimises
//! `|e − cos φ·δs − sin φ·δc|²` (e the residual without the force, δs and δc the two responses),
//! a one-dimensional problem solved on a grid and refined; the run's model then carries that phase.
//!
//! The run's z0, t0 and v0 are projected out of e, δs and δc first (as in the screen). A force
//! switched on at the kick leaves a velocity offset `A cos φ/ω` that grows into a drift of tens of
//! µm over a run, a hundred times the oscillation it comes with; v0 absorbs that drift, but a phase
//! chosen on the raw residual is the one that cancels it, not the one of the oscillation, and the
//! amplitude fitted with such phases comes out near 2/π of the truth.

use super::data::{RunData, N_LOCAL};
use super::sim::SimModel;
use crate::lsq::dense::{orthonormal_basis, project_out};
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
    crate::lsq::golden::minimize(|phi| objective(phi, k), best.0 - step, best.0 + step, 40)
        .rem_euclid(TAU)
}

/// The chance that `phases` (radians) gather about one value as closely as they do, were each
/// drawn uniformly on the circle (Rayleigh's test with Zar's approximation); 1 for fewer than
/// two.
pub fn phases_uniform_p(phases: &[f64]) -> f64 {
    let n = phases.len() as f64;
    if phases.len() < 2 {
        return 1.0;
    }
    let (s, c) = phases
        .iter()
        .fold((0.0, 0.0), |a, p| (a.0 + p.sin(), a.1 + p.cos()));
    let r2 = s * s + c * c;
    let p = ((1.0 + 4.0 * n + 4.0 * (n * n - r2)).sqrt() - (1.0 + 2.0 * n)).exp();
    p.clamp(0.0, 1.0)
}

/// The index, amplitude and frequency of the time-periodic force of `m` with a phase per run,
/// if it has one.
pub(super) fn time_term(m: &SimModel) -> Option<(usize, f64, f64)> {
    let idx = m.phased_term?;
    let Term::TimePeriodicForce {
        amp_mps2, freq_hz, ..
    } = m.terms[idx]
    else {
        return None;
    };
    Some((idx, amp_mps2, freq_hz))
}

/// The sums (ss, sc, cc, es, ec) of `run` for the time-periodic force `idx` of `m`: e the
/// residual without the force, s and c the responses to the force at its amplitude with phase
/// 0 and π/2, all with the run's z0, t0 and v0 projected out (metres², not noise units).
pub(super) fn run_sums(m: &SimModel, idx: usize, l: &[f64; N_LOCAL], run: &RunData) -> [f64; 5] {
    run_columns(m, idx, l, run).map_or([0.0; 5], |k| sums(&k.e, &k.s, &k.c))
}

/// (ss, sc, cc, es, ec) of the three columns.
fn sums(e: &[f64], s: &[f64], c: &[f64]) -> [f64; 5] {
    let mut k = [0.0; 5];
    for j in 0..e.len() {
        k[0] += s[j] * s[j];
        k[1] += s[j] * c[j];
        k[2] += c[j] * c[j];
        k[3] += e[j] * s[j];
        k[4] += e[j] * c[j];
    }
    k
}

/// A run's columns for its phase (metres).
struct Columns {
    /// The residual without the force and the responses to it at phase 0 and π/2, at the kept
    /// samples with the run's z0, t0 and v0 projected out.
    e: Vec<f64>,
    s: Vec<f64>,
    c: Vec<f64>,
    /// The two responses at every sample, nothing projected out.
    raw_s: Vec<f64>,
    raw_c: Vec<f64>,
    /// The kept samples' indices.
    kept: Vec<usize>,
}

/// The columns of `run` for the force `idx` of `m` (`Columns`).
fn run_columns(m: &SimModel, idx: usize, l: &[f64; N_LOCAL], run: &RunData) -> Option<Columns> {
    let Term::TimePeriodicForce {
        amp_mps2, freq_hz, ..
    } = m.terms[idx]
    else {
        return None;
    };
    let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
    let mut without = m.clone();
    without.terms.remove(idx);
    without.phased_term = None;
    let mut z0 = vec![0.0; tt.len()];
    let mut v = vec![0.0; tt.len()];
    without.simulate(l[0], l[2], &tt, &mut z0, Some(&mut v), None);
    // the run's own columns: z0, t0 (the velocity) and v0 (a step of the integrator)
    let dv = 1e-6 * l[2].abs().max(1e-3);
    let zv = simulate(&without, &[l[0], l[1], l[2] + dv], &tt);
    let kept: Vec<usize> = (0..tt.len()).filter(|&i| run.keep[i]).collect();
    let basis = orthonormal_basis(vec![
        vec![1.0; kept.len()],
        kept.iter().map(|&i| v[i]).collect(),
        kept.iter().map(|&i| (zv[i] - z0[i]) / dv).collect(),
    ]);
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
    let column = |z: &[f64]| -> Vec<f64> {
        let mut x: Vec<f64> = kept.iter().map(|&i| z[i] - z0[i]).collect();
        project_out(&basis, &mut x);
        x
    };
    let raw = |z: &[f64]| -> Vec<f64> { z.iter().zip(&z0).map(|(a, b)| a - b).collect() };
    Some(Columns {
        e: column(&run.z_m),
        s: column(&zs),
        c: column(&zc),
        raw_s: raw(&zs),
        raw_c: raw(&zc),
        kept,
    })
}

/// Noise replicates of [`noise_gain`].
const GAIN_REPLICATES: usize = 16;

/// What fitting the run's own phase, at the force's amplitude, takes from the run's noise alone:
/// the mean over replicates of the run's noise (its σ, its fast noise's shape and the dataset's
/// slow noise; z0, t0, v0 projected out) of the χ² drop (noise units) the best phase gives. A held-out run whose phase
/// is fitted on itself gains this much whatever the force, so a force with a phase per run is
/// charged it before its held-out error is compared.
pub fn noise_gain(m: &SimModel, l: &[f64; N_LOCAL], run: &RunData, seed: u64) -> f64 {
    use rand::SeedableRng;
    let Some((idx, amp, _)) = time_term(m) else {
        return 0.0;
    };
    if amp == 0.0 || !(run.sigma_m > 0.0) {
        return 0.0;
    }
    let Some(Columns { e, s, c, .. }) = run_columns(m, idx, l, run) else {
        return 0.0;
    };
    let model = run.noise();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut total = 0.0;
    for _ in 0..GAIN_REPLICATES {
        let mut noise = model.replicate(e.len(), &mut rng);
        noise.iter_mut().for_each(|x| *x *= run.sigma_m);
        // the noise is not projected here: s and c are, so its local part does not count
        let k = sums(&noise, &s, &c);
        let best = objective(best_phase(&k), &k);
        total += (-best).max(0.0);
    }
    total / GAIN_REPLICATES as f64 / (run.sigma_m * run.sigma_m)
}

/// Turn a column of the residuals at a held phase into the profiled residuals' column: take
/// off the phase's direction `g` times its first-order move, −(g_hat·column)/|g_hat|²
/// (`gg`; Gauss–Newton, the misfit's own curvature left out), with `g` and `g_hat` from
/// [`profile_with_direction`] in the column's units.
pub fn project_phase(column: &mut [f64], g: &[f64], g_hat: &[f64], gg: f64) {
    let along = g_hat
        .iter()
        .zip(column.iter())
        .map(|(a, b)| a * b)
        .sum::<f64>()
        / gg;
    for (c, g) in column.iter_mut().zip(g) {
        *c -= along * g;
    }
}

/// Set the phase of the time-periodic force in `m` to the one that fits `run` best.
pub fn profile_phase(m: &mut SimModel, l: &[f64; N_LOCAL], run: &RunData) {
    let Some((idx, amp_mps2, _)) = time_term(m) else {
        return;
    };
    if amp_mps2 == 0.0 {
        return;
    }
    hold_phase(m, best_phase(&run_sums(m, idx, l, run)));
}

/// Hold the phase of the time-periodic force of `m` with a phase per run at `phase_rad`.
pub fn hold_phase(m: &mut SimModel, phase_rad: f64) {
    if let Some((idx, amp_mps2, freq_hz)) = time_term(m) {
        m.terms[idx] = Term::TimePeriodicForce {
            amp_mps2,
            freq_hz,
            phase_rad,
        };
    }
}

/// The run's own phase and its direction, for the joint fit's derivatives: set the phase of
/// `m`'s force to the one that fits `run` best (as [`profile_phase`]) and return it with
/// ∂z/∂φ at every sample (`g`, metres per radian, zero where a sample is dropped) and the same
/// with z0, t0 and v0 projected out (`g_hat`, the direction the phase is profiled along). None
/// without such a force or at zero amplitude, when the phase is no parameter.
pub fn profile_with_direction(
    m: &mut SimModel,
    l: &[f64; N_LOCAL],
    run: &RunData,
) -> Option<(f64, Vec<f64>, Vec<f64>)> {
    let (idx, amp_mps2, _) = time_term(m)?;
    if amp_mps2 == 0.0 {
        return None;
    }
    let cols = run_columns(m, idx, l, run)?;
    let phase = best_phase(&sums(&cols.e, &cols.s, &cols.c));
    hold_phase(m, phase);
    let (sn, cs) = phase.sin_cos();
    let mut g = vec![0.0; run.t_s.len()];
    let mut g_hat = vec![0.0; run.t_s.len()];
    for (j, &i) in cols.kept.iter().enumerate() {
        g[i] = -sn * cols.raw_s[i] + cs * cols.raw_c[i];
        g_hat[i] = -sn * cols.s[j] + cs * cols.c[j];
    }
    Some((phase, g, g_hat))
}

/// Points of the phase integral (trapezoid on the circle: exact for the smooth periodic
/// integrand well beyond the concentration a run of 1 µm noise reaches).
const PHASE_POINTS: usize = 256;

/// ln of the mean over the phase circle of the run's likelihood ratio, at `scale` times the
/// amplitude its sums `k` were taken at (`var` the noise variance, m²).
pub(super) fn log_marginal(k: &[f64; 5], scale: f64, var: f64) -> f64 {
    let terms: Vec<f64> = (0..PHASE_POINTS)
        .map(|j| {
            let (sn, cs) = (TAU * j as f64 / PHASE_POINTS as f64).sin_cos();
            let fit = cs * k[3] + sn * k[4];
            let norm = cs * cs * k[0] + 2.0 * sn * cs * k[1] + sn * sn * k[2];
            (scale * fit - 0.5 * scale * scale * norm) / var
        })
        .collect();
    let top = terms.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    top + (terms.iter().map(|t| (t - top).exp()).sum::<f64>() / PHASE_POINTS as f64).ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run of 50 ms at 10 kHz under a vibration of 0.5 m/s² at 120 Hz with its own phase,
    /// recorded with a slow wiggle of 0.2 µm the model lacks (so the misfit is not zero), and
    /// its model.
    fn vibrating_run() -> (SimModel, RunData, [f64; N_LOCAL]) {
        let m = SimModel {
            terms: vec![Term::TimePeriodicForce {
                amp_mps2: 0.5,
                freq_hz: 120.0,
                phase_rad: 0.0,
            }],
            phased_term: Some(0),
            ..SimModel::baseline((70.6f64.to_radians() / 2.0).sin(), 2.5, 0.3, 0.05)
        };
        let l = [1e-3, 0.3e-4, 0.04];
        let t: Vec<f64> = (0..500).map(|k| k as f64 * 1e-4).collect();
        let mut truth = m.clone();
        hold_phase(&mut truth, 1.1);
        let tt: Vec<f64> = t.iter().map(|x| x + l[1]).collect();
        let z: Vec<f64> = simulate(&truth, &l, &tt)
            .iter()
            .zip(&t)
            .map(|(z, t)| z + 0.2e-6 * (TAU * 7.0 * t).sin())
            .collect();
        let run = RunData {
            run: "r".into(),
            material: 0,
            fps: 1e4,
            t_s: t,
            z_m: z,
            keep: vec![true; 500],
            sigma_m: 1e-6,
            fast: Default::default(),
            scale: Vec::new(),
            slow: Default::default(),
        };
        (m, run, l)
    }

    fn norm(x: &[f64]) -> f64 {
        x.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// The prediction's column in μ, the frequency and t0 at a held phase, projected, is the
    /// column of the prediction with the phase profiled at every step within 2 % (0.9, 0.2 and
    /// 0.05 %: what is left grows with the misfit, Gauss–Newton's neglect; with a wiggle of
    /// 2 µm it was 6, 3 and 0.2 %); unprojected, each is 28–105 % off (a later kick moves the
    /// force's clock, which the phase takes back).
    #[test]
    fn a_column_at_the_held_phase_projected_is_the_profiled_one() {
        let (m, run, l) = vibrating_run();
        let profiled = |m: &SimModel, l: &[f64; N_LOCAL]| {
            let mut m = m.clone();
            profile_phase(&mut m, l, &run);
            let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
            simulate(&m, l, &tt)
        };
        let mut held = m.clone();
        let (_, g, g_hat) = profile_with_direction(&mut held, &l, &run).expect("a phase");
        let gg: f64 = g_hat.iter().map(|x| x * x).sum();
        let z0 = profiled(&m, &l);
        let with_freq = |m: &SimModel, f: f64| {
            let mut m = m.clone();
            if let Term::TimePeriodicForce { freq_hz, .. } = &mut m.terms[0] {
                *freq_hz = f;
            }
            m
        };
        // (name, the model and locals stepped from `base` by h, h)
        type Step<'a> = Box<dyn Fn(&SimModel) -> (SimModel, [f64; N_LOCAL]) + 'a>;
        let steps: [(&str, Step, f64); 3] = [
            (
                "mu",
                Box::new(move |b: &SimModel| {
                    (
                        SimModel {
                            mu: b.mu + 1e-6,
                            ..b.clone()
                        },
                        l,
                    )
                }),
                1e-6,
            ),
            (
                "frequency",
                Box::new(move |b: &SimModel| (with_freq(b, 120.0 + 1e-4), l)),
                1e-4,
            ),
            (
                "t0",
                Box::new(move |b: &SimModel| (b.clone(), [l[0], l[1] + 1e-8, l[2]])),
                1e-8,
            ),
        ];
        for (name, step, h) in &steps {
            let (mp, lp) = step(&m);
            let exact: Vec<f64> = profiled(&mp, &lp)
                .iter()
                .zip(&z0)
                .map(|(a, b)| (a - b) / h)
                .collect();
            let (hp, lp) = step(&held);
            let tt: Vec<f64> = run.t_s.iter().map(|t| t + lp[1]).collect();
            let mut col: Vec<f64> = simulate(&hp, &lp, &tt)
                .iter()
                .zip(&z0)
                .map(|(a, b)| (a - b) / h)
                .collect();
            let unprojected = col.clone();
            project_phase(&mut col, &g, &g_hat, gg);
            let off = |c: &[f64]| {
                let d: Vec<f64> = c.iter().zip(&exact).map(|(a, b)| a - b).collect();
                norm(&d) / norm(&exact)
            };
            assert!(
                off(&col) < 0.02,
                "{name}: projected column off by {}",
                off(&col)
            );
            assert!(
                off(&unprojected) > 0.2,
                "{name} unprojected: {}",
                off(&unprojected)
            );
        }
    }

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

    #[test]
    fn phases_of_their_own_seldom_gather_and_locked_ones_do() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        // 200 sets of 60 uniform phases: the test's level holds (1 % at most a few times over)
        let gathered = (0..200)
            .filter(|_| {
                let ph: Vec<f64> = (0..60)
                    .map(|_| rng.random_range(0.0..std::f64::consts::TAU))
                    .collect();
                super::phases_uniform_p(&ph) < 0.01
            })
            .count();
        assert!(
            gathered <= 6,
            "{gathered} of 200 uniform sets gathered at 1 %"
        );
        // 60 phases about 1.3 rad, each off by up to ±1 rad (a kick time off by a few ms at 30 Hz)
        let ph: Vec<f64> = (0..60).map(|_| 1.3 + rng.random_range(-1.0..1.0)).collect();
        let p = super::phases_uniform_p(&ph);
        assert!(p < 1e-10, "locked phases: p {p}");
        assert_eq!(super::phases_uniform_p(&[0.3]), 1.0);
    }
}
