//! The operational detection limit of an effect in one dataset.
//!
//! The effect's signal is the change it makes to the noise-free recorded positions, frame by
//! frame, over the whole dataset (the same runs, kicks, frames and field of view with and
//! without it): SNR² = Σ (Δz/σ)², σ the tracker's per-frame standard deviation. The detection
//! limit is the size at which SNR² = 25 (five standard deviations over the dataset). It ignores
//! what the baseline's own free parameters (μ, T, v0, z0, t0 per run) absorb of the change, so it
//! is optimistic: an effect at 1× can be undetectable, one at 10× should not be.

use super::dataset::DatasetSpec;
use std::collections::HashMap;

/// SNR² defining the limit.
pub const LIMIT_SNR2: f64 = 25.0;

/// Σ (Δz/σ)² between two noise-free renderings of a dataset.
pub fn snr2(base: &DatasetSpec, with: &DatasetSpec) -> f64 {
    let sigma = base.noise.sigma_m();
    let a = base.render(true);
    let b = with.render(true);
    let mut total = 0.0;
    for (ra, rb) in a.iter().zip(&b) {
        for (ta, tb) in ra.tracks.iter().zip(&rb.tracks) {
            let by_frame: HashMap<usize, f64> = ta.iter().map(|f| (f.frame, f.z_m)).collect();
            for f in tb {
                if let Some(z) = by_frame.get(&f.frame) {
                    let d = (f.z_m - z) / sigma;
                    total += d * d;
                }
            }
        }
    }
    total
}
