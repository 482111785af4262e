//! A run's tracking noise as every test's null draws it, in units of the run's measured σ: a
//! fast part (an AR(1) over kept samples beside a white part, both scaled sample by sample when
//! the noise grows with speed) plus the dataset's slow drift. The replicates of the screen, the
//! particle check and the time force's held-out charge are drawn from it, and the named terms'
//! computed laws use its covariance, so the two always agree.
//!
//! - The fast part is `(1 − w)` of an AR(1) of lag-1 correlation ρ and `w` of white noise
//!   (`noise.rs` measures both); `w = 0` is the plain AR(1).
//! - A speed-dependent σ (motion blur, `blur.rs`) multiplies the fast part by each kept sample's
//!   `scale` (an empty scale is 1 everywhere); the slow drift is the tracker's and is not scaled.
//! - The slow part is an AR(1) of variance κ and lag-1 correlation ρ_s (`slow_noise.rs`).
//!
//! A run whose noise has no white part, no scale and no slow part draws exactly the random
//! numbers that a plain AR(1) draws.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;

/// The largest |ρ| a replicate is drawn with (a noise this correlated is a trend).
const RHO_CAP: f64 = 0.99;

/// The fast part of a run's noise: the lag-1 correlation of its AR(1) and the white share of
/// its variance.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Fast {
    pub rho: f64,
    pub white: f64,
}

impl Fast {
    /// A plain AR(1) of lag-1 correlation ρ.
    pub fn ar1(rho: f64) -> Fast {
        Fast { rho, white: 0.0 }
    }

    fn rho(&self) -> f64 {
        self.rho.clamp(-RHO_CAP, RHO_CAP)
    }

    /// Its covariance at lag `k` (unit variance).
    pub fn at_lag(&self, k: usize) -> f64 {
        if k == 0 {
            1.0
        } else {
            (1.0 - self.white) * self.rho().powi(k as i32)
        }
    }
}

/// A dataset's slow noise: variance (in units of each run's σ²) and lag-1 correlation per
/// kept sample. κ = 0 is no slow noise.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Slow {
    pub kappa: f64,
    pub rho: f64,
    /// Runs left out of its estimate: their wander is beyond what a drift shared by the runs
    /// explains (`slow_noise::estimate`); they still carry it.
    pub left_out: usize,
    /// The band of frequencies (cycles per kept sample) left out of its estimate for a line no
    /// drift's spectrum has (`slow_noise::estimate`); (0, 0) when none.
    pub line: (f64, f64),
    /// (κ, ρ_s) at the long end of its 99 % confidence set, where the variance at the lowest
    /// frequencies (κτ) is largest; (0, 0) when none. Its probes have each run's fit's columns
    /// projected out, so what a run's own μ and T collect from the drift is read from the AR(1)'s
    /// shape, not seen: a test whose statistic lies in those columns alone (`particles.rs`)
    /// takes this end (`Slow::cautious`).
    pub upper: (f64, f64),
}

impl Slow {
    /// This noise at the long end of its confidence set (itself when that is not known).
    pub fn cautious(self) -> Slow {
        if self.upper.0 > 0.0 {
            Slow {
                kappa: self.upper.0,
                rho: self.upper.1,
                ..self
            }
        } else {
            self
        }
    }
}

/// One run's whole noise model (noise units).
#[derive(Clone, Copy, Debug)]
pub struct RunNoise<'a> {
    pub fast: Fast,
    pub slow: Slow,
    /// The fast part's σ at each kept sample over the run's σ; empty is 1 everywhere.
    pub scale: &'a [f64],
}

impl<'a> RunNoise<'a> {
    /// The scale over `n` samples, when it applies to them.
    fn scale_for(&self, n: usize) -> Option<&[f64]> {
        (self.scale.len() == n).then_some(self.scale)
    }

    /// The covariance of x'e and y'e for the fast part alone.
    pub fn fast_cross(&self, x: &[f64], y: &[f64]) -> f64 {
        let plain = |x: &[f64], y: &[f64]| {
            let ar = ar1_cross(x, y, self.fast.rho());
            if self.fast.white > 0.0 {
                (1.0 - self.fast.white) * ar
                    + self.fast.white * x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>()
            } else {
                ar
            }
        };
        match self.scale_for(x.len()) {
            Some(s) => {
                let xs: Vec<f64> = x.iter().zip(s).map(|(a, b)| a * b).collect();
                let ys: Vec<f64> = y.iter().zip(s).map(|(a, b)| a * b).collect();
                plain(&xs, &ys)
            }
            None => plain(x, y),
        }
    }

    /// The covariance of x'e and y'e for the whole noise model.
    pub fn cross(&self, x: &[f64], y: &[f64]) -> f64 {
        let fast = self.fast_cross(x, y);
        if self.slow.kappa > 0.0 {
            fast + self.slow.kappa * ar1_cross(x, y, self.slow.rho)
        } else {
            fast
        }
    }

