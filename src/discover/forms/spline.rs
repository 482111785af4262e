//! The nonparametric fallback: a cubic B-spline force in one variable (z, v or t) with
//! `segments` knot intervals, reported as `unexplained` (no named form).

use super::form::{p, Entry, Fitted, Form, ParamInfo, Place, Search};
use crate::artifacts::diagnosis::{Estimate, Finding};
use crate::discover::data::RunData;
use crate::discover::forcemap::ForceMap;
use crate::discover::ranges::Proposals;
use crate::discover::screen_sums::{coherent, Trial, Typical};
use crate::physics::{spline_basis, spline_n_basis, SplineForce, Term, Variable};
use std::collections::BTreeMap;

#[derive(Clone, Debug, PartialEq)]
pub struct Spline {
    pub variable: Variable,
    pub lo: f64,
    pub dx: f64,
    pub segments: usize,
    /// Weight of the second-difference penalty on the coefficients, in χ² per (m/s²)² (the
    /// force map's, chosen by held-out runs); 0 for none.
    pub penalty: f64,
}

impl Default for Spline {
    fn default() -> Self {
        Spline {
            variable: Variable::Z,
            lo: 0.0,
            dx: 1.0,
            segments: 1,
            penalty: 0.0,
        }
    }
}

impl Spline {
    /// The spline in `var` on a force map's knots, with the map's penalty: the joint fit then
    /// smooths it as the map was smoothed. Unpenalized, a spline free where few runs go (at the
    /// edge of a 4 mm gap between the runs' stretches of groove) swung to 1.3 m/s² beside a
    /// 0.006 m/s² force and predicted held-out runs worse than none.
    pub fn on(map: &ForceMap, var: Variable) -> Option<Spline> {
        let (lo, dx, segments, _, penalty) = map.spline.clone()?;
        Some(Spline {
            variable: var,
            lo,
            dx,
            segments,
            penalty,
        })
    }

    /// The size of force `at` (a function of this spline's variable) where the runs go, on
    /// this spline's range and knot spacing: peak (and where), RMS, and the fraction of the
    /// range that two runs or more go through; in v beyond its part proportional to v, a
    /// linear drag that the drag time takes (`linear_drag_part_per_s`, the slope set aside).
    /// `grad(x)` is the gradient of `at(x)` in the parameters whose covariance is `cov`: the
    /// peak and RMS are of the force with its noise taken out (see `size_where_runs_go`).
    pub fn size_over_runs(
        &self,
        at: &dyn Fn(f64) -> f64,
        grad: &dyn Fn(f64) -> Vec<f64>,
        cov: &[Vec<f64>],
        runs: &[RunData],
        out: &mut BTreeMap<String, Estimate>,
    ) {
        let size = size_where_runs_go(self, at, grad, cov, runs);
        let est = |v: f64| Estimate::new(v, f64::NAN);
        out.insert("peak_accel_mps2".into(), est(size.peak));
        out.insert("rms_accel_mps2".into(), est(size.rms));
        out.insert("peak_as_fitted_mps2".into(), est(size.peak_as_fitted));
        out.insert("x_at_peak".into(), Estimate::new(size.at, 0.0));
        out.insert("covered_fraction".into(), Estimate::new(size.covered, 0.0));
        if self.variable == Variable::V {
            out.insert("linear_drag_part_per_s".into(), est(size.linear));
        }
    }

    /// The values of this spline's basis functions at `x`: the gradient of the force in its
    /// coefficients.
    fn basis_at(&self, x: f64) -> Vec<f64> {
        (0..spline_n_basis(self.segments))
            .map(|j| spline_basis(self.lo, self.dx, self.segments, j, x))
            .collect()
    }

    /// Coefficients on this spline's knots closest (least squares over a fine grid) to the
    /// spline on another's: a map's curve as this spline's start.
    pub fn resampled(
        &self,
        lo: f64,
        dx: f64,
        segments: usize,
        coefs: &[f64],
    ) -> Option<Vec<f64>> {
        let map = SplineForce {
            variable: self.variable,
            lo_x: lo,
            dx,
            coefs_mps2: coefs.to_vec(),
        };
        self.projected(&|x| map.at(x), segments)
    }

