//! The joint model's parameter layout, the physics of a run it gives, and its predictions.
//!
//! Global parameters are laid out as `[μ per material][T per material][extra terms…]`; each run
//! adds its own `[z0, t0, v0]`. An `Extra` (`forms/`) is either a candidate physical term (with
//! the effect id the diagnosis uses) or a drift probe: a phenomenological term that only locates
//! a mismatch.

use super::data::RunData;
pub use super::data::N_LOCAL;
use super::forms::{drag_time_names, p, Entry};
pub use super::forms::{Extra, ParamInfo};
use super::response::{Prepared, Projector, Track};
use super::sim::{Drag, SimModel};
use crate::artifacts::diagnosis::Estimate;
use std::collections::BTreeMap;

/// A material's own values in a joint model: μ and its drag time (T, or T0 beside a saturating
/// drag), with their standard errors.
#[derive(Clone, Debug, PartialEq)]
pub struct OwnValues {
    pub mu: Estimate,
    pub t_s: Estimate,
}

impl OwnValues {
    /// `material`'s values in `params` (a final model's parameters, named as `Spec::global_params`
    /// names them: diagnosis.json's `model_parameters`).
    pub fn of(params: &BTreeMap<String, Estimate>, material: &str) -> Result<OwnValues, String> {
        let mu = params
            .get(&format!("mu_{material}"))
            .ok_or_else(|| format!("no mu_{material} in the accepted model"))?;
        let t_s = drag_time_names()
            .into_iter()
            .find_map(|name| params.get(&format!("{name}_{material}")))
            .ok_or_else(|| format!("no drag time of {material} in the accepted model"))?;
        Ok(OwnValues { mu: *mu, t_s: *t_s })
    }
}

/// The structure of a joint model: materials and the extra terms.
#[derive(Clone, Debug, PartialEq)]
pub struct Spec {
    pub n_materials: usize,
    pub s: f64,
    pub k: f64,
    pub extras: Vec<Extra>,
}

impl Spec {
    pub fn with(&self, extra: Extra) -> Spec {
        let mut s = self.clone();
        s.extras.push(extra);
        s
    }

    /// Every global parameter, in layout order, named with the material names.
    pub fn global_params(&self, materials: &[String]) -> Vec<ParamInfo> {
        let name = self
            .extras
            .iter()
            .find_map(|e| e.drag_time_name())
            .unwrap_or("t_s");
        let mut out = Vec::new();
        for m in materials.iter().take(self.n_materials) {
            out.push(p(&format!("mu_{m}"), 0.3, 1e-3, 2.0, 1e-5));
        }
        for m in materials.iter().take(self.n_materials) {
            out.push(p(&format!("{name}_{m}"), 0.08, 1e-3, 1e3, 1e-5));
        }
        for e in &self.extras {
            out.extend(e.named_params(materials));
        }
        out
    }

    pub fn n_global(&self) -> usize {
        2 * self.n_materials + self.extras.iter().map(|e| e.params().len()).sum::<usize>()
    }

    /// Offset of extra `i` in the global vector.
    pub fn extra_offset(&self, i: usize) -> usize {
        2 * self.n_materials
            + self.extras[..i]
                .iter()
                .map(|e| e.params().len())
                .sum::<usize>()
    }

    /// Global parameters a run of `material` depends on.
    pub fn affecting(&self, material: usize) -> Vec<usize> {
        let mut v = vec![material, self.n_materials + material];
        v.extend(2 * self.n_materials..self.n_global());
        v
    }

    /// True when z0 enters other than as an additive offset (a position-dependent force).
    pub fn position_dependent(&self) -> bool {
        self.extras.iter().any(|e| e.position_dependent())
    }

    /// True when a term has a phase of its own in each run (profiled in `run_model`).
    pub fn has_run_phase(&self) -> bool {
        self.extras.iter().any(|e| e.run_phase())
    }

    /// The physics of one run, with each run's own phase of a time-periodic force chosen to fit
    /// the run's recorded positions best (locals `l` = z0, t0, v0).
    pub fn run_model(&self, g: &[f64], l: &[f64; N_LOCAL], run: &RunData) -> SimModel {
        let mut m = self.sim_model(g, run.material, l[2]);
        if self.has_run_phase() {
            super::timeforce::profile_phase(&mut m, l, run);
        }
        m
    }

    /// The physics of one run for global parameters `g` and the run's v0.
    pub fn sim_model(&self, g: &[f64], material: usize, v0_mps: f64) -> SimModel {
        let mu = g[material];
        let t_s = g[self.n_materials + material];
        let m = SimModel::baseline(self.s, self.k, mu, t_s);
        let mut e = Entry {
            model: m,
            mu,
            t_s,
            quad: 0.0,
            tp: None,
            material,
            v0_mps,
        };
        for (i, extra) in self.extras.iter().enumerate() {
            extra.enter(&g[self.extra_offset(i)..], &mut e);
        }
        let mut m = e.model;
        m.mu = e.mu.max(1e-6);
        let t_s = e.t_s.max(1e-4);
        m.drag = match e.tp {
            Some(tp) => Drag::Saturating {
                t0_s: t_s,
                tp_s_per_mps: tp,
            },
            None => Drag::Quadratic {
                t_s,
                c_per_m: e.quad,
            },
        };
        m
    }
}
/// Predicted positions of `run` at its sample times.
pub fn predict(spec: &Spec, g: &[f64], l: &[f64; N_LOCAL], run: &RunData, out: &mut [f64]) {
    let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
    let model = spec.run_model(g, l, run);
    model.simulate(l[0], l[2], &tt, out, None, None);
}

/// Prepare every run of a fitted joint model for regressions of its residuals.
pub fn prepare(
    spec: &Spec,
    params: &[ParamInfo],
    global: &[f64],
    local: &[[f64; N_LOCAL]],
    runs: &[RunData],
) -> Vec<Prepared> {
    use rayon::prelude::*;
    runs.par_iter()
        .zip(local.par_iter())
        .enumerate()
        .map(|(i, (run, l))| {
            let model = spec.run_model(global, l, run);
            let track = Track::new(&model, l[0], l[1], l[2], run);
            let mut pred = vec![0.0; run.t_s.len()];
            let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
            model.simulate(l[0], l[2], &tt, &mut pred, None, None);
            let mut cols = track.local_columns();
            for c in cols.iter_mut() {
                c.iter_mut().for_each(|x| *x *= track.w);
            }
            let proj = Projector::new(&cols);
            let mut y: Vec<f64> = (0..run.t_s.len())
                .filter(|k| run.keep[*k])
                .map(|k| (run.z_m[k] - pred[k]) * track.w)
                .collect();
            proj.apply(&mut y);
            let affecting = spec.affecting(run.material);
            let glob: Vec<Vec<f64>> = (0..global.len())
                .map(|j| {
                    let n = y.len();
                    if !affecting.contains(&j) || params[j].hi <= params[j].lo {
                        return vec![0.0; n];
                    }
                    let mut g = global.to_vec();
                    let mut h = params[j].step;
                    if g[j] + h > params[j].hi {
                        h = -h;
                    }
                    g[j] += h;
                    let mut z = vec![0.0; run.t_s.len()];
                    predict(spec, &g, l, run, &mut z);
                    let mut c: Vec<f64> = (0..run.t_s.len())
                        .filter(|k| run.keep[*k])
                        .map(|k| (z[k] - pred[k]) / h * track.w)
                        .collect();
                    proj.apply(&mut c);
                    c
                })
                .collect();
            Prepared {
                track,
                proj,
                y,
                glob,
                run: i,
            }
        })
        .collect()
}
