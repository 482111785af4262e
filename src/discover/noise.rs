//! A run's camera noise (σ and the shape of its fast part) and its tracking outliers, measured
//! from what a sliding local cubic leaves of the run's baseline residuals, so that a misfit of
//! the baseline that is slow next to the frame rate (a run that comes to rest, a slow force) is
//! not read as noise.
//!
//! The local cubic is a linear filter: each detrended residual is d_i = Σ_a g_ia e_a over the
//! samples of its window. Under AR(1) noise of scale σ and lag-1 correlation ρ (over consecutive
//! kept samples) E[Σ d_i d_{i+k}] are σ² times polynomials in ρ whose coefficients come from the
//! filter rows, so the moments are matched exactly: the cubic's share of the noise, the shorter
//! windows' at the ends and a correlated noise's share in the trend are all taken into account
//! rather than guessed.
//!
//! Lags 0 and 1 give the plain AR(1). A sub-pixel tracker often makes a white part beside a
//! correlated one (a share w of white noise, 1 − w of an AR(1) of larger ρ), which the plain
//! AR(1) of the same lag-1 correlation describes too flatly: it gives the slow shapes of a fit
//! (a run's μ and T) several times too little noise. Lag 2 tells the two apart: the white-plus-
//! AR(1) reading matches lags 0, 1 and 2, and `lag2_z` says how far lag 2 lies above what the
//! plain AR(1) gives it. One run cannot tell a small white part; the dataset's runs (one tracker)
//! decide together (`mixed_wanted`), and each then takes its own white-plus-AR(1) reading.

use super::noise_model::Fast;
use crate::lsq::dense::{chol_solve, cholesky_jittered};

/// Samples on each side of the one being detrended (the window holds 2·HALF + 1 samples).
pub const HALF: usize = 20;
/// Polynomial coefficients of the local fit (a cubic).
const COEFFS: usize = 4;
/// The cap on ρ (a noise this correlated is not told apart from a trend).
pub const RHO_MAX: f64 = 0.95;
/// Tracking outliers: farther than this many robust σ from the local cubic.
const OUTLIER_SIGMAS: f64 = 5.0;
/// Below this many kept samples the local cubic leaves too little to measure.
const MIN_SAMPLES: usize = 12;

/// Student's t the runs' lag-2 excesses must reach together for the white-plus-AR(1) reading to
/// be taken (each run's excess in its Bartlett errors; their scatter from run to run, not
/// Bartlett's, is the mean's error, since a detrended series is not quite an AR(1)).
const MIXED_T: f64 = 4.0;

/// What one run's noise measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Noise {
    /// The plain AR(1) reading.
    pub sigma_m: f64,
    pub fast: Fast,
    /// The white-plus-AR(1) reading (σ and shape), when lags 0–2 admit one.
    pub mixed: Option<(f64, Fast)>,
    /// Lag 2 of the detrended residual above what the plain AR(1) gives it, in standard errors
    /// (0 where not measured).
    pub lag2_z: f64,
}

impl Noise {
    fn plain(sigma_m: f64, rho: f64) -> Noise {
        Noise {
            sigma_m,
            fast: Fast::ar1(rho),
            mixed: None,
            lag2_z: 0.0,
        }
    }

    /// σ and shape as taken: the white-plus-AR(1) reading where the dataset wants it.
    pub fn taken(&self, mixed: bool) -> (f64, Fast) {
        match (mixed, self.mixed) {
            (true, Some(m)) => m,
            _ => (self.sigma_m, self.fast),
        }
    }
}

