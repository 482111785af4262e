//! The screen's linear algebra: each run's projected residual and noise replicates (`Vectors`),
//! and the sums over runs and replicates from which a trial's statistic, estimate and null law
//! are solved (`Sums`), with the noise covariance they need; the shared parameters' information
//! with each run's locals projected out (`shared_information`) also gives the joint fit its
//! errors where its covariance is singular (`profiled_se`). A searched form's grid of trials
//! is scanned in blocks (`coherent_scan`), each block reading a run's replicates once.

use super::data::RunData;
use super::response::Prepared;
use crate::lsq::dense::{chol_inverse, cholesky_jittered};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::ops::Range;

/// Each run's data residual (replicate 0) and noise replicates, projected and in noise units.
pub struct Vectors {
    /// `[run][b]`, each over the run's kept samples.
    pub(super) y: Vec<Vec<Vec<f64>>>,
    /// The shared parameters profiled: kept columns, (G'G)⁻¹ and G'y per replicate.
    pub(super) kept: Vec<usize>,
    pub(super) ginv: Vec<f64>,
    pub(super) gty: Vec<Vec<f64>>,
}

impl Vectors {
    pub fn new(prep: &[Prepared], runs: &[RunData], replicates: usize, seed: u64) -> Vectors {
        let y: Vec<Vec<Vec<f64>>> = prep
            .par_iter()
            .map(|p| {
                let run = &runs[p.run];
                let n = p.y.len();
                let mut out = Vec::with_capacity(replicates + 1);
                out.push(p.y.clone());
                let noise = run.noise();
                for b in 0..replicates {
                    let mut rng = ChaCha8Rng::seed_from_u64(
                        seed ^ (((p.run as u64) << 20) | (b as u64 + 1))
                            .wrapping_mul(0x9E37_79B9_7F4A_7C15),
                    );
                    let mut v = noise.replicate(n, &mut rng);
                    p.proj.apply(&mut v);
                    out.push(v);
                }
                out
            })
            .collect();
        let (kept, gtg) = shared_information(prep);
        let k = kept.len();
        let mut gty = vec![vec![0.0; k]; replicates + 1];
        for (p, yr) in prep.iter().zip(&y) {
            for (a, &ja) in kept.iter().enumerate() {
                for (bb, yb) in yr.iter().enumerate() {
                    gty[bb][a] += dot(&p.glob[ja], yb);
                }
            }
        }
        let ginv = if k == 0 {
            vec![]
        } else {
            match cholesky_jittered(&gtg, k) {
                Some(l) => chol_inverse(&l, k),
                None => vec![0.0; k * k],
            }
        };
        Vectors { y, kept, ginv, gty }
    }

    pub(super) fn n_rep(&self) -> usize {
        self.y.first().map(|r| r.len()).unwrap_or(1)
    }
}

/// The shared parameters' information with each run's z0, t0, v0 projected out: the columns
/// some run's data move (`kept`) and Σ G'G over the runs on them (k × k, row-major).
fn shared_information(prep: &[Prepared]) -> (Vec<usize>, Vec<f64>) {
    let ng = prep.first().map_or(0, |p| p.glob.len());
    let kept: Vec<usize> = (0..ng)
        .filter(|&j| prep.iter().any(|p| p.glob[j].iter().any(|x| *x != 0.0)))
        .collect();
    let k = kept.len();
    let mut gtg = vec![0.0; k * k];
    for p in prep {
        for (a, &ja) in kept.iter().enumerate() {
            for (b, &jb) in kept.iter().enumerate() {
                gtg[a * k + b] += dot(&p.glob[ja], &p.glob[jb]);
            }
        }
    }
    (kept, gtg)
}

/// Standard errors of the shared parameters (in their own units, the residuals weighed by each
/// run's noise) from `shared_information`, inverted (the caller scales them by χ² per degree of
/// freedom): NaN for a parameter no run's data moves, or when the information is singular. The
/// projector drops a local the data cannot tell from the others, where a Schur complement over
/// the runs' 3×3 blocks would have to invert it.
pub(super) fn profiled_se(prep: &[Prepared]) -> Vec<f64> {
    let ng = prep.first().map_or(0, |p| p.glob.len());
    let (kept, gtg) = shared_information(prep);
    let k = kept.len();
    let mut se = vec![f64::NAN; ng];
    if let Some(l) = crate::lsq::dense::cholesky(&gtg, k) {
        let inv = chol_inverse(&l, k);
        for (a, &j) in kept.iter().enumerate() {
            se[j] = inv[a * k + a].max(0.0).sqrt();
        }
    }
    se
}

