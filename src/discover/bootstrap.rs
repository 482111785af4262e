//! Parametric bootstrap of the likelihood-ratio statistics: simulate the fitted smaller model with
//! each run's measured noise (Gaussian AR(1): its σ and lag-1 autocorrelation, so frames within a
//! run stay dependent as in the data), refit the smaller and every larger model from warm starts.

use super::candidate::{ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::joint::{fit_joint, predict, FitControl, Fitted};
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
pub fn lr_replicates(
    null_spec: &Spec,
    null_params: &[ParamInfo],
    null_fit: &Fitted,
    alts: &[Alternative],
    runs: &[RunData],
    replicates: usize,
    seed: u64,
    iters: usize,
) -> Vec<Vec<f64>> {
    let per_rep: Vec<Vec<f64>> = (0..replicates)
        .into_par_iter()
        .map(|b| {
            let mut rng = ChaCha8Rng::seed_from_u64(
                seed ^ (b as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15),
            );
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
            alts.iter()
                .map(|a| {
                    let best = a
                        .extra_starts
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
        })
        .collect();
    (0..alts.len())
        .map(|a| per_rep.iter().map(|r| r[a]).collect())
        .collect()
}
