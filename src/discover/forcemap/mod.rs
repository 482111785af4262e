//! The force map: the missing acceleration as a smooth function of one variable (lab z, signed v,
//! time since the kick) or of the motion phase, estimated jointly over every single run.
//!
//! Files of this folder:
//!
//! - `mod.rs`: this file alone holds the force map
//!
//! The residuals of the current joint model are regressed on each run's linear response to the
//! cubic B-spline basis functions of the variable (`response.rs`), with each run's z0, t0, v0
//! projected out and the shared parameters (μ, T, accepted terms) refitted alongside, so the map
//! shows only what those cannot absorb. A second-difference penalty (P-spline) sets the
//! smoothness, chosen by leave-runs-out cross-validation (the same folds as the candidates); the
//! band is ±1.96 standard errors from the penalized normal equations, inflated by the residual
//! χ² per degree of freedom when that exceeds 1. A flat map inside its band is the picture of
//! "nothing missing" in that variable.

use super::response::{dot, Prepared};
use crate::lsq::dense::{chol_inverse, chol_solve, cholesky_jittered};
use crate::physics::{spline_basis, spline_n_basis, Phase, Variable};
use rayon::prelude::*;

/// Points at which a map is reported.
const GRID: usize = 101;

pub use crate::artifacts::diagnosis::ForceMap;

/// Normal-equation pieces of one run: X'X (p×p), X'y, y'y.
struct Piece {
    m: Vec<f64>,
    c: Vec<f64>,
    yy: f64,
}

fn piece(cols: &[Vec<f64>], y: &[f64]) -> Piece {
    let p = cols.len();
    let mut m = vec![0.0; p * p];
    for i in 0..p {
        for j in 0..=i {
            let v = dot(&cols[i], &cols[j]);
            m[i * p + j] = v;
            m[j * p + i] = v;
        }
    }
    Piece {
        m,
        c: cols.iter().map(|c| dot(c, y)).collect(),
        yy: dot(y, y),
    }
}

/// Solve (m + pen) θ = c; returns θ and the factor, None when singular.
fn solve(m: &[f64], pen: &[f64], c: &[f64], p: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    let a: Vec<f64> = m.iter().zip(pen).map(|(x, y)| x + y).collect();
    let l = cholesky_jittered(&a, p)?;
    let mut th = c.to_vec();
    chol_solve(&l, p, &mut th);
    Some((th, l))
}

/// The fitted map: coefficients, inverse penalized normal matrix, λ, edf, χ² drop, CV gain, RSS,
/// and the penalty's weight in χ² per (m/s²)² of second difference (λ times the mean diagonal).
type MapFit = (Vec<f64>, Vec<f64>, f64, f64, f64, f64, f64, f64);

fn quad(m: &[f64], th: &[f64], p: usize) -> f64 {
    let mut s = 0.0;
    for i in 0..p {
        for j in 0..p {
            s += th[i] * m[i * p + j] * th[j];
        }
    }
    s
}

