//! Means over runs: plain, inverse-variance weighted, and robust weighted (the Theil–Sen line
//! and the medians are in `stats`).

use crate::lsq::loss::HUBER_K;
use crate::stats::MAD_TO_SIGMA;

/// Mean of y over `idx` restricted to the entries where `keep` holds; NaN if none.
pub fn mean_where(y: &[f64], idx: &[usize], keep: impl Fn(usize) -> bool) -> f64 {
    let (mut s, mut m) = (0.0, 0usize);
    for &i in idx {
        if keep(i) {
            s += y[i];
            m += 1;
        }
    }
    if m == 0 {
        f64::NAN
    } else {
        s / m as f64
    }
}

/// Each entry's part in a `mean_where`: (y, 1) where `keep` holds, (0, 0) where not.
pub fn kept_table(y: &[f64], keep: impl Fn(usize) -> bool) -> Vec<(f64, u64)> {
    (0..y.len())
        .map(|i| if keep(i) { (y[i], 1) } else { (0.0, 0) })
        .collect()
}

/// `mean_where` from its `kept_table`: one read per index and no branch on `keep` (a
/// resample's indices come at random, and so would its branches). The same terms added in the
/// same order (adding 0.0 to a sum that starts at +0.0 leaves it as it is), so the same bits.
pub fn mean_kept(kept: &[(f64, u64)], idx: &[usize]) -> f64 {
    let (mut s, mut m) = (0.0, 0u64);
    for &i in idx {
        let (y, k) = kept[i];
        s += y;
        m += k;
    }
    if m == 0 {
        f64::NAN
    } else {
        s / m as f64
    }
}

/// Inverse-variance weighted mean of y over `idx` (entries with a non-positive or unknown
/// error are left out); NaN if none.
pub fn weighted_mean(y: &[f64], se: &[f64], idx: &[usize]) -> f64 {
    let (mut s, mut w) = (0.0, 0.0);
    for &i in idx {
        if se[i] > 0.0 && se[i].is_finite() {
            let wi = 1.0 / (se[i] * se[i]);
            s += wi * y[i];
            w += wi;
        }
    }
    if w > 0.0 {
        s / w
    } else {
        f64::NAN
    }
}

/// A weighted mean of y over `idx` that no single run can capture: each run's variance is its
/// se² plus the between-run scatter τ² (the runs' robust spread, 1.4826·MAD, squared, less their
/// median se²), then Huber weights on the runs' standardised deviations (reweighted from the
/// median until it settles), so a run far from the others with a tiny error counts like an
/// ordinary run at most, and less the further out it lies. Entries with a non-positive or unknown
/// error are left out; NaN if none. (`RobustMean` computes it for many resamples.)
pub fn robust_weighted_mean(y: &[f64], se: &[f64], idx: &[usize]) -> f64 {
    let mut w = vec![0u16; y.len()];
    for &i in idx {
        w[i] = w[i].saturating_add(1);
    }
    RobustMean::new(y, se).of(&w)
}

thread_local! {
    /// `RobustMean::of`'s running counts and drawn runs, kept between the calls of a thread
    /// (thousands of resamples) rather than allocated for each.
    static SCRATCH: std::cell::RefCell<(Vec<u64>, Vec<[f64; 3]>)> = const { std::cell::RefCell::new((Vec::new(), Vec::new())) };
}

/// `robust_weighted_mean` of the runs counted with multiplicities (a bootstrap resample): the
/// runs are sorted by y and by se² once, so each resample's medians are walks along those
/// orders weighted by its counts (no selection), and its Huber step (`huber_root`) visits each
/// drawn run once per Newton pass.
pub struct RobustMean {
    /// The usable runs (finite y, positive finite se) in ascending order of y, and of se².
    by_y: Vec<u32>,
    by_var: Vec<u32>,
    /// y and se² in the order of `by_y`, se² in the order of `by_var`: a resample's walks
    /// read them in sequence and only its counts by run.
    y_sorted: Vec<f64>,
    var_by_y: Vec<f64>,
    var_sorted: Vec<f64>,
}

