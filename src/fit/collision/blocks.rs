//! The one place the whole-run pair fits call a least-squares solver: a robust (Huber IRLS)
//! Levenberg–Marquardt over shared parameters plus one block of parameters per run, solved
//! through the Schur complement of the block-arrow normal equations. Residuals are expected
//! whitened (in units of each run's noise), so the cost is a χ²-like deviance.

use super::lm::ParamSpec;
use crate::lsq::Termination;
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
}

/// Solver settings.
#[derive(Debug, Clone, Copy)]
pub struct BlockOptions {
    pub max_iter: usize,
    pub irls_rounds: usize,
    /// Huber threshold in whitened units.
    pub huber_c: f64,
    /// Converged when a step lowers the cost by less than this (χ² units) plus a millionth of
    /// the cost (a change no statistic can see).
    pub cost_tol: f64,
}

impl Default for BlockOptions {
    fn default() -> Self {
        BlockOptions {
            max_iter: 60,
            irls_rounds: 3,
            huber_c: 3.0,
            cost_tol: 1e-3,
        }
    }
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
    pub fn shared_se(&self, i: usize) -> f64 {
        self.shared_cov[i][i].max(0.0).sqrt()
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

fn held(s: &ParamSpec) -> bool {
    s.lower == s.upper
}

struct BlockLin {
    r: Vec<f64>,
    w: Vec<f64>,
    /// own Jacobian columns, then shared columns (empty when unused / held)
    ja: Vec<Vec<f64>>,
    jb: Vec<Option<Vec<f64>>>,
}

fn eval<P: BlockProblem>(p: &P, b: usize, shared: &[f64], own: &[f64]) -> Vec<f64> {
    let mut r = vec![0.0; p.n_residuals(b)];
    p.residuals(b, shared, own, &mut r);
    r
}

fn weighted(r: &[f64], w: &[f64]) -> f64 {
    r.iter()
        .zip(w)
        .map(|(x, w)| {
            let v = w * x * x;
            if v.is_finite() {
                v
            } else {
                f64::INFINITY
            }
        })
        .sum()
}

fn fd_column<P: BlockProblem>(
    p: &P,
    b: usize,
    shared: &[f64],
    own: &[f64],
    r0: &[f64],
    spec: &ParamSpec,
    which: (bool, usize),
) -> Vec<f64> {
    let (is_shared, i) = which;
    let x = if is_shared { shared[i] } else { own[i] };
    let h = if x + spec.step > spec.upper {
        -spec.step
    } else {
        spec.step
    };
    let (mut s2, mut o2) = (shared.to_vec(), own.to_vec());
    if is_shared {
        s2[i] += h;
    } else {
        o2[i] += h;
    }
    let r1 = eval(p, b, &s2, &o2);
    r1.iter().zip(r0).map(|(a, b)| (a - b) / h).collect()
}

fn dot3(a: &[f64], b: &[f64], w: &[f64]) -> f64 {
    a.iter().zip(b).zip(w).map(|((a, b), w)| a * b * w).sum()
}

/// Minimize Σ_b Σ ρ(r_b) over shared and per-block parameters within their bounds.
pub fn minimize_blocks<P: BlockProblem>(
    problem: &P,
    shared_specs: &[ParamSpec],
    own_specs: &[Vec<ParamSpec>],
    opts: &BlockOptions,
) -> BlockResult {
    let nb = problem.n_blocks();
    let ms = shared_specs.len();
    let clamp = |x: f64, s: &ParamSpec| x.clamp(s.lower, s.upper);
    let mut shared: Vec<f64> = shared_specs.iter().map(|s| clamp(s.start, s)).collect();
    let mut own: Vec<Vec<f64>> = own_specs
        .iter()
        .map(|sp| sp.iter().map(|s| clamp(s.start, s)).collect())
        .collect();
    let mut iterations = 0;
    let mut termination = Termination::MaxIterations;
    let mut weights: Vec<Vec<f64>> = (0..nb).map(|b| vec![1.0; problem.n_residuals(b)]).collect();
    for round in 0..opts.irls_rounds.max(1) {
        let rs: Vec<Vec<f64>> = (0..nb)
            .into_par_iter()
            .map(|b| eval(problem, b, &shared, &own[b]))
            .collect();
        for (w, r) in weights.iter_mut().zip(&rs) {
            for (wi, ri) in w.iter_mut().zip(r) {
                let a = ri.abs();
                *wi = if a <= opts.huber_c || !a.is_finite() {
                    1.0
                } else {
                    opts.huber_c / a
                };
            }
        }
        let mut cost: f64 = rs.iter().zip(&weights).map(|(r, w)| weighted(r, w)).sum();
        let mut lambda = 1e-3;
        termination = Termination::MaxIterations;
        let mut rs = rs;
        for _ in 0..opts.max_iter {
            iterations += 1;
            let lins: Vec<BlockLin> = (0..nb)
                .into_par_iter()
                .map(|b| {
                    let r = rs[b].clone();
                    let ja = own_specs[b]
                        .iter()
                        .enumerate()
                        .map(|(i, s)| {
                            if held(s) {
                                vec![0.0; r.len()]
                            } else {
                                fd_column(problem, b, &shared, &own[b], &r, s, (false, i))
                            }
                        })
                        .collect();
                    let jb = shared_specs
                        .iter()
                        .enumerate()
                        .map(|(i, s)| {
                            (!held(s) && problem.uses(b, i))
                                .then(|| fd_column(problem, b, &shared, &own[b], &r, s, (true, i)))
                        })
                        .collect();
                    BlockLin {
                        r,
                        w: weights[b].clone(),
                        ja,
                        jb,
                    }
                })
                .collect();
            let mut improved = false;
            for _ in 0..12 {
                let Some((ds, dos)) = step(&lins, shared_specs, own_specs, lambda) else {
                    lambda *= 10.0;
                    continue;
                };
                let trial_s: Vec<f64> = shared
                    .iter()
                    .zip(&ds)
                    .zip(shared_specs)
                    .map(|((x, d), s)| clamp(x + d, s))
                    .collect();
                let trial_o: Vec<Vec<f64>> = own
                    .iter()
                    .zip(&dos)
                    .zip(own_specs)
                    .map(|((xs, dx), sp)| {
                        xs.iter()
                            .zip(dx)
                            .zip(sp)
                            .map(|((x, d), s)| clamp(x + d, s))
                            .collect()
                    })
                    .collect();
                let r_trial: Vec<Vec<f64>> = (0..nb)
                    .into_par_iter()
                    .map(|b| eval(problem, b, &trial_s, &trial_o[b]))
                    .collect();
                let c_trial: f64 = r_trial
                    .iter()
                    .zip(&weights)
                    .map(|(r, w)| weighted(r, w))
                    .sum();
                if c_trial.is_finite() && c_trial < cost {
                    let drop = cost - c_trial;
                    shared = trial_s;
                    own = trial_o;
                    rs = r_trial;
                    cost = c_trial;
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = true;
                    if drop < opts.cost_tol + 1e-6 * cost {
                        termination = Termination::SmallCostChange;
                    }
                    break;
                }
                lambda *= 4.0;
            }
            if !improved {
                termination = Termination::NoFurtherDecrease;
                break;
            }
            if termination.is_converged() {
                break;
            }
        }
        let _ = round;
    }
    // final: deviance, covariance of shared (Schur complement), own standard errors
    let rs: Vec<Vec<f64>> = (0..nb)
        .into_par_iter()
        .map(|b| eval(problem, b, &shared, &own[b]))
        .collect();
    let block_cost = rs
        .iter()
        .map(|r| r.iter().map(|u| huber_rho(*u, opts.huber_c)).sum())
        .collect();
    let lins: Vec<BlockLin> = (0..nb)
        .into_par_iter()
        .map(|b| {
            let r = rs[b].clone();
            let w = r
                .iter()
                .map(|x| {
                    let a = x.abs();
                    if a <= opts.huber_c {
                        1.0
                    } else {
                        opts.huber_c / a
                    }
                })
                .collect();
            let ja = own_specs[b]
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    if held(s) {
                        vec![0.0; r.len()]
                    } else {
                        fd_column(problem, b, &shared, &own[b], &r, s, (false, i))
                    }
                })
                .collect();
            let jb = shared_specs
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    (!held(s) && problem.uses(b, i))
                        .then(|| fd_column(problem, b, &shared, &own[b], &r, s, (true, i)))
                })
                .collect();
            BlockLin { r, w, ja, jb }
        })
        .collect();
    let (shared_cov, own_se) = covariance(&lins, shared_specs, own_specs, ms);
    if shared_cov.iter().any(|row| row.iter().any(|x| x.is_nan())) && ms > 0 {
        termination = Termination::Singular;
    }
    BlockResult {
        shared,
        own,
        shared_cov,
        own_se,
        block_cost,
        termination,
        iterations,
    }
}

