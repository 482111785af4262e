//! The pairs' tracking noise over the time a signature lasts: how much more a smooth term's χ²
//! gain varies than white noise would make it vary, read from a fit's residuals.
//!
//! A term that bends the tracks for a few milliseconds (a force between the particles acts over
//! the last and first few hundred micrometres around each impact) is fitted to the residuals
//! averaged over that time; its χ² gain scales with the noise's spectral density at those slow
//! frequencies over its variance, the long-run variance factor
//! 1 + 2 Σ_{k=1}^{L} (1 − k/(L+1)) ρ_k (Bartlett weights, L the frames of the signature), ρ_k
//! the residuals' autocorrelation at lag k pooled over every track. The lag-1 correlation alone
//! extrapolated as an AR(1) ((1 + ρ₁)/(1 − ρ₁)) misses a slow drift under white noise: ρ₁ ≈ 0.4
//! gives 2.3 where a drift of 5–30 ms makes the factor 10–40 over 5 ms, and a null with such a
//! drift accepted an attraction in 3 of 40 material tests.

use crate::fit::collision::wholerun::{residuals, GroupFit, PairRun};

/// Each whitened residual counts at most this far from zero.
const CLIP: f64 = 10.0;

/// The long-run variance factor of `fit`'s residuals over `window_s` (each run's frames at its
/// own rate), never below 1.
pub fn long_run_factor(runs: &[PairRun], fit: &GroupFit, window_s: f64) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (run, own) in runs.iter().zip(&fit.result.own) {
        let mut r = vec![0.0; run.n_samples()];
        residuals(run, &fit.spec, &fit.result.shared, own, &mut r);
        let lag = (window_s * run.fps).round().max(1.0) as usize;
        let (striker, target) = r.split_at(run.samples[0].len());
        for track in [striker, target] {
            let x: Vec<f64> = track.iter().map(|v| v.clamp(-CLIP, CLIP)).collect();
            let (n, d) = sums(&x, lag);
            num += n;
            den += d;
        }
    }
    if den > 0.0 {
        (num / den).max(1.0)
    } else {
        1.0
    }
}

/// The factor's numerator (Σx² + 2 Σ_k w_k Σ x_t x_{t+k}) and denominator (Σx²) of one track.
fn sums(x: &[f64], lag: usize) -> (f64, f64) {
    let square: f64 = x.iter().map(|v| v * v).sum();
    let cross: f64 = (1..=lag.min(x.len().saturating_sub(1)))
        .map(|k| {
            let w = 1.0 - k as f64 / (lag + 1) as f64;
            w * x.iter().zip(&x[k..]).map(|(a, b)| a * b).sum::<f64>()
        })
        .sum();
    (square + 2.0 * cross, square)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn factor(x: &[f64], lag: usize) -> f64 {
        let (n, d) = sums(x, lag);
        n / d
    }

    #[test]
    fn a_slow_wave_under_alternating_noise_reads_far_above_its_lag_one_guess() {
        // ±1 alternating (ρ₁ = −1) plus a slow component: the lag-1 correlation is negative, the
        // long-run factor well above 1
        let x: Vec<f64> = (0..2000)
            .map(|i| {
                let t = i as f64;
                (if i % 2 == 0 { 0.5 } else { -0.5 }) + (t / 200.0).sin()
            })
            .collect();
        let rho1 =
            x.windows(2).map(|w| w[0] * w[1]).sum::<f64>() / x.iter().map(|v| v * v).sum::<f64>();
        assert!(rho1 > 0.0 && rho1 < 0.7, "{rho1}");
        let f = factor(&x, 50);
        assert!(f > 10.0, "{f}");
        // alternating noise alone cancels over the window
        let alt: Vec<f64> = (0..2000)
            .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert!(factor(&alt, 50) < 0.1);
    }

    #[test]
    fn an_ar1_series_reads_its_long_run_variance() {
        // x_t = ρ x_{t−1} + e_t with a deterministic pseudo-random e: (1 + ρ)/(1 − ρ) = 4 at 0.6,
        // less the Bartlett weights' share over 200 lags
        let (mut x, mut v, mut s) = (Vec::new(), 0.0, 12345_u64);
        for _ in 0..200_000 {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let e = (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
            v = 0.6 * v + e;
            x.push(v);
        }
        let f = factor(&x, 200);
        assert!((f - 4.0).abs() < 0.3, "{f}");
        assert!((factor(&x, 0) - 1.0).abs() < 1e-12);
    }
}
