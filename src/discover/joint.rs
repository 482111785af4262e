//! The joint fit: shared physics parameters and per-run z0, t0, v0 by a block-sparse Levenberg–Marquardt.
//!
//! Each run's Jacobian touches only its own three local columns and the global columns it depends
//! on, so a step costs one simulation per run per (local or affecting global) parameter, and the
//! normal equations are reduced to the globals by a Schur complement over the 3×3 run blocks.

use super::candidate::{ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use crate::lsq::dense::{chol_inverse, chol_solve, cholesky_jittered};
use crate::lsq::fd::inward_step;
use rayon::prelude::*;

/// A fitted joint model.
#[derive(Clone, Debug)]
pub struct Fitted {
    pub global: Vec<f64>,
    pub local: Vec<[f64; N_LOCAL]>,
    /// Σ over runs and kept samples of (residual/σ_run)².
    pub chi2: f64,
    pub chi2_run: Vec<f64>,
    /// Standard errors of the globals from the Jacobian, scaled by √(χ²/dof) when that exceeds 1.
    pub global_se: Vec<f64>,
    pub iterations: usize,
    pub converged: bool,
}

/// How far a fit may go.
#[derive(Clone, Copy, Debug)]
pub struct FitControl {
    pub max_iter: usize,
    /// False: the globals stay fixed (held-out runs in cross-validation).
    pub free_global: bool,
}

/// Predicted positions of `run` at its sample times.
pub fn predict(spec: &Spec, g: &[f64], l: &[f64; N_LOCAL], run: &RunData, out: &mut [f64]) {
    let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
    let model = spec.run_model(g, l, run);
    model.simulate(l[0], l[2], &tt, out, None, None);
}

/// χ² of one run.
pub fn run_chi2(spec: &Spec, g: &[f64], l: &[f64; N_LOCAL], run: &RunData) -> f64 {
    let mut z = vec![0.0; run.t_s.len()];
    predict(spec, g, l, run, &mut z);
    let w = 1.0 / run.sigma_m;
    (0..z.len())
        .filter(|i| run.keep[*i])
        .map(|i| ((run.z_m[i] - z[i]) * w).powi(2))
        .sum()
}

/// Normal-equation pieces of one run (na = number of affecting globals).
struct Block {
    idx: Vec<usize>,
    a: Vec<f64>,  // na×na  Jgᵀ Jg
    b: Vec<f64>,  // na×3   Jgᵀ Jl
    c: [f64; 9],  // 3×3    Jlᵀ Jl
    bg: Vec<f64>, // na     Jgᵀ e
    bl: [f64; 3], // 3      Jlᵀ e
}

fn local_bounds(run: &RunData) -> [(f64, f64); N_LOCAL] {
    let frame = if run.fps > 0.0 { 1.0 / run.fps } else { 1e-3 };
    [
        (f64::NEG_INFINITY, f64::INFINITY),
        (0.0, frame),
        (-10.0, 10.0),
    ]
}

fn block(
    spec: &Spec,
    params: &[ParamInfo],
    g: &[f64],
    l: &[f64; N_LOCAL],
    run: &RunData,
    free_global: bool,
) -> Block {
    let n = run.t_s.len();
    let w = 1.0 / run.sigma_m;
    let mut base = vec![0.0; n];
    predict(spec, g, l, run, &mut base);
    let e: Vec<f64> = (0..n)
        .map(|i| {
            if run.keep[i] {
                (run.z_m[i] - base[i]) * w
            } else {
                0.0
            }
        })
        .collect();
    let idx: Vec<usize> = if free_global {
        spec.affecting(run.material)
            .into_iter()
            .filter(|j| params[*j].hi > params[*j].lo)
            .collect()
    } else {
        Vec::new()
    };
    let na = idx.len();
    let mut cols: Vec<Vec<f64>> = Vec::with_capacity(na + N_LOCAL);
    let mut buf = vec![0.0; n];
    let column = |pred: &[f64], h: f64| -> Vec<f64> {
        (0..n)
            .map(|i| {
                if run.keep[i] {
                    (pred[i] - base[i]) / h * w
                } else {
                    0.0
                }
            })
            .collect()
    };
    for &j in &idx {
        let mut gp = g.to_vec();
        let h = inward_step(gp[j], params[j].step, params[j].hi);
        gp[j] += h;
        predict(spec, &gp, l, run, &mut buf);
        cols.push(column(&buf, h));
    }
    let lb = local_bounds(run);
    let steps = [1e-8, 1e-7, 1e-7];
    for k in 0..N_LOCAL {
        if k == 0 && !spec.position_dependent() {
            cols.push((0..n).map(|i| if run.keep[i] { w } else { 0.0 }).collect());
            continue;
        }
        let mut lp = *l;
        let h = inward_step(lp[k], steps[k], lb[k].1);
        lp[k] += h;
        predict(spec, g, &lp, run, &mut buf);
        cols.push(column(&buf, h));
    }
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let mut blk = Block {
        a: vec![0.0; na * na],
        b: vec![0.0; na * 3],
        c: [0.0; 9],
        bg: vec![0.0; na],
        bl: [0.0; 3],
        idx,
    };
    for i in 0..na {
        for j in 0..=i {
            let v = dot(&cols[i], &cols[j]);
            blk.a[i * na + j] = v;
            blk.a[j * na + i] = v;
        }
        for k in 0..3 {
            blk.b[i * 3 + k] = dot(&cols[i], &cols[na + k]);
        }
        blk.bg[i] = dot(&cols[i], &e);
    }
    for k in 0..3 {
        for m in 0..3 {
            blk.c[k * 3 + m] = dot(&cols[na + k], &cols[na + m]);
        }
        blk.bl[k] = dot(&cols[na + k], &e);
    }
    blk
}

/// Parameters held at a bound for one step (active set), globals and per-run locals.
struct Frozen {
    global: Vec<bool>,
    local: Vec<[bool; N_LOCAL]>,
}

/// The step and the Schur matrix of one LM iteration: (δg, δl per run, Schur matrix).
type Step = (Vec<f64>, Vec<[f64; 3]>, Vec<f64>);

/// The LM step for damping λ (with the undamped Schur matrix when λ = 0); None when a run's block
/// or the reduced system is singular even with jitter (the step is then rejected, never faked).
fn solve_step(
    blocks: &[Block],
    ng: usize,
    lambda: f64,
    free_global: bool,
    frozen: &Frozen,
) -> Option<Step> {
    let mut s = vec![0.0; ng * ng];
    let mut rhs = vec![0.0; ng];
    let mut cfac = Vec::with_capacity(blocks.len());
    let mut held: Vec<Block> = Vec::new();
    for (r, blk) in blocks.iter().enumerate() {
        // a frozen parameter loses its column: zero its couplings, unit diagonal, no gradient
        let blk = if frozen.local[r].iter().any(|f| *f) || blk.idx.iter().any(|j| frozen.global[*j])
        {
            let mut b = Block {
                idx: blk.idx.clone(),
                a: blk.a.clone(),
                b: blk.b.clone(),
                c: blk.c,
                bg: blk.bg.clone(),
                bl: blk.bl,
            };
            let na = b.idx.len();
            for k in 0..3 {
                if frozen.local[r][k] {
                    for m in 0..3 {
                        b.c[k * 3 + m] = 0.0;
                        b.c[m * 3 + k] = 0.0;
                    }
                    b.c[k * 4] = 1.0;
                    b.bl[k] = 0.0;
                    for i in 0..na {
                        b.b[i * 3 + k] = 0.0;
                    }
                }
            }
            for i in 0..na {
                if frozen.global[b.idx[i]] {
                    for j in 0..na {
                        b.a[i * na + j] = 0.0;
                        b.a[j * na + i] = 0.0;
                    }
                    b.bg[i] = 0.0;
                    for k in 0..3 {
                        b.b[i * 3 + k] = 0.0;
                    }
                }
            }
            held.push(b);
            held.last().expect("just pushed")
        } else {
            blk
        };
        let mut c = blk.c;
        for k in 0..3 {
            c[k * 4] *= 1.0 + lambda;
            c[k * 4] += 1e-30;
        }
        let lc = cholesky_jittered(&c, 3)?;
        let na = blk.idx.len();
        // B C⁻¹ (na×3) via solving C x = B_rowᵀ
        let mut bci = vec![0.0; na * 3];
        for i in 0..na {
            let mut row = [blk.b[i * 3], blk.b[i * 3 + 1], blk.b[i * 3 + 2]];
            chol_solve(&lc, 3, &mut row);
            bci[i * 3..i * 3 + 3].copy_from_slice(&row);
        }
        for i in 0..na {
            let gi = blk.idx[i];
            for j in 0..na {
                let gj = blk.idx[j];
                let corr: f64 = (0..3).map(|k| bci[i * 3 + k] * blk.b[j * 3 + k]).sum();
                s[gi * ng + gj] += blk.a[i * na + j] - corr;
            }
            let corr: f64 = (0..3).map(|k| bci[i * 3 + k] * blk.bl[k]).sum();
            rhs[gi] += blk.bg[i] - corr;
        }
        cfac.push((lc, r));
    }
    for i in 0..ng {
        if s[i * ng + i] == 0.0 {
            s[i * ng + i] = 1.0; // a fixed parameter: no column, no step
        }
    }
    let schur = s.clone();
    let mut dg = vec![0.0; ng];
    if free_global && ng > 0 {
        let mut sd = s;
        for i in 0..ng {
            sd[i * ng + i] *= 1.0 + lambda;
        }
        let l = cholesky_jittered(&sd, ng)?;
        dg = rhs;
        chol_solve(&l, ng, &mut dg);
        for (d, f) in dg.iter_mut().zip(&frozen.global) {
            if *f {
                *d = 0.0;
            }
        }
    }
    let mut held_iter = held.iter();
    let dl = blocks
        .iter()
        .enumerate()
        .zip(&cfac)
        .map(|((r, orig), (lc, _))| {
            let modified =
                frozen.local[r].iter().any(|f| *f) || orig.idx.iter().any(|j| frozen.global[*j]);
            let blk = if modified {
                held_iter.next().expect("one per modified block")
            } else {
                orig
            };
            let mut x = blk.bl;
            for (i, &gi) in blk.idx.iter().enumerate() {
                for (k, xk) in x.iter_mut().enumerate() {
                    *xk -= blk.b[i * 3 + k] * dg[gi];
                }
            }
            chol_solve(lc, 3, &mut x);
            for (xk, f) in x.iter_mut().zip(&frozen.local[r]) {
                if *f {
                    *xk = 0.0;
                }
            }
            x
        })
        .collect();
    Some((dg, dl, schur))
}

/// Fit `spec` to `runs` from the given start, with box bounds on every parameter.
pub fn fit_joint(
    spec: &Spec,
    params: &[ParamInfo],
    runs: &[RunData],
    start_g: &[f64],
    start_l: &[[f64; N_LOCAL]],
    ctl: FitControl,
) -> Fitted {
    let ng = spec.n_global();
    let clamp_g = |g: &mut [f64]| {
        for (x, p) in g.iter_mut().zip(params) {
            *x = x.clamp(p.lo, p.hi);
        }
    };
    let mut g = start_g.to_vec();
    clamp_g(&mut g);
    let mut l: Vec<[f64; N_LOCAL]> = start_l.to_vec();
    let chi2_of = |g: &[f64], l: &[[f64; N_LOCAL]]| -> Vec<f64> {
        runs.par_iter()
            .zip(l.par_iter())
            .map(|(r, lr)| run_chi2(spec, g, lr, r))
            .collect()
    };
    let mut chi2_run = chi2_of(&g, &l);
    let mut chi2: f64 = chi2_run.iter().sum();
    let mut lambda = 1e-3;
    let mut converged = false;
    let mut iterations = 0;
    let mut schur = vec![0.0; ng * ng];
    'outer: for it in 0..ctl.max_iter {
        iterations = it + 1;
        let blocks: Vec<Block> = runs
            .par_iter()
            .zip(l.par_iter())
            .map(|(r, lr)| block(spec, params, &g, lr, r, ctl.free_global))
            .collect();
        let none = Frozen {
            global: vec![false; ng],
            local: vec![[false; N_LOCAL]; runs.len()],
        };
        // a singular undamped system leaves NaN standard errors (said as such), not made-up ones
        schur = solve_step(&blocks, ng, 0.0, false, &none).map_or(vec![f64::NAN; ng * ng], |s| s.2);
        loop {
            // active set: a parameter on a bound whose step points outward is held this step
            let mut frozen = Frozen {
                global: vec![false; ng],
                local: vec![[false; N_LOCAL]; runs.len()],
            };
            let Some((mut dg, mut dl, _)) =
                solve_step(&blocks, ng, lambda, ctl.free_global, &frozen)
            else {
                lambda *= 8.0;
                if lambda > 1e9 {
                    break 'outer;
                }
                continue;
            };
            for _ in 0..4 {
                let mut changed = false;
                for j in 0..ng {
                    let p = &params[j];
                    if !frozen.global[j]
                        && ((g[j] <= p.lo && dg[j] < 0.0) || (g[j] >= p.hi && dg[j] > 0.0))
                    {
                        frozen.global[j] = true;
                        changed = true;
                    }
                }
                for (r, run) in runs.iter().enumerate() {
                    let lb = local_bounds(run);
                    for k in 0..N_LOCAL {
                        let x = l[r][k];
                        if !frozen.local[r][k]
                            && ((x <= lb[k].0 && dl[r][k] < 0.0)
                                || (x >= lb[k].1 && dl[r][k] > 0.0))
                        {
                            frozen.local[r][k] = true;
                            changed = true;
                        }
                    }
                }
                if !changed {
                    break;
                }
                let Some((dg2, dl2, _)) = solve_step(&blocks, ng, lambda, ctl.free_global, &frozen)
                else {
                    break;
                };
                (dg, dl) = (dg2, dl2);
            }
            let mut g2: Vec<f64> = g.iter().zip(&dg).map(|(a, b)| a + b).collect();
            clamp_g(&mut g2);
            let l2: Vec<[f64; N_LOCAL]> = l
                .iter()
                .zip(&dl)
                .zip(runs)
                .map(|((lr, d), r)| {
                    let lb = local_bounds(r);
                    let mut x = *lr;
                    for k in 0..N_LOCAL {
                        x[k] = (x[k] + d[k]).clamp(lb[k].0, lb[k].1);
                    }
                    x
                })
                .collect();
            let c2 = chi2_of(&g2, &l2);
            let total: f64 = c2.iter().sum();
            if total.is_finite() && total <= chi2 {
                let gain = chi2 - total;
                g = g2;
                l = l2;
                chi2_run = c2;
                chi2 = total;
                lambda = (lambda / 4.0).max(1e-9);
                if gain <= 1e-7 * chi2 + 1e-9 {
                    converged = true;
                    break 'outer;
                }
                break;
            }
            lambda *= 8.0;
            if lambda > 1e9 {
                converged = true; // no downhill step left: a (local) minimum
                break 'outer;
            }
        }
    }
    let dof = runs.iter().map(|r| r.n_used()).sum::<usize>() as f64
        - (ng * usize::from(ctl.free_global) + N_LOCAL * runs.len()) as f64;
    let scale = (chi2 / dof.max(1.0)).max(1.0);
    let global_se = if ng > 0 && ctl.free_global {
        match cholesky_jittered(&schur, ng) {
            Some(lf) => {
                let inv = chol_inverse(&lf, ng);
                (0..ng)
                    .map(|i| (inv[i * ng + i].max(0.0) * scale).sqrt())
                    .collect()
            }
            // singular: no standard errors rather than the ~1 an identity factor would give
            None => vec![f64::NAN; ng],
        }
    } else {
        vec![0.0; ng]
    };
    Fitted {
        global: g,
        local: l,
        chi2,
        chi2_run,
        global_se,
        iterations,
        converged,
    }
}
