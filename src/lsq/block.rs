//! The block-arrow back-end of the [`lm`] driver: shared parameters plus one block of
//! own parameters per group of residuals (a run), forward-difference Jacobians per block in
//! parallel (but for the columns a problem knows in closed form or to first order, its
//! `own_column` and `known_columns`), and the normal equations solved through the Schur
//! complement on the shared parameters. Residuals are expected whitened (in units of each run's
//! noise), so the cost is a χ²-like deviance.

use super::dense;
use super::fd::inward_step;
use super::lm::{self, Model, Normal, ParamSpec, Settings};
use super::Termination;
use rayon::prelude::*;

/// A problem with shared parameters and one block of own parameters per run.
pub trait BlockProblem: Sync {
    fn n_blocks(&self) -> usize;
    /// Number of residuals of block `b`.
    fn n_residuals(&self, b: usize) -> usize;
    /// Whitened residuals of block `b` at shared `shared` and own `own`.
    fn residuals(&self, b: usize, shared: &[f64], own: &[f64], out: &mut [f64]);
    /// Whether block `b` depends on shared parameter `i` (false skips its derivative).
    fn uses(&self, _b: usize, _i: usize) -> bool {
        true
    }
    /// ∂r_b/∂own_k at `shared`, `own` into `out` when the problem knows it in closed form (then
    /// true, and the back-end skips that forward difference); false, the default, to difference.
    fn own_column(
        &self,
        _b: usize,
        _k: usize,
        _shared: &[f64],
        _own: &[f64],
        _out: &mut [f64],
    ) -> bool {
        false
    }
    /// Block `b`'s residuals for the forward differences of its Jacobian at (`shared`, `own`),
    /// when they differ from [`BlockProblem::residuals`]: a problem that profiles a parameter of
    /// its own out of each block's residuals (fits it inside each prediction) holds it at the
    /// point's value here, one evaluation a column instead of a profile, and projects its
    /// direction out of every column (Kaufman's variable projection: the same derivatives to
    /// first order). None, the default, differences the residuals themselves.
    fn linearize(&self, _b: usize, _shared: &[f64], _own: &[f64]) -> Option<Box<dyn Linear + '_>> {
        None
    }
    /// Block `b`'s columns at (`shared`, `own`) that the problem knows to first order without a
    /// difference (None entries are differenced): parameters that enter the model linearly,
    /// whose columns one linearization of the block gives all at once. Used for the steps; the
    /// covariance at the minimum differences every column. None, the default, differences
    /// them all.
    fn known_columns(&self, _b: usize, _shared: &[f64], _own: &[f64]) -> Option<Known> {
        None
    }
}

/// Columns a problem knows without differences (`BlockProblem::known_columns`), by shared and
/// by own index.
pub struct Known {
    pub shared: Vec<Option<Vec<f64>>>,
    pub own: Vec<Option<Vec<f64>>>,
}

/// A block's residuals with a profiled parameter held (`BlockProblem::linearize`).
pub trait Linear {
    /// The residuals at (`shared`, `own`) with the profiled parameter held.
    fn residuals(&self, shared: &[f64], own: &[f64], out: &mut [f64]);
    /// Turn a column at the held value into the profiled residuals' column.
    fn project(&self, column: &mut [f64]);
}

/// The solution.
#[derive(Debug, Clone)]
pub struct BlockResult {
    pub shared: Vec<f64>,
    pub own: Vec<Vec<f64>>,
    /// Covariance of the shared parameters (NaN when singular, 0 rows for held ones).
    pub shared_cov: Vec<Vec<f64>>,
    /// Standard errors of each block's own parameters.
    pub own_se: Vec<Vec<f64>>,
    /// Huber deviance Σ ρ(r) at the solution, per block.
    pub block_cost: Vec<f64>,
    pub termination: Termination,
    pub iterations: usize,
}

