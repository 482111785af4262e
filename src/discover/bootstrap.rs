//! Parametric bootstrap of the likelihood-ratio statistics: simulate the fitted smaller model with
//! each run's measured noise (Gaussian AR(1): its σ and lag-1 autocorrelation, so frames within a
//! run stay dependent as in the data), refit the smaller and every larger model from warm starts.

use super::candidate::{Extra, ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::joint::{fit_joint, predict, FitControl, Fitted};
use super::proposal::{propose, starts, wanted_for, Ranges};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use rayon::prelude::*;

/// A larger model to test against the null: its spec, parameters, and the starting values of its
/// extra parameters. The replicates are refitted from the same starts as the data (where the term
/// vanishes, plus the multi-starts of a nonlinear scale), keeping the best: a replicate searched
/// less thoroughly than the data would make the test anti-conservative.
pub struct Alternative {
    pub spec: Spec,
    pub params: Vec<ParamInfo>,
    pub extra_starts: Vec<Vec<f64>>,
    /// A term whose starts come from the residuals (periodogram, bump scan): each replicate
    /// proposes its own starts from its own residuals, as the data did.
    pub proposed: Option<(Extra, Ranges)>,
}

/// One synthetic data set drawn from the fitted null model.
pub fn synthetic_runs(
    spec: &Spec,
    fit: &Fitted,
    runs: &[RunData],
    rng: &mut ChaCha8Rng,
) -> Vec<RunData> {
    runs.iter()
        .zip(&fit.local)
        .map(|(run, l)| {
            let mut z = vec![0.0; run.t_s.len()];
            predict(spec, &fit.global, l, run, &mut z);
            let rho = run.rho1;
            let innov = (1.0 - rho * rho).sqrt() * run.sigma_m;
            let mut e: f64 = rng.sample::<f64, _>(StandardNormal) * run.sigma_m;
            for zi in z.iter_mut() {
                *zi += e;
                e = rho * e + innov * rng.sample::<f64, _>(StandardNormal);
            }
            RunData {
                z_m: z,
                ..run.clone()
            }
        })
        .collect()
}

/// LR replicates: `out[a][b]` for alternative `a` and replicate `b`.
#[allow(clippy::too_many_arguments)]
pub fn lr_replicates(
    null_spec: &Spec,
    null_params: &[ParamInfo],
    null_fit: &Fitted,
    alts: &[Alternative],
    runs: &[RunData],
    replicates: usize,
    seed: u64,
    iters: usize,
    stop: Option<&EarlyStop>,
) -> Vec<Vec<f64>> {
    let one = |b: usize| -> Vec<f64> {
        let mut rng =
            ChaCha8Rng::seed_from_u64(seed ^ (b as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
        let data = synthetic_runs(null_spec, null_fit, runs, &mut rng);
        let ctl = FitControl {
            max_iter: iters,
            free_global: true,
        };
        let f0 = fit_joint(
            null_spec,
            null_params,
            &data,
            &null_fit.global,
            &null_fit.local,
            ctl,
        );
        let needing: Vec<&Extra> = alts
            .iter()
            .filter_map(|a| a.proposed.as_ref().map(|p| &p.0))
            .collect();
        let props = match alts.iter().find_map(|a| a.proposed.as_ref()) {
            Some((_, rg)) => propose(
                null_spec,
                null_params,
                &f0.global,
                &f0.local,
                &data,
                rg,
                wanted_for(&needing),
                None,
            ),
            None => Default::default(),
        };
        alts.iter()
            .map(|a| {
                let own;
                let list = match &a.proposed {
                    Some((e, _)) => {
                        own = starts(e, &props);
                        &own
                    }
                    None => &a.extra_starts,
                };
                let best = list
                    .iter()
                    .map(|start| {
                        let mut g = f0.global.clone();
                        g.extend_from_slice(start);
                        let l: Vec<[f64; N_LOCAL]> = f0.local.clone();
                        fit_joint(&a.spec, &a.params, &data, &g, &l, ctl).chi2
                    })
                    .fold(f64::INFINITY, f64::min);
                (f0.chi2 - best).max(0.0)
            })
            .collect()
    };
    // replicates in batches; replicate b always has the same seed, so stopping early changes
    // only how many are drawn, never what they are
    let batch = 6;
    let mut per_rep: Vec<Vec<f64>> = Vec::with_capacity(replicates);
    while per_rep.len() < replicates {
        let from = per_rep.len();
        let to = (from + batch).min(replicates);
        let more: Vec<Vec<f64>> = (from..to).into_par_iter().map(one).collect();
        per_rep.extend(more);
        if let Some(st) = stop {
            if per_rep.len() < replicates && 2 * per_rep.len() >= replicates && st.clear(&per_rep) {
                break;
            }
        }
    }
    (0..alts.len())
        .map(|a| per_rep.iter().map(|r| r[a]).collect())
        .collect()
}

/// Sequential stopping of the bootstrap: once every statistic is far inside or far beyond its
/// null (p below `alpha`/100 or above 0.5 after at least 6 replicates and half of those asked), more replicates cannot
/// change a decision.
pub struct EarlyStop {
    /// Observed LR and degrees of freedom of each alternative.
    pub observed: Vec<(f64, f64)>,
    pub alpha: f64,
}

impl EarlyStop {
    fn clear(&self, per_rep: &[Vec<f64>]) -> bool {
        if per_rep.len() < 6 {
            return false;
        }
        self.observed.iter().enumerate().all(|(a, (lr, df))| {
            let reps: Vec<f64> = per_rep.iter().map(|r| r[a]).collect();
            let p = super::null_distribution::NullFit::from_replicates(&reps, *df).p_value(*lr);
            p < self.alpha / 100.0 || p > 0.5
        })
    }
}
