//! The joint fit: shared physics parameters and per-run z0, t0, v0, on the block-arrow back-end
//! of the least-squares core (`lsq::block`: per-run Jacobians in parallel, the normal equations
//! reduced to the globals by a Schur complement over the runs' 3×3 blocks).
//!
//! A run's Jacobian touches only its own three local columns and the global columns it depends
//! on. z0 is an additive offset unless a force depends on position, and then its column is
//! known exactly. A global that enters through the acceleration alone (a drag time, a force's
//! parameters) and the run's t0 and v0 take their columns from the run's linear response along
//! its fitted motion (`response::Track`, one simulation a run): the response to ∂a/∂x, the
//! force differenced at each point of the motion. Within 0.1–1.5 % of the forward differences
//! (3 % for the cosine of a force in time; the unit tests), which the steps tolerate. The
//! covariance at the minimum differences every column: from the responses, a map's errors
//! came out other than the differences' (a map in v lost the noise its size is corrected for
//! on a bench dataset, 1.11 → 1.16 of the truth). μ and friction's, measurement's and probes' parameters are
//! differenced: one simulation a column. Nothing is taken from the response beside a phase per
//! run (profiled inside every prediction).

use super::candidate::{predict, ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::forms::Place;
use super::response::Track;
use super::sim::SimModel;
use super::timeforce::{hold_phase, profile_with_direction, project_phase};
use crate::lsq::block::{descend_blocks, minimize_blocks, BlockProblem, Known, Linear};
use crate::lsq::lm::{ParamSpec, Scale, Settings};

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
    /// Their covariance, scaled as the errors are (empty when the globals were held; NaN where
    /// the system was singular).
    pub global_cov: Vec<Vec<f64>>,
    pub iterations: usize,
    pub converged: bool,
}

/// How far a fit may go.
#[derive(Clone, Copy, Debug)]
pub struct FitControl {
    pub max_iter: usize,
    /// False: the globals stay fixed (held-out runs in cross-validation).
    pub free_global: bool,
    /// False: no errors or covariance are wanted (a cross-validation fold reads the parameters
    /// and χ² alone), which spares the Jacobian at the minimum; `global_se` is then NaN for a
    /// free global and `global_cov` empty.
    pub covariance: bool,
    /// The damping the descent starts from (`lm::Settings::damping`): [`USUAL_DAMPING`], or
    /// [`NEAR_DAMPING`] for a fit that starts at a neighbouring minimum.
    pub damping: f64,
}

/// The driver's usual starting damping, for a fit whose start may be far from its minimum (a
/// screen's linear estimate, a proposal, one run's μ and T from the material's).
pub const USUAL_DAMPING: f64 = 1e-3;

/// The starting damping of a cross-validation fold, which starts at the whole data's minimum:
/// the Gauss–Newton step is nearly right from the first iteration, and 1e-3 shrank it along
/// the correlated directions (a map's coefficients, a drag time beside a map in v), so a fold
/// of a map in v took five or six Jacobians where three do. Not for a start that may be far:
/// fitted from it, the shipped data's slowest run (6.7 mm/s) ended with μ at its lower bound
/// (0.001) and T = 1.7 s instead of 0.59 and 0.061 s, and the drift of T with the kick speed
/// read t = −0.8 instead of above 5.
pub const NEAR_DAMPING: f64 = 1e-6;

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

/// Bounds of z0 (free), t0 (within one frame) and v0 (±10 m/s).
fn local_bounds(run: &RunData) -> [(f64, f64); N_LOCAL] {
    let frame = if run.fps > 0.0 { 1.0 / run.fps } else { 1e-3 };
    [
        (f64::NEG_INFINITY, f64::INFINITY),
        (0.0, frame),
        (-10.0, 10.0),
    ]
}

/// Forward-difference steps of z0, t0, v0.
const LOCAL_STEPS: [f64; N_LOCAL] = [1e-8, 1e-7, 1e-7];

