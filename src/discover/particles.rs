//! Differences between particles: μ and T varying from run to run beyond what each run's noise
//! allows, with nothing missing from the equations.
//!
//! Around the final joint model, each run's residual (in noise units, its z0, t0 and v0 projected
//! out) is regressed on that run's own μ and T columns. The statistic `LR` is the χ² those
//! per-run parameters take up; `RES` is what is left. Each run's measured noise (`noise_model.rs`:
//! σ, the fast part's shape, its growth with speed and the slow drift) is pushed through the same
//! projections in replicates, which give both their laws. The slow drift is taken at the long
//! end of its confidence set (`Slow::cautious`): `LR` lies in the μ and T columns alone, which
//! the drift's estimate never sees (it projects each run's fit out), so what they collect from
//! it is extrapolated, and the test must hold wherever the drift may be.
//! The test is on the ratio `F = (LR/E LR₀)/(RES/E RES₀)`: a noise larger than measured inflates
//! both alike, while particles that differ raise `LR` alone. The particles are said to differ only
//! when `F` lies beyond the replicates' at level α (a normal tail on ln F of the replicates), is
//! at least `MIN_RATIO`, and the per-run parameters leave the runs at their noise (`RES` within
//! `RESIDUAL_SLACK` of its expectation): a force or a friction the model lacks leaves structure a
//! run's own μ and T cannot take up, and that is no difference between particles. Nor is a noise
//! that wanders over many frames, which a run's own μ and T take up as well: the data's energy in
//! slow shapes that a run's μ and T cannot make (Legendre degrees 2–5, orthogonal to them) must
//! stay within `WANDER_LIMIT` of the noise's, or the check says it cannot decide. Nor is a
//! friction or force that varies along the groove, which gives runs sliding over the same stretch
//! the same μ: the runs' steps are tested for order in position (`position_order.rs`).
//!
//! The size is the spread of the per-run estimates beyond their own errors, per material (Paule
//! and Mandel's estimate: each run weighted by its noise variance plus the spread's). Each run's
//! step is its own fit's, refitted in full with the model's terms held, where that goes further
//! than the first order: a large spread leaves much of itself beyond the first order.

use super::candidate::prepare;
use super::data::RunData;
use super::model::Model;
use super::response::Prepared;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Noise replicates of the check.
const REPLICATES: usize = 200;

/// Smallest `F` said to be a difference between particles: the runs' own μ and T must take up
/// half as much again as the noise gives them. A tracker noise that wanders over many frames
/// lifts `F` above 1 by itself where its replicates do not wander alike (before the slow drift
/// was measured, by up to a third on the correlated-noise nulls of the test bed).
pub const MIN_RATIO: f64 = 1.5;

/// Largest ratio of the data's energy to the noise's in slow shapes that a run's own μ and T
/// cannot make (`wander`) for the check to decide: above it the tracker noise wanders over many
/// frames, which a run's μ and T would also take up, and the particles cannot be told apart from
/// it. Under white noise over 60 runs the ratio scatters by about 0.1.
pub const WANDER_LIMIT: f64 = 1.5;

/// Largest ratio of what the per-run parameters leave to its expectation under the noise for
/// the runs to count as explained by them.
pub const RESIDUAL_SLACK: f64 = 1.25;

/// The spread of one material's per-run parameters beyond their errors.
#[derive(Clone, Debug)]
pub struct Spread {
    pub material: String,
    pub n_runs: usize,
    /// Shared μ and T of the material (the joint model's).
    pub mu: f64,
    pub t_s: f64,
    /// Standard deviation of μ and T over the particles beyond the runs' noise (0: none seen).
    pub mu_sd: f64,
    pub t_sd: f64,
    /// The median error of one run's μ and T from its noise alone.
    pub mu_se: f64,
    pub t_se: f64,
}