/// Solve A x = b (A symmetric positive definite, as rows) with the `lsq` dense back-end.
fn solve_spd(a: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let flat: Vec<f64> = a.iter().flatten().copied().collect();
    crate::lsq::dense::solve_spd(&flat, n, b)
}

/// Normal-equation pieces of one block: U (own×own), W (own×shared), V part, gradients.
struct Pieces {
    u: Vec<Vec<f64>>,
    w: Vec<Vec<f64>>,
    v: Vec<Vec<f64>>,
    ga: Vec<f64>,
    gb: Vec<f64>,
}

fn pieces(l: &BlockLin, own_specs: &[ParamSpec], shared_specs: &[ParamSpec]) -> Pieces {
    let mo = l.ja.len();
    let ms = l.jb.len();
    let mut u = vec![vec![0.0; mo]; mo];
    let mut w = vec![vec![0.0; ms]; mo];
    let mut v = vec![vec![0.0; ms]; ms];
    let mut ga: Vec<f64> = l.ja.iter().map(|c| dot3(c, &l.r, &l.w)).collect();
    let gb: Vec<f64> =
        l.jb.iter()
            .map(|c| c.as_ref().map(|c| dot3(c, &l.r, &l.w)).unwrap_or(0.0))
            .collect();
    for i in 0..mo {
        for k in 0..=i {
            let x = dot3(&l.ja[i], &l.ja[k], &l.w);
            u[i][k] = x;
            u[k][i] = x;
        }
        for (j, cb) in l.jb.iter().enumerate() {
            if let Some(cb) = cb {
                w[i][j] = dot3(&l.ja[i], cb, &l.w);
            }
        }
    }
    for i in 0..ms {
        for k in 0..=i {
            if let (Some(a), Some(b)) = (&l.jb[i], &l.jb[k]) {
                let x = dot3(a, b, &l.w);
                v[i][k] = x;
                v[k][i] = x;
            }
        }
    }
    for (i, s) in own_specs.iter().enumerate() {
        if held(s) || u[i][i] <= 0.0 {
            for j in 0..mo {
                u[i][j] = 0.0;
                u[j][i] = 0.0;
            }
            u[i][i] = 1.0;
            ga[i] = 0.0;
            w[i].iter_mut().for_each(|x| *x = 0.0);
        }
    }
    let _ = shared_specs;
    Pieces { u, w, v, ga, gb }
}

