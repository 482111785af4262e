//! The start of a whole-run fit from an earlier analysis of the same runs (a material's part of
//! summary.json's `collisions.whole_run`): its shared values, its chosen restitution laws and
//! each run's kick, so that a fit under more physics (the `refit` stage) starts at the earlier
//! optimum instead of the defaults, from which a fit under a waviness can end at a local optimum
//! far from it (440c's μ_pp at 0.62 instead of 1.4) and need a restart and a second profile.

use super::restitution_law::with_chosen;
use super::wholerun::{law_slots, FitSpec, PairRun, LN_T0, MU_PG, MU_PP, TP, T_KICK, V0, Z1};
use crate::artifacts::collision_summary::{LawChoice, MaterialWholeRun};
use crate::recording::Setup;

/// Where a whole-run fit starts: its spec (the earlier fit's law forms), the shared values and
/// each run's own values, in the order of the runs.
#[derive(Debug, Clone)]
pub struct Start {
    pub spec: FitSpec,
    pub shared: Vec<f64>,
    pub own: Vec<Vec<f64>>,
}

/// Writes each chosen law's all-runs values into its slots of `shared` (v_ref through its
/// logarithm, the fitted slot); a law without a chosen candidate leaves its slots alone.
pub fn carry_laws(shared: &mut [f64], choices: &[LawChoice]) {
    for c in choices {
        let (ia, ib) = law_slots(c.setup);
        if let Some(cand) = c.chosen_candidate() {
            let [a, b] = cand.slots().unwrap_or([f64::NAN, 0.0]);
            shared[ia] = a;
            shared[ib] = b;
        }
    }
}

/// The start of a fit of `runs` under `spec` from `earlier`, the same material's analysis
/// under other physics: `spec` with the earlier law forms; μ_pg, the drag, μ_pp and the laws'
/// values from it; each run's kick speed and time from its row (matched by run id; the start
/// position moved along the striker's line to that time in the rolling setup, where the striker
/// moves at the kick speed until the impact). Values the earlier fit left undetermined (not
/// finite) keep the defaults.
pub fn from_summary(earlier: &MaterialWholeRun, runs: &[PairRun], spec: &FitSpec) -> Start {
    let spec = with_chosen(spec, &earlier.restitution);
    let defaults: Vec<f64> = spec
        .shared_specs(None, runs)
        .iter()
        .map(|s| s.start)
        .collect();
    let mut shared = defaults.clone();
    shared[MU_PG] = earlier.mu_pg.value;
    shared[LN_T0] = earlier.t0_s.value.ln();
    shared[TP] = earlier.tp_s_per_mps.value;
    shared[MU_PP] = earlier.mu_pp.value;
    carry_laws(&mut shared, &earlier.restitution);
    for (x, d) in shared.iter_mut().zip(&defaults) {
        if !x.is_finite() {
            *x = *d;
        }
    }
    let own = runs
        .iter()
        .map(|r| {
            let mut o = r.own_start().to_vec();
            let row = earlier.runs.iter().find(|w| w.run == r.run);
            if let Some((v0, tk)) = row
                .map(|w| (w.v0_mps.value, w.t_kick_s))
                .filter(|(v0, tk)| v0.is_finite() && tk.is_finite())
            {
                if r.setup == Setup::Rolling {
                    o[Z1] += o[V0] * (tk - o[T_KICK]);
                }
                o[V0] = v0;
                o[T_KICK] = tk;
            }
            o
        })
        .collect();
    Start { spec, shared, own }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::Summary;
    use crate::fit::collision::wholerun::fit_group_with;
    use crate::ingest::{read_dataset_dir, IngestParams};
    use crate::physics::Groove;
    use crate::recording::Experiment;
    use std::path::Path;

    /// The shipped 316 pair runs and their part of the shipped summary.json.
    fn shipped_316() -> (Vec<PairRun>, MaterialWholeRun) {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let recs = read_dataset_dir(&root.join("data"), &IngestParams::default()).unwrap();
        let runs: Vec<PairRun> = recs
            .iter()
            .filter(|r| r.info.experiment == Experiment::Collision && r.info.material == "316")
            .map(|r| PairRun::from_recording(r, r.info.setup).unwrap())
            .collect();
        let summary: Summary =
            serde_json::from_slice(&std::fs::read(root.join("reports/summary.json")).unwrap())
                .unwrap();
        let whole = summary.collisions.unwrap().whole_run.unwrap();
        let m = whole.materials.into_iter().find(|m| m.material == "316");
        (runs, m.unwrap())
    }

    #[test]
    fn the_start_is_the_earlier_fit_and_a_fit_from_it_stays_there() {
        let (runs, earlier) = shipped_316();
        let s = from_summary(&earlier, &runs, &FitSpec::new(Groove::CHAPTER));
        assert_eq!(s.shared[MU_PG], earlier.mu_pg.value);
        assert_eq!(s.shared[MU_PP], earlier.mu_pp.value);
        assert!((s.shared[LN_T0].exp() - earlier.t0_s.value).abs() < 1e-15);
        for (r, o) in runs.iter().zip(&s.own) {
            let row = earlier.runs.iter().find(|w| w.run == r.run).unwrap();
            assert_eq!((o[V0], o[T_KICK]), (row.v0_mps.value, row.t_kick_s));
        }
        // the same physics from that start: the earlier optimum, reached again at once
        let fit = fit_group_with(&runs, &s.spec, &s.shared, Some(&s.own), &|_| true, 80);
        assert!(
            fit.cost() <= earlier.deviance + 1.0 && fit.result.iterations < earlier.iterations,
            "deviance {} (earlier {}), {} iterations (earlier {})",
            fit.cost(),
            earlier.deviance,
            fit.result.iterations,
            earlier.iterations
        );
    }

    #[test]
    fn an_undetermined_value_or_a_run_the_summary_lacks_keeps_the_default() {
        let (runs, mut earlier) = shipped_316();
        earlier.mu_pp.value = f64::NAN;
        let gone = earlier.runs.remove(0);
        let s = from_summary(&earlier, &runs, &FitSpec::new(Groove::CHAPTER));
        let defaults = s.spec.shared_specs(None, &runs);
        assert_eq!(s.shared[MU_PP], defaults[MU_PP].start);
        let i = runs.iter().position(|r| r.run == gone.run).unwrap();
        assert_eq!(s.own[i], runs[i].own_start().to_vec());
    }
}