/// What the check found.
#[derive(Clone, Debug)]
pub struct Check {
    pub lr: f64,
    pub lr_null_mean: f64,
    pub residual_ratio: f64,
    /// The data's energy in slow shapes a run's μ and T cannot make, over the noise's.
    pub wander_ratio: f64,
    pub f: f64,
    pub p_value: f64,
    pub spreads: Vec<Spread>,
    pub differ: bool,
    /// Whether the runs' own μ or T drift with |v0| or direction beyond their scatter from run
    /// to run (a between-run test: the drift probes' null is the noise alone, and particles that
    /// differ make any per-run slope look significant against it).
    pub drift_beyond_scatter: bool,
    /// The p-value (Bonferroni over μ and T of every material) that the runs' own μ or T follow
    /// where each run slides (`position_order.rs`): a friction or force varying along the
    /// groove, not particles that differ.
    pub position_p: f64,
}

/// One run's orthonormal basis of its own μ and T columns (noise units, locals projected out),
/// with the coefficients that map basis coordinates back to (δμ, δT).
struct RunBasis {
    q: Vec<Vec<f64>>,
    /// Slow shapes orthogonal to the locals and to `q` (Legendre degrees 2–5 over the samples).
    slow: Vec<Vec<f64>>,
    /// Rows: δμ, δT per unit coordinate along each basis vector.
    back: [[f64; 2]; 2],
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Gram–Schmidt of the run's μ and T columns; `back` maps a vector of coordinates along `q`
/// to the parameter steps that make it (a column that the locals absorb is dropped).
fn basis(p: &Prepared, mu_col: usize, t_col: usize) -> RunBasis {
    let cols = [&p.glob[mu_col], &p.glob[t_col]];
    let mut q: Vec<Vec<f64>> = Vec::new();
    // r: the upper-triangular factor, cols = Q R
    let mut r = [[0.0f64; 2]; 2];
    for (j, c) in cols.iter().enumerate() {
        let mut x = c.to_vec();
        let n0 = dot(&x, &x).sqrt();
        for (i, qi) in q.iter().enumerate() {
            let d = dot(qi, &x);
            r[i][j] = d;
            x.iter_mut().zip(qi).for_each(|(a, b)| *a -= d * b);
        }
        let n = dot(&x, &x).sqrt();
        if n0 > 0.0 && n > 1e-6 * n0 {
            r[q.len()][j] = n;
            x.iter_mut().for_each(|a| *a /= n);
            q.push(x);
        }
    }
    // back = R⁻¹ (2×2 upper triangular); a run whose locals absorb one of the two columns gives
    // no per-run step (zero), though its χ² still counts
    let mut back = [[0.0; 2]; 2];
    if q.len() == 2 {
        back[0][0] = 1.0 / r[0][0];
        back[1][1] = 1.0 / r[1][1];
        back[0][1] = -r[0][1] / (r[0][0] * r[1][1]);
    }
    let n = p.y.len();
    let mut slow: Vec<Vec<f64>> = Vec::new();
    if n >= 16 {
        for deg in 2..=5 {
            let mut c: Vec<f64> = (0..n)
                .map(|i| legendre(deg, 2.0 * i as f64 / (n - 1) as f64 - 1.0))
                .collect();
            p.proj.apply(&mut c);
            for _ in 0..2 {
                for b in q.iter().chain(&slow) {
                    let a = dot(b, &c);
                    c.iter_mut().zip(b).for_each(|(x, y)| *x -= a * y);
                }
            }
            let norm = dot(&c, &c).sqrt();
            if norm > 1e-6 * (n as f64).sqrt() {
                c.iter_mut().for_each(|x| *x /= norm);
                slow.push(c);
            }
        }
    }
    RunBasis { q, slow, back }
}

/// Each run's own fit under the model `m` (μ and T free, the extra terms held): its residual in
/// noise units with the locals projected out, and its step (δμ, δT) from the material's values;
/// None where the fit did not converge.
fn own_fits(m: &Model, runs: &[RunData], prep: &[Prepared]) -> Vec<Option<(Vec<f64>, [f64; 2])>> {
    let nm = m.spec.n_materials;
    let (g, l) = (&m.fit.global, &m.fit.local);
    let fits = super::perrun::fits_under(runs, &m.spec, &m.params, g, l);
    prep.par_iter()
        .map(|p| {
            let (run, f) = (&runs[p.run], &fits[p.run]);
            if !f.converged {
                return None;
            }
            let r = super::perrun::residuals(run, &m.spec, &m.params, &g[2 * nm..], f);
            let mut y: Vec<f64> = r
                .iter()
                .zip(&run.keep)
                .filter(|q| *q.1)
                .map(|q| q.0 / run.sigma_m)
                .collect();
            p.proj.apply(&mut y);
            let k = run.material;
            Some((y, [f.mu - g[k], f.t_s - g[nm + k]]))
        })
        .collect()
}

/// The variance τ² of the true values behind estimates `d` of noise variances `v` (Paule and
/// Mandel: the τ² at which the weighted scatter Σ w (d − d̄)², w = 1/(v + τ²), is n − 1, its
/// expectation), 0 when the scatter is within the noise. Weights 1/v² instead let the one run
/// that knows its μ best decide the spread alone, a third of the truth on the test bed.
fn paule_mandel(dv: &[(f64, f64)]) -> f64 {
    let q = |tau2: f64| {
        let w: Vec<f64> = dv.iter().map(|p| 1.0 / (p.1 + tau2)).collect();
        let sw: f64 = w.iter().sum();
        let mean = dv.iter().zip(&w).map(|(p, w)| w * p.0).sum::<f64>() / sw;
        dv.iter()
            .zip(&w)
            .map(|(p, w)| w * (p.0 - mean).powi(2))
            .sum::<f64>()
    };
    let target = dv.len() as f64 - 1.0;
    if dv.len() < 2 || q(0.0) <= target {
        return 0.0;
    }
    // Q falls as τ² grows: bracket, then bisect on a log scale
    let mut hi = dv
        .iter()
        .map(|p| p.0 * p.0 + p.1)
        .fold(0.0, f64::max)
        .max(1e-300);
    while q(hi) > target {
        hi *= 4.0;
    }
    let mut lo = hi * 1e-12;
    for _ in 0..80 {
        let mid = (lo * hi).sqrt();
        if q(mid) > target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo * hi).sqrt()
}

/// The mean lab position of a run's sliding (of its whole track when it never slides).
fn sliding_position(t: &super::response::Track) -> f64 {
    let sliding: Vec<f64> =
        t.z.iter()
            .zip(&t.phase)
            .filter(|p| *p.1 == crate::physics::Phase::Sliding)
            .map(|p| *p.0)
            .collect();
    let z = if sliding.is_empty() { &t.z } else { &sliding };
    z.iter().sum::<f64>() / z.len().max(1) as f64
}

/// The Legendre polynomial of degree `n` at `x`.
fn legendre(n: usize, x: f64) -> f64 {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return p0;
    }
    for k in 1..n {
        let p2 = ((2 * k + 1) as f64 * x * p1 - k as f64 * p0) / (k + 1) as f64;
        p0 = p1;
        p1 = p2;
    }
    p1
}

