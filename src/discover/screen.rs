//! The screen: every candidate's likelihood-ratio statistic and its parametric-bootstrap null,
//! from the linear response of the current joint model, with no refits.
//!
//! Around the fitted model a small extra term moves the predicted positions linearly: along the
//! model's secant for a named term (each parameter stepped from where the term vanishes), along
//! the response to the force's basis functions for a form with a scale to search (`response.rs`: a
//! periodic force in z at each trial wavenumber, a bump at each trial centre and width, a force
//! periodic in time at each trial frequency with a phase per run, a spline). Each run's z0, t0, v0
//! are projected out and the shared parameters (μ, T, accepted terms) profiled, so the statistic
//! is the drop in χ² a refit would give to first order. The same statistic, maximised over the
//! same trials, is computed on replicates of each run's measured noise (Gaussian AR(1): its σ and
//! lag-1 correlation) pushed through the same projections: the null of a searched form carries
//! its look-elsewhere effect, for a few dot products per trial instead of a nonlinear refit per
//! replicate. Only the candidates the screen finds significant are fitted in full.

use super::candidate::{Extra, N_LOCAL};
use super::data::RunData;
use super::forward::Model;
use super::joint::predict;
use super::proposal::{bump_column, bump_trials, Ranges};
use super::response::Prepared;
use super::spectral::{f_grid, k_grid};
use crate::lsq::dense::{chol_inverse, cholesky_jittered};
use crate::physics::{spline_basis, spline_n_basis};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Noise replicates drawn for each screen (the data is replicate 0).
pub const REPLICATES: usize = 60;

/// What the screen found for one candidate.
#[derive(Clone, Debug)]
pub struct Screened {
    /// First-order χ² drop on the data, maximised over the form's trials.
    pub lr: f64,
    /// The same statistic on each noise replicate.
    pub replicates: Vec<f64>,
    /// Linear estimates of the term's parameters (in its own parameterization) and their
    /// standard errors (NaN where the trial grid, not a fit, set the value).
    pub estimate: Vec<f64>,
    pub se: Vec<f64>,
}

/// Each run's data residual (replicate 0) and noise replicates, projected and in noise units.
pub struct Vectors {
    /// `[run][b]`, each over the run's kept samples.
    y: Vec<Vec<Vec<f64>>>,
    /// The shared parameters profiled: kept columns, (G'G)⁻¹ and G'y per replicate.
    kept: Vec<usize>,
    ginv: Vec<f64>,
    gty: Vec<Vec<f64>>,
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
                let rho = run.rho1.clamp(-0.99, 0.99);
                let innov = (1.0 - rho * rho).sqrt();
                for b in 0..replicates {
                    let mut rng = ChaCha8Rng::seed_from_u64(
                        seed ^ (((p.run as u64) << 20) | (b as u64 + 1))
                            .wrapping_mul(0x9E37_79B9_7F4A_7C15),
                    );
                    let mut e: f64 = rng.sample(StandardNormal);
                    let mut v = Vec::with_capacity(n);
                    for _ in 0..n {
                        v.push(e);
                        e = rho * e + innov * rng.sample::<f64, _>(StandardNormal);
                    }
                    p.proj.apply(&mut v);
                    out.push(v);
                }
                out
            })
            .collect();
        let ng = prep.first().map(|p| p.glob.len()).unwrap_or(0);
        let kept: Vec<usize> = (0..ng)
            .filter(|&j| prep.iter().any(|p| p.glob[j].iter().any(|x| *x != 0.0)))
            .collect();
        let k = kept.len();
        let mut gtg = vec![0.0; k * k];
        let mut gty = vec![vec![0.0; k]; replicates + 1];
        for (p, yr) in prep.iter().zip(&y) {
            for (a, &ja) in kept.iter().enumerate() {
                for (b, &jb) in kept.iter().enumerate() {
                    gtg[a * k + b] += dot(&p.glob[ja], &p.glob[jb]);
                }
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

    fn n_rep(&self) -> usize {
        self.y.first().map(|r| r.len()).unwrap_or(1)
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Sums over runs for a set of q columns shared by every run (coherent).
struct Sums {
    q: usize,
    xtx: Vec<f64>,
    xtg: Vec<f64>,
    xty: Vec<Vec<f64>>,
}

impl Sums {
    fn new(q: usize, k: usize, nrep: usize) -> Sums {
        Sums {
            q,
            xtx: vec![0.0; q * q],
            xtg: vec![0.0; q * k],
            xty: vec![vec![0.0; q]; nrep],
        }
    }

    fn add(&mut self, cols: &[Vec<f64>], p: &Prepared, v: &Vectors, yr: &[Vec<f64>]) {
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
            for (bb, yb) in yr.iter().enumerate() {
                self.xty[bb][a] += dot(&cols[a], yb);
            }
        }
    }

    /// LR per replicate, the data's coefficients and their variances (shared parameters profiled).
    fn solve(&self, v: &Vectors) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let (q, k) = (self.q, v.kept.len());
        // A = X'X − X'G (G'G)⁻¹ G'X
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
        let l = cholesky_jittered(&am, q)?;
        let inv = chol_inverse(&l, q);
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
                                .map(|d| xg_ginv[a * k + d] * v.gty[bb][d])
                                .sum::<f64>()
                    }
                })
                .collect();
            let beta: Vec<f64> = (0..q)
                .map(|a| (0..q).map(|b| inv[a * q + b] * c[b]).sum())
                .collect();
            lr.push(dot(&beta, &c).max(0.0));
            if bb == 0 {
                beta0 = beta;
            }
        }
        let var = (0..q)
            .map(|a| if dead[a] { f64::NAN } else { inv[a * q + a] })
            .collect();
        Some((lr, beta0, var))
    }
}

