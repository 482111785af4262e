//! Leave-runs-out cross-validation of the simulated trajectories.
//!
//! Runs are dealt to folds after sorting by (material, direction, |v0|), so each fold spans the
//! conditions. For each fold the shared parameters are fitted on the other runs; each held-out run
//! then gets only its own z0, t0, v0, and its residual is the held-out error.

use super::candidate::{ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::joint::{fit_joint, FitControl, Fitted};
use serde::Serialize;

/// Held-out error of one model.
#[derive(Clone, Debug, Serialize)]
pub struct CvResult {
    /// RMS of held-out residuals over every kept sample (metres).
    pub cv_rms_m: f64,
    /// Per run: mean squared held-out residual over σ_run² (1 where the model predicts within noise).
    #[serde(skip)]
    pub per_run_msn: Vec<f64>,
}

/// Fold index of every run.
pub fn folds(runs: &[RunData], local: &[[f64; N_LOCAL]], k: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..runs.len()).collect();
    order.sort_by(|&a, &b| {
        (runs[a].material, local[a][2] < 0.0)
            .cmp(&(runs[b].material, local[b][2] < 0.0))
            .then(local[a][2].abs().total_cmp(&local[b][2].abs()))
            .then(runs[a].run.cmp(&runs[b].run))
    });
    let mut fold = vec![0; runs.len()];
    for (pos, &i) in order.iter().enumerate() {
        fold[i] = pos % k.max(1);
    }
    fold
}

/// Cross-validate `spec` starting every fold from the full-data fit `full`.
pub fn cross_validate(
    spec: &Spec,
    params: &[ParamInfo],
    runs: &[RunData],
    full: &Fitted,
    fold: &[usize],
    k: usize,
) -> CvResult {
    let mut sq = 0.0;
    let mut count = 0usize;
    let mut per_run = vec![0.0; runs.len()];
    for f in 0..k {
        let train: Vec<usize> = (0..runs.len()).filter(|i| fold[*i] != f).collect();
        let test: Vec<usize> = (0..runs.len()).filter(|i| fold[*i] == f).collect();
        if test.is_empty() || train.is_empty() {
            continue;
        }
        let pick = |idx: &[usize]| -> (Vec<RunData>, Vec<[f64; N_LOCAL]>) {
            (
                idx.iter().map(|i| runs[*i].clone()).collect(),
                idx.iter().map(|i| full.local[*i]).collect(),
            )
        };
        let (tr, trl) = pick(&train);
        let trained = fit_joint(
            spec,
            params,
            &tr,
            &full.global,
            &trl,
            FitControl {
                max_iter: 8,
                free_global: true,
            },
        );
        let (te, tel) = pick(&test);
        let held = fit_joint(
            spec,
            params,
            &te,
            &trained.global,
            &tel,
            FitControl {
                max_iter: 12,
                free_global: false,
            },
        );
        for (j, &i) in test.iter().enumerate() {
            let n = runs[i].n_used().max(1);
            // chi2_run is Σ (r/σ)²
            let chi2 = held.chi2_run[j];
            per_run[i] = chi2 / n as f64;
            sq += chi2 * runs[i].sigma_m.powi(2);
            count += n;
        }
    }
    CvResult {
        cv_rms_m: (sq / count.max(1) as f64).sqrt(),
        per_run_msn: per_run,
    }
}

/// `cv` with each run charged `gains[i]` (χ², noise units) of held-out error: what a term with a
/// parameter fitted on the held-out run itself (a phase) takes from that run's noise alone.
pub fn charged(cv: &CvResult, gains: &[f64], runs: &[RunData]) -> CvResult {
    let mut per_run = cv.per_run_msn.clone();
    let (mut sq, mut count) = (0.0, 0usize);
    for (i, run) in runs.iter().enumerate() {
        let n = run.n_used().max(1);
        per_run[i] += gains.get(i).copied().unwrap_or(0.0) / n as f64;
        sq += per_run[i] * n as f64 * run.sigma_m.powi(2);
        count += n;
    }
    CvResult {
        cv_rms_m: (sq / count.max(1) as f64).sqrt(),
        per_run_msn: per_run,
    }
}

/// One-sided paired t of the per-run improvement (base − extended); positive: the extension predicts better.
pub fn paired_t(base: &CvResult, ext: &CvResult) -> f64 {
    let d: Vec<f64> = base
        .per_run_msn
        .iter()
        .zip(&ext.per_run_msn)
        .map(|(a, b)| a - b)
        .collect();
    let n = d.len() as f64;
    if d.len() < 2 {
        return 0.0;
    }
    let m = d.iter().sum::<f64>() / n;
    let sd = (d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    if sd > 0.0 {
        m / (sd / n.sqrt())
    } else if m > 0.0 {
        f64::INFINITY
    } else {
        0.0
    }
}
