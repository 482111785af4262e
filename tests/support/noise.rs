//! Tracking noise for tests: AR(1) noise added to recordings' positions from a fixed seed.

use groove::recording::Recording;

/// Each track's positions with AR(1) noise added (lag-1 coefficient `phi`, marginal standard
/// deviation `sd`, in frame order), from a fixed seed.
pub fn with_correlated_noise(recs: &mut [Recording], phi: f64, sd: f64, seed: u64) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let innovation = sd * (1.0 - phi * phi).sqrt();
    for track in recs.iter_mut().flat_map(|r| r.tracks.iter_mut()) {
        let mut e = sd * rng.sample::<f64, _>(rand_distr::StandardNormal);
        for z in &mut track.z_m {
            *z += e;
            e = phi * e + innovation * rng.sample::<f64, _>(rand_distr::StandardNormal);
        }
    }
}