    /// The coefficients on this spline's basis nearest (least squares at 8 points per basis
    /// function and per `segments` of the source, evenly over the range) to force `f`.
    pub fn projected(&self, f: &dyn Fn(f64) -> f64, segments: usize) -> Option<Vec<f64>> {
        let nb = spline_n_basis(self.segments);
        let (mut m, mut c) = (vec![0.0; nb * nb], vec![0.0; nb]);
        let points = 8 * (nb + segments);
        for k in 0..=points {
            let x = self.lo + (self.hi() - self.lo) * k as f64 / points as f64;
            let b: Vec<f64> = (0..nb)
                .map(|j| spline_basis(self.lo, self.dx, self.segments, j, x))
                .collect();
            let y = f(x);
            for i in 0..nb {
                c[i] += b[i] * y;
                for j in 0..nb {
                    m[i * nb + j] += b[i] * b[j];
                }
            }
        }
        let l = crate::lsq::dense::cholesky_jittered(&m, nb)?;
        crate::lsq::dense::chol_solve(&l, nb, &mut c);
        Some(c)
    }


    fn force(&self, coefs: &[f64]) -> SplineForce {
        SplineForce {
            variable: self.variable,
            lo_x: self.lo,
            dx: self.dx,
            coefs_mps2: coefs[..self.segments + 3].to_vec(),
        }
    }

    fn hi(&self) -> f64 {
        self.lo + self.dx * self.segments as f64
    }
}