impl BlockResult {
    pub fn cost(&self) -> f64 {
        self.block_cost.iter().sum()
    }
    /// Standard error of shared parameter `i`: NaN when the fit does not determine it.
    pub fn shared_se(&self, i: usize) -> f64 {
        let v = self.shared_cov[i][i];
        if v.is_nan() {
            f64::NAN
        } else {
            v.max(0.0).sqrt()
        }
    }
}

/// Huber deviance of a whitened residual: u² inside c, 2c|u| − c² outside.
pub fn huber_rho(u: f64, c: f64) -> f64 {
    let a = u.abs();
    if a <= c {
        a * a
    } else {
        2.0 * c * a - c * c
    }
}

/// Row-major k×k matrix as rows (the Schur pieces are small).
type Mat = Vec<Vec<f64>>;

/// Normal-equation pieces of one block: U = JaᵀWJa (own×own), W = JaᵀWJb (own×shared),
/// V = JbᵀWJb (shared×shared), and the gradients.
#[derive(Debug, Clone)]
struct Pieces {
    u: Mat,
    w: Mat,
    v: Mat,
}

/// The block-arrow normal equations; parameters are ordered shared first, then each block's own.
#[derive(Debug, Clone)]
pub struct BlockNormal {
    ms: usize,
    /// Offset of each block's own parameters in the flat vector.
    offsets: Vec<usize>,
    pieces: Vec<Pieces>,
    g: Vec<f64>,
    /// False for a parameter the residuals do not depend on (zero diagonal): never stepped.
    live: Vec<bool>,
}

fn dot3(a: &[f64], b: &[f64], w: &[f64]) -> f64 {
    a.iter().zip(b).zip(w).map(|((a, b), w)| a * b * w).sum()
}

fn solve(a: &Mat, b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let flat: Vec<f64> = a.iter().flatten().copied().collect();
    dense::solve_spd(&flat, n, b)
}

/// `a` with the rows and columns of the parameters not `on` replaced by the identity, and the
/// diagonal of those `on` damped.
fn masked(a: &Mat, on: &[bool], lambda: f64) -> Mat {
    let n = a.len();
    let mut out = a.clone();
    for i in 0..n {
        if on[i] {
            out[i][i] += lambda * a[i][i].max(1e-30);
        } else {
            for j in 0..n {
                out[i][j] = 0.0;
                out[j][i] = 0.0;
            }
            out[i][i] = 1.0;
        }
    }
    out
}

impl BlockNormal {
    fn own_range(&self, b: usize) -> std::ops::Range<usize> {
        self.offsets[b]..self.offsets[b] + self.pieces[b].u.len()
    }

    /// The Schur complement S = Σ (V − Wᵀ U⁻¹ W) of the masked, damped system, and per block
    /// U⁻¹W (by shared column); None when a block or S is not positive definite.
    fn schur(&self, lambda: f64, on: &[bool]) -> Option<(Mat, Vec<Mat>, Vec<Mat>)> {
        let ms = self.ms;
        let mut s = vec![vec![0.0; ms]; ms];
        let mut us = Vec::with_capacity(self.pieces.len());
        let mut uws = Vec::with_capacity(self.pieces.len());
        for (b, p) in self.pieces.iter().enumerate() {
            let r = self.own_range(b);
            let u = masked(&p.u, &on[r.clone()], lambda);
            let mo = u.len();
            let uw: Mat = (0..ms)
                .map(|j| {
                    let col: Vec<f64> = (0..mo)
                        .map(|i| if on[r.start + i] { p.w[i][j] } else { 0.0 })
                        .collect();
                    solve(&u, &col)
                })
                .collect::<Option<_>>()?;
            for i in 0..ms {
                for j in 0..ms {
                    let x: f64 = (0..mo)
                        .filter(|&k| on[r.start + k])
                        .map(|k| p.w[k][i] * uw[j][k])
                        .sum();
                    s[i][j] += p.v[i][j] - x;
                }
            }
            us.push(u);
            uws.push(uw);
        }
        // damping of the shared block on the undamped V's diagonal (the Schur complement of
        // A + λ·diag A, consistent with `apply`)
        for i in 0..ms {
            let vdiag: f64 = self.pieces.iter().map(|p| p.v[i][i]).sum();
            if on[i] {
                s[i][i] += lambda * vdiag.max(1e-30);
            } else {
                for j in 0..ms {
                    s[i][j] = 0.0;
                    s[j][i] = 0.0;
                }
                s[i][i] = 1.0;
            }
        }
        Some((s, us, uws))
    }

