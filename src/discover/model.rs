//! A fitted joint model (the baseline with its extra terms) and where a term's parameters start.

use super::candidate::{Extra, ParamInfo, Spec, N_LOCAL};
use super::cv::{charged, cross_validate, CvResult};
use super::data::RunData;
use super::joint::{fit_joint, FitControl, Fitted, USUAL_DAMPING};
use super::proposal::{needs_proposal, starts as proposal_starts};
use super::ranges::Proposals;
use crate::artifacts::diagnosis::ModelScore;
use rayon::prelude::*;

/// A fitted joint model.
#[derive(Clone)]
pub struct Model {
    pub spec: Spec,
    pub params: Vec<ParamInfo>,
    pub fit: Fitted,
}

impl Model {
    pub fn fit(
        spec: Spec,
        materials: &[String],
        runs: &[RunData],
        g: &[f64],
        l: &[[f64; N_LOCAL]],
        max_iter: usize,
    ) -> Model {
        let params = spec.global_params(materials);
        let fit = fit_joint(
            &spec,
            &params,
            runs,
            g,
            l,
            FitControl {
                max_iter,
                free_global: true,
                covariance: true,
                damping: USUAL_DAMPING,
            },
        );
        Model { spec, params, fit }
    }

    /// The model with `extra` added, fitted from this model's values and each of `starts` for
    /// the term's parameters (the best fit is kept).
    pub fn extend(
        &self,
        extra: &Extra,
        starts: &[Vec<f64>],
        materials: &[String],
        runs: &[RunData],
        max_iter: usize,
    ) -> Model {
        starts
            .par_iter()
            .map(|s| {
                let mut g = self.fit.global.clone();
                g.extend(s.iter().copied());
                Model::fit(
                    self.spec.with(extra.clone()),
                    materials,
                    runs,
                    &g,
                    &self.fit.local,
                    max_iter,
                )
            })
            .min_by(|a, b| a.fit.chi2.total_cmp(&b.fit.chi2))
            .expect("at least one start")
    }

    /// The model without extra term `i`, refitted from the current values.
    pub fn without(
        &self,
        i: usize,
        materials: &[String],
        runs: &[RunData],
        max_iter: usize,
    ) -> Model {
        self.edited(i, None, materials, runs, max_iter)
    }

    /// The model's held-out error (`fold` of each run, `folds` folds). A model with a phase per
    /// run fits each held-out run's phase on that run, so every run is charged what fitting its
    /// phase takes from its noise alone (`timeforce::noise_gain`, seeded from `seed`): every
    /// model is judged so, the one a candidate is compared against too, or a term added beside a
    /// phase per run would be credited the phase's gain.
    pub fn held_out(&self, runs: &[RunData], fold: &[usize], folds: usize, seed: u64) -> CvResult {
        let cv = cross_validate(&self.spec, &self.params, runs, &self.fit, fold, folds);
        if !self.spec.has_run_phase() {
            return cv;
        }
        let gains: Vec<f64> = runs
            .par_iter()
            .enumerate()
            .map(|(r, run)| {
                // the phase is irrelevant here (the responses at 0 and π/2 are taken)
                let l = &self.fit.local[r];
                let sim = self.spec.sim_model(&self.fit.global, run.material, l[2]);
                let run_seed = seed ^ (r as u64 + 1).wrapping_mul(0x9E37_79B9);
                super::timeforce::noise_gain(&sim, l, run, run_seed)
            })
            .collect();
        charged(&cv, &gains, runs)
    }

    /// The model with extra term `i` replaced by `extra`, whose parameters start at `start`,
    /// refitted from the current values.
    pub fn replaced(
        &self,
        i: usize,
        extra: &Extra,
        start: &[f64],
        materials: &[String],
        runs: &[RunData],
        max_iter: usize,
    ) -> Model {
        self.edited(i, Some((extra, start)), materials, runs, max_iter)
    }

    /// The model with extra term `i` left out (`with` None) or replaced by a term and its
    /// starting parameters, refitted from the current values.
    fn edited(
        &self,
        i: usize,
        with: Option<(&Extra, &[f64])>,
        materials: &[String],
        runs: &[RunData],
        max_iter: usize,
    ) -> Model {
        let off = self.spec.extra_offset(i);
        let n = self.spec.extras[i].params().len();
        let mut g = self.fit.global.clone();
        let mut spec = self.spec.clone();
        match with {
            None => {
                g.drain(off..off + n);
                spec.extras.remove(i);
            }
            Some((extra, start)) => {
                g.splice(off..off + n, start.iter().copied());
                spec.extras[i] = extra.clone();
            }
        }
        Model::fit(spec, materials, runs, &g, &self.fit.local, max_iter)
    }

    pub fn score(&self, runs: &[RunData], cv: Option<&CvResult>) -> ModelScore {
        let n: usize = runs.iter().map(|r| r.n_used()).sum();
        let sq: f64 = self
            .fit
            .chi2_run
            .iter()
            .zip(runs)
            .map(|(c, r)| c * r.sigma_m * r.sigma_m)
            .sum();
        ModelScore {
            cv_rms_m: cv.map(|c| c.cv_rms_m).unwrap_or(f64::NAN),
            rms_m: (sq / n.max(1) as f64).sqrt(),
            chi2: self.fit.chi2,
            n_global_params: self.spec.n_global(),
            terms: self.spec.extras.iter().map(|e| e.form()).collect(),
        }
    }
}

/// Starts of a term on the data: proposed from the residuals where the form needs it, the
/// force map's spline (and its own starts) for another searched form, else the form's own.
pub fn data_starts(extra: &Extra, props: &Proposals) -> Vec<Vec<f64>> {
    if needs_proposal(extra) {
        return proposal_starts(extra, props);
    }
    if extra.searched() {
        let mut s = proposal_starts(extra, props);
        s.extend(extra.starts());
        s.dedup();
        return s;
    }
    extra.starts()
}