/// The runs as blocks of whitened residuals (predicted − observed)/σ, 0 at dropped samples,
/// and after them, when a term is penalized (a spline's smoothness), one block of its
/// pseudo-residuals with no parameters of its own.
struct Runs<'a> {
    spec: &'a Spec,
    runs: &'a [RunData],
    /// Per material: whether each global enters its runs' model.
    affects: Vec<Vec<bool>>,
    /// z0 only shifts the trajectory (no position-dependent force).
    z0_offset: bool,
    /// Number of penalty pseudo-residuals, and which globals they depend on.
    penalty_len: usize,
    penalized: Vec<bool>,
    /// Per global: it enters through the acceleration alone (a drag time, a force's parameters:
    /// `Form::through_force`), and its column comes from each run's linear response; none
    /// beside a phase per run or a probe. The step of each global's difference of the force.
    through_force: Vec<bool>,
    steps: Vec<f64>,
}

/// Every extra term's penalty pseudo-residuals at globals `g`, in order.
fn penalty_residuals(spec: &Spec, g: &[f64]) -> Vec<f64> {
    spec.extras
        .iter()
        .enumerate()
        .flat_map(|(i, e)| {
            let o = spec.extra_offset(i);
            e.penalty(&g[o..o + e.params().len()])
        })
        .collect()
}

impl<'a> Runs<'a> {
    /// The runs of `spec` as blocks, with globals at `start_g` (which decide whether a term is
    /// penalized) and the globals' difference steps `steps`.
    fn new(spec: &'a Spec, runs: &'a [RunData], start_g: &[f64], steps: &[f64]) -> Runs<'a> {
        let ng = spec.n_global();
        let n_materials = runs.iter().map(|r| r.material + 1).max().unwrap_or(0);
        let affects = (0..n_materials)
            .map(|m| {
                let mut on = vec![false; ng];
                for j in spec.affecting(m) {
                    on[j] = true;
                }
                on
            })
            .collect();
        let mut penalized = vec![false; ng];
        for (i, e) in spec.extras.iter().enumerate() {
            let (o, n) = (spec.extra_offset(i), e.params().len());
            if !e.penalty(&start_g[o..o + n]).is_empty() {
                penalized[o..o + n].iter_mut().for_each(|p| *p = true);
            }
        }
        Runs {
            spec,
            runs,
            affects,
            z0_offset: !spec.position_dependent(),
            penalty_len: penalty_residuals(spec, start_g).len(),
            penalized,
            through_force: through_force(spec),
            steps: steps.to_vec(),
        }
    }
}