impl Form for Spline {
    fn name(&self) -> &'static str {
        "spline"
    }
    fn effect(&self) -> Option<&'static str> {
        Some("unexplained")
    }
    fn place(&self) -> Place {
        Place::Force
    }
    fn form(&self) -> String {
        format!(
            "spline in {}: a = cubic B-spline with {} coefficients (no named form)",
            self.variable.label(),
            self.segments + 3
        )
    }
    fn size_name(&self) -> &'static str {
        "a smooth force"
    }
    /// The map's size where two runs or more go, in its own variable.
    fn in_words(&self, f: &Finding) -> Option<String> {
        use super::words::{num, value};
        let var = f.form.strip_prefix("spline in ")?.split(' ').next()?;
        let (unit, scale) = match var {
            "z" => ("mm", 1e3),
            "v" => ("mm/s", 1e3),
            _ => ("ms", 1e3),
        };
        Some(format!(
            "a force no named form explains, smooth in {var}, up to {} m/s² (RMS {} m/s²) where two runs or more go, largest at {var} = {} {unit}",
            num(value(f, "peak_accel_mps2")?),
            num(value(f, "rms_accel_mps2")?),
            num(scale * value(f, "x_at_peak")?)
        ))
    }
    fn params(&self) -> Vec<ParamInfo> {
        (0..self.segments + 3)
            .map(|j| p(&format!("coef{j}_mps2"), 0.0, -20.0, 20.0, 1e-4))
            .collect()
    }
    fn enter(&self, x: &[f64], e: &mut Entry) {
        e.model.terms.push(Term::Spline(self.force(x)));
    }
    fn position_dependent(&self) -> bool {
        self.variable == Variable::Z
    }
    fn speed_dependent(&self) -> bool {
        self.variable == Variable::V
    }
    fn map_variable(&self) -> Option<Variable> {
        Some(self.variable)
    }
    fn penalty(&self, x: &[f64]) -> Vec<f64> {
        if self.penalty <= 0.0 {
            return Vec::new();
        }
        let w = self.penalty.sqrt();
        let c = &x[..self.segments + 3];
        c.windows(3).map(|d| w * (d[0] - 2.0 * d[1] + d[2])).collect()
    }
    fn parameters(&self, f: &Fitted) -> BTreeMap<String, Estimate> {
        let est = Estimate::new;
        let sp = self.force(f.x);
        let (lo, hi) = (self.lo, self.hi());
        let (mut peak, mut at, mut ss) = (0.0f64, lo, 0.0);
        for j in 0..=200 {
            let x = lo + (hi - lo) * j as f64 / 200.0;
            let a = sp.at(x);
            ss += a * a;
            if a.abs() > peak {
                peak = a.abs();
                at = x;
            }
        }
        let mut out = BTreeMap::new();
        out.insert("peak_accel_mps2".into(), est(peak, f64::NAN));
        out.insert("rms_accel_mps2".into(), est((ss / 201.0).sqrt(), f64::NAN));
        out.insert("x_at_peak".into(), est(at, 0.0));
        out.insert("x_lo".into(), est(lo, 0.0));
        out.insert("x_hi".into(), est(hi, 0.0));
        out
    }
    fn searched(&self) -> bool {
        true
    }
    fn search(&self, s: &Search) -> (Option<Trial>, Option<Typical>) {
        let (var, lo, dx, segments) = (self.variable, self.lo, self.dx, self.segments);
        let nb = spline_n_basis(segments);
        let trial = coherent(s.prep, s.v, nb, s.reps.clone(), &[], |p| {
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
        })
        .map(|(lr, b, vv)| (lr, b, vv.iter().map(|x| x.sqrt()).collect()));
        (trial, None)
    }
    /// None of its own: the screen's estimate and the force map's curve start it (a spline
    /// that vanishes everywhere is a third fit of every coefficient that neither needs).
    fn starts(&self) -> Vec<Vec<f64>> {
        Vec::new()
    }
    fn proposal_supersedes_screen(&self) -> bool {
        true
    }
    fn proposed(&self, p: &Proposals) -> Vec<Vec<f64>> {
        let name = match self.variable {
            Variable::Z => "z",
            Variable::V => "v",
            Variable::T => "t",
        };
        p.maps
            .iter()
            .filter(|m| m.variable == name)
            .filter_map(|m| {
                let (lo, dx, segments, coefs, _) = m.spline.as_ref()?;
                if (*lo, *dx, *segments) == (self.lo, self.dx, self.segments) {
                    return Some(coefs.clone());
                }
                self.resampled(*lo, *dx, *segments, coefs)
            })
            .collect()
    }
    /// Its size where the runs go: peak (and where), RMS and the fraction of its range that
    /// holds data, over the points of its range that two runs or more go through. Over a
    /// gap between the runs the spline is held by its penalty alone and may swing far (13 m/s²
    /// at 6–7.4 mm on the shipped data, where no run went): that is no size of the data.
    fn report_over_runs(
        &self,
        x: &[f64],
        cov: &[Vec<f64>],
        runs: &[RunData],
        out: &mut BTreeMap<String, Estimate>,
    ) {
        let sp = self.force(x);
        self.size_over_runs(&|v| sp.at(v), &|v| self.basis_at(v), cov, runs, out);
    }
    fn reads(&self, f: &Finding) -> bool {
        Some(f.effect.as_str()) == self.effect() && f.form.starts_with("spline in ")
    }
    fn lab_force(&self, _f: &Finding) -> Option<Result<Term, String>> {
        Some(Err(
            "the accepted model has a spline force (no named form), which the pair fit does not carry".into(),
        ))
    }
}

struct SplineSize {
    /// The peak and RMS of the force with its noise taken out.
    peak: f64,
    at: f64,
    rms: f64,
    /// The peak of the fitted curve itself.
    peak_as_fitted: f64,
    covered: f64,
    /// The part proportional to v set aside (m/s² per m/s; 0 in z and t).
    linear: f64,
}

