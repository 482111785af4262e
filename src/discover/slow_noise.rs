//! The slow part of the tracking noise: a drift over many frames (a sub-pixel estimator that
//! wanders, camera shake, slow illumination changes) that a run's local cubic cannot see, since
//! the cubic takes it for a trend. Unmodelled, it reads as physics: a smooth column (a drag, a
//! distortion, a drift of T with |v0|) collects far more of it than white noise gives, and a
//! force periodic in time with a phase per run fits it in every run.
//!
//! Each run's noise, in units of its measured σ, is modelled as its fast part (`noise.rs`,
//! `blur.rs`) plus an independent slow AR(1) of variance κ and lag-1 correlation ρ_s per
//! kept sample, κ and ρ_s shared by the runs of a dataset (one tracker, one camera). They are
//! measured on each run's own fit (its μ, T, z0, t0, v0 free, so a misfit that a run's own μ
//! and T take up is not read as noise): the residual's projections on a run's slowest cosines,
//! with the fit's columns projected out of them, have expectations `A + κ·B(ρ_s)`
//! (`noise_model.rs`);
//! κ and ρ_s maximise the Gaussian quasi-likelihood (a grid of time constants from 8 samples,
//! refined between its points), and κ is kept only when it beats κ = 0 by the χ²₂ 1 % point, so
//! a noise without a slow part keeps exactly its fast model.
//! A physical misfit left in the runs' own fits is a wander too. Where it is strong it can sit in
//! a few runs whose motion their own fits cannot follow, and read as the tracker's drift it made
//! every replicate as rough as those runs, so that every test sat inside its null: the runs
//! whose probes the shared noise cannot explain are left out of the estimate one at a time
//! (`estimate`; the report says how many). What is
//! left of a misfit raises κ, which makes every test more cautious, never less.

use super::noise_model::{ar1_cross, Fast, RunNoise, Slow};
use crate::lsq::dense::{orthonormal_basis, project_out};

/// The χ²₂ 1 % point: the quasi-likelihood ratio κ must reach to be kept.
const KEEP_LR: f64 = 9.21;
/// Slow cosines per run (at most; a short run has fewer).
const PROBES: usize = 12;
/// The chance, over the number of runs, below which a run's probes are not the shared noise.
const RUN_ALPHA: f64 = 1e-3;
/// Kept samples per probe at least (a run of 60 samples has 6 probes).
const SAMPLES_PER_PROBE: usize = 10;

/// One run as the estimate sees it: its own fit's residual at its kept samples in noise units,
/// that fit's columns there (any scaling), and its fast noise (its shape and its scale by
/// sample).
pub struct Series {
    pub y: Vec<f64>,
    pub cols: Vec<Vec<f64>>,
    pub fast: Fast,
    pub scale: Vec<f64>,
}

/// One probe of one run: the observed square, the fast model's expectation and the slow
/// model's expectation per unit κ at each trial ρ_s.
#[derive(Clone)]
struct Probe {
    obs: f64,
    fast: f64,
    slow: Vec<f64>,
}