/// Σ aᵢbᵢ in four interleaved partial sums (a fixed order, so the same bits every time; four
/// chains instead of one keep the additions from waiting on each other).
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        s[0] += x[0] * y[0];
        s[1] += x[1] * y[1];
        s[2] += x[2] * y[2];
        s[3] += x[3] * y[3];
    }
    for (x, y) in ra.iter().zip(rb) {
        s[0] += x * y;
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// (Σ aᵢcᵢ, Σ bᵢcᵢ) in one pass over `c`, each in two interleaved partial sums.
pub(super) fn dot2(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    let n = a.len().min(b.len()).min(c.len());
    let (a, b, c) = (&a[..n], &b[..n], &c[..n]);
    let mut s = [0.0f64; 4];
    let (ca, cb, cc) = (a.chunks_exact(2), b.chunks_exact(2), c.chunks_exact(2));
    let (ra, rb, rc) = (ca.remainder(), cb.remainder(), cc.remainder());
    for ((x, y), z) in ca.zip(cb).zip(cc) {
        s[0] += x[0] * z[0];
        s[1] += x[1] * z[1];
        s[2] += y[0] * z[0];
        s[3] += y[1] * z[1];
    }
    for ((x, y), z) in ra.iter().zip(rb).zip(rc) {
        s[0] += x * z;
        s[2] += y * z;
    }
    (s[0] + s[1], s[2] + s[3])
}

/// `(dot2(a, b, y0), dot2(a, b, y1))` in one pass over `a` and `b`, each summed in `dot2`'s
/// order (the same bits): the columns are read once for two replicates.
pub(super) fn dot2_twice(a: &[f64], b: &[f64], y0: &[f64], y1: &[f64]) -> ((f64, f64), (f64, f64)) {
    let n = a.len().min(b.len()).min(y0.len()).min(y1.len());
    if y0.len() != y1.len() {
        return (dot2(a, b, y0), dot2(a, b, y1));
    }
    let (a, b, y0, y1) = (&a[..n], &b[..n], &y0[..n], &y1[..n]);
    let (mut s, mut t) = ([0.0f64; 4], [0.0f64; 4]);
    let (ca, cb) = (a.chunks_exact(2), b.chunks_exact(2));
    let (c0, c1) = (y0.chunks_exact(2), y1.chunks_exact(2));
    let (ra, rb, r0, r1) = (
        ca.remainder(),
        cb.remainder(),
        c0.remainder(),
        c1.remainder(),
    );
    for (((x, y), z), w) in ca.zip(cb).zip(c0).zip(c1) {
        s[0] += x[0] * z[0];
        s[1] += x[1] * z[1];
        s[2] += y[0] * z[0];
        s[3] += y[1] * z[1];
        t[0] += x[0] * w[0];
        t[1] += x[1] * w[1];
        t[2] += y[0] * w[0];
        t[3] += y[1] * w[1];
    }
    for (((x, y), z), w) in ra.iter().zip(rb).zip(r0).zip(r1) {
        s[0] += x * z;
        s[2] += y * z;
        t[0] += x * w;
        t[2] += y * w;
    }
    ((s[0] + s[1], s[2] + s[3]), (t[0] + t[1], t[2] + t[3]))
}

/// `(dot(a, y0), dot(a, y1))` in one pass over `a`, each summed in `dot`'s order.
pub(super) fn dot_twice(a: &[f64], y0: &[f64], y1: &[f64]) -> (f64, f64) {
    if y0.len() != y1.len() {
        return (dot(a, y0), dot(a, y1));
    }
    let n = a.len().min(y0.len());
    let (a, y0, y1) = (&a[..n], &y0[..n], &y1[..n]);
    let (mut s, mut t) = ([0.0f64; 4], [0.0f64; 4]);
    let (ca, c0, c1) = (a.chunks_exact(4), y0.chunks_exact(4), y1.chunks_exact(4));
    let (ra, r0, r1) = (ca.remainder(), c0.remainder(), c1.remainder());
    for ((x, z), w) in ca.zip(c0).zip(c1) {
        for k in 0..4 {
            s[k] += x[k] * z[k];
            t[k] += x[k] * w[k];
        }
    }
    for ((x, z), w) in ra.iter().zip(r0).zip(r1) {
        s[0] += x * z;
        t[0] += x * w;
    }
    ((s[0] + s[1]) + (s[2] + s[3]), (t[0] + t[1]) + (t[2] + t[3]))
}

/// Sums over runs for a set of q columns shared by every run (coherent), against the
/// replicates `reps` (indices into `Vectors::y`; 0 is the data).
pub(super) struct Sums {
    pub(super) q: usize,
    pub(super) reps: Range<usize>,
    pub(super) xtx: Vec<f64>,
    pub(super) xtg: Vec<f64>,
    pub(super) xty: Vec<Vec<f64>>,
}

impl Sums {
    pub(super) fn new(q: usize, k: usize, reps: Range<usize>) -> Sums {
        Sums {
            q,
            xtx: vec![0.0; q * q],
            xtg: vec![0.0; q * k],
            xty: vec![vec![0.0; q]; reps.len()],
            reps,
        }
    }

    pub(super) fn add(&mut self, cols: &[Vec<f64>], p: &Prepared, v: &Vectors, yr: &[Vec<f64>]) {
        self.add_design(cols, p, v);
        for (r, yb) in yr[self.reps.clone()].iter().enumerate() {
            self.add_replicate(r, cols, yb);
        }
    }

    /// A run's columns against each other and against the shared parameters' columns.
    pub(super) fn add_design(&mut self, cols: &[Vec<f64>], p: &Prepared, v: &Vectors) {
        let (q, k) = (self.q, v.kept.len());
        for a in 0..q {
            for b in a..q {
                let s = dot(&cols[a], &cols[b]);
                self.xtx[a * q + b] += s;
                if a != b {
                    self.xtx[b * q + a] += s;
                }
            }
            for (g, &jg) in v.kept.iter().enumerate() {
                self.xtg[a * k + g] += dot(&cols[a], &p.glob[jg]);
            }
        }
    }

    /// A run's projections `b` (one per column) on replicate `r` of `reps`, computed by the
    /// caller (`time_scan`, which shares them between two forms).
    pub(super) fn add_projections(&mut self, r: usize, b: &[f64]) {
        for (x, b) in self.xty[r].iter_mut().zip(b) {
            *x += b;
        }
    }

    /// `add_replicate` for replicates `r` and `r + 1` (`y0`, `y1`), the columns read once.
    fn add_replicates_two(&mut self, r: usize, cols: &[Vec<f64>], y0: &[f64], y1: &[f64]) {
        let q = self.q;
        let (lo, hi) = self.xty.split_at_mut(r + 1);
        let (x0, x1) = (&mut lo[r], &mut hi[0]);
        let mut a = 0;
        while a + 1 < q {
            let ((s0, s1), (t0, t1)) = dot2_twice(&cols[a], &cols[a + 1], y0, y1);
            x0[a] += s0;
            x0[a + 1] += s1;
            x1[a] += t0;
            x1[a + 1] += t1;
            a += 2;
        }
        if a < q {
            let (s, t) = dot_twice(&cols[a], y0, y1);
            x0[a] += s;
            x1[a] += t;
        }
    }

    /// A run's columns against its replicate `r` of `reps` (`yb`): one pass over the
    /// replicate for two columns at a time.
    fn add_replicate(&mut self, r: usize, cols: &[Vec<f64>], yb: &[f64]) {
        let (q, xty) = (self.q, &mut self.xty[r]);
        let mut a = 0;
        while a + 1 < q {
            let (s0, s1) = dot2(&cols[a], &cols[a + 1], yb);
            xty[a] += s0;
            xty[a + 1] += s1;
            a += 2;
        }
        if a < q {
            xty[a] += dot(&cols[a], yb);
        }
    }

    /// LR per replicate of `reps`, the data's coefficients (zero when the data is not among
    /// `reps`) and their variances (shared parameters profiled). `sign`, for a single column
    /// whose parameter starts at a bound (a drag slope or a resistance that vanishes at 0 and
    /// cannot go below), is the direction the coefficient may take: a fit pushed the other way
    /// stays at the bound, so that replicate's statistic is 0 (the one-sided, χ̄² test), in the
    /// data and in the null alike. Empty, or several columns: two-sided.
    pub(super) fn solve(
        &self,
        v: &Vectors,
        sign: &[f64],
    ) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let one_sided = one_sided(self.q, sign);
        let q = self.q;
        let (xg_ginv, am, dead) = self.profiled(v)?;
        let l = cholesky_jittered(&am, q)?;
        let inv = chol_inverse(&l, q);
        let k = v.kept.len();
        let mut lr = Vec::with_capacity(self.xty.len());
        let mut beta0 = vec![0.0; q];
        for (bb, xty) in self.xty.iter().enumerate() {
            let c: Vec<f64> = (0..q)
                .map(|a| {
                    if dead[a] {
                        0.0
                    } else {
                        xty[a]
                            - (0..k)
                                .map(|d| xg_ginv[a * k + d] * v.gty[self.reps.start + bb][d])
                                .sum::<f64>()
                    }
                })
                .collect();
            let beta: Vec<f64> = (0..q)
                .map(|a| (0..q).map(|b| inv[a * q + b] * c[b]).sum())
                .collect();
            let infeasible = one_sided.is_some_and(|s| beta[0] * s < 0.0);
            lr.push(if infeasible {
                0.0
            } else {
                dot(&beta, &c).max(0.0)
            });
            if self.reps.start + bb == 0 {
                beta0 = if infeasible { vec![0.0] } else { beta };
            }
        }
        let var = (0..q)
            .map(|a| if dead[a] { f64::NAN } else { inv[a * q + a] })
            .collect();
        Some((lr, beta0, var))
    }

    /// The profile of the shared parameters: X'G(G'G)⁻¹ (q × k) and A = X'X − X'G(G'G)⁻¹G'X,
    /// with the columns the form cannot move (outside every run, or absorbed by the shared
    /// parameters) set aside as dead (a unit row and column of A, not inverted); None when every
    /// column is dead.
    pub(super) fn profiled(&self, v: &Vectors) -> Option<(Vec<f64>, Vec<f64>, Vec<bool>)> {
        let (q, k) = (self.q, v.kept.len());
        let mut xg_ginv = vec![0.0; q * k];
        for a in 0..q {
            for c in 0..k {
                xg_ginv[a * k + c] = (0..k)
                    .map(|d| self.xtg[a * k + d] * v.ginv[d * k + c])
                    .sum();
            }
        }
        let mut am = self.xtx.clone();
        for a in 0..q {
            for b in 0..q {
                am[a * q + b] -= (0..k)
                    .map(|c| xg_ginv[a * k + c] * self.xtg[b * k + c])
                    .sum::<f64>();
            }
        }
        // a column the form cannot move (outside every run, or absorbed by the shared
        // parameters) carries nothing: it is set aside, not inverted
        let dead: Vec<bool> = (0..q)
            .map(|a| !(am[a * q + a] > 1e-9 * self.xtx[a * q + a] && self.xtx[a * q + a] > 0.0))
            .collect();
        if dead.iter().all(|d| *d) {
            return None;
        }
        for a in 0..q {
            if dead[a] {
                for b in 0..q {
                    am[a * q + b] = 0.0;
                    am[b * q + a] = 0.0;
                }
                am[a * q + a] = 1.0;
            }
        }
        Some((xg_ginv, am, dead))
    }

    /// The moments of the statistic under the noise model (`ExactNull`): `cols(p)` gives a run's
    /// columns as `add` took them, or None where the form cannot act.
    pub(super) fn null_moments<'c>(
        &self,
        v: &Vectors,
        prep: &[Prepared],
        runs: &[RunData],
        cols: impl Fn(&Prepared) -> Option<&'c [Vec<f64>]>,
    ) -> Option<(f64, f64)> {
        let (q, k) = (self.q, v.kept.len());
        let (xg_ginv, am, dead) = self.profiled(v)?;
        let inv = chol_inverse(&cholesky_jittered(&am, q)?, q);
        let mut c = vec![0.0; q * q];
        for p in prep {
            let Some(x) = cols(p) else { continue };
            let noise = runs[p.run].noise();
            let profiled: Vec<Vec<f64>> = (0..q)
                .map(|a| {
                    let mut col = x[a].clone();
                    if dead[a] {
                        col.iter_mut().for_each(|z| *z = 0.0);
                        return col;
                    }
                    for (d, &j) in v.kept.iter().enumerate() {
                        let f = xg_ginv[a * k + d];
                        for (z, g) in col.iter_mut().zip(&p.glob[j]) {
                            *z -= f * g;
                        }
                    }
                    col
                })
                .collect();
            for a in 0..q {
                for b in a..q {
                    let s = noise.cross(&profiled[a], &profiled[b]);
                    c[a * q + b] += s;
                    if a != b {
                        c[b * q + a] += s;
                    }
                }
            }
        }
        // M = A⁻¹C: its trace and the trace of its square
        let m: Vec<f64> = (0..q * q)
            .map(|ab| {
                let (a, b) = (ab / q, ab % q);
                (0..q).map(|d| inv[a * q + d] * c[d * q + b]).sum()
            })
            .collect();
        let mean: f64 = (0..q).filter(|a| !dead[*a]).map(|a| m[a * q + a]).sum();
        let square: f64 = (0..q * q).map(|ab| m[ab] * m[(ab % q) * q + ab / q]).sum();
        (mean > 0.0 && square > 0.0).then_some((mean, 2.0 * square))
    }
}