impl BlockProblem for Runs<'_> {
    fn n_blocks(&self) -> usize {
        self.runs.len() + usize::from(self.penalty_len > 0)
    }

    fn n_residuals(&self, b: usize) -> usize {
        match self.runs.get(b) {
            Some(r) => r.t_s.len(),
            None => self.penalty_len,
        }
    }

    fn residuals(&self, b: usize, shared: &[f64], own: &[f64], out: &mut [f64]) {
        let Some(run) = self.runs.get(b) else {
            out.copy_from_slice(&penalty_residuals(self.spec, shared));
            return;
        };
        let l: [f64; N_LOCAL] = own.try_into().expect("a run has three local parameters");
        predict(self.spec, shared, &l, run, out);
        whiten(out, run);
    }

    fn uses(&self, b: usize, i: usize) -> bool {
        match self.runs.get(b) {
            Some(r) => self.affects[r.material][i],
            None => self.penalized[i],
        }
    }

    fn linearize(&self, b: usize, shared: &[f64], own: &[f64]) -> Option<Box<dyn Linear + '_>> {
        let run = self.runs.get(b)?;
        if !self.spec.has_run_phase() {
            return None;
        }
        let l: [f64; N_LOCAL] = own.try_into().ok()?;
        let mut m = self.spec.sim_model(shared, run.material, l[2]);
        let (phase, g, g_hat) = profile_with_direction(&mut m, &l, run)?;
        let gg = g_hat.iter().map(|x| x * x).sum::<f64>();
        (gg > 0.0).then(|| {
            Box::new(AtPhase {
                spec: self.spec,
                run,
                phase,
                g,
                g_hat,
                gg,
            }) as Box<dyn Linear>
        })
    }

    /// The columns of every global that enters through the acceleration alone and of the
    /// run's t0 and v0: the run's linear response along its fitted motion (`Track`) to ∂a/∂x
    /// (the force differenced at each point of the motion, no simulation), one simulation for
    /// all where differences of the predictions take one each.
    fn known_columns(&self, b: usize, shared: &[f64], own: &[f64]) -> Option<Known> {
        let run = self.runs.get(b)?;
        if !self.through_force.iter().any(|&f| f) {
            return None;
        }
        let l: [f64; N_LOCAL] = own.try_into().ok()?;
        let m = self.spec.sim_model(shared, run.material, l[2]);
        let track = Track::new(&m, l[0], l[1], l[2], run);
        // values at the kept samples, in noise units, spread over every sample (0 at dropped ones)
        let whole = |kept: Vec<f64>| -> Vec<f64> {
            let mut kept = kept.into_iter();
            run.keep
                .iter()
                .map(|&k| {
                    if k {
                        kept.next().unwrap_or(0.0) * track.w
                    } else {
                        0.0
                    }
                })
                .collect()
        };
        let force = |m: &SimModel| -> Vec<f64> {
            let pm = m.to_physics();
            (0..track.len())
                .map(|k| pm.accel(track.z[k], track.v[k], track.t[k]))
                .collect()
        };
        let a0 = force(&m);
        let mut cols = vec![None; shared.len()];
        for (i, col) in cols.iter_mut().enumerate() {
            if !self.through_force[i] || !self.affects[run.material][i] {
                continue;
            }
            let h = self.steps[i];
            let mut g = shared.to_vec();
            g[i] += h;
            let a1 = force(&self.spec.sim_model(&g, run.material, l[2]));
            let da: Vec<f64> = a1.iter().zip(&a0).map(|(a, b)| (a - b) / h).collect();
            *col = Some(whole(track.respond_values(&da)));
        }
        let [_, t0, v0] = track.local_columns();
        Some(Known {
            shared: cols,
            own: vec![None, Some(whole(t0)), Some(whole(v0))],
        })
    }

    fn own_column(&self, b: usize, k: usize, _: &[f64], _: &[f64], out: &mut [f64]) -> bool {
        if k != 0 || !self.z0_offset {
            return false;
        }
        let Some(run) = self.runs.get(b) else {
            return false;
        };
        let w = 1.0 / run.sigma_m;
        for (o, keep) in out.iter_mut().zip(&run.keep) {
            *o = if *keep { w } else { 0.0 };
        }
        true
    }
}

/// Which globals of `spec` enter through the acceleration alone (`Runs::through_force`): each
/// material's drag time and the parameters of every term `Form::through_force`; none beside a
/// phase per run (the profile moves it with every parameter) or a probe (its μ or T follows
/// the run's v0, which the response's v0 column leaves out).
fn through_force(spec: &Spec) -> Vec<bool> {
    let mut on = vec![false; spec.n_global()];
    if spec.has_run_phase() || spec.extras.iter().any(|e| e.place() == Place::Probe) {
        return on;
    }
    let n = spec.n_materials;
    on[n..2 * n].iter_mut().for_each(|x| *x = true);
    for (i, e) in spec.extras.iter().enumerate() {
        if e.through_force() {
            let o = spec.extra_offset(i);
            on[o..o + e.params().len()]
                .iter_mut()
                .for_each(|x| *x = true);
        }
    }
    on
}

/// A run's residuals with its own phase held where the profile put it (`profile_with_direction`):
/// the phase's direction `g` (∂z/∂φ, metres) and the direction it was profiled along, `g_hat`
/// (z0, t0 and v0 projected out), with |g_hat|² = `gg`, both in metres (`project_phase` turns a
/// column in any units). z0 and v0 barely move the phase; t0 does, by −2πf a second, since the
/// force's clock starts at the kick.
struct AtPhase<'a> {
    spec: &'a Spec,
    run: &'a RunData,
    phase: f64,
    g: Vec<f64>,
    g_hat: Vec<f64>,
    gg: f64,
}