impl RobustMean {
    pub fn new(y: &[f64], se: &[f64]) -> Self {
        let ok: Vec<u32> = (0..y.len())
            .filter(|&i| se[i] > 0.0 && se[i].is_finite() && y[i].is_finite())
            .map(|i| i as u32)
            .collect();
        let mut by_y = ok.clone();
        by_y.sort_by(|&a, &b| y[a as usize].total_cmp(&y[b as usize]).then(a.cmp(&b)));
        let mut by_var = ok;
        let var = |i: u32| se[i as usize] * se[i as usize];
        by_var.sort_by(|&a, &b| var(a).total_cmp(&var(b)).then(a.cmp(&b)));
        RobustMean {
            y_sorted: by_y.iter().map(|&i| y[i as usize]).collect(),
            var_by_y: by_y.iter().map(|&i| var(i)).collect(),
            var_sorted: by_var.iter().map(|&i| var(i)).collect(),
            by_y,
            by_var,
        }
    }

    /// The robust weighted mean when run i counts `w[i]` times; NaN if no usable run is drawn.
    pub fn of(&self, w: &[u16]) -> f64 {
        let n = self.by_y.len();
        // running counts along the y order, and the drawn runs (y, se², count) in that order;
        // every run is written and the count of drawn ones moves on only past a drawn one (a
        // branch on the count, taken for 63 % of runs at random, cost more than the writes)
        SCRATCH.with_borrow_mut(|(cum, drawn)| {
            cum.resize(n + 1, 0);
            drawn.resize(n, [0.0; 3]);
            let mut total = 0u64;
            let mut len = 0;
            for (p, ((&i, &y), &var)) in self
                .by_y
                .iter()
                .zip(&self.y_sorted)
                .zip(&self.var_by_y)
                .enumerate()
            {
                let c = w[i as usize];
                drawn[len] = [y, var, f64::from(c)];
                len += usize::from(c > 0);
                total += u64::from(c);
                cum[p + 1] = total;
            }
            self.of_drawn(w, cum, &drawn[..len], total)
        })
    }

    /// `of` once the running counts `cum` along the y order and the drawn runs are known.
    fn of_drawn(&self, w: &[u16], cum: &[u64], drawn: &[[f64; 3]], total: u64) -> f64 {
        let n = self.by_y.len();
        if total == 0 {
            return f64::NAN;
        }
        let (r_lo, r_hi) = middle_ranks(total);
        let y_at = |p: usize| self.y_sorted[p];
        // the value of rank r: at the first position whose running count passes r
        let rank = |r: u64| y_at(cum[1..].partition_point(|&c| c <= r));
        let mid = 0.5 * (rank(r_lo) + rank(r_hi));
        // the distances |y − mid| rise from `split` outwards on either side, so how many drawn
        // runs lie within d of mid is a difference of two running counts
        let split = self.y_sorted.partition_point(|&y| y < mid);
        let dist = |p: usize| (y_at(p) - mid).abs();
        let within = |d: f64| {
            let first = first_where(0, split, |p| dist(p) <= d);
            let last = first_where(split, n, |p| dist(p) > d);
            cum[last] - cum[first]
        };
        // the distance of rank r: the least distance (of any run, drawn or not) with more than
        // r drawn runs within it, on either side
        let dist_rank = |r: u64| {
            let left = first_where(0, split, |j| within(dist(split - 1 - j)) > r);
            let right = first_where(split, n, |p| within(dist(p)) > r);
            let from_left = (left < split).then(|| dist(split - 1 - left));
            let from_right = (right < n).then(|| dist(right));
            match (from_left, from_right) {
                (Some(a), Some(b)) => a.min(b),
                (a, b) => a.or(b).expect("every drawn run is within its own distance"),
            }
        };
        let mad = MAD_TO_SIGMA * (0.5 * (dist_rank(r_lo) + dist_rank(r_hi)));
        let typical_var = weighted_median(
            self.by_var
                .iter()
                .zip(&self.var_sorted)
                .map(|(&i, &var)| (var, u64::from(w[i as usize]))),
            total,
        );
        let tau2 = (mad * mad - typical_var).max(0.0);
        // (y, count/variance, Huber band k·sd) of each drawn run
        let runs: Vec<[f64; 3]> = drawn
            .iter()
            .map(|&[y, se2, c]| {
                let var = se2 + tau2;
                [y, c / var, HUBER_K * var.sqrt()]
            })
            .collect();
        huber_root(&runs, mid)
    }
}