/// One trial of a form: LR per replicate, with the estimate and se it gives on the data.
pub(super) type Trial = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The elementwise maximum over trials; the estimate is the data's best trial's.
pub(super) fn best_of(trials: Vec<Option<Trial>>, nrep: usize) -> Option<Trial> {
    let mut lr = vec![0.0f64; nrep];
    let mut best: Option<(f64, Vec<f64>, Vec<f64>)> = None;
    for (t_lr, est, se) in trials.into_iter().flatten() {
        for (m, x) in lr.iter_mut().zip(&t_lr) {
            *m = m.max(*x);
        }
        if best.as_ref().is_none_or(|b| t_lr[0] > b.0) {
            best = Some((t_lr[0], est, se));
        }
    }
    best.map(|(_, est, se)| (lr, est, se))
}

/// The one-sided direction of a single column whose parameter starts at a bound (`sign`, as
/// `Sums::solve` takes it), None for a two-sided test.
pub(super) fn one_sided(q: usize, sign: &[f64]) -> Option<f64> {
    match sign {
        [s] if *s != 0.0 && q == 1 => Some(*s),
        _ => None,
    }
}

/// The sums of a coherent trial: the same columns' coefficients in every run; `cols(p)` gives a
/// run's columns (already in noise units with its locals projected) or None where the form
/// cannot act.
pub(super) fn coherent_sums<F>(
    prep: &[Prepared],
    v: &Vectors,
    q: usize,
    reps: Range<usize>,
    cols: F,
) -> Sums
where
    F: Fn(&Prepared) -> Option<Vec<Vec<f64>>>,
{
    let mut s = Sums::new(q, v.kept.len(), reps);
    for (p, yr) in prep.iter().zip(&v.y) {
        if let Some(c) = cols(p) {
            s.add(&c, p, v, yr);
        }
    }
    s
}

