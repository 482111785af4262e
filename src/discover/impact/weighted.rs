//! Weighted least squares of one quantity against a speed, from points (x, y, standard error):
//! the shapes a law can take — the chapter's candidates, named forms beyond them and a
//! piecewise-linear map in ln x — each a sum of amplitudes times known functions, with a search
//! over its one or two nonlinear parameters.

use crate::lsq::dense::{invert_spd_scaled, solve_spd};
use crate::lsq::golden::minimize;
use crate::stats::dist::f_sf;

/// One measured point: speed `x` (m/s), value `y`, its standard error, and the rank of its run
/// (the runs are split in halves by it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pt {
    pub x: f64,
    pub y: f64,
    pub se: f64,
    pub run: usize,
}

/// The shape of a law y(x); parameters `p` in the order written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// y = a.
    Constant,
    /// y = a − b x (the chapter's linear law).
    Linear,
    /// y = a + (1 − a) e^{−x/b} (the chapter's saturating law).
    Saturating,
    /// y = 1 − a x^(1/5): viscoelastic spheres, to first order.
    Viscoelastic,
    /// y = a √(1 − (b/x)²) above b, 0 below: adhesion, the contact sticks below b.
    Adhesive,
    /// y = a (x/x̄)^(−b), x̄ the points' geometric mean: plastic yield has b ≈ 1/4.
    PowerLaw,
    /// y = a √(1 − (b/x)²) e^{−x/c}: adhesion below b, losses growing with speed above.
    AdhesiveYield,
    /// y = a / (1 + x/b): falling with speed on the scale b.
    Weakening,
    /// Piecewise linear in ln x through its values at the nodes, constant beyond them.
    Map,
}

/// A fitted shape: its parameters, the nodes of a map (ln x; a power law's ln x̄), its χ².
#[derive(Clone, Debug, PartialEq)]
pub struct Fit {
    pub shape: Shape,
    pub p: Vec<f64>,
    pub nodes: Vec<f64>,
    pub chi2: f64,
    /// A nonlinear parameter ended at the end of its search: the data do not fix it.
    pub at_bound: bool,
}

fn adhesion(x: f64, b: f64) -> f64 {
    (1.0 - (b / x).powi(2)).max(0.0).sqrt()
}

/// The hat functions of the nodes at ln x (constant beyond the end nodes).
fn hats(nodes: &[f64], x: f64) -> Vec<f64> {
    let u = x.ln();
    let mut h = vec![0.0; nodes.len()];
    let last = nodes.len() - 1;
    if u <= nodes[0] {
        h[0] = 1.0;
    } else if u >= nodes[last] {
        h[last] = 1.0;
    } else {
        let i = nodes.windows(2).position(|w| u < w[1]).unwrap_or(last - 1);
        let t = (u - nodes[i]) / (nodes[i + 1] - nodes[i]);
        h[i] = 1.0 - t;
        h[i + 1] = t;
    }
    h
}

/// The offset and the functions multiplying the amplitudes of `shape` at `x`, given its
/// nonlinear parameters `theta`.
fn design(shape: Shape, theta: &[f64], nodes: &[f64], x: f64) -> (f64, Vec<f64>) {
    match shape {
        Shape::Constant => (0.0, vec![1.0]),
        Shape::Linear => (0.0, vec![1.0, -x]),
        Shape::Saturating => {
            let e = (-x / theta[0]).exp();
            (e, vec![1.0 - e])
        }
        Shape::Viscoelastic => (1.0, vec![-x.powf(0.2)]),
        Shape::Adhesive => (0.0, vec![adhesion(x, theta[0])]),
        Shape::PowerLaw => (0.0, vec![(-(x.ln() - nodes[0]) * theta[0]).exp()]),
        Shape::AdhesiveYield => (0.0, vec![adhesion(x, theta[0]) * (-x / theta[1]).exp()]),
        Shape::Weakening => (0.0, vec![1.0 / (1.0 + x / theta[0])]),
        Shape::Map => (0.0, hats(nodes, x)),
    }
}

impl Fit {
    /// The number of fitted parameters.
    pub fn k(&self) -> usize {
        self.p.len()
    }

    /// The amplitudes' count: the parameters before the nonlinear ones.
    fn n_amplitudes(&self) -> usize {
        match self.shape {
            Shape::Linear => 2,
            Shape::Map => self.p.len(),
            _ => 1,
        }
    }

