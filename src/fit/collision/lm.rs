//! A small robust Levenberg–Marquardt solver (Huber IRLS, box bounds, Jacobian standard errors)
//! for the joint multi-segment fit of a collision run.
//!
//! The fit helper's `fit::segment` fits one segment at a time; a collision run needs one problem
//! with shared μ, T, fitted impact times and z continuous across impacts, so this module keeps its
//! own dense solver. Problems are small (≤ ~40 parameters, a few thousand residuals).

/// Why the solver stopped; not converging is a result, not an error.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Termination {
    /// The relative cost change or the step fell below tolerance.
    Converged,
    /// The iteration budget ran out first.
    MaxIterations,
    /// The normal equations could not be solved even with heavy damping.
    Singular,
}

/// Solver settings.
#[derive(Debug, Clone, Copy)]
pub struct LmOptions {
    pub max_iter: usize,
    /// Outer IRLS rounds (each re-weights the residuals with the Huber function).
    pub irls_rounds: usize,
    /// Huber threshold in units of the robust residual scale.
    pub huber_c: f64,
    /// Lower bound of the robust residual scale (m), so a perfect fit does not divide by zero.
    pub scale_floor: f64,
    pub rel_tol: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iter: 60,
            irls_rounds: 4,
            huber_c: 2.5,
            scale_floor: 1e-9,
            rel_tol: 1e-10,
        }
    }
}

/// One parameter: start value, bounds and the finite-difference step.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    pub start: f64,
    pub lower: f64,
    pub upper: f64,
    pub step: f64,
}

/// The solution.
#[derive(Debug, Clone)]
pub struct LmResult {
    pub params: Vec<f64>,
    /// Covariance of the parameters: (JᵀWJ)⁻¹ · scale², NaN rows where not identified.
    pub covariance: Vec<Vec<f64>>,
    pub termination: Termination,
    pub iterations: usize,
    /// Robust residual scale (1.4826 · MAD), m.
    pub scale: f64,
    /// Final residuals (unweighted).
    pub residuals: Vec<f64>,
}

impl LmResult {
    /// Standard error of parameter `i` (NaN when not identified).
    pub fn se(&self, i: usize) -> f64 {
        self.covariance[i][i].max(0.0).sqrt()
    }
}

