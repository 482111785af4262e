//! Seeded bootstrap over whole runs: resample the runs with replacement, recompute the statistics,
//! and report percentile intervals (the resamples' statistics computed in parallel).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

pub use crate::artifacts::estimate::Interval;

/// Percentile intervals at `level` (e.g. 0.95) of K statistics of n items, from `resamples`
/// resamples drawn by ChaCha8 from `seed`. A statistic that is NaN on more than half of the
/// resamples (too few distinct items) gets no interval.
///
/// The resamples are drawn in order from the one stream, a batch at a time, and the statistics
/// of a batch are computed in parallel (rayon) and kept in draw order, so the intervals are the
/// same bytes on any number of threads.
pub fn percentile_intervals<const K: usize>(
    n: usize,
    resamples: usize,
    seed: u64,
    level: f64,
    stat: impl Fn(&[usize]) -> [f64; K] + Sync,
) -> [Option<Interval>; K] {
    percentile_intervals_in_groups(n, resamples, seed, level, 1, |group| {
        group.iter().map(|idx| stat(idx)).collect()
    })
}

/// `percentile_intervals` with the statistics computed `group` resamples at a time (`stats` gets
/// up to `group` resamples, in draw order, and gives their statistics in that order), for
/// statistics that share work across resamples (`stats::SlopeOrder::slopes_lanes`). The same
/// draws, so the same intervals as `percentile_intervals` of the same statistic.
pub fn percentile_intervals_in_groups<const K: usize>(
    n: usize,
    resamples: usize,
    seed: u64,
    level: f64,
    group: usize,
    stats: impl Fn(&[Vec<usize>]) -> Vec<[f64; K]> + Sync,
) -> [Option<Interval>; K] {
    let group = group.max(1);
    let mut out = [None; K];
    if n == 0 || resamples == 0 {
        return out;
    }
    let mut indices = Indices::new(ChaCha8Rng::seed_from_u64(seed), n);
    // About 8 MB of drawn indices at a time, in whole groups, and a group for every thread at
    // least: at 100,000 runs 8 MB is ten resamples, one group, and a summary's bootstrap ran on
    // one core (2 s of the 100,000-run aggregate with the other core idle)
    let per_batch = ((1 << 20) / n).clamp(2, 64);
    let batch = per_batch
        .max(group * rayon::current_num_threads())
        .div_ceil(group)
        * group;
    let mut draws: Vec<Vec<f64>> = vec![Vec::with_capacity(resamples); K];
    let mut done = 0;
    while done < resamples {
        let b = batch.min(resamples - done);
        let idx: Vec<Vec<usize>> = (0..b).map(|_| indices.resample()).collect();
        let groups: Vec<Vec<[f64; K]>> = idx.par_chunks(group).map(&stats).collect();
        for s in groups.into_iter().flatten() {
            for k in 0..K {
                if s[k].is_finite() {
                    draws[k].push(s[k]);
                }
            }
        }
        done += b;
    }
    for k in 0..K {
        let d = &mut draws[k];
        if d.len() * 2 < resamples {
            continue;
        }
        d.sort_by(f64::total_cmp);
        let q = |p: f64| crate::stats::quantile_interpolated(d, p);
        let a = 0.5 * (1.0 - level);
        out[k] = Some(Interval {
            lo: q(a),
            hi: q(1.0 - a),
        });
    }
    out
}

/// Uniform indices in 0..n, the ones `rng.random_range(0..n)` gives call after call, from the
/// generator's words taken a block at a time. rand 0.9 draws an index below 2³² as the high half
/// of a word times n, with a second word when the low half lands in the biased sliver (about n
/// in 2³²); ChaCha hands out whole words in order whether asked one at a time or a block, so
/// these are the same words, used the same way: the same indices, at a fraction of the calls.
pub struct Indices {
    rng: ChaCha8Rng,
    n: usize,
    words: [u32; WORDS],
    at: usize,
}

const WORDS: usize = 256;

impl Indices {
    pub fn new(rng: ChaCha8Rng, n: usize) -> Indices {
        Indices {
            rng,
            n,
            words: [0; WORDS],
            at: WORDS,
        }
    }

    #[inline(always)]
    fn word(&mut self) -> u32 {
        if self.at == WORDS {
            self.rng.fill(&mut self.words);
            self.at = 0;
        }
        self.at += 1;
        self.words[self.at - 1]
    }

    /// The next n indices: one resample.
    pub fn resample(&mut self) -> Vec<usize> {
        (0..self.n).map(|_| self.draw()).collect()
    }

    /// The next index (n ≥ 1).
    #[inline(always)]
    pub fn draw(&mut self) -> usize {
        let Ok(range) = u32::try_from(self.n) else {
            // above 2³² items rand takes 64-bit words: not worth a copy here
            assert_eq!(self.at, WORDS, "one way of drawing per stream");
            return self.rng.random_range(0..self.n);
        };
        let wide = u64::from(self.word()) * u64::from(range);
        let (mut hi, lo) = ((wide >> 32) as u32, wide as u32);
        if lo > range.wrapping_neg() {
            let carry = (u64::from(self.word()) * u64::from(range)) >> 32;
            hi += u32::from(lo.checked_add(carry as u32).is_none());
        }
        hi as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_distr::{Distribution, Normal};

    #[test]
    fn block_drawn_indices_are_rands_own() {
        // small and large n, powers of two, and n near 2³² where the second word is often needed
        for (seed, n, count) in [
            (1, 1, 1000),
            (2, 7, 100_000),
            (3, 1000, 300_000),
            (4, 1 << 16, 10_000),
            (5, 100_003, 300_000),
            (6, (u32::MAX - 5) as usize, 100_000),
            (7, (1u64 << 31) as usize + 12_345, 100_000),
        ] {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut indices = Indices::new(ChaCha8Rng::seed_from_u64(seed), n);
            for k in 0..count {
                assert_eq!(indices.draw(), rng.random_range(0..n), "n {n}, draw {k}");
            }
        }
    }

    #[test]
    fn mean_interval_has_the_textbook_width_and_is_reproducible() {
        // 400 draws of N(0, 1): the 95 % interval of the mean is about ±1.96/20 = ±0.098
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let normal = Normal::new(0.0, 1.0).unwrap();
        let y: Vec<f64> = (0..400).map(|_| normal.sample(&mut rng)).collect();
        let mean = |idx: &[usize]| [idx.iter().map(|&i| y[i]).sum::<f64>() / idx.len() as f64];
        let [iv] = percentile_intervals(y.len(), 2000, 11, 0.95, mean);
        let iv = iv.unwrap();
        let half = 0.5 * (iv.hi - iv.lo);
        assert!((half - 0.098).abs() < 0.015, "half width {half}");
        let [again] = percentile_intervals(y.len(), 2000, 11, 0.95, mean);
        assert_eq!(again.unwrap(), iv);
    }
}
