//! `summarize`: the collision results of a dataset — μ_pp (slope of Δv_a against Δv_z of the
//! target over slip impacts, and a fit of the whole impulse model), and the coefficient of
//! restitution against impact speed per material and setup, with seeded bootstrap intervals
//! over whole runs. Also the points behind Figs. 4.4a–c.

use super::curves::{exp_fit, one_minus_av};
use super::mu_pp::{impulse_fit, slip_slope};
use crate::artifacts::collision_fit::{CollisionFit, Contact, ImpactFit};
use crate::artifacts::collision_summary::{
    CollisionSummary, MuPp, RestitutionCurve, RestitutionPoint, SpinPoint,
};
use crate::recording::{RunInfo, Setup};
use crate::stats::{quantile_nearest, weighted_line as line_fit};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

/// A point estimate with a 95 % percentile bootstrap interval, written as `{value, lo, hi}`.
pub use crate::artifacts::estimate::Estimate;
use crate::artifacts::estimate::Interval;

/// Default bootstrap seed when the caller has none (the aggregate stage passes its own).
pub const DEFAULT_SEED: u64 = 20261122;
const RESAMPLES: usize = 400;
/// Impacts whose C has a larger standard error are left out of the curves.
const MAX_C_SE: f64 = 0.1;

/// Summarize with the default seed and k = 5/2.
pub fn summarize(fits: &[(RunInfo, CollisionFit)]) -> CollisionSummary {
    summarize_seeded(fits, 2.5, DEFAULT_SEED)
}

fn usable(f: &CollisionFit) -> bool {
    f.usable()
}

fn setup_of(info: &RunInfo, f: &CollisionFit) -> Option<Setup> {
    f.setup.or(info.setup)
}

/// The usable fits of a data set.
type Runs<'a> = [&'a (RunInfo, CollisionFit)];

/// Summarize collision fits; `k` = m R²/I; bootstrap seeded with `seed`.
pub fn summarize_seeded(fits: &[(RunInfo, CollisionFit)], k: f64, seed: u64) -> CollisionSummary {
    let runs: Vec<&(RunInfo, CollisionFit)> = fits.iter().filter(|(_, f)| usable(f)).collect();
    let (spin_points, restitution_points) = points(&runs);
    let mu_pp = mu_pp(&runs, k, seed);
    let mut notes = Vec::new();
    if mu_pp.n_slip == 0 {
        notes.push(
            "no slip impact was resolved: μ_pp is only bounded from below by the stick impacts"
                .into(),
        );
    }
    if runs.len() < fits.len() {
        notes.push(format!(
            "{} collision run(s) left out: fit failed or no impact",
            fits.len() - runs.len()
        ));
    }
    let restitution = restitution_curves(&runs, seed);
    CollisionSummary {
        n_runs: fits.len(),
        n_runs_fitted: runs.len(),
        n_impacts: spin_points.len(),
        k,
        mu_pp,
        restitution,
        spin_points,
        restitution_points,
        bootstrap_seed: seed,
        bootstrap_resamples: RESAMPLES,
        notes,
        whole_run: None,
    }
}

/// The points behind Figs. 4.4a–c: one spin point and one restitution point per impact.
fn points(runs: &Runs) -> (Vec<SpinPoint>, Vec<RestitutionPoint>) {
    let mut spin_points = Vec::new();
    let mut restitution_points = Vec::new();
    for (info, f) in runs {
        for im in &f.impacts {
            spin_points.push(SpinPoint {
                run: f.run.clone(),
                material: info.material.clone(),
                impact: im.index,
                dvz_mps: im.target_dvz_mps.value,
                dvz_se_mps: im.target_dvz_mps.se,
                dva_mps: im.target_dva_mps.value,
                dva_se_mps: im.target_dva_mps.se,
                contact: im.contact,
            });
            restitution_points.push(RestitutionPoint {
                run: f.run.clone(),
                material: info.material.clone(),
                setup: setup_of(info, f),
                impact: im.index,
                impact_speed_mps: im.impact_speed_mps.value,
                restitution: im.restitution.value,
                restitution_se: im.restitution.se,
                striker_before_source: im.striker_before_source,
            });
        }
    }
    (spin_points, restitution_points)
}

/// `RESAMPLES` resamples with replacement of `n` items.
fn draw_resamples(rng: &mut ChaCha8Rng, n: usize) -> Vec<Vec<usize>> {
    (0..RESAMPLES)
        .map(|_| (0..n).map(|_| rng.random_range(0..n.max(1))).collect())
        .collect()
}

/// The 95 % percentile interval (nearest order statistics) of the finite bootstrap values
/// around `value`; NaN bounds when fewer than half the resamples gave a value.
fn percentile_interval(value: f64, boots: impl Iterator<Item = Option<f64>>) -> Estimate {
    let mut boots: Vec<f64> = boots.flatten().filter(|x| x.is_finite()).collect();
    if boots.len() < RESAMPLES / 2 {
        return Estimate::with_interval(value, None);
    }
    boots.sort_by(f64::total_cmp);
    let interval = Interval {
        lo: quantile_nearest(&boots, 0.025),
        hi: quantile_nearest(&boots, 0.975),
    };
    Estimate::with_interval(value, Some(interval))
}

