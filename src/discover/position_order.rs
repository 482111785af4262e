//! Whether the runs' own μ (or T) follow where each run slides in the groove: particles that
//! differ scatter independently of where they were kicked, while a friction or a force that
//! varies along the groove gives runs that slide over the same stretch the same step. The runs'
//! steps (each in units of its own noise error) are ordered by the mean lab position of their
//! sliding, and von Neumann's ratio (the mean squared difference of neighbours over the
//! variance) is compared with its law under shuffles of the same steps: a smooth dependence on
//! position makes neighbours agree and the ratio small.

use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Shuffles of the permutation test.
const SHUFFLES: usize = 999;

/// Von Neumann's ratio of `y` in the order given.
fn ratio(y: &[f64]) -> f64 {
    let n = y.len() as f64;
    let mean = y.iter().sum::<f64>() / n;
    let var = y.iter().map(|a| (a - mean).powi(2)).sum::<f64>();
    let diff = y.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>();
    if var > 0.0 {
        diff / var
    } else {
        2.0
    }
}

/// The one-sided p-value (small ratio: neighbours in position agree) of the steps `y` at
/// positions `z`, by `SHUFFLES` shuffles drawn from `seed`; 1 for fewer than 6 runs.
pub fn p_value(z: &[f64], y: &[f64], seed: u64) -> f64 {
    if y.len() < 6 {
        return 1.0;
    }
    let mut order: Vec<usize> = (0..y.len()).collect();
    order.sort_by(|&a, &b| z[a].total_cmp(&z[b]).then(a.cmp(&b)));
    let mut sorted: Vec<f64> = order.iter().map(|&i| y[i]).collect();
    let observed = ratio(&sorted);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let below = (0..SHUFFLES)
        .filter(|_| {
            sorted.shuffle(&mut rng);
            ratio(&sorted) <= observed
        })
        .count();
    (below + 1) as f64 / (SHUFFLES + 1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_distr::{Distribution, StandardNormal};

    #[test]
    fn steps_that_follow_position_are_told_from_steps_that_scatter() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut normal = || -> f64 { StandardNormal.sample(&mut rng) };
        let z: Vec<f64> = (0..40).map(|i| ((i * 17) % 40) as f64 * 0.3e-3).collect();
        // a friction wave of 4 mm along the groove, twice each run's noise error
        let wave: Vec<f64> = z
            .iter()
            .map(|z| 2.0 * (std::f64::consts::TAU * z / 4e-3).sin() + normal())
            .collect();
        assert!(p_value(&z, &wave, 1) <= 0.002, "{}", p_value(&z, &wave, 1));
        let scattered = (0..20)
            .filter(|&s| {
                let y: Vec<f64> = (0..40).map(|_| 2.0 * normal()).collect();
                p_value(&z, &y, s) < 0.01
            })
            .count();
        assert!(
            scattered <= 2,
            "{scattered} of 20 scattered sets read as ordered"
        );
    }
}
