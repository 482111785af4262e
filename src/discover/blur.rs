//! Tracking noise that grows with speed: a moving sphere's image is smeared over the exposure
//! (motion blur) and the tracker's error grows with the smear. Read as one σ per run, the noise
//! is overstated where the particle is slow and understated where it is fast, so a run's μ,
//! which acts only while the particle slides fast, collects more noise than its replicates give
//! it, and the particles seem to differ.
//!
//! The fast noise's variance at a kept sample is modelled as σ₀² + c² v², σ₀ each run's own and
//! c (a length per unit speed: the smear's share that the tracker keeps, times the exposure)
//! shared by the dataset's runs, one camera and one tracker. What the local cubic leaves of a
//! run's baseline residual (`noise::detrended`) has E[d_i²] = σ₀² Σ_a g_ia² + c² Σ_a g_ia² v_a²
//! under white noise, so c² is the dataset's least-squares slope of d² on the second sum with
//! each run's σ₀² profiled out, runs weighted by 1/σ⁴. Only the interior samples count: at a
//! run's ends the cubic's window is one-sided and leaves a correlated noise a different share,
//! which the speed (highest at the start) would otherwise take for blur. The slope's error is
//! read from sums over blocks of the window's length (d is correlated within a window), and c
//! is kept only when the slope lies `Z_KEEP` errors above zero. Each run then carries the scale
//! √(σ₀² + c² v²) at each kept sample over its root mean square over the run (`noise_model.rs`),
//! v its baseline fit's speed there: the run's σ measures that mean whatever the noise's shape.

use super::data::RunData;
use super::noise::{detrended, HALF};
use super::response::dot;

/// Standard errors the slope must lie above zero for the blur to be kept.
const Z_KEEP: f64 = 4.0;
/// Samples per block of the slope's error.
const BLOCK: usize = 2 * HALF + 1;
/// The smallest variance a sample is given, as a share of the run's mean.
const FLOOR: f64 = 0.05;

/// The dataset's speed-dependent noise: c (m per m/s) and the slope's z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blur {
    pub gain_s: f64,
    pub z: f64,
}

/// One run's interior samples: d², the two energy sums, the speed² at every kept sample and
/// the run's weight.
struct Series {
    d2: Vec<f64>,
    gamma: Vec<f64>,
    h: Vec<f64>,
    v2: Vec<f64>,
    w: f64,
}

impl Series {
    /// h with γ projected out.
    fn h_tilde(&self) -> Vec<f64> {
        let k = dot(&self.gamma, &self.h) / dot(&self.gamma, &self.gamma);
        self.h
            .iter()
            .zip(&self.gamma)
            .map(|(h, g)| h - k * g)
            .collect()
    }

    /// σ₀² given the slope c².
    fn base(&self, c2: f64) -> f64 {
        let g = &self.gamma;
        (dot(g, &self.d2) - c2 * dot(g, &self.h)) / dot(g, g)
    }
}

/// Speeds at the kept samples from the fitted positions there (central differences).
fn speeds(t: &[f64], z: &[f64]) -> Vec<f64> {
    let n = t.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let dt = t[b] - t[a];
            if dt > 0.0 {
                ((z[b] - z[a]) / dt).abs()
            } else {
                0.0
            }
        })
        .collect()
}

/// One run's series from its baseline residual `res` (all samples).
fn series(run: &RunData, res: &[f64]) -> Option<Series> {
    let kept = |v: &[f64]| -> Vec<f64> {
        v.iter()
            .zip(&run.keep)
            .filter(|p| *p.1)
            .map(|p| *p.0)
            .collect()
    };
    let (t, r) = (kept(&run.t_s), kept(res));
    let fitted: Vec<f64> = kept(&run.z_m).iter().zip(&r).map(|(z, e)| z - e).collect();
    let v2: Vec<f64> = speeds(&t, &fitted).iter().map(|v| v * v).collect();
    let [d, gamma, h] = detrended(&t, &r, &v2)?;
    let n = t.len();
    if n <= 2 * HALF + BLOCK {
        return None;
    }
    let inner = HALF..n - HALF;
    Some(Series {
        d2: d[inner.clone()].iter().map(|x| x * x).collect(),
        gamma: gamma[inner.clone()].to_vec(),
        h: h[inner].to_vec(),
        v2,
        w: run.sigma_m.powi(-4),
    })
}

/// The slope c² over the runs' series and its z.
fn slope(all: &[&Series]) -> Option<(f64, f64)> {
    let tilde: Vec<Vec<f64>> = all.iter().map(|s| s.h_tilde()).collect();
    let (mut num, mut den) = (0.0, 0.0);
    for (s, t) in all.iter().zip(&tilde) {
        num += s.w * dot(t, &s.d2);
        den += s.w * dot(t, t);
    }
    if !(den > 0.0) {
        return None;
    }
    let c2 = num / den;
    // the score's variance from block sums
    let mut var = 0.0;
    for (s, t) in all.iter().zip(&tilde) {
        let a = s.base(c2);
        let u: Vec<f64> = (0..s.d2.len())
            .map(|i| s.w * t[i] * (s.d2[i] - a * s.gamma[i] - c2 * s.h[i]))
            .collect();
        var += u
            .chunks(BLOCK)
            .map(|b| b.iter().sum::<f64>().powi(2))
            .sum::<f64>();
    }
    let se = var.sqrt() / den;
    (se > 0.0).then(|| (c2, c2 / se))
}

