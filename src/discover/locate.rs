//! Residuals of a fitted joint model with the model's phase, speed and position at each sample.

use super::candidate::Spec;
use super::data::RunData;
use super::joint::Fitted;
use super::residual_structure::{structure, RunResiduals, Structure};
use super::sim::Motion;

/// Residual structure of `fit` over `runs` (kept samples only), and how many runs' simulations
/// stopped at their step budget before their last frame.
pub fn locate(
    spec: &Spec,
    fit: &Fitted,
    runs: &[RunData],
    materials: &[String],
) -> (Structure, usize) {
    let mut stalled = 0;
    let per_run: Vec<RunResiduals> = runs
        .iter()
        .zip(&fit.local)
        .map(|(run, l)| {
            let n = run.t_s.len();
            let tt: Vec<f64> = run.t_s.iter().map(|t| t + l[1]).collect();
            let (mut z, mut v, mut ph) = (vec![0.0; n], vec![0.0; n], vec![Motion::Sliding; n]);
            let model = spec.run_model(&fit.global, l, run);
            stalled +=
                usize::from(model.simulate(l[0], l[2], &tt, &mut z, Some(&mut v), Some(&mut ph)));
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
    (structure(&per_run), stalled)
}

/// What the diagnosis says when the final model's simulations of `stalled` of `runs` runs
/// stopped at their step budget (empty when none did).
pub fn stalled_note(stalled: usize, runs: usize) -> String {
    if stalled == 0 {
        return String::new();
    }
    format!(
        "the final model's simulation{s} of {stalled} of {runs} runs stopped at the integrator's step budget before the last frame: from there {those} residuals are the integrator's, not the physics', and the fit of {those} run{s} is in doubt",
        s = if stalled == 1 { "" } else { "s" },
        those = if stalled == 1 { "its" } else { "their" },
    )
}

#[cfg(test)]
mod tests {
    use super::stalled_note;

    #[test]
    fn a_stalled_simulation_is_said_and_none_is_silent() {
        assert_eq!(stalled_note(0, 60), "");
        let one = stalled_note(1, 60);
        assert!(
            one.contains("simulation of 1 of 60 runs") && one.contains("its residuals"),
            "{one}"
        );
        let two = stalled_note(2, 60);
        assert!(
            two.contains("simulations of 2 of 60 runs") && two.contains("their"),
            "{two}"
        );
    }
}