/// Energy of `y` in the run's slow shapes that its μ and T cannot make.
fn wander(b: &RunBasis, y: &[f64]) -> f64 {
    b.slow.iter().map(|s| dot(s, y).powi(2)).sum()
}

/// (LR, RES) of one projected residual `y` against the run's basis.
fn split(b: &RunBasis, y: &[f64]) -> (f64, f64, [f64; 2]) {
    let coords: Vec<f64> = b.q.iter().map(|q| dot(q, y)).collect();
    let lr: f64 = coords.iter().map(|c| c * c).sum();
    let mut coord = [0.0; 2];
    coord[..coords.len()].copy_from_slice(&coords);
    (lr, dot(y, y) - lr, coord)
}

/// Two-sided p-value of the least-squares slope of `y` on `x` against the scatter about the
/// line (Student's t with n − 2 degrees of freedom); 1 when it cannot be told (n < 4, no spread
/// of x).
fn slope_p(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len();
    if n < 4 {
        return 1.0;
    }
    let (mx, my) = (
        x.iter().sum::<f64>() / n as f64,
        y.iter().sum::<f64>() / n as f64,
    );
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    if !(sxx > 0.0) {
        return 1.0;
    }
    let b = x
        .iter()
        .zip(y)
        .map(|(a, c)| (a - mx) * (c - my))
        .sum::<f64>()
        / sxx;
    let rss: f64 = x
        .iter()
        .zip(y)
        .map(|(a, c)| (c - my - b * (a - mx)).powi(2))
        .sum();
    let se = (rss / (n - 2) as f64 / sxx).sqrt();
    if !(se > 0.0) {
        return if b == 0.0 { 1.0 } else { 0.0 };
    }
    use statrs::distribution::{ContinuousCDF, StudentsT};
    StudentsT::new(0.0, 1.0, (n - 2) as f64)
        .map(|t| 2.0 * (1.0 - t.cdf((b / se).abs())))
        .unwrap_or(1.0)
}