fn damp(a: &mut [Vec<f64>], lambda: f64) {
    for (i, row) in a.iter_mut().enumerate() {
        row[i] += lambda * row[i].max(1e-30);
    }
}

fn fix_shared(v: &mut [Vec<f64>], g: &mut [f64], specs: &[ParamSpec]) {
    for (i, s) in specs.iter().enumerate() {
        if held(s) || v[i][i] <= 0.0 {
            for j in 0..v.len() {
                v[i][j] = 0.0;
                v[j][i] = 0.0;
            }
            v[i][i] = 1.0;
            g[i] = 0.0;
        }
    }
}

/// One damped Gauss–Newton step through the Schur complement.
fn step(
    lins: &[BlockLin],
    shared_specs: &[ParamSpec],
    own_specs: &[Vec<ParamSpec>],
    lambda: f64,
) -> Option<(Vec<f64>, Vec<Vec<f64>>)> {
    let ms = shared_specs.len();
    let ps: Vec<Pieces> = lins
        .iter()
        .zip(own_specs)
        .map(|(l, sp)| pieces(l, sp, shared_specs))
        .collect();
    let mut s = vec![vec![0.0; ms]; ms];
    let mut rhs = vec![0.0; ms];
    let mut uinv_parts = Vec::with_capacity(ps.len());
    for p in &ps {
        for i in 0..ms {
            rhs[i] -= p.gb[i];
            for j in 0..ms {
                s[i][j] += p.v[i][j];
            }
        }
        let mut u = p.u.clone();
        damp(&mut u, lambda);
        // U⁻¹ W and U⁻¹ g
        let mo = u.len();
        let ug = solve_spd(&u, &p.ga)?;
        let uw: Vec<Vec<f64>> = (0..ms)
            .map(|j| {
                let col: Vec<f64> = (0..mo).map(|i| p.w[i][j]).collect();
                solve_spd(&u, &col)
            })
            .collect::<Option<_>>()?;
        for i in 0..ms {
            for j in 0..ms {
                let x: f64 = (0..mo).map(|k| p.w[k][i] * uw[j][k]).sum();
                s[i][j] -= x;
            }
            rhs[i] += (0..mo).map(|k| p.w[k][i] * ug[k]).sum::<f64>();
        }
        uinv_parts.push((u, ug, uw));
    }
    // damping of the shared block (on the undamped V's diagonal)
    let vdiag: Vec<f64> = (0..ms)
        .map(|i| ps.iter().map(|p| p.v[i][i]).sum())
        .collect();
    for i in 0..ms {
        s[i][i] += lambda * vdiag[i].max(1e-30);
    }
    fix_shared(&mut s, &mut rhs, shared_specs);
    let ds = if ms > 0 {
        solve_spd(&s, &rhs)?
    } else {
        Vec::new()
    };
    let dos = uinv_parts
        .iter()
        .map(|(_, ug, uw)| {
            (0..ug.len())
                .map(|k| -ug[k] - (0..ms).map(|j| uw[j][k] * ds[j]).sum::<f64>())
                .collect::<Vec<f64>>()
        })
        .collect();
    Some((ds, dos))
}