    /// Covariance of the shared parameters (inverse Schur complement, NaN when singular) and
    /// the standard errors of the own ones (diagonal of U⁻¹ + U⁻¹W Σ WᵀU⁻¹), with `free`
    /// marking the parameters that are not held; true when the system is singular (everything
    /// NaN). A free parameter the residuals do not depend on gets NaN alone.
    fn covariance(&self, free: &[bool]) -> (Mat, Vec<Vec<f64>>, bool) {
        let ms = self.ms;
        let nan = || {
            (
                vec![vec![f64::NAN; ms]; ms],
                self.pieces
                    .iter()
                    .map(|p| vec![f64::NAN; p.u.len()])
                    .collect(),
                true,
            )
        };
        // a free parameter with no information is left out of the solve (its row and column the
        // identity, which decouples it) and gets no standard error below
        let mut on = free.to_vec();
        for (b, p) in self.pieces.iter().enumerate() {
            for k in 0..p.u.len() {
                on[self.offsets[b] + k] &= p.u[k][k] > 0.0;
            }
        }
        let vdiag: Vec<f64> = (0..ms)
            .map(|i| self.pieces.iter().map(|p| p.v[i][i]).sum())
            .collect();
        for i in 0..ms {
            on[i] &= vdiag[i] > 0.0;
        }
        let Some((s, us, uws)) = self.schur(0.0, &on) else {
            return nan();
        };
        let cov: Option<Mat> = (0..ms)
            .map(|j| {
                let mut e = vec![0.0; ms];
                e[j] = 1.0;
                solve(&s, &e)
            })
            .collect();
        let Some(cov) = cov else {
            return nan();
        };
        let cov: Mat = (0..ms)
            .map(|i| {
                (0..ms)
                    .map(|j| if free[i] && free[j] { cov[j][i] } else { 0.0 })
                    .collect()
            })
            .collect();
        let mut own_se = Vec::with_capacity(us.len());
        for (b, (u, uw)) in us.iter().zip(&uws).enumerate() {
            let mo = u.len();
            let mut se = Vec::with_capacity(mo);
            for k in 0..mo {
                if !free[self.offsets[b] + k] {
                    se.push(0.0);
                    continue;
                }
                let mut e = vec![0.0; mo];
                e[k] = 1.0;
                let Some(col) = solve(u, &e) else {
                    return nan();
                };
                let extra: f64 = (0..ms)
                    .flat_map(|i| (0..ms).map(move |j| (i, j)))
                    .map(|(i, j)| uw[i][k] * cov[i][j] * uw[j][k])
                    .sum();
                se.push((col[k] + extra).max(0.0).sqrt());
            }
            own_se.push(se);
        }
        // not determined by the residuals: NaN, never the 1 the identity would give
        let mut cov = cov;
        for i in (0..ms).filter(|&i| free[i] && !on[i]) {
            for j in 0..ms {
                cov[i][j] = f64::NAN;
                cov[j][i] = f64::NAN;
            }
        }
        for (b, se) in own_se.iter_mut().enumerate() {
            for (k, x) in se.iter_mut().enumerate() {
                let i = self.offsets[b] + k;
                if free[i] && !on[i] {
                    *x = f64::NAN;
                }
            }
        }
        (cov, own_se, false)
    }
}

impl Normal for BlockNormal {
    fn gradient(&self) -> &[f64] {
        &self.g
    }