    /// y at speed `x`.
    pub fn at(&self, x: f64) -> f64 {
        let m = self.n_amplitudes();
        let (off, b) = design(self.shape, &self.p[m..], &self.nodes, x);
        off + b.iter().zip(&self.p[..m]).map(|(b, a)| b * a).sum::<f64>()
    }

    /// Σ ((y − law)/se)² over `pts`.
    pub fn chi2_on(&self, pts: &[Pt]) -> f64 {
        pts.iter()
            .map(|q| ((q.y - self.at(q.x)) / q.se).powi(2))
            .sum()
    }

    /// Standard errors of the parameters from the curvature of χ², scaled by `s2` (the
    /// residual variance per point in units of the points' errors, at least 1); NaN where the
    /// data do not constrain a parameter.
    pub fn standard_errors(&self, pts: &[Pt], s2: f64) -> Vec<f64> {
        let n = self.k();
        let chi = |p: &[f64]| {
            let f = Fit {
                p: p.to_vec(),
                ..self.clone()
            };
            f.chi2_on(pts)
        };
        let h: Vec<f64> = self.p.iter().map(|v| 1e-4 * v.abs().max(1e-6)).collect();
        let mut hess = vec![0.0; n * n];
        let c0 = chi(&self.p);
        for i in 0..n {
            for j in 0..=i {
                let mut q = self.p.clone();
                let val = if i == j {
                    q[i] += h[i];
                    let up = chi(&q);
                    q[i] -= 2.0 * h[i];
                    (up - 2.0 * c0 + chi(&q)) / (h[i] * h[i])
                } else {
                    let mut pp = q.clone();
                    pp[i] += h[i];
                    pp[j] += h[j];
                    let mut pm = q.clone();
                    pm[i] += h[i];
                    pm[j] -= h[j];
                    let mut mp = q.clone();
                    mp[i] -= h[i];
                    mp[j] += h[j];
                    q[i] -= h[i];
                    q[j] -= h[j];
                    (chi(&pp) - chi(&pm) - chi(&mp) + chi(&q)) / (4.0 * h[i] * h[j])
                };
                hess[i * n + j] = 0.5 * val;
                hess[j * n + i] = 0.5 * val;
            }
        }
        match invert_spd_scaled(&hess, n, 0.0) {
            Some(cov) => (0..n)
                .map(|i| (cov[i * n + i] * s2.max(1.0)).max(0.0).sqrt())
                .collect(),
            None => vec![f64::NAN; n],
        }
    }
}

/// The amplitudes minimizing χ² for fixed nonlinear parameters, and that χ²; a map's values are
/// tied by a faint second-difference penalty so that a node no point reaches follows its
/// neighbours (or, with two nodes, its neighbour). None when the amplitudes are not determined.
fn amplitudes(shape: Shape, theta: &[f64], nodes: &[f64], pts: &[Pt]) -> Option<(Vec<f64>, f64)> {
    let m = design(shape, theta, nodes, pts.first()?.x).1.len();
    let mut a = vec![0.0; m * m];
    let mut r = vec![0.0; m];
    for q in pts {
        let (off, b) = design(shape, theta, nodes, q.x);
        let w = 1.0 / (q.se * q.se);
        for i in 0..m {
            r[i] += w * b[i] * (q.y - off);
            for j in 0..m {
                a[i * m + j] += w * b[i] * b[j];
            }
        }
    }
    if shape == Shape::Map && m >= 2 {
        let lambda = 1e-6 * (0..m).map(|i| a[i * m + i]).sum::<f64>() / m as f64;
        // second differences (first ones for two nodes): a node no point reaches follows the line
        let rows: Vec<Vec<(usize, f64)>> = if m == 2 {
            vec![vec![(0, 1.0), (1, -1.0)]]
        } else {
            (0..m - 2)
                .map(|k| vec![(k, 1.0), (k + 1, -2.0), (k + 2, 1.0)])
                .collect()
        };
        for d in &rows {
            for &(i, di) in d {
                for &(j, dj) in d {
                    a[i * m + j] += lambda * di * dj;
                }
            }
        }
    }
    let c = solve_spd(&a, m, &r)?;
    let chi2: f64 = pts
        .iter()
        .map(|q| {
            let (off, b) = design(shape, theta, nodes, q.x);
            let y = off + b.iter().zip(&c).map(|(b, c)| b * c).sum::<f64>();
            ((q.y - y) / q.se).powi(2)
        })
        .sum();
    chi2.is_finite().then_some((c, chi2))
}