/// Each sample's noise σ over the root mean square of the track's, from the samples' variances.
pub fn relative(var: &[f64]) -> Vec<f64> {
    let mean = var.iter().sum::<f64>() / var.len().max(1) as f64;
    var.iter().map(|v| (v / mean).sqrt()).collect()
}

/// Measure the dataset's blur from the runs' baseline residuals `res` and give each run its
/// scale by kept sample; None (and every scale left empty) when no blur is seen.
pub fn measure(runs: &mut [RunData], res: &[Vec<f64>]) -> Option<Blur> {
    let all: Vec<Option<Series>> = runs.iter().zip(res).map(|(r, e)| series(r, e)).collect();
    let used: Vec<&Series> = all.iter().flatten().collect();
    let (c2, z) = slope(&used)?;
    if !(c2 > 0.0 && z > Z_KEEP) {
        return None;
    }
    for (run, s) in runs.iter_mut().zip(&all) {
        let Some(s) = s else { continue };
        // σ₀² and c² are in the white noise's units; the scale is their ratio to the run's
        // mean over its kept samples, which the run's σ measures whatever the noise's shape
        let var: Vec<f64> = s.v2.iter().map(|v2| s.base(c2) + c2 * v2).collect();
        let floor = FLOOR * var.iter().sum::<f64>() / var.len() as f64;
        let var: Vec<f64> = var.iter().map(|v| v.max(floor)).collect();
        run.scale = relative(&var);
    }
    Some(Blur {
        gain_s: c2.sqrt(),
        z,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    /// `n_runs` runs of 500 samples at 10 kHz decelerating from 0.3–0.6 m/s, each with noise of
    /// variance σ₀² + c² v² (white) or a homoscedastic AR(1) of correlation `rho` when c = 0;
    /// the residuals are the noise itself (a perfect baseline).
    fn dataset(n_runs: usize, c: f64, rho: f64, seed: u64) -> (Vec<RunData>, Vec<Vec<f64>>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (s0, n) = (1e-6, 500);
        (0..n_runs)
            .map(|k| {
                let v0 = 0.3 + 0.3 * k as f64 / n_runs as f64;
                let t: Vec<f64> = (0..n).map(|i| i as f64 * 1e-4).collect();
                let z: Vec<f64> = t
                    .iter()
                    .map(|t| v0 * 0.02 * (1.0 - (-t / 0.02).exp()))
                    .collect();
                let mut ar = 0.0;
                let e: Vec<f64> = t
                    .iter()
                    .map(|t| {
                        let v = v0 * (-t / 0.02).exp();
                        let g: f64 = StandardNormal.sample(&mut rng);
                        ar = rho * ar + (1.0 - rho * rho).sqrt() * g;
                        if c > 0.0 {
                            (s0 * s0 + c * c * v * v).sqrt() * g
                        } else {
                            s0 * ar
                        }
                    })
                    .collect();
                let ms = e.iter().map(|x| x * x).sum::<f64>() / n as f64;
                let run = RunData {
                    run: format!("r{k}"),
                    material: 0,
                    fps: 1e4,
                    z_m: z.iter().zip(&e).map(|(a, b)| a + b).collect(),
                    keep: vec![true; n],
                    t_s: t,
                    sigma_m: ms.sqrt(),
                    fast: Default::default(),
                    scale: Vec::new(),
                    slow: Default::default(),
                };
                (run, e)
            })
            .unzip()
    }

    #[test]
    fn a_noise_growing_with_speed_is_measured() {
        // c = 5 µs: 2.5 µm of blur at 0.5 m/s beside 1 µm at rest
        for seed in 0..5 {
            let (mut runs, res) = dataset(24, 5e-6, 0.0, seed);
            let b = measure(&mut runs, &res).expect("the blur is seen");
            assert!(
                (b.gain_s / 5e-6 - 1.0).abs() < 0.15,
                "seed {seed}: c {:.3e} s (z {:.1})",
                b.gain_s,
                b.z
            );
            // the scale follows the speed: large at the start, small at the end
            let s = &runs[0].scale;
            assert!(
                s[0] > 1.3 && s[s.len() - 1] < 1.0,
                "scale {} … {}",
                s[0],
                s[s.len() - 1]
            );
        }
    }

    #[test]
    fn a_correlated_noise_of_constant_size_is_no_blur() {
        let seen = (0..20)
            .filter(|&seed| {
                let (mut runs, res) = dataset(24, 0.0, 0.7, 100 + seed);
                let b = measure(&mut runs, &res);
                assert_eq!(b.is_none(), runs.iter().all(|r| r.scale.is_empty()));
                b.is_some()
            })
            .count();
        assert_eq!(seen, 0, "{seen} of 20 homoscedastic datasets read a blur");
    }
}