    fn solve(&self, lambda: f64, on: &[bool], rhs: &[f64]) -> Option<Vec<f64>> {
        let ms = self.ms;
        let on: Vec<bool> = on.iter().zip(&self.live).map(|(a, b)| *a && *b).collect();
        let on = &on[..];
        let (s, us, uws) = self.schur(lambda, on)?;
        // reduced right-hand side: rhs_s − Σ Wᵀ U⁻¹ rhs_o
        let mut rs: Vec<f64> = (0..ms).map(|i| if on[i] { rhs[i] } else { 0.0 }).collect();
        let mut urs = Vec::with_capacity(us.len());
        for (b, (u, p)) in us.iter().zip(&self.pieces).enumerate() {
            let r = self.own_range(b);
            let ro: Vec<f64> = r
                .clone()
                .map(|i| if on[i] { rhs[i] } else { 0.0 })
                .collect();
            let ur = solve(u, &ro)?;
            for (i, x) in rs.iter_mut().enumerate().filter(|(i, _)| on[*i]) {
                *x -= (0..ur.len())
                    .filter(|&k| on[r.start + k])
                    .map(|k| p.w[k][i] * ur[k])
                    .sum::<f64>();
            }
            urs.push(ur);
        }
        let ds = if ms > 0 { solve(&s, &rs)? } else { Vec::new() };
        let mut out = vec![0.0; self.g.len()];
        for i in 0..ms {
            out[i] = if on[i] { ds[i] } else { 0.0 };
        }
        for (b, (ur, uw)) in urs.iter().zip(&uws).enumerate() {
            let start = self.offsets[b];
            for k in 0..ur.len() {
                if on[start + k] {
                    out[start + k] = ur[k] - (0..ms).map(|j| uw[j][k] * ds[j]).sum::<f64>();
                }
            }
        }
        Some(out)
    }

    fn apply(&self, lambda: f64, x: &[f64]) -> Vec<f64> {
        let ms = self.ms;
        let mut out = vec![0.0; x.len()];
        let xs = &x[..ms];
        let mut vdiag = vec![0.0; ms];
        for (b, p) in self.pieces.iter().enumerate() {
            let r = self.own_range(b);
            let xo = &x[r.clone()];
            for i in 0..ms {
                vdiag[i] += p.v[i][i];
                out[i] += (0..ms).map(|j| p.v[i][j] * xs[j]).sum::<f64>()
                    + (0..xo.len()).map(|k| p.w[k][i] * xo[k]).sum::<f64>();
            }
            for k in 0..xo.len() {
                let d = p.u[k][k];
                out[r.start + k] = (0..xo.len()).map(|l| p.u[k][l] * xo[l]).sum::<f64>()
                    + (0..ms).map(|j| p.w[k][j] * xs[j]).sum::<f64>()
                    + lambda * d.max(1e-30) * xo[k];
            }
        }
        for i in 0..ms {
            out[i] += lambda * vdiag[i].max(1e-30) * xs[i];
        }
        out
    }
}

/// The driver's view of a [`BlockProblem`] with its parameter specs.
struct Flat<'a, P> {
    problem: &'a P,
    shared_specs: &'a [ParamSpec],
    own_specs: &'a [Vec<ParamSpec>],
    /// Offsets of each block's own parameters and residuals in the flat vectors.
    param_offsets: Vec<usize>,
    res_offsets: Vec<usize>,
    /// Whether the columns the problem knows (`BlockProblem::known_columns`) stand for their
    /// differences: while descending, not for the covariance at the minimum.
    known_columns: bool,
}

impl<'a, P: BlockProblem> Flat<'a, P> {
    fn new(problem: &'a P, shared_specs: &'a [ParamSpec], own_specs: &'a [Vec<ParamSpec>]) -> Self {
        let mut param_offsets = Vec::with_capacity(own_specs.len());
        let mut res_offsets = Vec::with_capacity(own_specs.len() + 1);
        let (mut po, mut ro) = (shared_specs.len(), 0);
        for (b, sp) in own_specs.iter().enumerate() {
            param_offsets.push(po);
            res_offsets.push(ro);
            po += sp.len();
            ro += problem.n_residuals(b);
        }
        res_offsets.push(ro);
        Flat {
            problem,
            shared_specs,
            own_specs,
            param_offsets,
            res_offsets,
            known_columns: true,
        }
    }