/// The parameters the points' gradients use (any nonzero), and the covariance over them as a
/// row-major matrix; None without a usable covariance (none given, too small, or not finite
/// where it is used: a singular fit).
fn active_covariance(points: &[(f64, f64, Vec<f64>)], cov: &[Vec<f64>]) -> Option<(Vec<usize>, Vec<f64>)> {
    let n = points.first()?.2.len();
    let idx: Vec<usize> = (0..n)
        .filter(|&i| points.iter().any(|p| p.2[i] != 0.0))
        .collect();
    if idx.is_empty() || cov.len() < n || cov.iter().any(|r| r.len() < n) {
        return None;
    }
    let c: Vec<f64> = idx
        .iter()
        .flat_map(|&i| idx.iter().map(move |&j| cov[i][j]))
        .collect();
    c.iter().all(|v| v.is_finite()).then_some((idx, c))
}

/// The magnitude of a fitted value `a` of variance `var` with its noise taken out: its square
/// is the force's square plus the noise's variance on average, so √(a² − var), floored at 0.
fn denoised(a: f64, var: f64) -> f64 {
    (a * a - var).max(0.0).sqrt()
}

/// g'Cg for C row-major of g's length.
fn quadratic(g: &[f64], c: &[f64]) -> f64 {
    let n = g.len();
    let v: f64 = (0..n)
        .map(|i| g[i] * (0..n).map(|j| c[i * n + j] * g[j]).sum::<f64>())
        .sum();
    v.max(0.0)
}