/// One trial of a form: LR per replicate, with the estimate and se it gives on the data.
type Trial = (Vec<f64>, Vec<f64>, Vec<f64>);

/// The elementwise maximum over trials; the estimate is the data's best trial's.
fn best_of(trials: Vec<Option<Trial>>, nrep: usize) -> Option<Trial> {
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

/// Coherent trial: the same columns' coefficients in every run; `cols(p)` gives a run's columns
/// (already in noise units with its locals projected) or None where the form cannot act.
fn coherent<F>(
    prep: &[Prepared],
    v: &Vectors,
    q: usize,
    cols: F,
) -> Option<(Vec<f64>, Vec<f64>, Vec<f64>)>
where
    F: Fn(&Prepared) -> Option<Vec<Vec<f64>>>,
{
    let mut s = Sums::new(q, v.kept.len(), v.n_rep());
    for (p, yr) in prep.iter().zip(&v.y) {
        if let Some(c) = cols(p) {
            s.add(&c, p, v, yr);
        }
    }
    s.solve(v)
}

/// Secant columns of a named term: each parameter stepped from where the term vanishes.
fn secant(
    current: &Model,
    extra: &Extra,
    theta0: &[f64],
    steps: &[(usize, f64)],
    runs: &[RunData],
    prep: &[Prepared],
    null_pred: &[Vec<f64>],
    v: &Vectors,
) -> Option<Trial> {
    let spec = current.spec.with(extra.clone());
    let q = steps.len();
    let (lr, beta, var) = coherent(prep, v, q, |p| {
        let run = &runs[p.run];
        let l: &[f64; N_LOCAL] = &current.fit.local[p.run];
        let cols = steps
            .iter()
            .map(|&(j, to)| {
                let mut g = current.fit.global.clone();
                g.extend_from_slice(theta0);
                let n0 = current.fit.global.len();
                let d = to - theta0[j];
                g[n0 + j] = to;
                let mut z = vec![0.0; run.t_s.len()];
                predict(&spec, &g, l, run, &mut z);
                let kept: Vec<f64> = (0..run.t_s.len())
                    .filter(|&i| run.keep[i])
                    .map(|i| (z[i] - null_pred[p.run][i]) / d)
                    .collect();
                p.column(kept)
            })
            .collect();
        Some(cols)
    })?;
    let mut est = theta0.to_vec();
    let mut se = vec![f64::NAN; theta0.len()];
    for (a, &(j, _)) in steps.iter().enumerate() {
        est[j] = theta0[j] + beta[a];
        se[j] = var[a].sqrt();
    }
    Some((lr, est, se))
}

/// Screen `extras` against `current` (prepared in `prep`) with `replicates` noise draws.
#[allow(clippy::too_many_arguments)]
pub fn screen(
    extras: &[&Extra],
    current: &Model,
    runs: &[RunData],
    prep: &[Prepared],
    rg: &Ranges,
    replicates: usize,
    seed: u64,
) -> Vec<Option<Screened>> {
    let v = Vectors::new(prep, runs, replicates, seed);
    let nrep = v.n_rep();
    let null_pred: Vec<Vec<f64>> = runs
        .par_iter()
        .zip(&current.fit.local)
        .map(|(run, l)| {
            let mut z = vec![0.0; run.t_s.len()];
            predict(&current.spec, &current.fit.global, l, run, &mut z);
            z
        })
        .collect();
    extras
        .iter()
        .map(|e| {
            let t = match e {
                Extra::PeriodicZ {
                    k_lo,
                    k_hi,
                    z_ref_m,
                } => periodic_z(prep, &v, rg, *z_ref_m, *k_lo, *k_hi),
                Extra::Localized { w_lo, w_hi, .. } => localized(prep, &v, rg, *w_lo, *w_hi),
                Extra::TimePeriodic { f_lo, f_hi } => time_periodic(prep, &v, rg, *f_lo, *f_hi),
                Extra::Spline {
                    variable,
                    lo,
                    dx,
                    segments,
                } => spline(prep, &v, *variable, *lo, *dx, *segments),
                Extra::VelocityFriction { materials } => {
                    let lo = e.params()[0].lo;
                    let theta0 = vec![lo; *materials];
                    let trials: Vec<Option<Trial>> = [1e-3f64, 3e-3, 1e-2, 3e-2]
                        .par_iter()
                        .map(|vc| {
                            let steps: Vec<(usize, f64)> =
                                (0..*materials).map(|m| (m, vc.ln())).collect();
                            secant(current, e, &theta0, &steps, runs, prep, &null_pred, &v).map(
                                |(lr, _, se)| {
                                    (lr, vec![vc.ln(); *materials], vec![f64::NAN; se.len()])
                                },
                            )
                        })
                        .collect();
                    best_of(trials, nrep)
                }
                _ => {
                    let ps = e.params();
                    let theta0: Vec<f64> = ps.iter().map(|p| p.start).collect();
                    let steps: Vec<(usize, f64)> = ps
                        .iter()
                        .enumerate()
                        .map(|(j, p)| {
                            let up = p.start + 100.0 * p.step;
                            (
                                j,
                                if up <= p.hi {
                                    up
                                } else {
                                    p.start - 100.0 * p.step
                                },
                            )
                        })
                        .collect();
                    secant(current, e, &theta0, &steps, runs, prep, &null_pred, &v)
                }
            };
            t.map(|(lr, estimate, se)| Screened {
                lr: lr[0],
                replicates: lr[1..].to_vec(),
                estimate,
                se,
            })
        })
        .collect()
}

fn periodic_z(
    prep: &[Prepared],
    v: &Vectors,
    rg: &Ranges,
    z_ref: f64,
    k_lo: f64,
    k_hi: f64,
) -> Option<Trial> {
    let ks: Vec<f64> = k_grid(rg.span(), rg.lambda_min_m)
        .into_iter()
        .filter(|k| *k >= k_lo && *k <= k_hi)
        .collect();
    let trials: Vec<Option<Trial>> = ks
        .par_iter()
        .map(|&k| {
            let (lr, b, var) = coherent(prep, v, 2, |p| {
                let z = p.track.variable(crate::physics::Variable::Z);
                let fs: Vec<f64> = z.iter().map(|z| (k * (z - z_ref)).sin()).collect();
                let fc: Vec<f64> = z.iter().map(|z| (k * (z - z_ref)).cos()).collect();
                Some(vec![
                    p.column(p.track.respond_values(&fs)),
                    p.column(p.track.respond_values(&fc)),
                ])
            })?;
            Some((
                lr,
                vec![k, b[0], b[1]],
                vec![f64::NAN, var[0].sqrt(), var[1].sqrt()],
            ))
        })
        .collect();
    best_of(trials, v.n_rep())
}

fn localized(prep: &[Prepared], v: &Vectors, rg: &Ranges, w_lo: f64, w_hi: f64) -> Option<Trial> {
    let trials = bump_trials(rg, w_lo, w_hi);
    let out: Vec<Option<Trial>> = trials
        .par_iter()
        .map(|&(c, w)| {
            let (lr, b, var) = coherent(prep, v, 1, |p| bump_column(p, c, w).map(|x| vec![x]))?;
            Some((
                lr,
                vec![b[0], c, w],
                vec![var[0].sqrt(), f64::NAN, f64::NAN],
            ))
        })
        .collect();
    best_of(out, v.n_rep())
}

/// A force periodic in time with one amplitude and each run's own phase. Per run the (sin, cos)
/// responses carry information a_r (half the trace of their normal matrix, the two being nearly
/// orthogonal over many periods) and the data project to |b_r| at the best phase; a shared
/// amplitude α drops χ² by Σ(2α|b_r| − α²a_r), at best (Σ|b_r|)²/Σa_r. A free amplitude per run
/// would absorb any structure at all one run at a time; the shared one does not.
fn time_periodic(
    prep: &[Prepared],
    v: &Vectors,
    rg: &Ranges,
    f_lo: f64,
    f_hi: f64,
) -> Option<Trial> {
    let fs: Vec<f64> = f_grid(rg.duration_s, rg.f_max_hz)
        .into_iter()
        .filter(|f| *f >= f_lo && *f <= f_hi)
        .collect();
    let nrep = v.n_rep();
    let out: Vec<Option<Trial>> = fs
        .par_iter()
        .map(|&f| {
            let mut sb = vec![0.0; nrep];
            let mut sa = 0.0;
            for (p, yr) in prep.iter().zip(&v.y) {
                let (rs, rc) = p.track.respond_time(TAU * f);
                let xs = p.column(rs);
                let xc = p.column(rc);
                let a = 0.5 * (dot(&xs, &xs) + dot(&xc, &xc));
                if a <= 0.0 {
                    continue;
                }
                sa += a;
                for (bb, yb) in yr.iter().enumerate() {
                    sb[bb] += dot(&xs, yb).hypot(dot(&xc, yb));
                }
            }
            if sa <= 0.0 {
                return None;
            }
            let lr: Vec<f64> = sb.iter().map(|b| b * b / sa).collect();
            Some((lr, vec![f, sb[0] / sa], vec![f64::NAN, 1.0 / sa.sqrt()]))
        })
        .collect();
    best_of(out, nrep)
}

fn spline(
    prep: &[Prepared],
    v: &Vectors,
    var: crate::physics::Variable,
    lo: f64,
    dx: f64,
    segments: usize,
) -> Option<Trial> {
    let nb = spline_n_basis(segments);
    let (lr, b, vv) = coherent(prep, v, nb, |p| {
        let x = p.track.variable(var);
        Some(
            (0..nb)
                .map(|j| {
                    let f: Vec<f64> = x
                        .iter()
                        .map(|xv| spline_basis(lo, dx, segments, j, *xv))
                        .collect();
                    p.column(p.track.respond_values(&f))
                })
                .collect(),
        )
    })?;
    Some((lr, b, vv.iter().map(|x| x.sqrt()).collect()))
}