    fn specs(&self) -> Vec<ParamSpec> {
        let mut out = self.shared_specs.to_vec();
        out.extend(self.own_specs.iter().flatten());
        out
    }

    fn own<'x>(&self, x: &'x [f64], b: usize) -> &'x [f64] {
        &x[self.param_offsets[b]..self.param_offsets[b] + self.own_specs[b].len()]
    }

    fn block_residuals(&self, b: usize, shared: &[f64], own: &[f64]) -> Vec<f64> {
        let mut r = vec![0.0; self.problem.n_residuals(b)];
        self.problem.residuals(b, shared, own, &mut r);
        r
    }

    /// ∂r_b/∂(one parameter) by a forward difference stepping inward at an upper bound, of the
    /// residuals `lin` holds when given.
    #[allow(clippy::too_many_arguments)]
    fn column(
        &self,
        b: usize,
        x: &[f64],
        r0: &[f64],
        spec: &ParamSpec,
        shared: Option<usize>,
        own: Option<usize>,
        lin: Option<&dyn Linear>,
    ) -> Vec<f64> {
        let ms = self.shared_specs.len();
        let (mut s2, mut o2) = (x[..ms].to_vec(), self.own(x, b).to_vec());
        let h = match (shared, own) {
            (Some(i), _) => {
                let h = inward_step(s2[i], spec.step, spec.upper);
                s2[i] += h;
                h
            }
            (_, Some(i)) => {
                let h = inward_step(o2[i], spec.step, spec.upper);
                o2[i] += h;
                h
            }
            _ => unreachable!("a column is of a shared or an own parameter"),
        };
        let r1 = match lin {
            Some(lin) => {
                let mut r = vec![0.0; r0.len()];
                lin.residuals(&s2, &o2, &mut r);
                r
            }
            None => self.block_residuals(b, &s2, &o2),
        };
        r1.iter().zip(r0).map(|(a, b)| (a - b) / h).collect()
    }

    /// ∂r_b/∂(own parameter `k`): the problem's closed form if it has one, else a difference.
    fn own_column(
        &self,
        b: usize,
        x: &[f64],
        r0: &[f64],
        spec: &ParamSpec,
        k: usize,
        lin: Option<&dyn Linear>,
    ) -> Vec<f64> {
        let ms = self.shared_specs.len();
        let mut out = vec![0.0; r0.len()];
        if self
            .problem
            .own_column(b, k, &x[..ms], self.own(x, b), &mut out)
        {
            out
        } else {
            self.column(b, x, r0, spec, None, Some(k), lin)
        }
    }

    /// The normal-equation pieces and gradient parts of block `b`.
    fn block_pieces(
        &self,
        b: usize,
        x: &[f64],
        r: &[f64],
        w: &[f64],
    ) -> (Pieces, Vec<f64>, Vec<f64>) {
        let ms = self.shared_specs.len();
        let lin = self.problem.linearize(b, &x[..ms], self.own(x, b));
        let lin = lin.as_deref();
        let mut known = if self.known_columns {
            self.problem.known_columns(b, &x[..ms], self.own(x, b))
        } else {
            None
        };
        let ja: Vec<Option<Vec<f64>>> = self.own_specs[b]
            .iter()
            .enumerate()
            .map(|(i, s)| {
                (!s.held()).then(|| {
                    let given = known.as_mut().and_then(|k| k.own.get_mut(i)?.take());
                    let mut c = match given {
                        Some(c) => c,
                        None => self.own_column(b, x, r, s, i, lin),
                    };
                    if let Some(lin) = lin {
                        lin.project(&mut c);
                    }
                    c
                })
            })
            .collect();
        let jb: Vec<Option<Vec<f64>>> = self
            .shared_specs
            .iter()
            .enumerate()
            .map(|(i, s)| {
                (!s.held() && self.problem.uses(b, i)).then(|| {
                    let given = known.as_mut().and_then(|k| k.shared.get_mut(i)?.take());
                    let mut c = match given {
                        Some(c) => c,
                        None => self.column(b, x, r, s, Some(i), None, lin),
                    };
                    if let Some(lin) = lin {
                        lin.project(&mut c);
                    }
                    c
                })
            })
            .collect();
        let mo = ja.len();
        let d = |a: &Option<Vec<f64>>, c: &Option<Vec<f64>>| match (a, c) {
            (Some(a), Some(c)) => dot3(a, c, w),
            _ => 0.0,
        };
        let mut u = vec![vec![0.0; mo]; mo];
        let mut wm = vec![vec![0.0; ms]; mo];
        let mut v = vec![vec![0.0; ms]; ms];
        for i in 0..mo {
            for k in 0..=i {
                let x = d(&ja[i], &ja[k]);
                u[i][k] = x;
                u[k][i] = x;
            }
            for j in 0..ms {
                wm[i][j] = d(&ja[i], &jb[j]);
            }
        }
        for i in 0..ms {
            for k in 0..=i {
                let x = d(&jb[i], &jb[k]);
                v[i][k] = x;
                v[k][i] = x;
            }
        }
        let grad = |c: &Option<Vec<f64>>| c.as_ref().map(|c| dot3(c, r, w)).unwrap_or(0.0);
        let ga = ja.iter().map(grad).collect();
        let gb = jb.iter().map(grad).collect();
        (Pieces { u, w: wm, v }, ga, gb)
    }
}

