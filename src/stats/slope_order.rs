//! Theil–Sen slopes of bootstrap resamples without redrawing pairs: every pair of points sorted
//! by slope once, and a resample's slope read as a weighted median along that order.
//!
//! A bootstrap resample is the original points with multiplicities w (how often each was
//! drawn). Its pairs of positions are, for each pair of distinct points i < j, w_i·w_j copies of
//! the slope (y_j − y_i)/(x_j − x_i) (a point paired with its own copy has no slope), so its
//! Theil–Sen slope is the median of the sorted pair slopes weighted by w_i·w_j: one pass over
//! the pairs, no sorting, no selection. With every pair kept this is exactly the slope
//! `theil_sen_indexed` gives on the resample's picks.
//!
//! Above `max_pairs` pairs a fixed uniform draw of pairs stands for all of them (seeded, so the
//! same points give the same draw), and the resamples' spread exceeds that of the full
//! statistic: each point sits in only about 2·max_pairs/n drawn pairs. Measured on scattered
//! points about a line, the resamples' standard error of the slope is ≈ 15 % above every pair's
//! at 20 pairs per point, ≈ 35 % at 10 and ≈ 0.4 % at 1,000 (the test below bounds it at 20);
//! the excess variance falls as 1/(pairs per point). The interval errs wide, never narrow.

/// Pairs of points ordered by slope for each of K series over the same x.
pub struct SlopeOrder<const K: usize> {
    /// Per series: the pairs (i, j) in ascending order of slope, and those slopes.
    pairs: [Vec<[u32; 2]>; K],
    slopes: [Vec<f64>; K],
    /// Per series: the pairs below the middle of that order and those from it on, each sorted
    /// by point (i, then j), for the sums of weights, which need no order: read in point order,
    /// a resample's counts are met nearly in memory order, not at random.
    halves: [[Vec<[u32; 2]>; 2]; K],
    /// Points whose y is not finite in some series (a resample holding one has no line).
    bad: [Vec<u32>; K],
    /// Whether every pair of distinct x is kept (exact), or a draw.
    pub every_pair: bool,
}

