//! The restitution law C(v) of one material and setup from the whole-run fits: each form
//! (constant, linear, saturating) fitted to the runs of that setup with the rest of the shared
//! physics held at the material's best fit, and chosen by its error on held-out runs
//! (k-fold over runs: the law is fitted on the other runs, then only the held-out runs' own
//! parameters are fitted). Intervals are ±1.96 standard errors of the all-runs fit. A setup
//! whose law the spec holds (the law discovery accepted, under `refit`) is not chosen: its
//! choice says the law held (`held_choice`).

use super::wholerun::{
    fit_group_with, fit_own_only, law_slots, law_start, setup_index, FitSpec, GroupFit, PairRun,
};
use crate::artifacts::collision_summary::{LawCandidate, LawChoice, LawForm};
use crate::artifacts::estimate::{Estimate, Interval};
use crate::recording::Setup;
use std::collections::BTreeMap;

/// A simpler form is kept unless a richer one lowers the held-out deviance by more than this.
const PREFER_SIMPLER: f64 = 4.0;

/// The fitted law's parameters (slots `ia`, `ib` of `all`), each with its standard error and
/// 95 % interval (v_ref's through its logarithm, the fitted slot).
fn law_parameters(
    form: LawForm,
    all: &GroupFit,
    ia: usize,
    ib: usize,
) -> BTreeMap<String, Estimate> {
    let cov = &all.result.shared_cov;
    let se = |i: usize| cov[i][i].max(0.0).sqrt();
    let (a, b) = (all.result.shared[ia], all.result.shared[ib]);
    let names = form.parameter_names();
    let linear = |x: f64, s: f64| Estimate {
        value: x,
        se: s.is_finite().then_some(s),
        interval: Some(Interval {
            lo: x - 1.96 * s,
            hi: x + 1.96 * s,
        }),
    };
    let mut parameters = BTreeMap::from([(names[0].to_string(), linear(a, se(ia)))]);
    match form {
        LawForm::Constant | LawForm::FromDiscovery => {}
        LawForm::Linear => {
            parameters.insert(names[1].into(), linear(b, se(ib)));
        }
        LawForm::Saturating => {
            let v = b.exp();
            let s = se(ib);
            parameters.insert(
                names[1].into(),
                Estimate {
                    value: v,
                    se: (v * s).is_finite().then_some(v * s),
                    interval: Some(Interval {
                        lo: (b - 1.96 * s).exp(),
                        hi: (b + 1.96 * s).exp(),
                    }),
                },
            );
        }
    }
    parameters
}

/// The held-out deviance of `spec` over `k` folds of the runs `sub` (every k-th run held out,
/// the law fitted on the rest from `all`), and the number of held-out samples.
fn heldout_deviance(
    sub: &[PairRun],
    spec: &FitSpec,
    all: &GroupFit,
    k: usize,
    free: &dyn Fn(usize) -> bool,
    max_iter: usize,
) -> (f64, usize) {
    let (mut dev, mut n) = (0.0, 0usize);
    for f in 0..k {
        let train: Vec<usize> = (0..sub.len()).filter(|i| i % k != f).collect();
        let test: Vec<usize> = (0..sub.len()).filter(|i| i % k == f).collect();
        let pick = |ix: &[usize]| ix.iter().map(|&i| sub[i].clone()).collect::<Vec<_>>();
        let own_train: Vec<Vec<f64>> = train.iter().map(|&i| all.result.own[i].clone()).collect();
        let fitted = fit_group_with(
            &pick(&train),
            spec,
            &all.result.shared,
            Some(own_train.as_slice()),
            free,
            max_iter,
        );
        let held = pick(&test);
        let out = fit_own_only(&held, spec, &fitted.result.shared, max_iter);
        dev += out.cost();
        n += held.iter().map(PairRun::n_samples).sum::<usize>();
    }
    (dev, n)
}

/// Choose the law of `setup` among `runs` (one material) around the material's fit `best`.
/// None when fewer than 3 runs have this setup.
pub fn choose_law(
    runs: &[PairRun],
    best: &GroupFit,
    setup: Setup,
    folds: usize,
    max_iter: usize,
) -> Option<LawChoice> {
    let sub: Vec<PairRun> = runs.iter().filter(|r| r.setup == setup).cloned().collect();
    if sub.len() < 3 {
        return None;
    }
    let own_sub: Vec<Vec<f64>> = runs
        .iter()
        .zip(&best.result.own)
        .filter(|(r, _)| r.setup == setup)
        .map(|(_, o)| o.clone())
        .collect();
    let k = folds.clamp(2, sub.len());
    let (ia, ib) = law_slots(setup);
    let free = |i: usize| i == ia || i == ib;
    let slot = setup_index(setup);
    let mut candidates = Vec::new();
    for form in LawForm::ALL {
        let mut spec = best.spec.clone();
        spec.laws[slot] = form;
        let mut shared = best.result.shared.clone();
        if form != best.spec.laws[slot] {
            [shared[ia], shared[ib]] = law_start(form);
            if form == LawForm::Linear {
                // start from the best law's line through its speeds
                shared[ia] = 0.95;
            }
        }
        let all = fit_group_with(
            &sub,
            &spec,
            &shared,
            Some(own_sub.as_slice()),
            &free,
            max_iter,
        );
        let parameters = law_parameters(form, &all, ia, ib);
        // k-fold over runs
        let (dev, n) = heldout_deviance(&sub, &spec, &all, k, &free, max_iter);
        candidates.push(LawCandidate {
            form,
            parameters,
            heldout_rms_noise: (dev / n.max(1) as f64).sqrt(),
            heldout_deviance: dev,
        });
    }
    // the simplest form within PREFER_SIMPLER of the lowest held-out deviance
    let min = candidates
        .iter()
        .map(|c| c.heldout_deviance)
        .fold(f64::INFINITY, f64::min);
    let chosen = candidates
        .iter()
        .find(|c| c.heldout_deviance <= min + PREFER_SIMPLER)
        .map(|c| c.form)
        .unwrap_or(LawForm::Saturating);
    Some(LawChoice {
        setup,
        n_runs: sub.len(),
        folds: k,
        chosen,
        candidates,
        discovered: None,
    })
}

/// The spec with each setup's chosen law form; a setup whose law `spec` holds keeps it, and a
/// choice that holds a law (`LawChoice::held`) holds it.
pub fn with_chosen(spec: &FitSpec, choices: &[LawChoice]) -> FitSpec {
    let mut out = spec.clone();
    for c in choices {
        if spec.held_law(c.setup).is_some() {
            continue;
        }
        match (c.chosen, c.discovered) {
            (LawForm::FromDiscovery, Some(law)) => out.hold_law(c.setup, law),
            // a held form without its law (not written by this crate): the default form
            (LawForm::FromDiscovery, None) => {}
            (form, _) => out.laws[setup_index(c.setup)] = form,
        }
    }
    out
}

/// The choice of a setup whose law `spec` holds (the law discovery accepted): nothing chosen,
/// nothing fitted; None when no run has this setup or no law is held.
pub fn held_choice(runs: &[PairRun], spec: &FitSpec, setup: Setup) -> Option<LawChoice> {
    let held = spec.held_law(setup)?;
    let n_runs = runs.iter().filter(|r| r.setup == setup).count();
    (n_runs > 0).then_some(LawChoice {
        setup,
        n_runs,
        folds: 0,
        chosen: LawForm::FromDiscovery,
        candidates: Vec::new(),
        discovered: Some(held),
    })
}