impl<P: BlockProblem> Model for Flat<'_, P> {
    type Normal = BlockNormal;

    fn n_residuals(&self) -> usize {
        *self.res_offsets.last().unwrap_or(&0)
    }

    fn residuals(&self, x: &[f64], out: &mut [f64]) {
        let ms = self.shared_specs.len();
        let rs: Vec<Vec<f64>> = (0..self.problem.n_blocks())
            .into_par_iter()
            .map(|b| self.block_residuals(b, &x[..ms], self.own(x, b)))
            .collect();
        for (b, r) in rs.iter().enumerate() {
            out[self.res_offsets[b]..self.res_offsets[b + 1]].copy_from_slice(r);
        }
    }

    fn normal(&self, x: &[f64], r: &[f64], w: &[f64]) -> BlockNormal {
        let ms = self.shared_specs.len();
        let parts: Vec<(Pieces, Vec<f64>, Vec<f64>)> = (0..self.problem.n_blocks())
            .into_par_iter()
            .map(|b| {
                let range = self.res_offsets[b]..self.res_offsets[b + 1];
                self.block_pieces(b, x, &r[range.clone()], &w[range])
            })
            .collect();
        let mut g = vec![0.0; x.len()];
        let mut pieces = Vec::with_capacity(parts.len());
        for (b, (p, ga, gb)) in parts.into_iter().enumerate() {
            for (i, v) in gb.iter().enumerate() {
                g[i] += v;
            }
            g[self.param_offsets[b]..self.param_offsets[b] + ga.len()].copy_from_slice(&ga);
            pieces.push(p);
        }
        let mut live = vec![true; x.len()];
        for i in 0..ms {
            live[i] = pieces.iter().map(|p| p.v[i][i]).sum::<f64>() > 0.0;
        }
        for (b, p) in pieces.iter().enumerate() {
            for k in 0..p.u.len() {
                live[self.param_offsets[b] + k] = p.u[k][k] > 0.0;
            }
        }
        BlockNormal {
            ms,
            offsets: self.param_offsets.clone(),
            pieces,
            g,
            live,
        }
    }
}