/// μ_pp from the slip impacts (the slope of Δv_a against Δv_z, and the whole impulse model),
/// bootstrapped over whole runs, and the lower bound the stick impacts set.
fn mu_pp(runs: &Runs, k: f64, seed: u64) -> MuPp {
    let impacts_of = |sel: &[usize]| -> Vec<&ImpactFit> {
        sel.iter().flat_map(|&i| runs[i].1.impacts.iter()).collect()
    };
    let all: Vec<usize> = (0..runs.len()).collect();
    let count = |c: Contact| impacts_of(&all).iter().filter(|im| im.contact == c).count();
    let (n_slip, n_stick, n_undetermined) = (
        count(Contact::Slip),
        count(Contact::Stick),
        count(Contact::Undetermined),
    );
    let resamples = draw_resamples(&mut ChaCha8Rng::seed_from_u64(seed), runs.len());
    let interval = |est: &dyn Fn(&[usize]) -> Option<f64>| -> Option<Estimate> {
        let value = est(&all)?;
        Some(percentile_interval(value, resamples.iter().map(|s| est(s))))
    };
    let slope = |sel: &[usize]| slip_slope(&impacts_of(sel), k);
    let impulse = |sel: &[usize]| impulse_fit(&impacts_of(sel), k);
    let from_slip_slope = if n_slip > 0 { interval(&slope) } else { None };
    let from_impulse_fit = if n_slip > 0 { interval(&impulse) } else { None };
    let stick_lower_bound = impacts_of(&all)
        .iter()
        .filter(|im| im.contact == Contact::Stick && im.target_dvz_mps.value > 0.0)
        .map(|im| im.spin_sum_before_mps.abs() / (2.0 * k * im.target_dvz_mps.value))
        .reduce(f64::max);
    MuPp {
        value: from_impulse_fit.or(from_slip_slope),
        from_slip_slope,
        from_impulse_fit,
        stick_lower_bound,
        n_slip,
        n_stick,
        n_undetermined,
    }
}

/// Restitution curves per (material, setup), in that order.
fn restitution_curves(runs: &Runs, seed: u64) -> Vec<RestitutionCurve> {
    let mut groups: BTreeMap<(String, String), Vec<usize>> = BTreeMap::new();
    for (i, (info, f)) in runs.iter().enumerate() {
        let setup = setup_of(info, f)
            .map(|s| format!("{s:?}"))
            .unwrap_or_default();
        groups
            .entry((info.material.clone(), setup))
            .or_default()
            .push(i);
    }
    groups
        .values()
        .filter_map(|idx| restitution_curve(runs, idx, seed))
        .collect()
}

/// The restitution curve of the runs `idx` (their first impacts with a usable C), bootstrapped
/// over those runs; None with fewer than two points.
fn restitution_curve(runs: &Runs, idx: &[usize], seed: u64) -> Option<RestitutionCurve> {
    let pts = |sel: &[usize]| -> Vec<(f64, f64, f64)> {
        sel.iter()
            .flat_map(|&i| runs[idx[i]].1.impacts.first())
            .filter_map(|im| {
                let se = im.restitution.se?;
                (se <= MAX_C_SE
                    && im.restitution.value.is_finite()
                    && im.impact_speed_mps.value > 0.0)
                    .then_some((
                        im.impact_speed_mps.value,
                        im.restitution.value,
                        se.max(0.01),
                    ))
            })
            .collect()
    };
    let local: Vec<usize> = (0..idx.len()).collect();
    let all_pts = pts(&local);
    if all_pts.len() < 2 {
        return None;
    }
    let mut local_rng = ChaCha8Rng::seed_from_u64(seed ^ (idx[0] as u64).wrapping_mul(0x9E37_79B9));
    let local_samples = draw_resamples(&mut local_rng, idx.len());
    let iv = |f: &dyn Fn(&[(f64, f64, f64)]) -> Option<f64>| -> Estimate {
        let value = f(&all_pts).unwrap_or(f64::NAN);
        percentile_interval(value, local_samples.iter().map(|s| f(&pts(s))))
    };
    let (info, f) = runs[idx[0]];
    let speeds = all_pts.iter().map(|p| p.0);
    Some(RestitutionCurve {
        material: info.material.clone(),
        setup: setup_of(info, f),
        n_impacts: all_pts.len(),
        n_runs: idx.len(),
        c0: iv(&|p| line_fit(p).map(|l| l.0)),
        slope_per_mps: iv(&|p| line_fit(p).map(|l| -l.1)),
        a_per_mps: iv(&one_minus_av),
        c_inf: iv(&|p| exp_fit(p).map(|f| f.0)),
        v_ref_mps: iv(&|p| exp_fit(p).map(|f| f.1)),
        mean_c: all_pts.iter().map(|p| p.1).sum::<f64>() / all_pts.len() as f64,
        min_speed_mps: speeds.clone().fold(f64::INFINITY, f64::min),
        max_speed_mps: speeds.fold(0.0, f64::max),
    })
}