impl<const K: usize> SlopeOrder<K> {
    /// Order the pairs of the points `(x, ys[k])` by slope; every pair when there are at most
    /// `max_pairs`, otherwise `max_pairs` pairs of distinct points drawn uniformly with `seed`.
    /// Pairs of equal x have no slope and are left out.
    pub fn new(x: &[f64], ys: [&[f64]; K], max_pairs: usize, seed: u64) -> Self {
        let n = x.len();
        assert!(n <= u32::MAX as usize, "too many points for a slope order");
        let every_pair = n * n.saturating_sub(1) / 2 <= max_pairs;
        let mut drawn: Vec<[u32; 2]> = Vec::new();
        if every_pair {
            drawn.reserve(n * n.saturating_sub(1) / 2);
            for i in 0..n {
                for j in i + 1..n {
                    if x[j] != x[i] {
                        drawn.push([i as u32, j as u32]);
                    }
                }
            }
        } else {
            drawn.reserve(max_pairs);
            let mut state = seed ^ (n as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
            let mut attempts = 0usize;
            while drawn.len() < max_pairs && attempts < 4 * max_pairs {
                attempts += 1;
                state = super::line::splitmix(state);
                let i = (state % n as u64) as usize;
                let j = ((state >> 32) % n as u64) as usize;
                if i != j && x[i] != x[j] {
                    drawn.push([i.min(j) as u32, i.max(j) as u32]);
                }
            }
        }
        let bad: [Vec<u32>; K] = std::array::from_fn(|k| {
            (0..n)
                .filter(|&i| !ys[k][i].is_finite())
                .map(|i| i as u32)
                .collect()
        });
        let mut pairs: [Vec<[u32; 2]>; K] = std::array::from_fn(|_| Vec::new());
        let mut slopes: [Vec<f64>; K] = std::array::from_fn(|_| Vec::new());
        for k in 0..K {
            let y = ys[k];
            let mut keyed: Vec<(f64, [u32; 2])> = drawn
                .iter()
                .filter(|[i, j]| y[*i as usize].is_finite() && y[*j as usize].is_finite())
                .map(|&[i, j]| {
                    let (i, j) = (i as usize, j as usize);
                    ((y[j] - y[i]) / (x[j] - x[i]), [i as u32, j as u32])
                })
                .collect();
            keyed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            slopes[k] = keyed.iter().map(|p| p.0).collect();
            pairs[k] = keyed.into_iter().map(|p| p.1).collect();
        }
        let halves = std::array::from_fn(|k| {
            let (below, above) = pairs[k].split_at(pairs[k].len() / 2);
            [below, above].map(|half| {
                let mut half = half.to_vec();
                half.sort_unstable();
                half
            })
        });
        SlopeOrder {
            pairs,
            slopes,
            halves,
            bad,
            every_pair,
        }
    }

    /// The Theil–Sen slope of series `k` when point i counts `w[i]` times (a resample's
    /// multiplicities, saturating at 65,535; all ones for the points themselves): the median of
    /// the ordered slopes weighted by w_i·w_j (the mean of the two middle ones for an even
    /// total). NaN when no pair has weight or a point of non-finite y is drawn.
    pub fn slope(&self, k: usize, w: &[u16]) -> f64 {
        self.slope_given_total(k, w, None).0
    }

    /// `slope` of every series: when no point is bad the series share one set of pairs, so
    /// their total weight is summed once (a pass over half the pairs saved per series).
    pub fn slopes(&self, w: &[u16]) -> [f64; K] {
        if K == 0 || self.bad.iter().any(|b| !b.is_empty()) {
            return std::array::from_fn(|k| self.slope(k, w));
        }
        let (first, total) = self.slope_given_total(0, w, None);
        std::array::from_fn(|k| match k {
            0 => first,
            _ => self.slope_given_total(k, w, Some(total)).0,
        })
    }

    /// `slopes` of each resample's counts (`w[r][i]`: how often point i was drawn in resample
    /// r), `LANES` resamples per pass (`slopes_lanes`); resamples whose counts do not fit a lane
    /// (one above 255: only tiny or freak resamples) are read one at a time. The same bits as
    /// `slopes` of each.
    pub fn slopes_many(&self, w: &[Vec<u16>]) -> Vec<[f64; K]> {
        let mut out = Vec::with_capacity(w.len());
        for group in w.chunks(LANES) {
            if group.iter().flatten().any(|&c| c > 255) {
                out.extend(group.iter().map(|w| self.slopes(w)));
                continue;
            }
            let n = group.first().map_or(0, Vec::len);
            let mut lanes = vec![[0u8; LANES]; n];
            for (l, w) in group.iter().enumerate() {
                for (lane, &c) in lanes.iter_mut().zip(w) {
                    lane[l] = c as u8;
                }
            }
            out.extend_from_slice(&self.slopes_lanes(&lanes)[..group.len()]);
        }
        out
    }

    /// `slopes` of `LANES` resamples at once: `w[i][l]` is how often point i was drawn in
    /// resample l (a lane of zeros gives NaN; a count above 255 does not fit: use `slopes`).
    /// The pass over the pairs is shared: each pair's two points' counts are read once for
    /// every lane, and the lanes' products (at most 255², in 16 bits) are summed side by side in
    /// 32 bits over at most 65,536 pairs at a time, so sixteen resamples cost little more than
    /// one. Lane l gives exactly `slopes` of its counts.
    pub fn slopes_lanes(&self, w: &[[u8; LANES]]) -> [[f64; K]; LANES] {
        if K == 0 || self.bad.iter().any(|b| !b.is_empty()) {
            return std::array::from_fn(|l| {
                let lane: Vec<u16> = w.iter().map(|v| u16::from(v[l])).collect();
                self.slopes(&lane)
            });
        }
        // with no bad point every series holds the same pairs (in its own order)
        let sums = |pairs: &[[u32; 2]]| -> [u64; LANES] {
            let mut acc = [0u64; LANES];
            for chunk in pairs.chunks(1 << 16) {
                let mut part = [0u32; LANES];
                for &[i, j] in chunk {
                    let (a, b) = (&w[i as usize], &w[j as usize]);
                    for l in 0..LANES {
                        part[l] += u32::from(u16::from(a[l]) * u16::from(b[l]));
                    }
                }
                for l in 0..LANES {
                    acc[l] += u64::from(part[l]);
                }
            }
            acc
        };
        let [below_first, above_first] = self.halves[0].each_ref().map(|h| sums(h));
        let mut out = [[f64::NAN; K]; LANES];
        for k in 0..K {
            let below = if k == 0 {
                below_first
            } else {
                sums(&self.halves[k][0])
            };
            for (l, slopes) in out.iter_mut().enumerate() {
                let pairs = &self.pairs[k];
                let wt = |p: usize| {
                    let [i, j] = pairs[p];
                    u64::from(w[i as usize][l]) * u64::from(w[j as usize][l])
                };
                let total = below_first[l] + above_first[l];
                slopes[k] = self.weighted_median(k, wt, below[l], total);
            }
        }
        out
    }

    /// The slope and the total weight of the pairs (summed unless given).
    fn slope_given_total(&self, k: usize, w: &[u16], total: Option<u64>) -> (f64, u64) {
        if self.bad[k].iter().any(|&i| w[i as usize] > 0) {
            return (f64::NAN, 0);
        }
        let pairs = &self.pairs[k];
        let wt = |p: usize| {
            let [i, j] = pairs[p];
            w[i as usize] as u64 * w[j as usize] as u64
        };
        let mid = pairs.len() / 2;
        let below: u64 = (0..mid).map(wt).sum();
        let total = total.unwrap_or_else(|| below + (mid..pairs.len()).map(wt).sum::<u64>());
        (self.weighted_median(k, wt, below, total), total)
    }

    /// The median of series k's ordered slopes, pair p weighing `wt(p)`, given the weight
    /// `below` of the first half of the pairs and the `total`: NaN for no weight; the mean of the
    /// two middle ones for an even total.
    fn weighted_median(&self, k: usize, wt: impl Fn(usize) -> u64, below: u64, total: u64) -> f64 {
        if total == 0 {
            return f64::NAN;
        }
        let slopes = &self.slopes[k];
        let mid = slopes.len() / 2;
        // The slope of 0-based rank r in the weighted order, walking from the middle (the
        // weighted median lies near it, so the walk is short).
        let at = |r: u64| -> f64 {
            let (mut p, mut before) = (mid, below);
            if r < before {
                loop {
                    p -= 1;
                    before -= wt(p);
                    if before <= r {
                        return slopes[p];
                    }
                }
            }
            loop {
                let wp = wt(p);
                if r < before + wp {
                    return slopes[p];
                }
                before += wp;
                p += 1;
            }
        };
        if total % 2 == 1 {
            at(total / 2)
        } else {
            0.5 * (at(total / 2 - 1) + at(total / 2))
        }
    }
}

/// Resamples `SlopeOrder::slopes_lanes` takes at once.
pub const LANES: usize = 16;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::theil_sen_indexed;