/// Trials per pass over a run's replicates in `coherent_scan` (at most).
const SCAN_BLOCK: usize = 16;

/// How many of `trials` a scan takes per pass over a run's replicates: at most `SCAN_BLOCK`,
/// and few enough that every core has several blocks. The bits do not depend on it.
pub(super) fn scan_block(trials: usize) -> usize {
    (trials / (4 * rayon::current_num_threads()).max(1)).clamp(1, SCAN_BLOCK)
}

/// `coherent` at every trial `x` of `grid` (`cols(p, x)` a run's columns there), the same
/// numbers trial by trial, but a run's replicates are read once for a block of trials instead
/// of once per trial: they are tens of megabytes over the runs, far more than the caches
/// hold, and reading them was the scan's cost.
pub(super) fn coherent_scan<X, F>(
    prep: &[Prepared],
    v: &Vectors,
    q: usize,
    reps: Range<usize>,
    grid: &[X],
    cols: F,
) -> Vec<Option<(Vec<f64>, Vec<f64>, Vec<f64>)>>
where
    X: Sync,
    F: Fn(&Prepared, &X) -> Option<Vec<Vec<f64>>> + Sync,
{
    coherent_scan_blocks(prep, v, q, reps, grid, |p, xs| {
        xs.iter().map(|x| cols(p, x)).collect()
    })
}