/// Covariance of the shared parameters (inverse Schur complement) and own standard errors
/// (diagonal of U⁻¹ + U⁻¹ W Σ Wᵀ U⁻¹).
fn covariance(
    lins: &[BlockLin],
    shared_specs: &[ParamSpec],
    own_specs: &[Vec<ParamSpec>],
    ms: usize,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let ps: Vec<Pieces> = lins
        .iter()
        .zip(own_specs)
        .map(|(l, sp)| pieces(l, sp, shared_specs))
        .collect();
    let mut s = vec![vec![0.0; ms]; ms];
    let mut uws = Vec::new();
    let mut uinvs = Vec::new();
    for p in &ps {
        let mo = p.u.len();
        let uinv: Option<Vec<Vec<f64>>> = (0..mo)
            .map(|j| {
                let mut e = vec![0.0; mo];
                e[j] = 1.0;
                solve_spd(&p.u, &e)
            })
            .collect();
        let Some(uinv) = uinv else {
            return (
                vec![vec![f64::NAN; ms]; ms],
                own_specs
                    .iter()
                    .map(|sp| vec![f64::NAN; sp.len()])
                    .collect(),
            );
        };
        let uw: Vec<Vec<f64>> = (0..ms)
            .map(|j| {
                (0..mo)
                    .map(|i| (0..mo).map(|k| uinv[i][k] * p.w[k][j]).sum::<f64>())
                    .collect::<Vec<f64>>()
            })
            .collect();
        for i in 0..ms {
            for j in 0..ms {
                s[i][j] += p.v[i][j] - (0..mo).map(|k| p.w[k][i] * uw[j][k]).sum::<f64>();
            }
        }
        uws.push(uw);
        uinvs.push(uinv);
    }
    let mut g = vec![0.0; ms];
    fix_shared(&mut s, &mut g, shared_specs);
    let cov: Option<Vec<Vec<f64>>> = (0..ms)
        .map(|j| {
            let mut e = vec![0.0; ms];
            e[j] = 1.0;
            solve_spd(&s, &e)
        })
        .collect();
    let cov: Vec<Vec<f64>> = match cov {
        Some(c) => {
            // columns → matrix (symmetric), zero for held parameters
            (0..ms)
                .map(|i| {
                    (0..ms)
                        .map(|j| {
                            if held(&shared_specs[i]) || held(&shared_specs[j]) {
                                0.0
                            } else {
                                c[j][i]
                            }
                        })
                        .collect::<Vec<f64>>()
                })
                .collect()
        }
        None => vec![vec![f64::NAN; ms]; ms],
    };
    let own_se = uinvs
        .iter()
        .zip(&uws)
        .zip(own_specs)
        .map(|((uinv, uw), sp)| {
            (0..uinv.len())
                .map(|k| {
                    if held(&sp[k]) {
                        return 0.0;
                    }
                    let extra: f64 = (0..ms)
                        .flat_map(|i| (0..ms).map(move |j| (i, j)))
                        .map(|(i, j)| uw[i][k] * cov[i][j] * uw[j][k])
                        .sum();
                    (uinv[k][k] + extra).max(0.0).sqrt()
                })
                .collect()
        })
        .collect();
    (cov, own_se)
}

#[cfg(test)]
mod tests {
    use super::*;

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

    #[test]
    fn shared_slope_and_offsets_are_recovered() {
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
        let spec = |x: f64| ParamSpec {
            start: x,
            lower: -10.0,
            upper: 10.0,
            step: 1e-6,
        };
        let res = minimize_blocks(
            &Lines { t, y },
            &[spec(0.0)],
            &vec![vec![spec(0.0)]; 3],
            &BlockOptions::default(),
        );
        assert!((res.shared[0] - 0.7).abs() < 0.01, "{:?}", res.shared);
        for (o, a) in res.own.iter().zip(offs) {
            assert!((o[0] - a).abs() < 0.02, "{o:?}");
        }
        let se = res.shared_se(0);
        assert!(se > 0.0 && se < 0.01, "se {se}");
        assert!(res.termination.is_converged());
    }
}
