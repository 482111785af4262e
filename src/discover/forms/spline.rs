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
    pub fn size_over_runs(
        &self,
        at: &dyn Fn(f64) -> f64,
        runs: &[RunData],
        out: &mut BTreeMap<String, Estimate>,
    ) {
        let size = size_where_runs_go(self, at, runs);
        let est = |v: f64| Estimate::new(v, f64::NAN);
        out.insert("peak_accel_mps2".into(), est(size.peak));
        out.insert("rms_accel_mps2".into(), est(size.rms));
        out.insert("x_at_peak".into(), Estimate::new(size.at, 0.0));
        out.insert("covered_fraction".into(), Estimate::new(size.covered, 0.0));
        if self.variable == Variable::V {
            out.insert("linear_drag_part_per_s".into(), est(size.linear));
        }
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
    fn report_over_runs(&self, x: &[f64], runs: &[RunData], out: &mut BTreeMap<String, Estimate>) {
        let sp = self.force(x);
        self.size_over_runs(&|v| sp.at(v), runs, out);
    }
    fn reads(&self, f: &Finding) -> bool {
        Some(f.effect.as_str()) == self.effect() && f.form.starts_with("spline in ")
    }
}

struct SplineSize {
    peak: f64,
    at: f64,
    rms: f64,
    covered: f64,
    /// The part proportional to v set aside (m/s² per m/s; 0 in z and t).
    linear: f64,
}

fn size_where_runs_go(sp: &Spline, at: &dyn Fn(f64) -> f64, runs: &[RunData]) -> SplineSize {
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
    let mut points: Vec<(f64, f64)> = (0..=200)
        .map(|j| sp.lo + (hi - sp.lo) * j as f64 / 200.0)
        .filter(|&x| near(x))
        .map(|x| (x, at(x)))
        .collect();
    // in v, a part proportional to v is a linear drag: the drag time T of each material takes
    // it exactly, so the map's own share of it is arbitrary (at the fastest run's speed a map
    // beside a 0.005 m/s² bump read 0.22 m/s², its slope a 13 % change of 1/T); the size is
    // the map's beyond it (the least-squares line through zero over the points where runs go)
    let linear = if sp.variable == Variable::V {
        let sxx: f64 = points.iter().map(|(x, _)| x * x).sum();
        let sxa: f64 = points.iter().map(|(x, a)| x * a).sum();
        if sxx > 0.0 {
            sxa / sxx
        } else {
            0.0
        }
    } else {
        0.0
    };
    for (x, a) in points.iter_mut() {
        *a -= linear * *x;
    }
    let (mut peak, mut at_peak, mut ss) = (0.0f64, sp.lo, 0.0);
    for &(x, a) in &points {
        ss += a * a;
        if a.abs() > peak {
            peak = a.abs();
            at_peak = x;
        }
    }
    let n = points.len();
    SplineSize {
        peak,
        at: at_peak,
        rms: (ss / n.max(1) as f64).sqrt(),
        covered: n as f64 / 201.0,
        linear,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