/// The check on the fitted model `m` of `runs` (`seed` for the replicates); None when there are
/// too few runs per material to tell a spread (fewer than 4).
pub fn check(
    m: &Model,
    runs: &[RunData],
    materials: &[String],
    alpha: f64,
    seed: u64,
) -> Option<Check> {
    let nm = m.spec.n_materials;
    if (0..nm).any(|k| runs.iter().filter(|r| r.material == k).count() < 4) {
        return None;
    }
    let prep = prepare(&m.spec, &m.params, &m.fit.global, &m.fit.local, runs);
    let bases: Vec<RunBasis> = prep
        .iter()
        .map(|p| {
            let k = runs[p.run].material;
            basis(p, k, nm + k)
        })
        .collect();
    // the data, then the replicates: (LR, RES) summed over runs
    let data: Vec<(f64, f64, [f64; 2])> = prep
        .iter()
        .zip(&bases)
        .map(|(p, b)| split(b, &p.y))
        .collect();
    // each run's own μ and T refitted in full: where the particles differ much, the first order
    // leaves part of what they take up in the residual, read as slow noise
    let nl = own_fits(m, runs, &prep);
    let n_res = |i: usize| match &nl[i] {
        Some((y, _)) => data[i].1.min(dot(y, y)),
        None => data[i].1,
    };
    let lr: f64 = (0..prep.len())
        .map(|i| dot(&prep[i].y, &prep[i].y) - n_res(i))
        .sum();
    let res: f64 = (0..prep.len()).map(n_res).sum();
    let wander_data: f64 = (0..prep.len())
        .map(|i| match &nl[i] {
            Some((y, _)) if dot(y, y) < data[i].1 => wander(&bases[i], y),
            _ => wander(&bases[i], &prep[i].y),
        })
        .sum();
    let reps: Vec<(f64, f64, Vec<[f64; 2]>, f64)> = (0..REPLICATES)
        .into_par_iter()
        .map(|b| {
            let mut rng =
                ChaCha8Rng::seed_from_u64(seed ^ (b as u64 + 1).wrapping_mul(0x9E37_79B9));
            let (mut l, mut r, mut w) = (0.0, 0.0, 0.0);
            let mut coords = Vec::with_capacity(prep.len());
            for (p, base) in prep.iter().zip(&bases) {
                let mut noise = runs[p.run].noise();
                noise.slow = noise.slow.cautious();
                let mut e = noise.replicate(p.y.len(), &mut rng);
                p.proj.apply(&mut e);
                let (a, c, coord) = split(base, &e);
                w += wander(base, &e);
                l += a;
                r += c;
                coords.push(coord);
            }
            (l, r, coords, w)
        })
        .collect();
    let n = REPLICATES as f64;
    let lr0 = reps.iter().map(|r| r.0).sum::<f64>() / n;
    let res0 = reps.iter().map(|r| r.1).sum::<f64>() / n;
    if !(lr0 > 0.0 && res0 > 0.0) {
        return None;
    }
    let ratio = |l: f64, r: f64| (l / lr0) / (r / res0).max(1e-12);
    let f = ratio(lr, res);
    let logs: Vec<f64> = reps.iter().map(|r| ratio(r.0, r.1).ln()).collect();
    let mean = logs.iter().sum::<f64>() / n;
    let sd = (logs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let z = (f.ln() - mean) / sd.max(1e-12);
    let p_value = 0.5 * statrs::function::erf::erfc(z / std::f64::consts::SQRT_2);
    let residual_ratio = res / res0;
    let wander0 = reps.iter().map(|r| r.3).sum::<f64>() / n;
    let wander_ratio = if wander0 > 0.0 {
        wander_data / wander0
    } else {
        1.0
    };
    let step = |base: &RunBasis, c: &[f64; 2]| -> [f64; 2] {
        [
            base.back[0][0] * c[0] + base.back[0][1] * c[1],
            base.back[1][0] * c[0] + base.back[1][1] * c[1],
        ]
    };
    // each run's step (δμ, δT) on the data: its own fit's where that fit went further than the
    // first order, else the first order's
    let steps: Vec<[f64; 2]> = (0..prep.len())
        .map(|i| match &nl[i] {
            Some((y, s)) if dot(y, y) < data[i].1 => *s,
            _ => step(&bases[i], &data[i].2),
        })
        .collect();
    // per material: the per-run steps (δμ, δT) on the data and their noise variance
    let spreads: Vec<Spread> = (0..nm)
        .map(|k| {
            let idx: Vec<usize> = (0..runs.len()).filter(|&i| runs[i].material == k).collect();
            // each run's step on the data and its noise variance over the replicates; the
            // spread is the weighted excess of the squared steps over their noise variances,
            // weights 1/v² (a slow run hardly knows its μ and counts little)
            let spread = |which: usize| -> (f64, f64) {
                let dv: Vec<(f64, f64)> = idx
                    .iter()
                    .map(|&i| {
                        let v = reps
                            .iter()
                            .map(|r| step(&bases[i], &r.2[i])[which].powi(2))
                            .sum::<f64>()
                            / n;
                        (steps[i][which], v)
                    })
                    .filter(|p| p.1 > 0.0)
                    .collect();
                let mut ses: Vec<f64> = dv.iter().map(|p| p.1.sqrt()).collect();
                ses.sort_by(f64::total_cmp);
                let typical = ses.get(ses.len() / 2).copied().unwrap_or(f64::NAN);
                (paule_mandel(&dv).sqrt(), typical)
            };
            let ((mu_sd, mu_se), (t_sd, t_se)) = (spread(0), spread(1));
            Spread {
                material: materials.get(k).cloned().unwrap_or_default(),
                n_runs: idx.len(),
                mu: m.fit.global[k],
                t_s: m.fit.global[nm + k],
                mu_sd,
                t_sd,
                mu_se,
                t_se,
            }
        })
        .collect();
    let drift_beyond_scatter = (0..nm).any(|k| {
        let idx: Vec<usize> = (0..runs.len()).filter(|&i| runs[i].material == k).collect();
        let v0: Vec<f64> = idx.iter().map(|&i| m.fit.local[i][2]).collect();
        (0..2).any(|which| {
            let y: Vec<f64> = idx.iter().map(|&i| steps[i][which]).collect();
            let speed: Vec<f64> = v0.iter().map(|v| v.abs()).collect();
            let dir: Vec<f64> = v0.iter().map(|v| v.signum()).collect();
            // Bonferroni over the four slopes (μ and T, on speed and on direction) of every material
            let level = alpha / (4 * nm) as f64;
            slope_p(&speed, &y) < level || slope_p(&dir, &y) < level
        })
    });
    // each run's steps in units of their noise error, against where the run slides
    let slide_z: Vec<f64> = prep.iter().map(|p| sliding_position(&p.track)).collect();
    let position_p = (0..nm)
        .flat_map(|k| [(k, 0), (k, 1)])
        .map(|(k, which)| {
            let (z, y): (Vec<f64>, Vec<f64>) = (0..runs.len())
                .filter(|&i| runs[i].material == k)
                .filter_map(|i| {
                    let v = reps
                        .iter()
                        .map(|r| step(&bases[i], &r.2[i])[which].powi(2))
                        .sum::<f64>()
                        / n;
                    (v > 0.0).then(|| (slide_z[i], steps[i][which] / v.sqrt()))
                })
                .unzip();
            super::position_order::p_value(&z, &y, seed ^ (2 * k + which) as u64)
        })
        .fold(1.0f64, f64::min)
        * (2 * nm) as f64;
    Some(Check {
        position_p: position_p.min(1.0),
        drift_beyond_scatter,
        lr,
        lr_null_mean: lr0,
        residual_ratio,
        wander_ratio,
        f,
        p_value,
        differ: p_value < alpha
            && f >= MIN_RATIO
            && residual_ratio <= RESIDUAL_SLACK
            && wander_ratio <= WANDER_LIMIT,
        spreads,
    })
}
