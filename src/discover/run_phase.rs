//! The held-out error of a run under a term with a phase of the run's own: the phase chosen on
//! one half of the run's samples, the other half scored with it, both ways round.

use super::candidate::{Spec, N_LOCAL};
use super::data::RunData;

/// Fewest kept samples in each half for the split to mean anything; shorter runs are scored whole.
const MIN_HALF: usize = 8;

/// Σ (residual/σ)² over the kept samples of `run`, each half predicted with the run's phase
/// profiled on the other half (globals `g`, the run's locals `l`).
pub fn split_phase_chi2(spec: &Spec, g: &[f64], l: &[f64; N_LOCAL], run: &RunData) -> f64 {
    let kept: Vec<usize> = (0..run.t_s.len()).filter(|&i| run.keep[i]).collect();
    let half = kept.len() / 2;
    let whole = || super::joint::run_chi2(spec, g, l, run);
    if half < MIN_HALF {
        return whole();
    }
    let mid_t = run.t_s[kept[half]];
    let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
    let w = 1.0 / run.sigma_m;
    let mut total = 0.0;
    for early in [true, false] {
        let in_fit = |i: usize| (run.t_s[i] < mid_t) == early;
        let mut fit_on = run.clone();
        for (i, k) in fit_on.keep.iter_mut().enumerate() {
            *k = *k && in_fit(i);
        }
        let model = spec.run_model(g, l, &fit_on);
        let mut z = vec![0.0; tt.len()];
        model.simulate(l[0], l[2], &tt, &mut z, None, None);
        total += (0..z.len())
            .filter(|&i| run.keep[i] && !in_fit(i))
            .map(|i| ((run.z_m[i] - z[i]) * w).powi(2))
            .sum::<f64>();
    }
    total
}