/// Trial time constants of the slow noise, in kept samples: 8 to 8192, a factor 2 apart. A
/// correlation shorter than 8 samples is the fast noise's, which the local cubic's window of
/// 41 measures; a slow part allowed there stood in for a fast AR(1) read too weakly (a white
/// part beside a correlated one) with a large variance at 2 samples, and overstated the noise
/// everywhere but where the fast one fell short.
fn trial_rhos() -> Vec<f64> {
    (3..14).map(|i| (-1.0 / 2f64.powi(i)).exp()).collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The probes of one run: its slowest cosines with its fit's columns projected out.
fn probes(s: &Series, rhos: &[f64]) -> Vec<Probe> {
    let n = s.y.len();
    let k_max = PROBES.min(n / SAMPLES_PER_PROBE);
    let q = orthonormal_basis(s.cols.clone());
    (1..=k_max)
        .filter_map(|k| {
            let mut u: Vec<f64> = (0..n)
                .map(|i| (std::f64::consts::PI * k as f64 * (i as f64 + 0.5) / n as f64).cos())
                .collect();
            project_out(&q, &mut u);
            let norm = dot(&u, &u).sqrt();
            if !(norm > 1e-6 * (n as f64).sqrt()) {
                return None;
            }
            u.iter_mut().for_each(|a| *a /= norm);
            let fast = RunNoise {
                fast: s.fast,
                slow: Slow::default(),
                scale: &s.scale,
            }
            .fast_cross(&u, &u);
            let slow = rhos.iter().map(|&r| ar1_cross(&u, &u, r)).collect();
            let b = dot(&u, &s.y);
            Some(Probe {
                obs: b * b,
                fast,
                slow,
            })
        })
        .collect()
}

/// The quasi-log-likelihood of κ at trial `j`: −½ Σ (ln E + obs/E), E = fast + κ·slow.
fn loglik(ps: &[Probe], j: usize, kappa: f64) -> f64 {
    -0.5 * ps
        .iter()
        .map(|p| {
            let e = (p.fast + kappa * p.slow[j]).max(1e-300);
            e.ln() + p.obs / e
        })
        .sum::<f64>()
}

/// The best κ at each trial ρ_s of the grid: (slow noise, its likelihood ratio against none).
fn grid_fit(ps: &[Probe], rhos: &[f64]) -> (Slow, f64) {
    let l0 = loglik(ps, 0, 0.0);
    let mut best = (Slow::default(), 0.0);
    for (j, &rho) in rhos.iter().enumerate() {
        // κ on a log scale from a hundredth of each run's σ² to 10⁶ of it
        let f = |s: f64| -loglik(ps, j, s.exp());
        let s = crate::lsq::golden::minimize(f, (1e-2f64).ln(), (1e6f64).ln(), 60);
        let lr = 2.0 * (loglik(ps, j, s.exp()) - l0);
        if lr > best.1 {
            best = (
                Slow {
                    kappa: s.exp(),
                    rho,
                    left_out: 0,
                },
                lr,
            );
        }
    }
    best
}

/// How far a run's probes stand from the shared noise `slow` (trial `j`): the chance of a
/// χ² as large as Σ obs/E on as many degrees of freedom as it has probes.
fn run_p(ps: &[Probe], j: usize, slow: Slow) -> f64 {
    let d: f64 = ps
        .iter()
        .map(|p| p.obs / (p.fast + slow.kappa * p.slow[j]).max(1e-300))
        .sum();
    crate::stats::dist::chi2_sf(d, ps.len() as f64)
}

/// The slow noise of a dataset and its quasi-likelihood ratio against none (0 when none kept).
///
/// The tracker's drift is shared by the runs; a wander that only a few runs show is what their
/// own fits cannot follow, and read as drift it would make
/// every replicate as rough as those few runs. So, while a slow part is kept, the run least
/// consistent with it (its probes' Σ obs/E on the χ² of as many probes, beyond
/// `RUN_ALPHA` over the number of runs) is left out of the estimate and the noise measured
/// again, a quarter of the runs at most. The runs left out still carry the noise measured on
/// the others.
pub fn estimate(series: &[Series]) -> (Slow, f64) {
    let rhos = trial_rhos();
    let per_run: Vec<Vec<Probe>> = series.iter().map(|s| probes(s, &rhos)).collect();
    let mut used: Vec<bool> = per_run.iter().map(|p| !p.is_empty()).collect();
    let n_runs = used.iter().filter(|u| **u).count();
    let gathered = |used: &[bool]| -> Vec<Probe> {
        per_run
            .iter()
            .zip(used)
            .filter(|(_, u)| **u)
            .flat_map(|(p, _)| p.iter().cloned())
            .collect()
    };
    let mut best;
    let mut left_out = 0;
    loop {
        let ps = gathered(&used);
        if ps.len() < 8 {
            return (Slow::default(), 0.0);
        }
        best = grid_fit(&ps, &rhos);
        if best.1 < KEEP_LR || 4 * (left_out + 1) > n_runs {
            break;
        }
        let j = rhos.iter().position(|r| *r == best.0.rho).unwrap_or(0);
        let worst = per_run
            .iter()
            .enumerate()
            .filter(|(i, _)| used[*i])
            .map(|(i, p)| (i, run_p(p, j, best.0)))
            .fold((usize::MAX, 1.0), |b, x| if x.1 < b.1 { x } else { b });
        if worst.0 == usize::MAX || worst.1 >= RUN_ALPHA / n_runs as f64 {
            break;
        }
        used[worst.0] = false;
        left_out += 1;
    }
    // the grid's time constants are a factor 2 apart, and the variance a smooth column (a run's
    // μ or T) collects from the drift goes as κτ: refine τ between the best one's neighbours
    if best.1 > 0.0 {
        let l0 = loglik(&gathered(&used), 0, 0.0);
        let j = rhos.iter().position(|r| *r == best.0.rho).unwrap_or(0);
        let tau = |r: f64| -1.0 / r.ln();
        let lo = tau(rhos[j.saturating_sub(1)]).ln();
        let hi = tau(rhos[(j + 1).min(rhos.len() - 1)]).ln();
        let profile = |ln_tau: f64| -> (f64, f64, f64) {
            let rho = (-1.0 / ln_tau.exp()).exp();
            let local: Vec<Probe> = series
                .iter()
                .zip(&used)
                .filter(|(_, u)| **u)
                .flat_map(|(s, _)| probes(s, &[rho]))
                .collect();
            let f = |s: f64| -loglik(&local, 0, s.exp());
            let s = crate::lsq::golden::minimize(f, (1e-2f64).ln(), (1e6f64).ln(), 60);
            (rho, s.exp(), 2.0 * (loglik(&local, 0, s.exp()) - l0))
        };
        let ln_tau = crate::lsq::golden::minimize(|x| -profile(x).2, lo, hi, 30);
        let (rho, kappa, lr) = profile(ln_tau);
        if lr > best.1 {
            best = (
                Slow {
                    kappa,
                    rho,
                    left_out: 0,
                },
                lr,
            );
        }
    }
    if best.1 >= KEEP_LR {
        best.0.left_out = left_out;
        best
    } else {
        (Slow::default(), best.1.max(0.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// `runs` series of `n` samples: fast AR(1) of correlation 0.3 plus a slow one, the fit's
    /// columns a constant, a line and a decaying exponential, projected out of the residual.
    fn dataset(runs: usize, n: usize, slow: Slow, seed: u64) -> Vec<Series> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..runs)
            .map(|_| {
                let cols: Vec<Vec<f64>> = vec![
                    vec![1.0; n],
                    (0..n).map(|i| i as f64 / n as f64).collect(),
                    (0..n)
                        .map(|i| (-(i as f64) / (0.4 * n as f64)).exp())
                        .collect(),
                ];
                let noise = RunNoise {
                    fast: Fast::ar1(0.3),
                    slow,
                    scale: &[],
                };
                let mut y = noise.replicate(n, &mut rng);
                project_out(&orthonormal_basis(cols.clone()), &mut y);
                Series {
                    y,
                    cols,
                    fast: Fast::ar1(0.3),
                    scale: Vec::new(),
                }
            })
            .collect()
    }

    #[test]
    fn a_fast_noise_alone_keeps_no_slow_part_on_most_datasets() {
        let kept = (0..40)
            .filter(|&s| estimate(&dataset(30, 400, Slow::default(), s)).0.kappa > 0.0)
            .count();
        // the χ²₂ 1 % point over 13 trial time constants: a few percent at most
        assert!(kept <= 3, "{kept} of 40 null datasets kept a slow noise");
    }

    /// The first `count` runs given a slow misfit of a hundred noise units (a run whose motion
    /// its own fit cannot follow), with the fit's columns projected out of it.
    fn wander_in_first(runs: &mut [Series], count: usize) {
        for (r, s) in runs.iter_mut().take(count).enumerate() {
            let n = s.y.len();
            let mut wander: Vec<f64> = (0..n)
                .map(|i| 100.0 * (3.0 * (i as f64 / n as f64) + r as f64).sin())
                .collect();
            project_out(&orthonormal_basis(s.cols.clone()), &mut wander);
            s.y.iter_mut().zip(&wander).for_each(|(y, w)| *y += w);
        }
    }

    /// A drift of the white noise's variance over 40 samples (ρ_s = e^(−1/40)).
    fn drift_truth() -> Slow {
        Slow {
            kappa: 1.0,
            rho: (-1.0f64 / 40.0).exp(),
            left_out: 0,
        }
    }

    /// `s` is `drift_truth` within the estimate's errors.
    fn assert_drift_read(s: Slow, seed: u64) {
        // the grid's time constants are a factor 2 apart
        let tau = -1.0 / s.rho.ln();
        assert!((16.0..=128.0).contains(&tau), "seed {seed}: τ {tau}");
        // κ traded against τ along the grid: the variance within a factor 2.5
        assert!(
            (0.4..2.5).contains(&s.kappa),
            "seed {seed}: κ {} at τ {tau}",
            s.kappa
        );
    }

    #[test]
    fn a_wander_in_a_few_runs_is_not_the_trackers_drift() {
        // 3 runs of 30 carry a slow misfit of a hundred noise units (a run the model cannot
        // follow); the others are the fast noise alone
        for seed in 0..5 {
            let mut runs = dataset(30, 400, Slow::default(), 200 + seed);
            wander_in_first(&mut runs, 3);
            let (slow, lr) = estimate(&runs);
            assert_eq!(
                slow.kappa, 0.0,
                "seed {seed}: κ {} kept (lr {lr})",
                slow.kappa
            );
        }
    }

    #[test]
    fn a_drift_beside_a_few_wandering_runs_is_measured_on_the_others() {
        // the drift of the test below in every run, and in 3 runs of 40 a misfit of a hundred
        // noise units: those 3 are left out, and the drift is read within the same errors
        let truth = drift_truth();
        for seed in 0..5 {
            let mut runs = dataset(40, 500, truth, 300 + seed);
            wander_in_first(&mut runs, 3);
            let (s, _) = estimate(&runs);
            assert_eq!(s.left_out, 3, "seed {seed}: {} runs left out", s.left_out);
            assert_drift_read(s, seed);
        }
    }

    #[test]
    fn a_slow_drift_is_measured_within_its_errors() {
        let truth = drift_truth();
        for seed in 0..5 {
            let (s, lr) = estimate(&dataset(40, 500, truth, 100 + seed));
            assert!(lr > 50.0, "seed {seed}: lr {lr}");
            assert_eq!(
                s.left_out, 0,
                "seed {seed}: a run of the drift itself left out"
            );
            assert_drift_read(s, seed);
        }
    }
}
