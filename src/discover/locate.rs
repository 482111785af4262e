//! Residuals of a fitted joint model with the model's phase, speed and position at each sample.

use super::candidate::Spec;
use super::data::RunData;
use super::joint::Fitted;
use super::residual_structure::{structure, RunResiduals, Structure};
use super::sim::Motion;

/// Residual structure of `fit` over `runs` (kept samples only).
pub fn locate(spec: &Spec, fit: &Fitted, runs: &[RunData], materials: &[String]) -> Structure {
    let per_run: Vec<RunResiduals> = runs
        .iter()
        .zip(&fit.local)
        .map(|(run, l)| {
            let n = run.t_s.len();
            let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
            let (mut z, mut v, mut ph) = (vec![0.0; n], vec![0.0; n], vec![Motion::Sliding; n]);
            let model = spec.run_model(&fit.global, l, run);
            model.simulate(l[0], l[2], &tt, &mut z, Some(&mut v), Some(&mut ph));
            let keep = |i: &usize| run.keep[*i];
            RunResiduals {
                material: materials[run.material].clone(),
                direction: l[2].signum(),
                sigma_m: run.sigma_m,
                residual_m: (0..n).filter(keep).map(|i| run.z_m[i] - z[i]).collect(),
                speed_mps: (0..n).filter(keep).map(|i| v[i]).collect(),
                z_m: (0..n).filter(keep).map(|i| z[i]).collect(),
                phase: (0..n).filter(keep).map(|i| ph[i]).collect(),
            }
        })
        .collect();
    structure(&per_run)
}
