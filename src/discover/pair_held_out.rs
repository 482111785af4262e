//! Held-out runs for the pair tests: a model with more freed (a force between the particles,
//! friction and drag of their own) and the model without, each fitted on one half of the runs
//! from its fit on all and judged on the other half with only the runs' own parameters refitted.

use crate::fit::collision::wholerun::{fit_group_with, fit_own_only, GroupFit, PairRun};

/// The χ² gains (over the inflation `inflate`) of model `with` (its shared slots `free_with`
/// fitted) over model `without` (slots `free_without`) on each half of `runs` held out (every
/// other run), after a fit on the other half. Both sides learn μ_pp and the restitution laws
/// from the same few runs; judged against the fit of all runs instead, the test runs' own
/// impacts favoured the smaller model (a half of three touching pairs lost 7 to 48 χ² under a
/// force found at p 1e-55 and more). None when the runs are too few to split (fewer than 4).
pub fn gains(
    runs: &[PairRun],
    (with, free_with): (&GroupFit, &dyn Fn(usize) -> bool),
    (without, free_without): (&GroupFit, &dyn Fn(usize) -> bool),
    inflate: f64,
    max_iter: usize,
) -> Option<[f64; 2]> {
    if runs.len() < 4 {
        return None;
    }
    let half = |k: usize| -> Vec<usize> { (0..runs.len()).filter(|i| i % 2 == k).collect() };
    let pick = |idx: &[usize]| -> Vec<PairRun> { idx.iter().map(|&i| runs[i].clone()).collect() };
    let own = |f: &GroupFit, idx: &[usize]| -> Vec<Vec<f64>> {
        idx.iter().map(|&i| f.result.own[i].clone()).collect()
    };
    let train = |f: &GroupFit, free: &dyn Fn(usize) -> bool, idx: &[usize]| {
        fit_group_with(
            &pick(idx),
            &f.spec,
            &f.result.shared,
            Some(own(f, idx).as_slice()),
            free,
            max_iter,
        )
    };
    let mut out = [0.0; 2];
    for (k, gain) in out.iter_mut().enumerate() {
        let (fit_half, test_half) = (half(k), half(1 - k));
        let with_train = train(with, free_with, &fit_half);
        let without_train = train(without, free_without, &fit_half);
        let test_runs = pick(&test_half);
        let w = fit_own_only(&test_runs, &with.spec, &with_train.result.shared, max_iter);
        let wo = fit_own_only(
            &test_runs,
            &without.spec,
            &without_train.result.shared,
            max_iter,
        );
        *gain = (wo.cost() - w.cost()) / inflate;
    }
    Some(out)
}