/// Minimize Σ ρ(r_i) over `specs`; `residuals(p, out)` fills `out` (length `n`).
pub fn minimize<F>(residuals: F, n: usize, specs: &[ParamSpec], opts: &LmOptions) -> LmResult
where
    F: Fn(&[f64], &mut [f64]),
{
    let m = specs.len();
    let mut p: Vec<f64> = specs
        .iter()
        .map(|s| s.start.clamp(s.lower, s.upper))
        .collect();
    let mut r = vec![0.0; n];
    let mut w = vec![1.0; n];
    let mut jac = vec![vec![0.0; n]; m];
    let mut iterations = 0;
    let mut termination = Termination::MaxIterations;
    let mut scale;
    for _ in 0..opts.irls_rounds.max(1) {
        residuals(&p, &mut r);
        scale = robust_scale(&r).max(opts.scale_floor);
        huber_weights(&r, opts.huber_c * scale, &mut w);
        let mut lambda = 1e-3;
        let mut cost = weighted_cost(&r, &w);
        termination = Termination::MaxIterations;
        for _ in 0..opts.max_iter {
            iterations += 1;
            jacobian(&residuals, &p, specs, &r, &mut jac);
            let (mut a, g) = normal_equations(&jac, &r, &w);
            hold_fixed(specs, &mut a);
            let mut improved = false;
            for _ in 0..12 {
                let mut damped = a.clone();
                for i in 0..m {
                    damped[i][i] += lambda * a[i][i].max(1e-30);
                }
                let neg_g: Vec<f64> = g.iter().map(|x| -x).collect();
                let Some(step) = solve_spd(&damped, &neg_g) else {
                    lambda *= 10.0;
                    continue;
                };
                let trial: Vec<f64> = p
                    .iter()
                    .zip(&step)
                    .zip(specs)
                    .map(|((x, d), s)| {
                        if s.lower == s.upper {
                            *x
                        } else {
                            (x + d).clamp(s.lower, s.upper)
                        }
                    })
                    .collect();
                let mut r_trial = vec![0.0; n];
                residuals(&trial, &mut r_trial);
                let c_trial = weighted_cost(&r_trial, &w);
                if c_trial.is_finite() && c_trial < cost {
                    let rel = (cost - c_trial) / cost.max(1e-300);
                    p = trial;
                    r = r_trial;
                    cost = c_trial;
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = true;
                    if rel < opts.rel_tol {
                        termination = Termination::Converged;
                    }
                    break;
                }
                lambda *= 4.0;
            }
            if !improved {
                // no downhill step at any damping: a (local) minimum for these weights
                termination = Termination::Converged;
                break;
            }
            if termination == Termination::Converged {
                break;
            }
        }
    }
    residuals(&p, &mut r);
    scale = robust_scale(&r).max(opts.scale_floor);
    huber_weights(&r, opts.huber_c * scale, &mut w);
    jacobian(&residuals, &p, specs, &r, &mut jac);
    let (mut a, _) = normal_equations(&jac, &r, &w);
    hold_fixed(specs, &mut a);
    let covariance = match invert_spd(&a) {
        Some(inv) => inv
            .into_iter()
            .enumerate()
            .map(|(i, row)| {
                row.into_iter()
                    .enumerate()
                    .map(|(j, x)| {
                        if specs[i].lower == specs[i].upper || specs[j].lower == specs[j].upper {
                            0.0
                        } else {
                            x * scale * scale
                        }
                    })
                    .collect()
            })
            .collect(),
        None => {
            termination = Termination::Singular;
            vec![vec![f64::NAN; m]; m]
        }
    };
    LmResult {
        params: p,
        covariance,
        termination,
        iterations,
        scale,
        residuals: r,
    }
}

/// 1.4826 · median |r| (the residuals of a good fit have median ≈ 0).
pub fn robust_scale(r: &[f64]) -> f64 {
    let mut a: Vec<f64> = r
        .iter()
        .map(|x| x.abs())
        .filter(|x| x.is_finite())
        .collect();
    if a.is_empty() {
        return f64::NAN;
    }
    let mid = a.len() / 2;
    a.select_nth_unstable_by(mid, |x, y| x.total_cmp(y));
    1.4826 * a[mid]
}

/// A parameter with lower == upper is held: its row and column become the identity.
fn hold_fixed(specs: &[ParamSpec], a: &mut [Vec<f64>]) {
    for (i, s) in specs.iter().enumerate() {
        if s.lower == s.upper {
            for j in 0..a.len() {
                a[i][j] = 0.0;
                a[j][i] = 0.0;
            }
            a[i][i] = 1.0;
        }
    }
}

fn huber_weights(r: &[f64], c: f64, w: &mut [f64]) {
    for (wi, ri) in w.iter_mut().zip(r) {
        let a = ri.abs();
        *wi = if a <= c { 1.0 } else { c / a };
    }
}

fn weighted_cost(r: &[f64], w: &[f64]) -> f64 {
    r.iter().zip(w).map(|(x, wi)| wi * x * x).sum()
}

fn jacobian<F>(f: &F, p: &[f64], specs: &[ParamSpec], r0: &[f64], jac: &mut [Vec<f64>])
where
    F: Fn(&[f64], &mut [f64]),
{
    let mut q = p.to_vec();
    let mut r1 = vec![0.0; r0.len()];
    for (j, s) in specs.iter().enumerate() {
        if s.lower == s.upper {
            jac[j].iter_mut().for_each(|x| *x = 0.0);
            continue;
        }
        // step inward when at the upper bound so the Jacobian stays inside the box
        let h = if p[j] + s.step > s.upper {
            -s.step
        } else {
            s.step
        };
        q[j] = p[j] + h;
        f(&q, &mut r1);
        for (i, col) in jac[j].iter_mut().enumerate() {
            *col = (r1[i] - r0[i]) / h;
        }
        q[j] = p[j];
    }
}

