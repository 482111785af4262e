//! Theil–Sen intercepts of bootstrap resamples without a selection over every pick: the points
//! sorted once by their residual from the estimate's line, and a resample's median read from a
//! short stretch of that order.
//!
//! A resample's intercept is the median of y_i − b·x_i over its picks, for its own slope b, which
//! lies close to the estimate's b₀. Each value is the point's residual r_i = y_i − b₀·x_i moved by
//! (b₀ − b)·x_i, so two points' values differ from their residuals' difference by at most
//! 2D = |b − b₀|·(max x − min x) (plus a margin for rounding). A point whose residual lies more
//! than 2D below that of the point holding the wanted rank (in the residual order, counted with
//! the resample's multiplicities) is below the wanted value, and one more than 2D above is above
//! it; only the points between need their values computed and ordered. The
//! result is the value `theil_sen_intercept` selects from the written-out picks, bit for bit (unit
//! test). When that stretch is long (a slope far from b₀), the caller selects as before.

/// Points in ascending order of their residual from a line of slope b₀.
pub struct InterceptOrder {
    b0: f64,
    /// The residuals y − b₀·x of the finite points, ascending, and the points they belong to.
    r: Vec<f64>,
    at: Vec<u32>,
    /// Points with a non-finite x or y (a resample holding one is left to the selection).
    bad: Vec<u32>,
    /// Half the range of the finite x, and the largest |x| and |y| (for the rounding margin).
    half_range_x: f64,
    max_abs_x: f64,
    max_abs_y: f64,
}

impl InterceptOrder {
    pub fn new(x: &[f64], y: &[f64], b0: f64) -> Self {
        let finite = |i: usize| x[i].is_finite() && y[i].is_finite();
        let mut keyed: Vec<(f64, u32)> = (0..x.len())
            .filter(|&i| finite(i))
            .map(|i| (y[i] - b0 * x[i], i as u32))
            .collect();
        keyed.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let max_abs = |v: &[f64]| {
            v.iter()
                .filter(|a| a.is_finite())
                .fold(0.0f64, |m, a| m.max(a.abs()))
        };
        let xs = || x.iter().filter(|a| a.is_finite());
        let (lo, hi) = (
            xs().copied().fold(f64::INFINITY, f64::min),
            xs().copied().fold(f64::NEG_INFINITY, f64::max),
        );
        InterceptOrder {
            half_range_x: if hi >= lo { 0.5 * (hi - lo) } else { 0.0 },
            b0,
            r: keyed.iter().map(|k| k.0).collect(),
            at: keyed.iter().map(|k| k.1).collect(),
            bad: (0..x.len())
                .filter(|&i| !finite(i))
                .map(|i| i as u32)
                .collect(),
            max_abs_x: max_abs(x),
            max_abs_y: max_abs(y),
        }
    }