/// Minimise Σ_b Σ ρ(r_b) over shared and per-block parameters within their bounds (Huber with
/// threshold `settings.huber_k` on the whitened residuals).
pub fn minimize_blocks<P: BlockProblem>(
    problem: &P,
    shared_specs: &[ParamSpec],
    own_specs: &[Vec<ParamSpec>],
    settings: &Settings,
) -> BlockResult {
    let mut flat = Flat::new(problem, shared_specs, own_specs);
    let specs = flat.specs();
    let d = lm::descend(&flat, &specs, settings);
    // the covariance from differences of every column: the known ones serve the steps
    flat.known_columns = false;
    let sol = lm::Solution {
        normal: flat.normal(&d.x, &d.r, &d.w),
        x: d.x,
        r: d.r,
        w: d.w,
        scale: d.scale,
        termination: d.termination,
        iterations: d.iterations,
    };
    let free: Vec<bool> = specs.iter().map(|s| !s.held()).collect();
    let (shared_cov, own_se, singular) = sol.normal.covariance(&free);
    let mut res = block_result(&flat, &sol, settings);
    if singular && !shared_specs.is_empty() {
        res.termination = Termination::Singular;
    }
    res.shared_cov = shared_cov;
    res.own_se = own_se;
    res
}

/// [`minimize_blocks`] without the covariance (`shared_cov` and `own_se` empty, and no test of
/// the normal equations' singularity): the same minimum one Jacobian sooner, for a fit whose
/// parameters and cost are all that is read (a cross-validation fold).
pub fn descend_blocks<P: BlockProblem>(
    problem: &P,
    shared_specs: &[ParamSpec],
    own_specs: &[Vec<ParamSpec>],
    settings: &Settings,
) -> BlockResult {
    let flat = Flat::new(problem, shared_specs, own_specs);
    let sol = lm::descend(&flat, &flat.specs(), settings);
    block_result(&flat, &sol, settings)
}