/// The Huber mean of runs (y, a, b): the root of F(m) = Σ a·clip(y − m, −b, b), where the
/// reweighting (weights a·min(1, b/|y − m|)) settles. F falls, piecewise linear, so Newton
/// steps (slope −Σ a over the runs within their band) reach the root exactly once the runs
/// within their bands stop changing, about three passes (IRLS took ten); a step that would
/// leave the bracket the signs of F give is a bisection instead. Stops at a step of 1e-12
/// relative, as the reweighting did.
fn huber_root(runs: &[[f64; 3]], start: f64) -> f64 {
    // the bracket: where F > 0 and where F < 0 was seen; open until a bisection needs it
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut m = start;
    for _ in 0..100 {
        let (mut f, mut slope) = (0.0, 0.0);
        for &[y, a, b] in runs {
            let d = y - m;
            f += a * d.clamp(-b, b);
            if d.abs() < b {
                slope += a;
            }
        }
        if f == 0.0 {
            break;
        }
        if f > 0.0 {
            lo = m;
        } else {
            hi = m;
        }
        let newton = m + f / slope;
        if (newton - m).abs() <= 1e-12 * m.abs().max(f64::MIN_POSITIVE) {
            return newton;
        }
        if newton > lo && newton < hi {
            m = newton;
            continue;
        }
        if !(lo.is_finite() && hi.is_finite()) {
            // below every y − b, F > 0; above every y + b, F < 0 (`runs` ascend in y)
            let reach = runs.iter().fold(0.0_f64, |r, &[_, _, b]| r.max(b));
            lo = lo.max(runs[0][0] - reach);
            hi = hi.min(runs[runs.len() - 1][0] + reach);
        }
        if hi - lo <= 1e-12 * m.abs().max(f64::MIN_POSITIVE) {
            return m; // at a kink where no run is within its band
        } else {
            m = 0.5 * (lo + hi);
        }
    }
    m
}

/// The ranks of the two middle values of `total` (the same rank twice for an odd total).
fn middle_ranks(total: u64) -> (u64, u64) {
    match total % 2 {
        1 => (total / 2, total / 2),
        _ => (total / 2 - 1, total / 2),
    }
}

/// The first index in lo..hi where `pred` holds (it must hold from some index on), or hi.
fn first_where(mut lo: usize, mut hi: usize, pred: impl Fn(usize) -> bool) -> usize {
    while lo < hi {
        let m = lo + (hi - lo) / 2;
        if pred(m) {
            hi = m;
        } else {
            lo = m + 1;
        }
    }
    lo
}