impl Linear for AtPhase<'_> {
    fn residuals(&self, shared: &[f64], own: &[f64], out: &mut [f64]) {
        let l: [f64; N_LOCAL] = own.try_into().expect("a run has three local parameters");
        let mut m = self.spec.sim_model(shared, self.run.material, l[2]);
        hold_phase(&mut m, self.phase);
        let tt: Vec<f64> = self.run.t_s.iter().map(|t| t + l[1]).collect();
        m.simulate(l[0], l[2], &tt, out, None, None);
        whiten(out, self.run);
    }

    fn project(&self, column: &mut [f64]) {
        project_phase(column, &self.g, &self.g_hat, self.gg);
    }
}

/// (prediction − observation)/σ at the kept samples of `run`, 0 at the dropped ones.
fn whiten(out: &mut [f64], run: &RunData) {
    let w = 1.0 / run.sigma_m;
    for ((o, z), keep) in out.iter_mut().zip(&run.z_m).zip(&run.keep) {
        *o = if *keep { (*o - z) * w } else { 0.0 };
    }
}

/// Fit `spec` to `runs` from the given start, with box bounds on every parameter: plain least
/// squares on the whitened residuals (no robust weights: the runs' outliers are already dropped).
pub fn fit_joint(
    spec: &Spec,
    params: &[ParamInfo],
    runs: &[RunData],
    start_g: &[f64],
    start_l: &[[f64; N_LOCAL]],
    ctl: FitControl,
) -> Fitted {
    let ng = spec.n_global();
    let steps: Vec<f64> = params.iter().map(|p| p.step).collect();
    let problem = Runs::new(spec, runs, start_g, &steps);
    let shared: Vec<ParamSpec> = params
        .iter()
        .zip(start_g)
        .map(|(p, &x)| {
            let x = x.clamp(p.lo, p.hi);
            let (lower, upper) = if ctl.free_global {
                (p.lo, p.hi)
            } else {
                (x, x)
            };
            ParamSpec {
                start: x,
                lower,
                upper,
                step: p.step,
            }
        })
        .collect();
    let mut own: Vec<Vec<ParamSpec>> = runs
        .iter()
        .zip(start_l)
        .map(|(run, l)| {
            local_bounds(run)
                .iter()
                .zip(l)
                .zip(LOCAL_STEPS)
                .map(|((&(lower, upper), &start), step)| ParamSpec {
                    start,
                    lower,
                    upper,
                    step,
                })
                .collect()
        })
        .collect();
    let settings = Settings {
        max_iter: ctl.max_iter,
        rounds: 1,
        huber_k: f64::INFINITY,
        scale: Scale::Fixed(1.0),
        cost_tol: 1e-9,
        rel_tol: 1e-7,
        damping: ctl.damping,
    };
    if problem.penalty_len > 0 {
        own.push(Vec::new());
    }
    let res = if ctl.covariance {
        minimize_blocks(&problem, &shared, &own, &settings)
    } else {
        descend_blocks(&problem, &shared, &own, &settings)
    };
    // the data's χ², without the penalty's block
    let chi2_run: Vec<f64> = res.block_cost[..runs.len()].to_vec();
    let chi2: f64 = chi2_run.iter().sum();
    let dof = runs.iter().map(|r| r.n_used()).sum::<usize>() as f64
        - (ng * usize::from(ctl.free_global) + N_LOCAL * runs.len()) as f64;
    let scale = (chi2 / dof.max(1.0)).max(1.0);
    let local: Vec<[f64; N_LOCAL]> = res.own[..runs.len()]
        .iter()
        .map(|o| o.as_slice().try_into().expect("three locals"))
        .collect();
    // a singular system leaves NaN standard errors (said as such), not made-up ones; when the
    // Schur complement failed on a run whose locals the data cannot tell apart (a 2 kHz null:
    // every error NaN, and the pair test then took the single runs' physics as exact), the
    // information with each run's locals projected out gives them
    let mut profiled: Option<Vec<f64>> = None;
    let global_se = (0..ng)
        .map(|i| {
            let v = res.shared_cov.get(i).map_or(f64::NAN, |row| row[i]);
            match (ctl.free_global, v.is_nan()) {
                (false, _) => 0.0,
                (true, true) if !ctl.covariance => f64::NAN,
                (true, true) => {
                    let se = profiled.get_or_insert_with(|| {
                        let prep =
                            super::candidate::prepare(spec, params, &res.shared, &local, runs);
                        super::screen_sums::profiled_se(&prep)
                    });
                    se[i] * scale.sqrt()
                }
                (true, false) => (v.max(0.0) * scale).sqrt(),
            }
        })
        .collect();
    let global_cov = if ctl.free_global {
        res.shared_cov
            .iter()
            .map(|row| row.iter().map(|c| c * scale).collect())
            .collect()
    } else {
        Vec::new()
    };
    Fitted {
        global: res.shared,
        local,
        chi2,
        chi2_run,
        global_se,
        global_cov,
        iterations: res.iterations,
        converged: res.termination.is_converged(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discover::forms::{
        Extra, GrooveTilt, Localized, PeriodicZ, RollingResistance, SaturatingDrag, Spline,
        TimeCommon,
    };
    use crate::physics::{Groove, Variable};

    fn norm(x: &[f64]) -> f64 {
        x.iter().map(|v| v * v).sum::<f64>().sqrt()
    }

    /// A spline force in v (its coefficients), the drag time and the run's t0 and v0: the
    /// response's columns are the forward differences of the predictions within 1 % (0.1–0.6 %
    /// measured), on a run that slides, switches to rolling and rolls (the switch moves with
    /// every parameter).
    #[test]
    fn the_responses_columns_are_the_differences_in_v() {
        let mut g = vec![0.3, 0.05];
        g.extend([0.05, 0.1, 0.3, 0.2, -0.1, 0.05, 0.0, 0.02, 0.0]);
        let offs = responses_against_differences(vec![spline(Variable::V, 0.01)], &g);
        assert!(offs.len() >= 7, "too few columns reached: {offs:?}");
        assert!(offs.iter().all(|o| o.1 < 0.01), "{offs:?}");
    }

    /// The same in z over knots 0.5 mm apart, within 2 % (0.03–1.5 % measured): the response
    /// leaves out how the force changes with the position it moves (∂a/∂z δz).
    #[test]
    fn the_responses_columns_are_the_differences_in_z() {
        let mut g = vec![0.3, 0.05];
        g.extend([0.05, 0.1, 0.3, 0.2, -0.1, 0.05, 0.0, 0.02, 0.0]);
        let offs = responses_against_differences(vec![spline(Variable::Z, 0.5e-3)], &g);
        assert!(offs.len() >= 7, "too few columns reached: {offs:?}");
        assert!(offs.iter().all(|o| o.1 < 0.02), "{offs:?}");
    }

    /// The named forces: a saturating drag (T0, T'), a tilt, a constant resistance, a force
    /// periodic in z, a localized one and one periodic in time, each parameter within 4 %
    /// (0.4–1.2 % measured, and 3.1 % for the cosine of the force in time, whole at the kick).
    #[test]
    fn the_responses_columns_are_the_differences_of_named_forces() {
        let extras = vec![
            Extra::SaturatingDrag(SaturatingDrag),
            Extra::GrooveTilt(GrooveTilt),
            Extra::RollingResistance(RollingResistance),
            Extra::PeriodicZ(PeriodicZ {
                z_ref_m: 0.0,
                k_lo: 100.0,
                k_hi: 5000.0,
            }),
            Extra::Localized(Localized {
                z_lo: 0.0,
                z_hi: 0.01,
                w_lo: 1e-4,
                w_hi: 2e-3,
            }),
            Extra::TimeCommon(TimeCommon {
                f_lo: 10.0,
                f_hi: 500.0,
            }),
        ];
        let g = [
            0.3, 0.05, // μ, T0
            0.2,  // T'
            0.05, // tilt (degrees)
            0.01, // resistance
            2000.0, 0.05, -0.03, // periodic in z: k, sin, cos
            0.2, 2e-3, 0.5e-3, // localized: A, centre, width
            80.0, 0.05, 0.02, // periodic in time: f, sin, cos
        ];
        let offs = responses_against_differences(extras, &g);
        assert_eq!(
            offs.len(),
            g.len() - 1 + 2,
            "every column but μ's: {offs:?}"
        );
        assert!(offs.iter().all(|o| o.1 < 0.04), "{offs:?}");
    }

    fn spline(variable: Variable, dx: f64) -> Extra {
        Extra::Spline(Spline {
            variable,
            lo: 0.0,
            dx,
            segments: 6,
            penalty: 0.0,
        })
    }

    /// On one run of 60 ms under `extras` at globals `g` (μ, T, then the terms'), each column
    /// the response gives (a global's index, or 100 + a local's) against its forward difference
    /// of the predictions: the relative norm of their difference. A global whose difference is
    /// negligible (a basis function the run never reaches) is left out.
    fn responses_against_differences(extras: Vec<Extra>, g: &[f64]) -> Vec<(usize, f64)> {
        let groove = Groove::CHAPTER;
        let spec = Spec {
            n_materials: 1,
            s: groove.s,
            k: groove.k,
            extras,
        };
        let steps: Vec<f64> = spec
            .global_params(&["m".to_string()])
            .iter()
            .map(|p| p.step)
            .collect();
        let l = [1e-3, 0.3e-4, 0.06];
        let t: Vec<f64> = (0..600).map(|k| k as f64 * 1e-4).collect();
        let mut run = RunData {
            run: "r".into(),
            material: 0,
            fps: 1e4,
            t_s: t.clone(),
            z_m: vec![0.0; t.len()],
            keep: (0..t.len()).map(|i| i % 97 != 5).collect(),
            sigma_m: 1e-6,
            fast: Default::default(),
            scale: Vec::new(),
            slow: Default::default(),
        };
        let mut z = vec![0.0; t.len()];
        predict(&spec, g, &l, &run, &mut z);
        run.z_m = z;
        let runs = [run];
        let problem = Runs::new(&spec, &runs, g, &steps);
        let known = problem.known_columns(0, g, &l).expect("known columns");
        assert!(
            known.shared[0].is_none() && known.own[0].is_none(),
            "μ and z0 differenced"
        );
        let n = runs[0].t_s.len();
        let mut r0 = vec![0.0; n];
        problem.residuals(0, g, &l, &mut r0);
        let difference = |g: &[f64], l: &[f64], h: f64| -> Vec<f64> {
            let mut r = vec![0.0; n];
            problem.residuals(0, g, l, &mut r);
            r.iter().zip(&r0).map(|(a, b)| (a - b) / h).collect()
        };
        let off = |col: &[f64], exact: &[f64]| {
            let d: Vec<f64> = col.iter().zip(exact).map(|(a, b)| a - b).collect();
            norm(&d) / norm(exact)
        };
        let mut offs = Vec::new();
        for j in 1..g.len() {
            let mut gp = g.to_vec();
            gp[j] += steps[j];
            let exact = difference(&gp, &l, steps[j]);
            if norm(&exact) < 1e-3 {
                continue;
            }
            let col = known.shared[j]
                .as_ref()
                .expect("a column through the force");
            offs.push((j, off(col, &exact)));
        }
        for (k, h) in [(1, 1e-8), (2, 1e-7)] {
            let mut lp = l;
            lp[k] += h;
            let exact = difference(g, &lp, h);
            let col = known.own[k].as_ref().expect("a local's column");
            offs.push((100 + k, off(col, &exact)));
        }
        offs
    }
}
