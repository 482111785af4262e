//! Whitening by the tracker noise's own covariance, so that a detection limit counts what an
//! ideal detector could see through correlated noise, not through white noise of the same size.
//!
//! A track's error is a sum of a white part (white noise, motion blur growing with speed, the
//! sub-pixel grid and the pixel-locking ripple, all frame by frame) and two AR(1) parts (the
//! AR(1) component and the Ornstein–Uhlenbeck drift). That is a linear state-space model with a
//! two-number state, so a Kalman filter run over a series gives its innovations; divided by
//! their standard deviations they are the series multiplied by C^(−1/2) (C the noise
//! covariance), and Σ (innovation²/variance) = yᵀ C⁻¹ y. The filter's gains depend only on the
//! covariance, so one pass whitens every column of a design at once. Outliers are left out (a
//! robust fit downweights them; they cost little information at a rate of a few per cent).

use crate::indsim::noise::Noise;

/// The noise model of one recording, per frame.
pub struct Whitener {
    white_var: f64,
    /// (marginal variance, coefficient per frame) of the AR(1) component and of the drift.
    ar: [(f64, f64); 2],
    /// (σ, v_ref): extra white variance (σ |v| / v_ref)².
    blur: Option<(f64, f64)>,
}

impl Whitener {
    /// The whitener of `noise` filmed at `fps`.
    pub fn new(noise: &Noise, fps: f64) -> Whitener {
        let mut white_var = noise.white_m * noise.white_m;
        if let Some((pixel, beta, grid)) = noise.lock {
            // the rounding to the grid, and the locking ripple of amplitude β p / 2π seen by a
            // moving particle (at rest it is a constant offset, which the start position takes)
            let ripple = beta * pixel / std::f64::consts::TAU;
            white_var += grid * grid / 12.0 + 0.5 * ripple * ripple;
        }
        let ar1 = noise.ar1.map_or((0.0, 0.0), |(s, phi)| (s * s, phi));
        let drift = noise
            .drift
            .map_or((0.0, 0.0), |(s, tau)| (s * s, (-1.0 / (fps * tau)).exp()));
        Whitener {
            white_var,
            ar: [ar1, drift],
            blur: noise.blur,
        }
    }

    /// Whitens `cols` (each a series over `frames`, increasing frame numbers with gaps where
    /// frames were dropped; `speed` the particle's speed at each frame).
    pub fn apply(&self, frames: &[usize], speed: &[f64], cols: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let k = cols.len();
        let mut out = (0..k)
            .map(|_| Vec::with_capacity(frames.len()))
            .collect::<Vec<Vec<f64>>>();
        // state estimate per column, and the shared state covariance
        let mut x = vec![[0.0f64; 2]; k];
        let mut p = [[self.ar[0].0, 0.0], [0.0, self.ar[1].0]];
        let mut last: Option<usize> = None;
        for (i, &frame) in frames.iter().enumerate() {
            if let Some(prev) = last {
                let gap = (frame - prev) as i32;
                let f = [self.ar[0].1.powi(gap), self.ar[1].1.powi(gap)];
                for xc in x.iter_mut() {
                    xc[0] *= f[0];
                    xc[1] *= f[1];
                }
                for a in 0..2 {
                    for b in 0..2 {
                        p[a][b] *= f[a] * f[b];
                    }
                    p[a][a] += self.ar[a].0 * (1.0 - f[a] * f[a]);
                }
            }
            last = Some(frame);
            let blur = self
                .blur
                .map_or(0.0, |(s, v_ref)| (s * speed[i] / v_ref).powi(2));
            let r = (self.white_var + blur).max(1e-30);
            // observation: the sum of the two states plus the white part
            let ph = [p[0][0] + p[0][1], p[1][0] + p[1][1]];
            let s = ph[0] + ph[1] + r;
            let gain = [ph[0] / s, ph[1] / s];
            let root = s.sqrt();
            for (c, col) in cols.iter().enumerate() {
                let e = col[i] - x[c][0] - x[c][1];
                out[c].push(e / root);
                x[c][0] += gain[0] * e;
                x[c][1] += gain[1] * e;
            }
            for a in 0..2 {
                for b in 0..2 {
                    p[a][b] -= gain[a] * ph[b];
                }
            }
        }
        out
    }
}