/// The driver's solution `sol` by block, its covariance not yet filled in.
fn block_result<P: BlockProblem, N>(
    flat: &Flat<P>,
    sol: &lm::Solution<N>,
    settings: &Settings,
) -> BlockResult {
    let (x, r) = (&sol.x, &sol.r);
    let block_cost = (0..flat.problem.n_blocks())
        .map(|b| {
            r[flat.res_offsets[b]..flat.res_offsets[b + 1]]
                .iter()
                .map(|u| huber_rho(*u, settings.huber_k))
                .sum()
        })
        .collect();
    BlockResult {
        shared: x[..flat.shared_specs.len()].to_vec(),
        own: (0..flat.own_specs.len())
            .map(|b| flat.own(x, b).to_vec())
            .collect(),
        shared_cov: Vec::new(),
        own_se: Vec::new(),
        block_cost,
        termination: sol.termination,
        iterations: sol.iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lsq::lm::Scale;

    /// Lines y = a_b + s·t per block with one shared slope.
    struct Lines {
        t: Vec<f64>,
        y: Vec<Vec<f64>>,
    }

    impl BlockProblem for Lines {
        fn n_blocks(&self) -> usize {
            self.y.len()
        }
        fn n_residuals(&self, b: usize) -> usize {
            self.y[b].len()
        }
        fn residuals(&self, b: usize, shared: &[f64], own: &[f64], out: &mut [f64]) {
            for (i, o) in out.iter_mut().enumerate() {
                *o = (own[0] + shared[0] * self.t[i] - self.y[b][i]) / 0.01;
            }
        }
    }

    fn settings() -> Settings {
        Settings {
            max_iter: 60,
            rounds: 3,
            huber_k: 3.0,
            scale: Scale::Fixed(1.0),
            cost_tol: 1e-3,
            rel_tol: 1e-6,
            damping: 1e-3,
        }
    }

    fn lines() -> (Lines, [f64; 3]) {
        let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.05).collect();
        let offs = [0.3, -1.2, 2.0];
        let y = offs
            .iter()
            .enumerate()
            .map(|(b, a)| {
                t.iter()
                    .enumerate()
                    .map(|(i, t)| a + 0.7 * t + 0.01 * (((i * 37 + b * 11) % 7) as f64 - 3.0) / 3.0)
                    .collect()
            })
            .collect();
        (Lines { t, y }, offs)
    }

    fn spec(x: f64, lower: f64, upper: f64) -> ParamSpec {
        ParamSpec {
            start: x,
            lower,
            upper,
            step: 1e-6,
        }
    }

    #[test]
    fn shared_slope_and_offsets_are_recovered() {
        let (problem, offs) = lines();
        let res = minimize_blocks(
            &problem,
            &[spec(0.0, -10.0, 10.0)],
            &vec![vec![spec(0.0, -10.0, 10.0)]; 3],
            &settings(),
        );
        assert!((res.shared[0] - 0.7).abs() < 0.01, "{:?}", res.shared);
        for (o, a) in res.own.iter().zip(offs) {
            assert!((o[0] - a).abs() < 0.02, "{o:?}");
        }
        let se = res.shared_se(0);
        assert!(se > 0.0 && se < 0.01, "se {se}");
        assert!(res.termination.is_converged(), "{:?}", res.termination);
    }

    #[test]
    fn descending_without_the_covariance_reaches_the_same_minimum() {
        let (problem, _) = lines();
        let shared = [spec(0.0, -10.0, 10.0)];
        let own = vec![vec![spec(0.0, -10.0, 10.0)]; 3];
        let full = minimize_blocks(&problem, &shared, &own, &settings());
        let bare = descend_blocks(&problem, &shared, &own, &settings());
        // the same steps from the same start: the same bits, only the covariance left out
        assert_eq!(bare.shared, full.shared);
        assert_eq!(bare.own, full.own);
        assert_eq!(bare.block_cost, full.block_cost);
        assert_eq!(bare.iterations, full.iterations);
        assert_eq!(bare.termination, full.termination);
        assert!(bare.shared_cov.is_empty() && bare.own_se.is_empty());
        assert_eq!(full.shared_cov.len(), 1);
    }

    /// [`Lines`] with a second shared parameter the residuals do not depend on.
    struct Unused(Lines);

    impl BlockProblem for Unused {
        fn n_blocks(&self) -> usize {
            self.0.n_blocks()
        }
        fn n_residuals(&self, b: usize) -> usize {
            self.0.n_residuals(b)
        }
        fn residuals(&self, b: usize, shared: &[f64], own: &[f64], out: &mut [f64]) {
            self.0.residuals(b, &shared[..1], own, out)
        }
    }

    #[test]
    fn a_parameter_the_data_do_not_determine_has_no_standard_error() {
        let (lines, _) = lines();
        let res = minimize_blocks(
            &Unused(lines),
            &[spec(0.0, -10.0, 10.0), spec(0.5, -10.0, 10.0)],
            &vec![vec![spec(0.0, -10.0, 10.0)]; 3],
            &settings(),
        );
        assert!((res.shared[0] - 0.7).abs() < 0.01, "{:?}", res.shared);
        assert_eq!(res.shared[1], 0.5, "never stepped");
        let se = res.shared_se(0);
        assert!(se > 0.0 && se < 0.01, "the slope keeps its error: {se}");
        assert!(res.shared_cov[1][1].is_nan(), "{:?}", res.shared_cov);
        assert!(res.own_se.iter().all(|s| s[0].is_finite() && s[0] > 0.0));
        // the minimum itself is found: the fit converged, one parameter is just not determined
        assert!(res.termination.is_converged(), "{:?}", res.termination);
    }

    #[test]
    fn a_shared_bound_holds_the_slope_and_the_offsets_follow() {
        // slope capped at 0.69 < 0.7: each offset becomes the mean of y − 0.69 t of its block
        // (the residuals stay inside Huber's threshold)
        let (problem, _) = lines();
        let res = minimize_blocks(
            &problem,
            &[spec(0.0, -10.0, 0.69)],
            &vec![vec![spec(0.0, -10.0, 10.0)]; 3],
            &settings(),
        );
        assert_eq!(res.shared[0], 0.69);
        for (b, o) in res.own.iter().enumerate() {
            let n = problem.t.len() as f64;
            let want: f64 = problem.y[b]
                .iter()
                .zip(&problem.t)
                .map(|(y, t)| y - 0.69 * t)
                .sum::<f64>()
                / n;
            assert!((o[0] - want).abs() < 1e-4, "block {b}: {} vs {want}", o[0]);
        }
        assert!(res.termination.is_converged(), "{:?}", res.termination);
    }
}