/// The best of a log-spaced grid on [lo, hi] (in the search variable), refined by golden section
/// between its neighbours.
fn search_1d(f: &dyn Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    const GRID: usize = 60;
    let at = |i: usize| lo + (hi - lo) * i as f64 / GRID as f64;
    let best = (0..=GRID)
        .min_by(|&a, &b| f(at(a)).total_cmp(&f(at(b))))
        .unwrap_or(0);
    minimize(f, at(best.saturating_sub(1)), at((best + 1).min(GRID)), 40)
}

/// The nodes of a map with `k` values: quantiles of ln x over `pts`, evenly spaced in rank (none
/// without points or for fewer than two).
pub fn map_nodes(pts: &[Pt], k: usize) -> Vec<f64> {
    if pts.is_empty() || k < 2 {
        return Vec::new();
    }
    let mut u: Vec<f64> = pts.iter().map(|q| q.x.ln()).collect();
    u.sort_by(f64::total_cmp);
    let mut nodes: Vec<f64> = (0..k)
        .map(|i| crate::stats::quantile_interpolated(&u, i as f64 / (k - 1) as f64))
        .collect();
    nodes.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    nodes
}

/// `shape` fitted to `pts` (a map through `nodes`); None when fewer points than parameters or
/// the fit is not determined.
pub fn fit(shape: Shape, pts: &[Pt], nodes: &[f64]) -> Option<Fit> {
    let (xmin, xmax) = pts.iter().fold((f64::INFINITY, 0.0f64), |(a, b), q| {
        (a.min(q.x), b.max(q.x))
    });
    if pts.is_empty() || !(xmin > 0.0) || (shape == Shape::Map && nodes.len() < 2) {
        return None;
    }
    let mean_ln = pts.iter().map(|q| q.x.ln()).sum::<f64>() / pts.len() as f64;
    let nodes: Vec<f64> = match shape {
        Shape::Map => nodes.to_vec(),
        Shape::PowerLaw => vec![mean_ln],
        _ => Vec::new(),
    };
    let chi = |theta: &[f64]| amplitudes(shape, theta, &nodes, pts).map_or(f64::INFINITY, |a| a.1);
    let (wide_lo, wide_hi) = ((xmin / 30.0).ln(), (xmax * 30.0).ln());
    let (stick_lo, stick_hi) = ((xmin * 1e-3).ln(), (xmin * 0.999).ln());
    let mut at_bound = false;
    let mut edge = |u: f64, lo: f64, hi: f64| {
        at_bound |= (u - lo).min(hi - u) < 1e-3 * (hi - lo);
        u
    };
    let theta: Vec<f64> = match shape {
        Shape::Constant | Shape::Linear | Shape::Viscoelastic | Shape::Map => Vec::new(),
        Shape::Saturating | Shape::Weakening => {
            let u = search_1d(&|u| chi(&[u.exp()]), wide_lo, wide_hi);
            vec![edge(u, wide_lo, wide_hi).exp()]
        }
        Shape::Adhesive => {
            let u = search_1d(&|u| chi(&[u.exp()]), stick_lo, stick_hi);
            vec![edge(u, stick_lo, stick_hi).exp()]
        }
        Shape::PowerLaw => vec![edge(search_1d(&|p| chi(&[p]), -2.0, 2.0), -2.0, 2.0)],
        Shape::AdhesiveYield => {
            let (mut b, mut c) = (stick_lo, wide_hi);
            let mut best = f64::INFINITY;
            for i in 0..=20 {
                for j in 0..=20 {
                    let bi = stick_lo + (stick_hi - stick_lo) * i as f64 / 20.0;
                    let cj = (xmin / 3.0).ln() + (wide_hi - (xmin / 3.0).ln()) * j as f64 / 20.0;
                    let v = chi(&[bi.exp(), cj.exp()]);
                    if v < best {
                        (best, b, c) = (v, bi, cj);
                    }
                }
            }
            for _ in 0..3 {
                b = minimize(|u| chi(&[u.exp(), c.exp()]), stick_lo, stick_hi, 40);
                c = minimize(|u| chi(&[b.exp(), u.exp()]), (xmin / 3.0).ln(), wide_hi, 40);
            }
            edge(b, stick_lo, stick_hi);
            edge(c, (xmin / 3.0).ln(), wide_hi);
            vec![b.exp(), c.exp()]
        }
    };
    let (amps, chi2) = amplitudes(shape, &theta, &nodes, pts)?;
    let p: Vec<f64> = amps.into_iter().chain(theta).collect();
    (pts.len() >= p.len()).then_some(Fit {
        shape,
        p,
        nodes,
        chi2,
        at_bound,
    })
}