    /// One replicate over `n` kept samples: the fast AR(1), then the slow AR(1) when there is
    /// one, then the white part when there is one (each drawn after the last, so a plain AR(1)
    /// draws the numbers it always drew).
    pub fn replicate(&self, n: usize, rng: &mut ChaCha8Rng) -> Vec<f64> {
        let w = self.fast.white.clamp(0.0, 1.0);
        let mut v = ar1(n, self.fast.rho(), (1.0 - w).sqrt(), rng);
        let slow =
            (self.slow.kappa > 0.0).then(|| ar1(n, self.slow.rho, self.slow.kappa.sqrt(), rng));
        if w > 0.0 {
            let sd = w.sqrt();
            v.iter_mut()
                .for_each(|a| *a += sd * rng.sample::<f64, _>(StandardNormal));
        }
        if let Some(s) = self.scale_for(n) {
            v.iter_mut().zip(s).for_each(|(a, b)| *a *= b);
        }
        if let Some(s) = slow {
            v.iter_mut().zip(s).for_each(|(a, b)| *a += b);
        }
        v
    }
}

/// Σᵢⱼ xᵢ yⱼ ρ^|i−j|: the covariance of x'e and y'e for unit-variance AR(1) noise e of lag-1
/// correlation ρ, in one pass (sₓ carries Σ_{j<i} xⱼ ρ^(i−1−j)).
pub fn ar1_cross(x: &[f64], y: &[f64], rho: f64) -> f64 {
    let (mut sx, mut sy, mut total) = (0.0, 0.0, 0.0);
    for (&xi, &yi) in x.iter().zip(y) {
        total += xi * yi + rho * (xi * sy + yi * sx);
        sx = xi + rho * sx;
        sy = yi + rho * sy;
    }
    total
}

/// Stationary AR(1) of lag-1 correlation ρ and standard deviation `sd`.
fn ar1(n: usize, rho: f64, sd: f64, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let rho = rho.clamp(-0.999_999, 0.999_999);
    let innov = (1.0 - rho * rho).sqrt();
    let mut e: f64 = rng.sample(StandardNormal);
    (0..n)
        .map(|_| {
            let x = sd * e;
            e = rho * e + innov * rng.sample::<f64, _>(StandardNormal);
            x
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn dot(a: &[f64], b: &[f64]) -> f64 {
        a.iter().zip(b).map(|(x, y)| x * y).sum()
    }

    #[test]
    fn the_ar1_covariance_in_one_pass_is_the_double_sum() {
        let x: Vec<f64> = (0..41).map(|i| (i as f64 * 0.37).sin()).collect();
        let y: Vec<f64> = (0..41).map(|i| 1.0 / (2.0 + i as f64)).collect();
        for rho in [0.0, 0.6, -0.3] {
            let mut plain = 0.0;
            for (i, xi) in x.iter().enumerate() {
                for (j, yj) in y.iter().enumerate() {
                    plain += xi * yj * f64::powi(rho, (i as i32 - j as i32).abs());
                }
            }
            let fast = ar1_cross(&x, &y, rho);
            assert!(
                (fast - plain).abs() < 1e-12 * (1.0 + plain.abs()),
                "ρ {rho}: {fast} {plain}"
            );
        }
    }

    /// The model's covariance against the replicates' over `b` draws, within 4 standard errors.
    fn agrees(noise: RunNoise, n: usize) {
        let x: Vec<f64> = (0..n).map(|i| (i as f64 / 17.0).sin()).collect();
        let y: Vec<f64> = (0..n).map(|i| 1.0 - i as f64 / n as f64).collect();
        let want = noise.cross(&x, &y);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let b = 20_000;
        let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
        for _ in 0..b {
            let e = noise.replicate(n, &mut rng);
            let (a, c) = (dot(&x, &e), dot(&y, &e));
            sxy += a * c;
            sxx += a * a;
            syy += c * c;
        }
        let got = sxy / b as f64;
        let se = (sxx * syy).sqrt() / b as f64 / (b as f64).sqrt() * 2.0;
        assert!(
            (got - want).abs() < 4.0 * se,
            "{noise:?}: {got} against {want} ± {se}"
        );
    }

    #[test]
    fn the_model_covariance_is_the_replicates_covariance() {
        let n = 120;
        let scale: Vec<f64> = (0..n).map(|i| 0.5 + 1.5 * i as f64 / n as f64).collect();
        let slow = Slow {
            kappa: 2.0,
            rho: 0.97,
            ..Slow::default()
        };
        for (fast, slow, scale) in [
            (Fast::ar1(0.4), slow, &[][..]),
            (
                Fast {
                    rho: 0.9,
                    white: 0.5,
                },
                Slow::default(),
                &[][..],
            ),
            (
                Fast {
                    rho: 0.6,
                    white: 0.3,
                },
                slow,
                &scale[..],
            ),
        ] {
            agrees(RunNoise { fast, slow, scale }, n);
        }
    }

    #[test]
    fn a_plain_ar1_draws_the_numbers_it_always_drew() {
        let noise = RunNoise {
            fast: Fast::ar1(0.3),
            slow: Slow::default(),
            scale: &[],
        };
        let a = noise.replicate(50, &mut ChaCha8Rng::seed_from_u64(3));
        let b = ar1(50, 0.3, 1.0, &mut ChaCha8Rng::seed_from_u64(3));
        assert_eq!(a, b);
    }
}