    fn points() -> (Vec<f64>, Vec<f64>) {
        let x: Vec<f64> = (0..60)
            .map(|i| 0.01 + 0.001 * ((i * 37) % 60) as f64)
            .collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, v)| 0.05 + 1.1 * v + 3e-3 * (((i * 7919) % 17) as f64 / 8.0 - 1.0))
            .collect();
        (x, y)
    }

    #[test]
    fn a_weighted_median_of_every_pair_is_the_resamples_theil_sen_slope() {
        let (x, y) = points();
        let order = SlopeOrder::new(&x, [&y], usize::MAX, 1);
        assert!(order.every_pair);
        let mut buf = Vec::new();
        // resamples with repeats (and a point drawn three times), odd and even totals
        for picks in [
            (0..60).collect::<Vec<usize>>(),
            (0..60).map(|i| (i * 13 + 5) % 41).collect(),
            vec![3, 3, 3, 8, 8, 20, 41, 59, 2],
            vec![1, 1, 2, 2],
        ] {
            let mut w = vec![0u16; x.len()];
            for &i in &picks {
                w[i] += 1;
            }
            let (_, exact) = theil_sen_indexed(&x, &y, &picks, &mut buf, usize::MAX);
            assert_eq!(order.slope(0, &w), exact, "{picks:?}");
            let both = SlopeOrder::new(&x, [&y, &x], usize::MAX, 1);
            assert_eq!(both.slopes(&w), [exact, both.slope(1, &w)], "{picks:?}");
        }
        // one point drawn many times has no slope
        let mut w = vec![0u16; x.len()];
        w[7] = 9;
        assert!(order.slope(0, &w).is_nan());
    }

    #[test]
    fn sixteen_lanes_give_each_resamples_own_slopes_exactly() {
        use rand::{Rng, SeedableRng};
        use rand_chacha::ChaCha8Rng;
        let (x, y) = points();
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let bad_y: Vec<f64> = y
            .iter()
            .enumerate()
            .map(|(i, v)| if i == 5 { f64::NAN } else { *v })
            .collect();
        for (ys, max_pairs) in [
            ([&y, &x], usize::MAX),
            ([&y, &x], 500),
            ([&bad_y, &y], usize::MAX),
        ] {
            let order = SlopeOrder::new(&x, [ys[0].as_slice(), ys[1].as_slice()], max_pairs, 2);
            let mut lanes = vec![[0u8; LANES]; x.len()];
            let mut each = Vec::new();
            for l in 0..LANES - 1 {
                // the last lane stays empty; lane 0 draws few points; lane 1 draws one point
                // 200 times among others
                let draws = if l == 0 { 3 } else { x.len() };
                let mut w = vec![0u16; x.len()];
                for _ in 0..draws {
                    w[rng.random_range(0..x.len())] += 1;
                }
                if l == 1 {
                    w[9] += 200;
                }
                for i in 0..x.len() {
                    lanes[i][l] = u8::try_from(w[i]).unwrap();
                }
                each.push(order.slopes(&w));
            }
            let got = order.slopes_lanes(&lanes);
            for l in 0..LANES - 1 {
                for k in 0..2 {
                    assert_eq!(
                        got[l][k].to_bits(),
                        each[l][k].to_bits(),
                        "lane {l} series {k}"
                    );
                }
            }
            assert!(got[LANES - 1].iter().all(|s| s.is_nan()));
        }
    }

    #[test]
    fn many_resamples_give_each_ones_slopes_lanes_or_not() {
        use rand::{Rng, SeedableRng};
        use rand_chacha::ChaCha8Rng;
        let (x, y) = points();
        let order = SlopeOrder::new(&x, [&y, &x], usize::MAX, 2);
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        // 40 resamples: two full groups and a part; one resample of the second group has a
        // point drawn 300 times, so that group is read one resample at a time
        let w: Vec<Vec<u16>> = (0..40)
            .map(|r| {
                let mut w = vec![0u16; x.len()];
                for _ in 0..x.len() {
                    w[rng.random_range(0..x.len())] += 1;
                }
                if r == 20 {
                    w[3] += 300;
                }
                w
            })
            .collect();
        let got = order.slopes_many(&w);
        assert_eq!(got.len(), w.len());
        for (r, (g, w)) in got.iter().zip(&w).enumerate() {
            let want = order.slopes(w);
            for k in 0..2 {
                assert_eq!(g[k].to_bits(), want[k].to_bits(), "resample {r} series {k}");
            }
        }
    }

    #[test]
    fn a_drawn_order_gives_nearly_the_slope_and_a_bad_point_none() {
        let (x, mut y) = points();
        let all = SlopeOrder::new(&x, [&y], usize::MAX, 1);
        let drawn = SlopeOrder::new(&x, [&y], 600, 1);
        assert!(!drawn.every_pair && drawn.pairs[0].len() == 600);
        let ones = vec![1u16; x.len()];
        let (a, d) = (all.slope(0, &ones), drawn.slope(0, &ones));
        assert!((a - 1.1).abs() < 0.05 && (d - a).abs() < 0.05, "{a} {d}");
        // the same seed gives the same draw
        assert_eq!(SlopeOrder::new(&x, [&y], 600, 1).slope(0, &ones), d);
        y[4] = f64::NAN;
        let bad = SlopeOrder::new(&x, [&y], usize::MAX, 1);
        assert!(bad.slope(0, &ones).is_nan());
        let mut w = ones;
        w[4] = 0;
        assert!((bad.slope(0, &w) - a).abs() < 0.02);
    }

    #[test]
    fn a_draw_of_20_pairs_per_point_widens_the_resamples_by_less_than_a_third() {
        use rand::{Rng, SeedableRng};
        use rand_chacha::ChaCha8Rng;
        let n = 800;
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let x: Vec<f64> = (0..n).map(|_| rng.random_range(0.01..0.1)).collect();
        let y: Vec<f64> = x
            .iter()
            .map(|v| 0.05 + 1.1 * v + 0.01 * (rng.random::<f64>() - 0.5))
            .collect();
        let (all, drawn) = (
            SlopeOrder::new(&x, [&y], usize::MAX, 7),
            SlopeOrder::new(&x, [&y], 20 * n, 7),
        );
        assert!(all.every_pair && !drawn.every_pair);
        let (mut a, mut d) = (Vec::new(), Vec::new());
        for _ in 0..400 {
            let mut w = vec![0u16; n];
            for _ in 0..n {
                w[rng.random_range(0..n)] += 1;
            }
            a.push(all.slope(0, &w));
            d.push(drawn.slope(0, &w));
        }
        let sd = |b: &[f64]| {
            let m = b.iter().sum::<f64>() / b.len() as f64;
            (b.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (b.len() - 1) as f64).sqrt()
        };
        let ratio = sd(&d) / sd(&a);
        // ≈ 1.15 expected; 400 resamples leave about ±5 % on each spread
        assert!((1.0..1.33).contains(&ratio), "{ratio}");
    }
}