/// The median of a multiset given as (value, count) in ascending order of value with `total`
/// counts in all: the middle value, or the mean of the two middle ones for an even total (as
/// `stats::median_in_place` of the values written out).
fn weighted_median(sorted: impl Iterator<Item = (f64, u64)>, total: u64) -> f64 {
    let (r_lo, r_hi) = middle_ranks(total);
    let (mut seen, mut lo) = (0u64, f64::NAN);
    // a run not drawn (c = 0) changes nothing, without a branch of its own to mispredict
    for (v, c) in sorted {
        if seen <= r_lo && r_lo < seen + c {
            lo = v;
        }
        seen += c;
        if r_hi < seen {
            return 0.5 * (lo + v);
        }
    }
    f64::NAN
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsq::loss::huber_weight;

    #[test]
    fn exact_line_and_means() {
        let x = [0.0, 1.0, 2.0, 3.0];
        let y = [1.0, 3.0, 5.0, 7.0];
        assert_eq!(mean_where(&y, &[0, 1, 2, 3], |i| x[i] > 1.5), 6.0);
        // weights 1 and 1/4: (1·1 + 0.25·7)/1.25
        let w = weighted_mean(&y, &[1.0, f64::NAN, 0.0, 2.0], &[0, 1, 2, 3]);
        assert!((w - (1.0 + 0.25 * 7.0) / 1.25).abs() < 1e-12);
    }

    #[test]
    fn the_kept_table_gives_mean_where_bit_for_bit() {
        // values of both signs, a NaN and an infinity where not kept, ±0, drawn with repeats
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut next = || rng.random::<u64>();
        let n = 500;
        let x: Vec<f64> = (0..n).map(|_| (next() % 1000) as f64 / 1000.0).collect();
        let mut y: Vec<f64> = (0..n)
            .map(|_| (next() % 2_000_001) as f64 * 1e-7 - 0.1)
            .collect();
        let keep = |i: usize| x[i] > 0.3;
        let dropped: Vec<usize> = (0..n).filter(|&i| !keep(i)).take(3).collect();
        y[dropped[0]] = f64::NAN;
        y[dropped[1]] = f64::INFINITY;
        y[dropped[2]] = -0.0;
        let kept = kept_table(&y, keep);
        for draw in 0..200 {
            let idx: Vec<usize> = (0..(draw % 50) * 10)
                .map(|_| (next() % n as u64) as usize)
                .collect();
            let (a, b) = (mean_where(&y, &idx, keep), mean_kept(&kept, &idx));
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{draw}: {a} against {b}"
            );
        }
        assert!(mean_kept(&kept, &[]).is_nan());
        assert!(mean_kept(&kept, &dropped).is_nan(), "none kept");
    }

    /// The definition of `robust_weighted_mean` computed directly: medians by selection over the
    /// values written out, then the Huber reweighting.
    fn by_selection(y: &[f64], se: &[f64]) -> f64 {
        use crate::stats::median_in_place;
        let median = |mut v: Vec<f64>| median_in_place(&mut v);
        let mid = median(y.to_vec());
        let mad = MAD_TO_SIGMA * median(y.iter().map(|v| (v - mid).abs()).collect());
        let typical_var = median(se.iter().map(|s| s * s).collect());
        let tau2 = (mad * mad - typical_var).max(0.0);
        let mut mean = mid;
        for _ in 0..20 {
            let (mut s, mut w) = (0.0, 0.0);
            for (yi, si) in y.iter().zip(se) {
                let var = si * si + tau2;
                let h = huber_weight((yi - mean).abs() / var.sqrt(), HUBER_K) / var;
                s += h * yi;
                w += h;
            }
            mean = s / w;
        }
        mean
    }

    #[test]
    fn one_wild_run_moves_the_robust_mean_by_less_than_its_share() {
        // nine runs around 0.30 (se 0.01) and one at 0.02 with a tiny error
        let mut y: Vec<f64> = (0..9).map(|i| 0.30 + 0.004 * (i as f64 - 4.0)).collect();
        let mut se = vec![0.01; 9];
        let idx: Vec<usize> = (0..10).collect();
        y.push(0.02);
        se.push(1e-4);
        let fixed = weighted_mean(&y, &se, &idx);
        let robust = robust_weighted_mean(&y, &se, &idx);
        // inverse-variance weights let it capture the mean; its share (1/10) would move it by 0.028
        assert!(fixed < 0.05, "{fixed}");
        // its share (1/10 of its 0.28 offset) would be 0.028; it moves the mean by far less
        assert!((robust - 0.30).abs() < 0.01, "{robust}");
        // counts are the same as the runs written out (a resample with repeats), for an even and
        // an odd number of picks (the medians' two conventions), the wild run in one of them
        for picks in [&[0, 0, 3, 5, 5, 5, 9, 2][..], &[0, 0, 1, 3, 5, 5, 5, 8, 2]] {
            let mut w = vec![0u16; 10];
            for &i in picks {
                w[i] += 1;
            }
            let written: Vec<f64> = picks.iter().map(|&i| y[i]).collect();
            let written_se: Vec<f64> = picks.iter().map(|&i| se[i]).collect();
            let all: Vec<usize> = (0..picks.len()).collect();
            let by_counts = RobustMean::new(&y, &se).of(&w);
            let written_out = robust_weighted_mean(&written, &written_se, &all);
            let selected = by_selection(&written, &written_se);
            // the reference reweights 20 times; the root is found exactly
            assert!(
                (by_counts - written_out).abs() < 1e-14 && (by_counts - selected).abs() < 1e-11,
                "{by_counts} {written_out} {selected}"
            );
        }
        // without a wild run it is the ordinary weighted mean
        let calm = robust_weighted_mean(&y[..9], &se[..9], &idx[..9]);
        assert!(
            (calm - weighted_mean(&y[..9], &se[..9], &idx[..9])).abs() < 2e-3,
            "{calm}"
        );
    }

    #[test]
    fn the_huber_root_is_where_the_reweighting_settles() {
        // (y, a, b) and a start: ordinary runs, a far one, and a start where no run lies within
        // its band (F is flat there, its slope 0: the first steps are bisections)
        let reweighted = |runs: &[[f64; 3]], start: f64| {
            let mut m = start;
            for _ in 0..2000 {
                let (mut s, mut w) = (0.0, 0.0);
                for &[y, a, b] in runs {
                    let h = a * huber_weight((y - m).abs() / b, 1.0);
                    s += h * y;
                    w += h;
                }
                m = s / w;
            }
            m
        };
        let sets: [(&[[f64; 3]], f64); 3] = [
            (
                &[
                    [0.30, 1.0, 0.02],
                    [0.31, 2.0, 0.01],
                    [0.33, 1.0, 0.03],
                    [0.34, 0.5, 0.02],
                ],
                0.31,
            ),
            (
                &[
                    [0.02, 100.0, 0.001],
                    [0.29, 1.0, 0.02],
                    [0.30, 1.0, 0.02],
                    [0.31, 1.0, 0.02],
                ],
                0.30,
            ),
            (&[[0.0, 1.0, 0.1], [1.0, 3.0, 0.1]], 0.5),
        ];
        for (runs, start) in sets {
            // at the third set's start both runs are outside their bands
            assert!(start != 0.5 || runs.iter().all(|&[y, _, b]| (y - start).abs() >= b));
            let (got, want) = (huber_root(runs, start), reweighted(runs, start));
            assert!((got - want).abs() <= 1e-13, "{runs:?}: {got} vs {want}");
            // F(got) = 0 up to rounding
            let f: f64 = runs
                .iter()
                .map(|&[y, a, b]| a * (y - got).clamp(-b, b))
                .sum();
            assert!(f.abs() < 1e-12, "{f}");
        }
    }

    #[test]
    fn counts_give_the_medians_of_the_runs_written_out_with_ties_and_outliers() {
        // 300 runs on a coarse grid (many equal values and distances), some far out, and
        // resamples of every size parity; the reference takes every median by selection
        let mut state = 99u64;
        let mut next = |m: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % m
        };
        let n = 300;
        let y: Vec<f64> = (0..n)
            .map(|i| match i % 25 {
                0 => 0.9,
                _ => 0.3 + 0.001 * next(20) as f64,
            })
            .collect();
        let se: Vec<f64> = (0..n).map(|_| 0.001 * (1 + next(5)) as f64).collect();
        let robust = RobustMean::new(&y, &se);
        for picks in [n, n - 1, 7, 8, 1, 2] {
            let idx: Vec<usize> = (0..picks).map(|_| next(n as u64) as usize).collect();
            let mut w = vec![0u16; n];
            for &i in &idx {
                w[i] += 1;
            }
            let written: Vec<f64> = idx.iter().map(|&i| y[i]).collect();
            let written_se: Vec<f64> = idx.iter().map(|&i| se[i]).collect();
            let (got, want) = (robust.of(&w), by_selection(&written, &written_se));
            assert!(
                (got - want).abs() <= 1e-12 * want.abs(),
                "{picks} picks: {got} {want}"
            );
        }
    }
}