    /// The median of y_i − b·x_i over `picks` picks where point i counts `w[i]` times (the mean
    /// of the two middle values for an even count), as `theil_sen_intercept` gives it on the
    /// picks written out; `None` when this order cannot tell it cheaply (a non-finite b, a bad
    /// point drawn, no pick, or a slope so far from b₀ that the stretch to order is long): then
    /// select.
    pub fn median(
        &self,
        (x, y): (&[f64], &[f64]),
        w: &[u16],
        picks: usize,
        b: f64,
        buf: &mut Vec<(f64, u16)>,
    ) -> Option<f64> {
        let n = self.r.len();
        if !b.is_finite() || !self.b0.is_finite() || picks == 0 || n == 0 {
            return None;
        }
        if self.bad.iter().any(|&i| w[i as usize] > 0) {
            return None;
        }
        let total = picks as u64;
        let (r_lo, r_hi) = match total % 2 {
            1 => (total / 2, total / 2),
            _ => (total / 2 - 1, total / 2),
        };
        let (mx, my) = (self.max_abs_x, self.max_abs_y);
        let d = (b - self.b0).abs() * self.half_range_x * (1.0 + 1e-12)
            + 1e-12 * (my + (b.abs() + self.b0.abs()) * mx)
            + f64::MIN_POSITIVE;
        let weight = |p: usize| u64::from(w[self.at[p] as usize]);
        // the positions holding ranks r_lo and r_hi in the residual order
        let (mut p, mut before) = (0usize, 0u64);
        let mut p_lo = None;
        let mut before_lo = 0;
        while p < n {
            let c = weight(p);
            if p_lo.is_none() && before + c > r_lo {
                p_lo = Some(p);
                before_lo = before;
            }
            if before + c > r_hi {
                break;
            }
            before += c;
            p += 1;
        }
        let (p_lo, p_hi) = (p_lo?, p);
        if p_hi >= n {
            return None;
        }
        let (lo_val, hi_val) = (self.r[p_lo] - 2.0 * d, self.r[p_hi] + 2.0 * d);
        let start = self.r.partition_point(|&v| v < lo_val);
        let end = self.r.partition_point(|&v| v <= hi_val);
        if end - start > (n / 8).max(64) {
            return None;
        }
        // the weight below the stretch: that before p_lo less what lies in start..p_lo
        let below = before_lo - (start..p_lo).map(weight).sum::<u64>();
        buf.clear();
        for q in start..end {
            let i = self.at[q] as usize;
            if w[i] > 0 {
                buf.push((y[i] - b * x[i], w[i]));
            }
        }
        buf.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let mut seen = below;
        let (mut lo, mut hi) = (None, None);
        for &(v, c) in buf.iter() {
            let c = u64::from(c);
            if lo.is_none() && seen + c > r_lo {
                lo = Some(v);
            }
            if seen + c > r_hi {
                hi = Some(v);
                break;
            }
            seen += c;
        }
        let (lo, hi) = (lo?, hi?);
        Some(match total % 2 {
            1 => hi,
            _ => 0.5 * (lo + hi),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stats::theil_sen_intercept;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn a_resamples_intercept_is_the_selected_one_bit_for_bit() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for n in [1usize, 2, 7, 60, 3000] {
            let x: Vec<f64> = (0..n).map(|_| rng.random_range(0.005..0.1)).collect();
            // scattered values rounded to 1e-4, so that ties and equal residuals occur
            let mut y: Vec<f64> = x
                .iter()
                .map(|v| {
                    let e: f64 = rng.random_range(-0.005..0.005);
                    0.02 + 0.3 * v + (e * 1e4).round() * 1e-4
                })
                .collect();
            if n > 10 {
                y[3] = y[2];
            }
            let order = InterceptOrder::new(&x, &y, 0.3);
            let (mut buf, mut pairs) = (Vec::new(), Vec::new());
            let mut told = 0;
            for trial in 0..200 {
                let picks = match trial % 3 {
                    0 => n,
                    1 => n + 1,
                    _ => 1 + rng.random_range(0..n),
                };
                let idx: Vec<usize> = (0..picks).map(|_| rng.random_range(0..n)).collect();
                let mut w = vec![0u16; n];
                for &i in &idx {
                    w[i] += 1;
                }
                // slopes near b₀, and some far from it
                let b = match trial % 10 {
                    9 => 0.3 + rng.random_range(-5.0..5.0),
                    _ => 0.3 + rng.random_range(-0.005..0.005),
                };
                let want = theil_sen_intercept(&x, &y, &idx, b, &mut buf);
                if let Some(got) = order.median((&x, &y), &w, idx.len(), b, &mut pairs) {
                    assert_eq!(got.to_bits(), want.to_bits(), "n {n} trial {trial} b {b}");
                    told += 1;
                }
            }
            if n >= 60 {
                assert!(told > 150, "n {n}: only {told} of 200 told by the order");
            }
        }
    }

    #[test]
    fn a_drawn_non_finite_point_is_left_to_the_selection() {
        let x = [0.01, 0.02, 0.03, 0.04];
        let y = [0.1, f64::NAN, 0.12, 0.13];
        let order = InterceptOrder::new(&x, &y, 1.0);
        let mut buf = Vec::new();
        assert!(order
            .median((&x, &y), &[1, 1, 1, 1], 4, 1.0, &mut buf)
            .is_none());
        let got = order.median((&x, &y), &[1, 0, 1, 1], 3, 1.0, &mut buf);
        assert_eq!(got, Some(0.12 - 0.03));
    }
}