fn size_where_runs_go(
    sp: &Spline,
    at: &dyn Fn(f64) -> f64,
    grad: &dyn Fn(f64) -> Vec<f64>,
    cov: &[Vec<f64>],
    runs: &[RunData],
) -> SplineSize {
    let hi = sp.hi();
    // (value, run) of every kept sample
    let mut xs: Vec<(f64, usize)> = Vec::new();
    for (id, r) in runs.iter().enumerate() {
        let kept = |j: usize| r.keep[j];
        match sp.variable {
            Variable::Z => {
                xs.extend((0..r.z_m.len()).filter(|&j| kept(j)).map(|j| (r.z_m[j], id)))
            }
            Variable::T => {
                xs.extend((0..r.t_s.len()).filter(|&j| kept(j)).map(|j| (r.t_s[j], id)))
            }
            Variable::V => {
                // a velocity over four frames: its noise is far below a knot spacing
                let h = 4;
                xs.extend((0..r.z_m.len().saturating_sub(h)).filter_map(|j| {
                    let dt = r.t_s[j + h] - r.t_s[j];
                    (kept(j) && kept(j + h) && dt > 0.0)
                        .then(|| ((r.z_m[j + h] - r.z_m[j]) / dt, id))
                }))
            }
        }
    }
    // each run's stretch of the variable (a run goes through every value between its ends)
    let mut stretch: Vec<(f64, f64)> = vec![(f64::INFINITY, f64::NEG_INFINITY); runs.len()];
    for &(x, id) in xs.iter().filter(|x| x.0.is_finite()) {
        stretch[id] = (stretch[id].0.min(x), stretch[id].1.max(x));
    }
    // a point is where runs go when two runs or more go through it: what only one run shows is
    // that run's own z0, t0 and v0 over again (on two bench fields of 0.006 m/s², a map in z
    // read 0.010 and 0.041 m/s² where one run went, 0.007 and 0.010 without those stretches)
    let near = |x: f64| stretch.iter().filter(|(lo, hi)| *lo <= x && x <= *hi).count() >= 2;
    // (x, force, its gradient in the parameters)
    let mut points: Vec<(f64, f64, Vec<f64>)> = (0..=200)
        .map(|j| sp.lo + (hi - sp.lo) * j as f64 / 200.0)
        .filter(|&x| near(x))
        .map(|x| (x, at(x), grad(x)))
        .collect();
    // in v, a part proportional to v is a linear drag: the drag time T of each material takes
    // it exactly, so the map's own share of it is arbitrary (at the fastest run's speed a map
    // beside a 0.005 m/s² bump read 0.22 m/s², its slope a 13 % change of 1/T); the size is
    // the map's beyond it (the least-squares line through zero over the points where runs go),
    // and that line is taken out of the gradient too
    let sxx: f64 = points.iter().map(|(x, _, _)| x * x).sum();
    let linear = if sp.variable == Variable::V && sxx > 0.0 {
        let sxa: f64 = points.iter().map(|(x, a, _)| x * a).sum();
        let n = points.first().map_or(0, |p| p.2.len());
        let gk: Vec<f64> = (0..n)
            .map(|i| points.iter().map(|(x, _, g)| x * g[i]).sum::<f64>() / sxx)
            .collect();
        for (x, a, g) in points.iter_mut() {
            *a -= sxa / sxx * *x;
            for (gi, k) in g.iter_mut().zip(&gk) {
                *gi -= k * *x;
            }
        }
        sxa / sxx
    } else {
        0.0
    };
    // the size is of the force with its noise taken out: the fitted curve is the force plus its
    // noise, so its square is the force's square plus the noise's variance on average, and the
    // peak and RMS are of √(a² − var) (`denoised`). Where few runs go the map is poorly held and
    // its fitted peak mostly noise: two bench fields of 0.0058 m/s² in z peaked at 0.0072 and
    // 0.0103 m/s², the second at the edge of a stretch where runs turn back (0.0071 and 0.0067
    // with the noise out). Shrinking the curve by one signal power for the whole map (a Wiener
    // filter) did better on fields spread over z but took 19 % and 63 % off two bumps in v: a
    // localized force has little power over the whole range, and a prior that says otherwise
    // cannot tell its peak from a swing of the noise
    let active = active_covariance(&points, cov);
    let g_active = |g: &[f64]| -> Vec<f64> {
        active.as_ref().map_or(Vec::new(), |(idx, _)| idx.iter().map(|&i| g[i]).collect())
    };
    let with_var: Vec<(f64, f64)> = points
        .iter()
        .map(|(x, a, g)| {
            let var = active.as_ref().map_or(0.0, |(_, c)| quadratic(&g_active(g), c));
            (*x, denoised(*a, var))
        })
        .collect();
    let ms = with_var.iter().map(|(_, d)| d * d).sum::<f64>() / with_var.len().max(1) as f64;
    let (peak, k_peak) = with_var
        .iter()
        .enumerate()
        .map(|(k, (_, d))| (*d, k))
        .fold((0.0f64, 0), |best, p| if p.0 > best.0 { p } else { best });
    let at_peak = with_var.get(k_peak).map_or(sp.lo, |p| p.0);
    let peak_as_fitted = points.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    let n = points.len();
    SplineSize {
        peak,
        at: at_peak,
        rms: ms.sqrt(),
        peak_as_fitted,
        covered: n as f64 / 201.0,
        linear,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use rand_distr::{Distribution, StandardNormal};

    fn spline(lo: f64, hi: f64, segments: usize) -> Spline {
        Spline {
            variable: Variable::Z,
            lo,
            dx: (hi - lo) / segments as f64,
            segments,
            penalty: 0.0,
        }
    }

    /// A map's curve carried onto other knots: the same knots give the same coefficients, and
    /// knots halved over the same range (the coarse spline lies in the fine one's space) the
    /// same curve.
    #[test]
    fn a_maps_curve_is_carried_onto_other_knots() {
        let coarse = spline(0.0, 0.01, 4);
        let coefs = [0.3, -0.1, 0.5, 0.2, -0.4, 0.1, 0.0];
        let same = coarse.resampled(0.0, 0.0025, 4, &coefs).unwrap();
        for (a, b) in same.iter().zip(&coefs) {
            assert!((a - b).abs() < 1e-9, "{same:?}");
        }
        let fine = spline(0.0, 0.01, 8);
        let c = fine.resampled(0.0, 0.0025, 4, &coefs).unwrap();
        assert_eq!(c.len(), 11);
        let (a, b) = (coarse.force(&coefs), fine.force(&c));
        let range = (0..=100).map(|k| a.at(k as f64 * 1e-4).abs()).fold(0.0, f64::max);
        for k in 0..=100 {
            let x = k as f64 * 1e-4;
            assert!((a.at(x) - b.at(x)).abs() < 1e-6 * range, "at {x}: {} vs {}", a.at(x), b.at(x));
        }
    }

    /// The size of a map with its noise taken out: a force of peak 1 on 16 knot intervals whose
    /// coefficients carry independent errors of 0.1, and of 1 on the last three (an edge where
    /// the runs turn back and the map is poorly held), drawn 200 times. The fitted curve's RMS
    /// reads high by the noise (4 % here) and its peak swings high at that edge (a mean
    /// error of 0.26); with the noise taken out the RMS is within 3 % on average (1 %) and the peak's
    /// mean error is smaller (0.22).
    #[test]
    fn a_maps_size_has_its_noise_taken_out() {
        let sp = spline(0.0, 0.016, 16);
        let n = spline_n_basis(sp.segments);
        let truth = |x: f64| (std::f64::consts::TAU * x / 0.008).sin();
        let c0 = sp.projected(&truth, 16).unwrap();
        let se: Vec<f64> = (0..n).map(|j| if j + 3 >= n { 1.0 } else { 0.1 }).collect();
        let run = |z: Vec<f64>| RunData {
            run: "r".into(),
            material: 0,
            fps: 1e4,
            t_s: (0..z.len()).map(|k| k as f64 * 1e-4).collect(),
            keep: vec![true; z.len()],
            z_m: z,
            sigma_m: 1e-6,
            fast: Default::default(),
            scale: Vec::new(),
            slow: Default::default(),
        };
        let span: Vec<f64> = (0..=160).map(|k| k as f64 * 1e-4).collect();
        let runs = [run(span.clone()), run(span)];
        let cov: Vec<Vec<f64>> = (0..n)
            .map(|i| (0..n).map(|j| if i == j { se[i] * se[i] } else { 0.0 }).collect())
            .collect();
        let true_rms = {
            let ss: f64 = (0..=200).map(|j| truth(0.016 * j as f64 / 200.0).powi(2)).sum();
            (ss / 201.0).sqrt()
        };
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let (mut fitted_err, mut reported_err, mut rms, mut fitted_rms) = (0.0, 0.0, 0.0, 0.0);
        let draws = 200;
        for _ in 0..draws {
            let c: Vec<f64> = c0
                .iter()
                .zip(&se)
                .map(|(c, s)| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    c + s * z
                })
                .collect();
            let f = sp.force(&c);
            let mut out = BTreeMap::new();
            sp.size_over_runs(&|x| f.at(x), &|x| sp.basis_at(x), &cov, &runs, &mut out);
            fitted_err += (out["peak_as_fitted_mps2"].value - 1.0).abs() / draws as f64;
            reported_err += (out["peak_accel_mps2"].value - 1.0).abs() / draws as f64;
            rms += out["rms_accel_mps2"].value / draws as f64;
            let ss: f64 = (0..=200).map(|j| f.at(0.016 * j as f64 / 200.0).powi(2)).sum();
            fitted_rms += (ss / 201.0).sqrt() / draws as f64;
        }
        assert!(fitted_err > 0.2, "the fitted peak swings at the edge: {fitted_err}");
        assert!(reported_err < 0.9 * fitted_err, "{reported_err} against {fitted_err}");
        assert!(fitted_rms / true_rms > 1.03, "the fitted rms reads high: {fitted_rms}");
        assert!((rms / true_rms - 1.0).abs() < 0.03, "rms {rms} against {true_rms}");
    }

    /// The penalty is the second differences of the coefficients, scaled by the weight's root,
    /// and nothing without a weight.
    #[test]
    fn the_penalty_is_the_weighted_second_differences() {
        let mut s = spline(0.0, 0.01, 2);
        assert!(s.penalty(&[1.0, 2.0, 4.0, 8.0, 16.0]).is_empty());
        s.penalty = 4.0;
        assert_eq!(s.penalty(&[1.0, 2.0, 4.0, 8.0, 16.0]), vec![2.0, 4.0, 8.0]);
    }
}