/// Whether the dataset's runs, together, ask for a white part beside the correlated one.
pub fn mixed_wanted(noises: &[Noise]) -> bool {
    let z: Vec<f64> = noises.iter().map(|m| m.lag2_z).collect();
    let n = z.len() as f64;
    if z.len() < 4 {
        return false;
    }
    let mean = z.iter().sum::<f64>() / n;
    let sd = (z.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    mean / (sd / n.sqrt()).max(1e-12) > MIXED_T
}

/// The windows' filter rows over a series: for sample i, its window's first index and the weights
/// g_i (the sample minus its local cubic's value there).
struct Filter {
    lo: Vec<usize>,
    g: Vec<Vec<f64>>,
}

/// Samples in a window of a series of `n`.
fn window_len(n: usize) -> usize {
    (2 * HALF + 1).min(n)
}

/// The window of sample `i` among `n`: `w` samples, centred where the ends allow.
fn window(i: usize, n: usize, w: usize) -> usize {
    i.saturating_sub(w / 2).min(n - w)
}

/// The local cubic through the `w` samples of `t` around position `p`, as weights over
/// `t[lo..lo + w]` that give its value at `tq`; `None` if those times cannot carry a cubic.
fn cubic_weights(t: &[f64], p: usize, tq: f64) -> (usize, Option<Vec<f64>>) {
    let n = t.len();
    let w = window_len(n);
    let l = window(p, n, w);
    let ts = &t[l..l + w];
    let span = (ts[w - 1] - ts[0]).max(1e-300) / 2.0;
    let basis = |tj: f64| {
        let u = (tj - tq) / span;
        [1.0, u, u * u, u * u * u]
    };
    let mut m = [0.0; COEFFS * COEFFS];
    for &tj in ts {
        let p = basis(tj);
        for a in 0..COEFFS {
            for b in 0..COEFFS {
                m[a * COEFFS + b] += p[a] * p[b];
            }
        }
    }
    // the value at tq is the intercept: weights φ_jᵀ M⁻¹ e₁
    let Some(ch) = cholesky_jittered(&m, COEFFS) else {
        return (l, None);
    };
    let mut c = [1.0, 0.0, 0.0, 0.0];
    chol_solve(&ch, COEFFS, &mut c);
    let wts = ts
        .iter()
        .map(|&tj| {
            let p = basis(tj);
            (0..COEFFS).map(|a| p[a] * c[a]).sum()
        })
        .collect();
    (l, Some(wts))
}

/// The local cubic's filter over a series: row i of (I − S), S the smoother of `t`.
fn filter(t: &[f64]) -> Filter {
    let (lo, g) = (0..t.len())
        .map(|i| {
            let (l, wts) = cubic_weights(t, i, t[i]);
            let row = match wts {
                Some(wts) => wts
                    .iter()
                    .enumerate()
                    .map(|(j, x)| f64::from(u8::from(l + j == i)) - x)
                    .collect(),
                None => vec![0.0; window_len(t.len())],
            };
            (l, row)
        })
        .unzip();
    Filter { lo, g }
}

/// Each sample's distance from the local cubic of the kept samples around it (a kept sample's
/// window holds itself, a flagged one's does not).
fn distances(t: &[f64], res: &[f64], keep: &[bool]) -> Vec<f64> {
    let (tk, rk): (Vec<f64>, Vec<f64>) = t
        .iter()
        .zip(res)
        .zip(keep)
        .filter(|p| *p.1)
        .map(|p| p.0)
        .unzip();
    let mut p = 0;
    t.iter()
        .zip(res)
        .zip(keep)
        .map(|((&ti, &ri), &k)| {
            let (l, wts) = cubic_weights(&tk, p, ti);
            p += usize::from(k);
            wts.map_or(ri, |w| {
                ri - w.iter().zip(&rk[l..]).map(|(a, b)| a * b).sum::<f64>()
            })
        })
        .collect()
}

impl Filter {
    fn apply(&self, e: &[f64]) -> Vec<f64> {
        self.g
            .iter()
            .zip(&self.lo)
            .map(|(g, &l)| g.iter().zip(&e[l..]).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// Coefficients by lag d of E[Σ d_i d_{i+k}] / σ² = Σ_d c_k[d] ρ^d, for k = 0, 1, 2.
    fn moment_coefficients(&self) -> [Vec<f64>; 3] {
        let w = self.g.first().map_or(0, Vec::len);
        let mut c: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; w + 3]);
        for (i, (g, &l)) in self.g.iter().zip(&self.lo).enumerate() {
            for (k, ck) in c.iter_mut().enumerate() {
                let (Some(h), Some(&lh)) = (self.g.get(i + k), self.lo.get(i + k)) else {
                    continue;
                };
                for (a, ga) in g.iter().enumerate() {
                    for (b, hb) in h.iter().enumerate() {
                        ck[(l + a).abs_diff(lh + b)] += ga * hb;
                    }
                }
            }
        }
        c
    }
}

fn poly(c: &[f64], rho: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, ci| acc * rho + ci)
}