fn normal_equations(jac: &[Vec<f64>], r: &[f64], w: &[f64]) -> (Vec<Vec<f64>>, Vec<f64>) {
    let m = jac.len();
    let mut a = vec![vec![0.0; m]; m];
    let mut g = vec![0.0; m];
    for i in 0..m {
        g[i] = jac[i]
            .iter()
            .zip(r)
            .zip(w)
            .map(|((j, r), w)| j * r * w)
            .sum();
        for k in 0..=i {
            let v: f64 = jac[i]
                .iter()
                .zip(&jac[k])
                .zip(w)
                .map(|((a, b), w)| a * b * w)
                .sum();
            a[i][k] = v;
            a[k][i] = v;
        }
    }
    (a, g)
}

/// Cholesky solve of a symmetric positive definite system; None when not positive definite.
pub fn solve_spd(a: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let l = cholesky(a)?;
    let n = b.len();
    let mut y = vec![0.0; n];
    for i in 0..n {
        let s: f64 = (0..i).map(|k| l[i][k] * y[k]).sum();
        y[i] = (b[i] - s) / l[i][i];
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|k| l[k][i] * x[k]).sum();
        x[i] = (y[i] - s) / l[i][i];
    }
    Some(x)
}

fn cholesky(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i][k] * l[j][k]).sum();
            if i == j {
                let d = a[i][i] - s;
                if !(d > 0.0) || !d.is_finite() {
                    return None;
                }
                l[i][i] = d.sqrt();
            } else {
                l[i][j] = (a[i][j] - s) / l[j][j];
            }
        }
    }
    Some(l)
}

/// Inverse of a symmetric positive definite matrix (scaled to unit diagonal for conditioning).
fn invert_spd(a: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
    let n = a.len();
    let d: Vec<f64> = (0..n).map(|i| a[i][i].max(1e-300).sqrt()).collect();
    // a tiny ridge keeps a parameter the data barely constrain from spoiling the others' errors
    let scaled: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| a[i][j] / (d[i] * d[j]) + if i == j { 1e-12 } else { 0.0 })
                .collect()
        })
        .collect();
    let mut inv = vec![vec![0.0; n]; n];
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let col = solve_spd(&scaled, &e)?;
        for i in 0..n {
            inv[i][j] = col[i] / (d[i] * d[j]);
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_a_line_with_an_outlier() {
        let t: Vec<f64> = (0..50).map(|i| i as f64 * 0.1).collect();
        let mut y: Vec<f64> = t.iter().map(|t| 2.0 + 0.5 * t).collect();
        for (i, yi) in y.iter_mut().enumerate() {
            *yi += 1e-3 * ((i * 7919) % 13) as f64 / 13.0 - 0.5e-3;
        }
        y[17] += 5.0;
        let specs = [
            ParamSpec {
                start: 0.0,
                lower: -10.0,
                upper: 10.0,
                step: 1e-6,
            },
            ParamSpec {
                start: 0.0,
                lower: -10.0,
                upper: 10.0,
                step: 1e-6,
            },
        ];
        let res = minimize(
            |p, out| {
                for i in 0..t.len() {
                    out[i] = p[0] + p[1] * t[i] - y[i];
                }
            },
            t.len(),
            &specs,
            &LmOptions::default(),
        );
        assert!((res.params[0] - 2.0).abs() < 2e-3, "{:?}", res.params);
        assert!((res.params[1] - 0.5).abs() < 1e-3, "{:?}", res.params);
        assert!(res.se(1) > 0.0 && res.se(1) < 1e-3);
    }
}