/// F test of `big` against `small` (fewer parameters) over `n` points: the statistic and its
/// p-value; (NaN, NaN) when the degrees of freedom do not allow one.
pub fn f_test(small: &Fit, big: &Fit, n: usize) -> (f64, f64) {
    let (d1, d2) = (big.k() as f64 - small.k() as f64, n as f64 - big.k() as f64);
    if d1 < 1.0 || d2 < 1.0 || !(big.chi2 > 0.0) {
        return (f64::NAN, f64::NAN);
    }
    let f = ((small.chi2 - big.chi2).max(0.0) / d1) / (big.chi2 / d2);
    (f, f_sf(f, d1, d2))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(law: impl Fn(f64) -> f64) -> Vec<Pt> {
        (0..24)
            .map(|i| {
                let x = 0.02 * 1.08f64.powi(i);
                // a deterministic ±1 se scatter
                let e = if i % 2 == 0 { 0.002 } else { -0.002 };
                Pt {
                    x,
                    y: law(x) + e,
                    se: 0.002,
                    run: i as usize,
                }
            })
            .collect()
    }

    #[test]
    fn each_named_shape_recovers_its_parameters() {
        let pts = points(|x| 0.9 * adhesion(x, 0.015));
        let f = fit(Shape::Adhesive, &pts, &[]).unwrap();
        assert!(
            (f.p[0] - 0.9).abs() < 0.01 && (f.p[1] - 0.015).abs() < 5e-4,
            "{f:?}"
        );
        let pts = points(|x| 0.3 + 0.7 * (-x / 0.05).exp());
        let f = fit(Shape::Saturating, &pts, &[]).unwrap();
        assert!(
            (f.p[0] - 0.3).abs() < 0.01 && (f.p[1] - 0.05).abs() < 2e-3,
            "{f:?}"
        );
        let pts = points(|x| 0.5 / (1.0 + x / 0.04));
        let f = fit(Shape::Weakening, &pts, &[]).unwrap();
        assert!(
            (f.p[0] - 0.5).abs() < 0.01 && (f.p[1] - 0.04).abs() < 2e-3,
            "{f:?}"
        );
        let pts = points(|x| 0.8 * adhesion(x, 0.012) * (-x / 0.2).exp());
        let f = fit(Shape::AdhesiveYield, &pts, &[]).unwrap();
        assert!(
            (f.p[1] - 0.012).abs() < 1e-3 && (f.p[2] / 0.2 - 1.0).abs() < 0.1,
            "{f:?}"
        );
        // the scatter is ±1 se: χ² ≈ n
        assert!((f.chi2 - 24.0).abs() < 6.0, "{}", f.chi2);
    }

    #[test]
    fn a_map_beats_a_line_on_a_hump_and_not_on_a_line() {
        let hump = points(|x| 0.7 - 2.0 * (x.ln() - 0.05f64.ln()).powi(2) * 0.05);
        let nodes = map_nodes(&hump, 5);
        let line = fit(Shape::Linear, &hump, &[]).unwrap();
        let map = fit(Shape::Map, &hump, &nodes).unwrap();
        let (_, p) = f_test(&line, &map, hump.len());
        assert!(p < 1e-6, "{p}");
        let straight = points(|x| 0.9 - 1.5 * x);
        let line = fit(Shape::Linear, &straight, &[]).unwrap();
        let map = fit(Shape::Map, &straight, &map_nodes(&straight, 5)).unwrap();
        let (_, p) = f_test(&line, &map, straight.len());
        assert!(p > 0.01, "{p}");
    }

    #[test]
    fn standard_errors_shrink_with_the_points_errors() {
        let pts = points(|x| 0.9 - 1.5 * x);
        let f = fit(Shape::Linear, &pts, &[]).unwrap();
        let se = f.standard_errors(&pts, 1.0);
        let tight: Vec<Pt> = pts
            .iter()
            .map(|q| Pt {
                se: q.se / 10.0,
                ..*q
            })
            .collect();
        let g = fit(Shape::Linear, &tight, &[]).unwrap();
        let se2 = g.standard_errors(&tight, 1.0);
        assert!(
            se[0] > 0.0 && (se[0] / se2[0] - 10.0).abs() < 0.1,
            "{se:?} {se2:?}"
        );
    }
}