/// `coherent_scan` with a run's columns made for a block of consecutive trials at once
/// (`cols(p, xs)`, one entry per trial of `xs`), for columns that are cheaper made in sequence
/// (a wave's values at successive wavenumbers, by rotation).
pub(super) fn coherent_scan_blocks<X, F>(
    prep: &[Prepared],
    v: &Vectors,
    q: usize,
    reps: Range<usize>,
    grid: &[X],
    cols: F,
) -> Vec<Option<(Vec<f64>, Vec<f64>, Vec<f64>)>>
where
    X: Sync,
    F: Fn(&Prepared, &[X]) -> Vec<Option<Vec<Vec<f64>>>> + Sync,
{
    grid.par_chunks(scan_block(grid.len()))
        .flat_map_iter(|xs| {
            let mut sums: Vec<Sums> = xs
                .iter()
                .map(|_| Sums::new(q, v.kept.len(), reps.clone()))
                .collect();
            for (p, yr) in prep.iter().zip(&v.y) {
                let c = cols(p, xs);
                for (s, c) in sums.iter_mut().zip(&c) {
                    if let Some(c) = c {
                        s.add_design(c, p, v);
                    }
                }
                // two replicates at a time: each column is read once for both
                let ys = &yr[reps.clone()];
                for (pair, two) in ys.chunks(2).enumerate() {
                    for (s, c) in sums.iter_mut().zip(&c) {
                        match (c, two) {
                            (Some(c), [y0, y1]) => s.add_replicates_two(2 * pair, c, y0, y1),
                            (Some(c), [y0]) => s.add_replicate(2 * pair, c, y0),
                            _ => {}
                        }
                    }
                }
            }
            sums.into_iter()
                .map(|s| s.solve(v, &[]))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// Coherent trial (`coherent_sums`) solved.
pub(super) fn coherent<F>(
    prep: &[Prepared],
    v: &Vectors,
    q: usize,
    reps: Range<usize>,
    sign: &[f64],
    cols: F,
) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)>
where
    F: Fn(&Prepared) -> Option<Vec<Vec<f64>>>,
{
    coherent_sums(prep, v, q, reps, cols).solve(v, sign)
}

/// The information about a searched form's size at its most sensitive trial (the grid's trial
/// of most information: a long wavelength, a wide bump, a low frequency), with that trial in
/// words; not the trial the data liked best, whose information can be anything from the grid's
/// best to its worst (a frequency near the Nyquist limit hardly moves the positions).
#[derive(Clone, Debug)]
pub enum Typical {
    /// Standard error of the size (an amplitude) of a form coherent over the runs.
    Se { se: f64, at: String },
    /// Each run's information a_r about the amplitude of a force periodic in time with a phase
    /// per run (`time_periodic`), and the data's noise floor there (≥ 1: how far the data's
    /// statistic runs above the replicates' around that frequency, `noise_floor.rs`).
    PerRun { a: Vec<f64>, floor: f64, at: String },
}

/// The trial of least standard error `se_of(trial's se)` (the first of equals).
pub(super) fn most_sensitive(
    trials: &[Option<Trial>],
    se_of: impl Fn(&[f64]) -> f64,
) -> Option<(f64, &Trial)> {
    let mut best: Option<(f64, &Trial)> = None;
    for t in trials.iter().flatten() {
        let se = se_of(&t.2);
        if se.is_finite() && best.is_none_or(|b| se < b.0) {
            best = Some((se, t));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_four_chain_dot_products_agree_with_the_plain_sums() {
        let a: Vec<f64> = (0..37).map(|i| (i as f64 * 0.7).sin()).collect();
        let b: Vec<f64> = (0..37).map(|i| (i as f64 * 0.3).cos()).collect();
        let c: Vec<f64> = (0..37).map(|i| 1.0 / (1.0 + i as f64)).collect();
        let plain = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(p, q)| p * q).sum::<f64>();
        assert!((dot(&a, &c) - plain(&a, &c)).abs() < 1e-13);
        let (s, t) = dot2(&a, &b, &c);
        assert!((s - plain(&a, &c)).abs() < 1e-13);
        assert!((t - plain(&b, &c)).abs() < 1e-13);
        // two replicates in one pass give each one's bits, odd and even lengths alike
        for n in [32, 33, 34, 35] {
            let (y0, y1) = (&c[..n], &a[1..n + 1]);
            let ((s0, s1), (t0, t1)) = dot2_twice(&a[..n], &b[..n], y0, y1);
            let (w0, w1) = (dot2(&a[..n], &b[..n], y0), dot2(&a[..n], &b[..n], y1));
            assert_eq!(
                [s0, s1, t0, t1].map(f64::to_bits),
                [w0.0, w0.1, w1.0, w1.1].map(f64::to_bits)
            );
            let (u, v) = dot_twice(&b[..n], y0, y1);
            assert_eq!(
                [u, v].map(f64::to_bits),
                [dot(&b[..n], y0), dot(&b[..n], y1)].map(f64::to_bits)
            );
        }
    }
}
