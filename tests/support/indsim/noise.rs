//! Tracker noise as trackers make it: white, correlated over frames (AR(1) and slow drifts),
//! growing with speed (motion blur), locked to and quantized on a sub-pixel grid, with outliers,
//! and mixtures of these.

use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// One noise model; the components add (white, AR(1), drift, blur), then the position is pulled
/// towards pixel centres and rounded to the sub-pixel grid, then outliers replace a few frames.
#[derive(Clone, Debug, Default)]
pub struct Noise {
    /// Name of the model in the bench's tables.
    pub label: String,
    /// White noise standard deviation (m).
    pub white_m: f64,
    /// AR(1) over frames: (marginal standard deviation m, coefficient).
    pub ar1: Option<(f64, f64)>,
    /// A slow drift (Ornstein–Uhlenbeck): (standard deviation m, time constant s).
    pub drift: Option<(f64, f64)>,
    /// Motion blur: white noise whose standard deviation grows as σ |v| / v_ref: (σ m, v_ref m/s).
    pub blur: Option<(f64, f64)>,
    /// Pixel locking: (pixel m, strength β in [0, 1), grid m): z − β p/(2π) sin(2π z/p), rounded.
    pub lock: Option<(f64, f64, f64)>,
    /// Outliers: (rate per frame, size m).
    pub outliers: Option<(f64, f64)>,
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

impl Noise {
    /// The standard deviation of one frame's error at rest (m), outliers aside.
    pub fn sigma_m(&self) -> f64 {
        let mut var = self.white_m * self.white_m;
        if let Some((s, _)) = self.ar1 {
            var += s * s;
        }
        if let Some((s, _)) = self.drift {
            var += s * s;
        }
        if let Some((_, _, grid)) = self.lock {
            var += grid * grid / 12.0;
        }
        var.sqrt()
    }

    /// The measured positions of one track: `z` and `v` at consecutive frames `fps` apart.
    pub fn apply(&self, z: &[f64], v: &[f64], fps: f64, rng: &mut ChaCha8Rng) -> Vec<f64> {
        let n = z.len();
        let mut out = Vec::with_capacity(n);
        let mut ar = 0.0;
        let mut dr = 0.0;
        if let Some((s, _)) = self.ar1 {
            ar = s * normal(rng);
        }
        if let Some((s, _)) = self.drift {
            dr = s * normal(rng);
        }
        for i in 0..n {
            let mut e = self.white_m * normal(rng);
            if let Some((s, phi)) = self.ar1 {
                if i > 0 {
                    ar = phi * ar + s * (1.0 - phi * phi).sqrt() * normal(rng);
                }
                e += ar;
            }
            if let Some((s, tau)) = self.drift {
                let phi = (-1.0 / (fps * tau)).exp();
                if i > 0 {
                    dr = phi * dr + s * (1.0 - phi * phi).sqrt() * normal(rng);
                }
                e += dr;
            }
            if let Some((s, v_ref)) = self.blur {
                e += s * v[i].abs() / v_ref * normal(rng);
            }
            let mut y = z[i] + e;
            if let Some((p, beta, grid)) = self.lock {
                y -= beta * p / std::f64::consts::TAU * (std::f64::consts::TAU * y / p).sin();
                y = (y / grid).round() * grid;
            }
            if let Some((rate, size)) = self.outliers {
                if rng.random::<f64>() < rate {
                    y = z[i]
                        + size
                            * if rng.random::<bool>() { 1.0 } else { -1.0 }
                            * (0.5 + rng.random::<f64>());
                }
            }
            out.push(y);
        }
        out
    }
}