/// Fit a penalized map from per-run columns: `glob` unpenalized, `basis` penalized by `pen_b`
/// (second differences when `smooth`), λ by leave-runs-out CV over `fold`.
fn fit_map(
    pieces: &[Piece],
    n_glob: usize,
    n_b: usize,
    smooth: bool,
    fold: &[usize],
    k: usize,
) -> Option<MapFit> {
    let p = n_glob + n_b;
    let mut m = vec![0.0; p * p];
    let mut c = vec![0.0; p];
    let mut yy = 0.0;
    let mut mf = vec![vec![0.0; p * p]; k];
    let mut cf = vec![vec![0.0; p]; k];
    let mut yyf = vec![0.0; k];
    for (r, pc) in pieces.iter().enumerate() {
        let f = fold[r] % k;
        for i in 0..p * p {
            m[i] += pc.m[i];
            mf[f][i] += pc.m[i];
        }
        for i in 0..p {
            c[i] += pc.c[i];
            cf[f][i] += pc.c[i];
        }
        yy += pc.yy;
        yyf[f] += pc.yy;
    }
    let mean_diag =
        (n_glob..p).map(|i| m[i * p + i]).sum::<f64>() / n_b.max(1) as f64 + f64::MIN_POSITIVE;
    let ridge_of = |i: usize| 1e-9 * m[i * p + i].abs().max(1e-300);
    // penalty matrix for relative λ = 1
    let mut d2 = vec![0.0; p * p];
    if smooth && n_b >= 3 {
        for j in 0..n_b - 2 {
            let idx = [n_glob + j, n_glob + j + 1, n_glob + j + 2];
            let w = [1.0, -2.0, 1.0];
            for a in 0..3 {
                for b in 0..3 {
                    d2[idx[a] * p + idx[b]] += w[a] * w[b];
                }
            }
        }
    }
    let pen_at = |lam: f64, zero_map: bool| -> Vec<f64> {
        let mut pen: Vec<f64> = d2.iter().map(|x| x * lam * mean_diag).collect();
        for i in 0..p {
            pen[i * p + i] += ridge_of(i);
            if zero_map && i >= n_glob {
                pen[i * p + i] += 1e12 * mean_diag;
            }
        }
        pen
    };
    let held_out = |pen: &[f64]| -> f64 {
        (0..k)
            .map(|f| {
                let mt: Vec<f64> = m.iter().zip(&mf[f]).map(|(a, b)| a - b).collect();
                let ct: Vec<f64> = c.iter().zip(&cf[f]).map(|(a, b)| a - b).collect();
                match solve(&mt, pen, &ct, p) {
                    Some((th, _)) => yyf[f] - 2.0 * dot(&th, &cf[f]) + quad(&mf[f], &th, p),
                    None => f64::INFINITY,
                }
            })
            .sum()
    };
    let ss0 = held_out(&pen_at(0.0, true));
    let lambdas: Vec<f64> = if smooth {
        (0..21).map(|i| 10f64.powf(-6.0 + 0.5 * i as f64)).collect()
    } else {
        vec![0.0]
    };
    let scores: Vec<f64> = lambdas
        .par_iter()
        .map(|&l| held_out(&pen_at(l, false)))
        .collect();
    let (best, ss) =
        scores.iter().enumerate().fold(
            (0, f64::INFINITY),
            |b, (i, s)| if *s < b.1 { (i, *s) } else { b },
        );
    let lam = lambdas[best];
    let pen = pen_at(lam, false);
    let (th, l) = solve(&m, &pen, &c, p)?;
    let inv = chol_inverse(&l, p);
    // edf of the map part: trace((M + P)⁻¹ M) over the basis block
    let mut edf = 0.0;
    for i in n_glob..p {
        for j in 0..p {
            edf += inv[i * p + j] * m[j * p + i];
        }
    }
    let rss = yy - 2.0 * dot(&th, &c) + quad(&m, &th, p);
    let (th0, _) = solve(&m, &pen_at(0.0, true), &c, p)?;
    let rss0 = yy - 2.0 * dot(&th0, &c) + quad(&m, &th0, p);
    Some((
        th,
        inv,
        lam,
        edf,
        rss0 - rss,
        ss0 - ss,
        rss,
        lam * mean_diag,
    ))
}

/// Range of a variable over the sampled, moving part of every run.
fn range(prep: &[Prepared], var: Variable) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for p in prep {
        let x = p.track.variable(var);
        for (k, xv) in x.iter().enumerate() {
            if p.track.phase[k] != Phase::Rest && k + 1 < x.len() {
                lo = lo.min(*xv);
                hi = hi.max(*xv);
            }
        }
    }
    (hi > lo).then_some((lo, hi))
}