/// σ and ρ of AR(1) noise whose filtered values are `d`, by matching Σ d² and Σ d_i d_{i+1};
/// then the white-plus-AR(1) reading that matches Σ d_i d_{i+2} as well.
fn match_moments(f: &Filter, d: &[f64]) -> Noise {
    let a0: f64 = d.iter().map(|x| x * x).sum();
    let a1: f64 = d.windows(2).map(|p| p[0] * p[1]).sum();
    let a2: f64 = d.windows(3).map(|p| p[0] * p[2]).sum();
    let [c0, c1, c2] = f.moment_coefficients();
    let ratio = |rho: f64| poly(&c1, rho) / poly(&c0, rho);
    let target = a1 / a0.max(1e-300);
    // the ratio rises with ρ: bisect within [0, RHO_MAX], the ends taken as they are (and
    // nothing left, a model through every sample, has no correlation to read)
    let rho = if a0 <= 0.0 || target <= ratio(0.0) {
        0.0
    } else if target >= ratio(RHO_MAX) {
        RHO_MAX
    } else {
        let (mut lo, mut hi) = (0.0, RHO_MAX);
        for _ in 0..50 {
            let mid = 0.5 * (lo + hi);
            if ratio(mid) < target {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    };
    let plain = Noise::plain((a0 / poly(&c0, rho).max(1e-300)).sqrt().max(1e-12), rho);
    if !(a0 > 0.0) {
        return plain;
    }
    let (r1, r2) = (a1 / a0, a2 / a0);
    // lag 2's excess over the plain AR(1), against its sampling error (Bartlett's for an AR(1))
    let n = d.len() as f64;
    let se = ((1.0 + 2.0 * rho * rho - 3.0 * rho.powi(4)).max(0.1) / n).sqrt();
    let lag2_z = (r2 - poly(&c2, rho) / poly(&c0, rho)) / se;
    // white share w beside an AR(1) of correlation ρ' ≥ ρ keeping lag 1 matched; ρ' then
    // matches lag 2 as nearly as it can
    let at = |c: &[f64], w: f64, r: f64| w * c[0] + (1.0 - w) * poly(c, r);
    let share = |r: f64| {
        let den = c1[0] - poly(&c1, r) - r1 * (c0[0] - poly(&c0, r));
        let w = (r1 * poly(&c0, r) - poly(&c1, r)) / den;
        (den.abs() > 1e-300 && (0.0..1.0).contains(&w)).then_some(w)
    };
    let mismatch = |r: f64| share(r).map(|w| (at(&c2, w, r) / at(&c0, w, r) - r2).abs());
    let steps = 400;
    let best = (0..=steps)
        .map(|i| rho + (RHO_MAX - rho) * i as f64 / steps as f64)
        .filter_map(|r| mismatch(r).map(|m| (r, m)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    let mixed = best.and_then(|(r, _)| {
        let w = share(r)?;
        let s = (a0 / at(&c0, w, r).max(1e-300)).sqrt().max(1e-12);
        Some((s, Fast { rho: r, white: w }))
    });
    Noise {
        mixed,
        lag2_z,
        ..plain
    }
}

/// The plain reading for a series too short to detrend: rms about the fit, lag-1 of what is left.
fn short_series(res: &[f64], keep: &mut [bool]) -> Noise {
    let scale = crate::stats::abs_scale(res).max(1e-12);
    for (k, r) in keep.iter_mut().zip(res) {
        *k = r.abs() <= OUTLIER_SIGMAS * scale;
    }
    let kept: Vec<f64> = res
        .iter()
        .zip(&*keep)
        .filter(|p| *p.1)
        .map(|p| *p.0)
        .collect();
    let dof = (kept.len() as f64 - 5.0).max(1.0);
    Noise::plain(
        (kept.iter().map(|r| r * r).sum::<f64>() / dof)
            .sqrt()
            .max(1e-12),
        super::residual_structure::lag1_autocorrelation(&kept).clamp(0.0, RHO_MAX),
    )
}

/// What the local cubic leaves of `y` at times `t` (kept samples), and for each sample
/// Σ_a g_ia² and Σ_a g_ia² x_a: the variance it leaves there of unit white noise, and of white
/// noise whose variance at sample a is x_a. None for a series too short to detrend.
pub fn detrended(t: &[f64], y: &[f64], x: &[f64]) -> Option<[Vec<f64>; 3]> {
    if t.len() < MIN_SAMPLES {
        return None;
    }
    let f = filter(t);
    let d = f.apply(y);
    let (gamma, h) =
        f.g.iter()
            .zip(&f.lo)
            .map(|(g, &l)| {
                g.iter().zip(&x[l..]).fold((0.0, 0.0), |(a, b), (gi, xi)| {
                    (a + gi * gi, b + gi * gi * xi)
                })
            })
            .unzip();
    Some([d, gamma, h])
}

/// Measure a run's noise from its baseline residuals `res` at times `t`, flagging as outliers
/// (`keep` false) the samples farther than 5 robust σ from the local cubic of the kept samples
/// around them. The moments are then taken over the kept samples, detrended among themselves.
pub fn measure(t: &[f64], res: &[f64], keep: &mut [bool]) -> Noise {
    if t.len() < MIN_SAMPLES {
        return short_series(res, keep);
    }
    // twice: an outlier drags the cubic near the ends, so its neighbours are judged again
    // against the cubic of what the first look kept
    keep.fill(true);
    for _ in 0..2 {
        if keep.iter().filter(|k| **k).count() < MIN_SAMPLES {
            keep.fill(true);
            return short_series(res, keep);
        }
        let d = distances(t, res, keep);
        let scale = crate::stats::abs_scale(&d).max(1e-12);
        for (k, x) in keep.iter_mut().zip(&d) {
            *k = x.abs() <= OUTLIER_SIGMAS * scale;
        }
    }
    let (tk, rk): (Vec<f64>, Vec<f64>) = t
        .iter()
        .zip(res)
        .zip(&*keep)
        .filter(|p| *p.1)
        .map(|p| p.0)
        .unzip();
    if tk.len() < MIN_SAMPLES {
        return short_series(res, keep);
    }
    let f = filter(&tk);
    let d = f.apply(&rk);
    match_moments(&f, &d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// AR(1) noise of scale σ and lag-1 correlation ρ (stationary from the first sample).
    fn ar1(n: usize, sigma: f64, rho: f64, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut e = Vec::with_capacity(n);
        let mut x: f64 = StandardNormal.sample(&mut rng);
        for _ in 0..n {
            e.push(sigma * x);
            let z: f64 = StandardNormal.sample(&mut rng);
            x = rho * x + (1.0 - rho * rho).sqrt() * z;
        }
        e
    }

    /// A slow misfit far above the noise: what the exponential baseline leaves of a run that
    /// comes to rest at 0.12 s (there the acceleration jumps by c·g ≈ 0.03 m/s²), plus a 30 Hz
    /// oscillation of 2 µm.
    fn misfit(t: f64) -> f64 {
        let after = (t - 0.12f64).max(0.0);
        20e-6 * (-t / 0.05f64).exp()
            + 0.5 * 0.03 * after * after
            + 2e-6 * (2.0 * std::f64::consts::PI * 30.0 * t).sin()
    }

    #[test]
    fn sigma_and_rho_of_ar1_noise_are_recovered_beside_a_slow_misfit() {
        let n = 2500;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-4).collect();
        for (rho, seed) in [(0.0, 1), (0.3, 2), (0.6, 3)] {
            let mut sig = Vec::new();
            let mut rhos = Vec::new();
            for rep in 0..20 {
                let e = ar1(n, 1e-6, rho, seed * 100 + rep);
                let res: Vec<f64> = t.iter().zip(&e).map(|(t, e)| misfit(*t) + e).collect();
                let mut keep = vec![true; n];
                let m = measure(&t, &res, &mut keep);
                assert!(
                    keep.iter().all(|k| *k),
                    "gaussian noise has no 5σ outliers here"
                );
                sig.push(m.sigma_m);
                rhos.push(m.fast.rho);
            }
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            // one run of 2,500 samples measures σ to about 2 % and ρ to about 0.03 at ρ = 0.6
            assert!(
                (mean(&sig) / 1e-6 - 1.0).abs() < 0.03,
                "ρ {rho}: mean σ {:.4} µm",
                mean(&sig) * 1e6
            );
            assert!(
                (mean(&rhos) - rho).abs() < 0.03,
                "ρ {rho}: mean ρ̂ {:.4}",
                mean(&rhos)
            );
            for s in &sig {
                assert!((s / 1e-6 - 1.0).abs() < 0.1, "one run's σ {s:e}");
            }
        }
    }

    /// A share `w` of white noise beside an AR(1) of correlation ρ, of total scale σ.
    fn mixture(n: usize, sigma: f64, rho: f64, w: f64, seed: u64) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5151);
        ar1(n, sigma * (1.0 - w).sqrt(), rho, seed)
            .into_iter()
            .map(|a| {
                let z: f64 = StandardNormal.sample(&mut rng);
                a + sigma * w.sqrt() * z
            })
            .collect()
    }

    #[test]
    fn a_white_part_beside_a_correlated_one_is_read_from_lag_two() {
        // half white, half AR(0.9): the plain AR(1) of the same lag-1 correlation (about 0.45)
        // gives the slowest shapes a quarter of the noise they carry
        let n = 2500;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-4).collect();
        let noises: Vec<Noise> = (0..20)
            .map(|rep| {
                let e = mixture(n, 1e-6, 0.9, 0.5, 300 + rep);
                let res: Vec<f64> = t.iter().zip(&e).map(|(t, e)| misfit(*t) + e).collect();
                measure(&t, &res, &mut vec![true; n])
            })
            .collect();
        assert!(mixed_wanted(&noises));
        let taken: Vec<(f64, Fast)> = noises.iter().map(|m| m.taken(true)).collect();
        let mean = |f: &dyn Fn(&(f64, Fast)) -> f64| taken.iter().map(f).sum::<f64>() / 20.0;
        let (s, w, r) = (mean(&|m| m.0), mean(&|m| m.1.white), mean(&|m| m.1.rho));
        eprintln!("σ {s:e}, white share {w}, ρ {r}");
        assert!((s / 1e-6 - 1.0).abs() < 0.08, "σ {s:e}");
        assert!((w - 0.5).abs() < 0.1, "white share {w}");
        assert!((r - 0.9).abs() < 0.05, "ρ {r}");
    }

    #[test]
    fn a_plain_ar1_or_white_noise_wants_no_white_part() {
        let n = 500;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-4).collect();
        for rho in [0.0, 0.6, 0.9] {
            let wanted = (0..20)
                .filter(|&d| {
                    let noises: Vec<Noise> = (0..24)
                        .map(|k| {
                            let e = ar1(n, 1e-6, rho, 1000 * d + k);
                            let res: Vec<f64> =
                                t.iter().zip(&e).map(|(t, e)| misfit(*t) + e).collect();
                            measure(&t, &res, &mut vec![true; n])
                        })
                        .collect();
                    mixed_wanted(&noises)
                })
                .count();
            assert!(
                wanted <= 1,
                "ρ {rho}: {wanted} of 20 datasets wanted a white part"
            );
        }
    }

    #[test]
    fn the_plain_residual_rms_reads_the_same_misfit_as_noise() {
        // the reading this module replaces, on the same series: the misfit dominates it
        let n = 2500;
        let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-4).collect();
        let e = ar1(n, 1e-6, 0.0, 9);
        let res: Vec<f64> = t.iter().zip(&e).map(|(t, e)| misfit(*t) + e).collect();
        let rms = (res.iter().map(|r| r * r).sum::<f64>() / n as f64).sqrt();
        assert!(rms > 3e-6, "rms {rms:e}");
        let mut keep = vec![true; n];
        let m = measure(&t, &res, &mut keep);
        assert!((m.sigma_m / 1e-6 - 1.0).abs() < 0.1, "σ {:e}", m.sigma_m);
    }

    #[test]
    fn outliers_are_flagged_and_left_out_of_the_noise() {
        let n = 1500;
        // uneven times: dropped frames leave gaps
        let t: Vec<f64> = (0..n).map(|i| (i + i / 97) as f64 * 2e-4).collect();
        let mut res: Vec<f64> = t
            .iter()
            .zip(ar1(n, 1e-6, 0.2, 4))
            .map(|(t, e)| misfit(*t) + e)
            .collect();
        let bad = [0, 3, 400, 401, 777, n - 1];
        for (k, &i) in bad.iter().enumerate() {
            res[i] += if k % 2 == 0 { 30e-6 } else { -25e-6 };
        }
        let mut keep = vec![true; n];
        let m = measure(&t, &res, &mut keep);
        let flagged: Vec<usize> = (0..n).filter(|i| !keep[*i]).collect();
        assert_eq!(flagged, bad);
        assert!((m.sigma_m / 1e-6 - 1.0).abs() < 0.1, "σ {:e}", m.sigma_m);
        assert!((m.fast.rho - 0.2).abs() < 0.1, "ρ {}", m.fast.rho);
    }

    #[test]
    fn residuals_that_are_all_zero_read_as_the_floor_without_a_correlation() {
        let t: Vec<f64> = (0..200).map(|i| i as f64 * 1e-4).collect();
        let mut keep = vec![true; 200];
        let m = measure(&t, &[0.0; 200], &mut keep);
        assert_eq!(m, Noise::plain(1e-12, 0.0));
        assert!(keep.iter().all(|k| *k));
    }

    #[test]
    fn a_short_series_is_read_plainly() {
        let t: Vec<f64> = (0..8).map(|i| i as f64).collect();
        let res = [1e-6, -1e-6, 1e-6, -1e-6, 1e-6, -1e-6, 1e-6, 50e-6];
        let mut keep = vec![true; 8];
        let m = measure(&t, &res, &mut keep);
        assert!(!keep[7] && keep[..7].iter().all(|k| *k));
        assert_eq!(m.fast.rho, 0.0);
        assert!((m.sigma_m - (7e-12f64 / 2.0).sqrt()).abs() < 1e-15);
    }
}