/// The force map of `var` with `segments` knot intervals over the observed range.
pub fn force_map(
    prep: &[Prepared],
    var: Variable,
    segments: usize,
    fold: &[usize],
    k: usize,
    n_obs: usize,
) -> Option<ForceMap> {
    let (lo, hi) = range(prep, var)?;
    let n_b = spline_n_basis(segments);
    let dx = (hi - lo) / segments as f64;
    let n_glob = prep.first().map(|p| p.glob.len()).unwrap_or(0);
    let pieces: Vec<Piece> = prep
        .par_iter()
        .map(|p| {
            let x = p.track.variable(var);
            let (rlo, rhi) = x
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(*v), b.max(*v))
                });
            let mut cols: Vec<Vec<f64>> = p.glob.clone();
            for j in 0..n_b {
                // support of basis j: [lo + (j−3)dx, lo + (j+1)dx]
                let s_lo = lo + (j as f64 - 3.0) * dx;
                let s_hi = lo + (j as f64 + 1.0) * dx;
                let inside = s_hi >= rlo.clamp(lo, hi) && s_lo <= rhi.clamp(lo, hi);
                if !inside {
                    cols.push(vec![0.0; p.y.len()]);
                    continue;
                }
                let f: Vec<f64> = x
                    .iter()
                    .map(|v| spline_basis(lo, dx, segments, j, *v))
                    .collect();
                cols.push(p.column(p.track.respond_values(&f)));
            }
            piece(&cols, &p.y)
        })
        .collect();
    let (th, inv, lambda, edf, chi2_drop, cv_gain, rss, weight) =
        fit_map(&pieces, n_glob, n_b, true, fold, k)?;
    let p = n_glob + n_b;
    let scale = (rss / (n_obs as f64 - edf - n_glob as f64).max(1.0))
        .max(1.0)
        .sqrt();
    let coefs = th[n_glob..].to_vec();
    let x: Vec<f64> = (0..GRID)
        .map(|i| lo + (hi - lo) * i as f64 / (GRID - 1) as f64)
        .collect();
    let mut accel = Vec::with_capacity(GRID);
    let mut se = Vec::with_capacity(GRID);
    for xv in &x {
        let b: Vec<f64> = (0..n_b)
            .map(|j| spline_basis(lo, dx, segments, j, *xv))
            .collect();
        accel.push(dot(&b, &coefs));
        let mut v = 0.0;
        for i in 0..n_b {
            for j in 0..n_b {
                v += b[i] * inv[(n_glob + i) * p + n_glob + j] * b[j];
            }
        }
        se.push(v.max(0.0).sqrt() * scale);
    }
    let max_abs_z = accel
        .iter()
        .zip(&se)
        .map(|(a, s)| if *s > 0.0 { a.abs() / s } else { 0.0 })
        .fold(0.0, f64::max);
    let (variable, unit) = match var {
        Variable::Z => ("z", "m"),
        Variable::V => ("v", "m/s"),
        Variable::T => ("t", "s"),
    };
    Some(ForceMap {
        variable: variable.into(),
        unit: unit.into(),
        x,
        accel_mps2: accel,
        se_mps2: se,
        lambda,
        edf,
        chi2_drop,
        cv_gain,
        max_abs_z,
        spline: Some((lo, dx, segments, coefs, weight)),
    })
}

/// The map over the motion phase: one constant missing acceleration while sliding, one while
/// rolling (x = 0 sliding, 1 rolling).
pub fn phase_map(prep: &[Prepared], fold: &[usize], k: usize, n_obs: usize) -> Option<ForceMap> {
    let n_glob = prep.first()?.glob.len();
    let pieces: Vec<Piece> = prep
        .par_iter()
        .map(|p| {
            let mut cols = p.glob.clone();
            for ph in [Phase::Sliding, Phase::Rolling] {
                let f: Vec<f64> = p
                    .track
                    .phase
                    .iter()
                    .map(|q| if *q == ph { 1.0 } else { 0.0 })
                    .collect();
                cols.push(p.column(p.track.respond_values(&f)));
            }
            piece(&cols, &p.y)
        })
        .collect();
    let (th, inv, lambda, edf, chi2_drop, cv_gain, rss, _) =
        fit_map(&pieces, n_glob, 2, false, fold, k)?;
    let p = n_glob + 2;
    let scale = (rss / (n_obs as f64 - edf - n_glob as f64).max(1.0))
        .max(1.0)
        .sqrt();
    let accel = vec![th[n_glob], th[n_glob + 1]];
    let se: Vec<f64> = (0..2)
        .map(|i| inv[(n_glob + i) * p + n_glob + i].max(0.0).sqrt() * scale)
        .collect();
    let max_abs_z = accel
        .iter()
        .zip(&se)
        .map(|(a, s)| if *s > 0.0 { a.abs() / s } else { 0.0 })
        .fold(0.0, f64::max);
    Some(ForceMap {
        variable: "phase".into(),
        unit: String::new(),
        x: vec![0.0, 1.0],
        accel_mps2: accel,
        se_mps2: se,
        lambda,
        edf,
        chi2_drop,
        cv_gain,
        max_abs_z,
        spline: None,
    })
}
