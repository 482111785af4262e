//! The whole-run collision analysis of a dataset, per material: the joint fit of every
//! collision run (`wholerun`), the restitution law of each setup chosen by held-out error
//! (`restitution_law`; a law the spec takes from discovery is kept, not chosen), and the profile
//! of μ_pp (`profile`). What goes into summary.json.

use super::profile::{default_grid, profile_and_lowest};
use super::restitution_law::{choose_law, held_choice, with_chosen};
use super::warm_start::{carry_laws, Start};
use super::wholerun::{
    fit_group, fit_group_with, simulate_run, DragSpec, FitSpec, GroupFit, PairRun, LN_T0, MU_PG,
    MU_PP, TP, T_KICK, V0,
};
use crate::artifacts::collision_summary::{
    LawChoice, MaterialWholeRun, MuPpProfile, ProfileVerdict, WholeRun, WholeRunSummary,
};
use crate::artifacts::estimate::Estimate;
use crate::fit::residual_stats::SINCE_IMPACT_EDGES_S;
use crate::lsq::Termination;
use crate::physics::{Groove, Phase, Restitution};
use crate::recording::{Experiment, Recording, Setup};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Settings of the whole-run analysis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct WholeRunOptions {
    /// Iteration limit of the joint fits (a fit that reaches it is reported as such).
    pub max_iter: usize,
    /// Iteration limit of each profile and cross-validation fit (they start near a solution).
    pub step_iter: usize,
    /// μ_pp values of the profile.
    pub grid: Vec<f64>,
    /// Folds of the held-out choice of the restitution law.
    pub folds: usize,
}

impl Default for WholeRunOptions {
    fn default() -> Self {
        WholeRunOptions {
            max_iter: 80,
            step_iter: 25,
            grid: default_grid(),
            folds: 3,
        }
    }
}

fn est(res: &GroupFit, i: usize) -> Estimate {
    Estimate::new(res.result.shared[i], res.result.shared_se(i))
}

/// Analyze every collision run of `recs` (per material).
pub fn analyze(recs: &[Recording], groove: Groove, opts: &WholeRunOptions) -> WholeRunSummary {
    let mut by_material: BTreeMap<String, Vec<PairRun>> = BTreeMap::new();
    let mut notes = Vec::new();
    for rec in recs
        .iter()
        .filter(|r| r.info.experiment == Experiment::Collision)
    {
        match PairRun::from_recording(rec, rec.info.setup) {
            Ok(run) => by_material
                .entry(rec.info.material.clone())
                .or_default()
                .push(run),
            Err(e) => notes.push(format!(
                "{} left out of the whole-run fit: {e}",
                rec.info.run
            )),
        }
    }
    let materials = by_material
        .into_iter()
        .map(|(material, runs)| analyze_material(&material, &runs, groove, opts))
        .collect();
    WholeRunSummary { materials, notes }
}

/// Deviance by which a profile fit must end below the joint fit for the joint fit to be started
/// again from it (below that, the two are the same minimum reached to the fits' tolerance).
const RESTART_GAIN: f64 = 1.0;

/// The whole-run analysis of the runs of one material.
pub fn analyze_material(
    material: &str,
    runs: &[PairRun],
    groove: Groove,
    opts: &WholeRunOptions,
) -> MaterialWholeRun {
    analyze_material_with(material, runs, &FitSpec::new(groove), opts)
}

/// The whole-run analysis of the runs of one material under `spec`'s physics (the `refit` stage
/// carries discovery's accepted terms in `spec.drag`).
pub fn analyze_material_with(
    material: &str,
    runs: &[PairRun],
    spec: &FitSpec,
    opts: &WholeRunOptions,
) -> MaterialWholeRun {
    analyze_material_from(material, runs, spec, opts, None)
}

/// `analyze_material_with`, the joint fit started from `start` (an earlier analysis of the same
/// runs, whose law forms its spec carries) instead of the defaults when given.
pub fn analyze_material_from(
    material: &str,
    runs: &[PairRun],
    spec: &FitSpec,
    opts: &WholeRunOptions,
    start: Option<&Start>,
) -> MaterialWholeRun {
    let (spec, first) = match start {
        Some(s) => (
            s.spec.clone(),
            fit_group_with(
                runs,
                &s.spec,
                &s.shared,
                Some(&s.own),
                &|_| true,
                opts.max_iter,
            ),
        ),
        None => (spec.clone(), fit_group(runs, spec, None, opts.max_iter)),
    };
    let mut notes = carried_notes(&spec);
    // a law the spec holds (discovery's) is not chosen
    let choices: Vec<LawChoice> = [Setup::Rolling, Setup::Contact]
        .into_iter()
        .filter_map(|s| match spec.held_law(s) {
            Some(_) => held_choice(runs, &spec, s),
            None => choose_law(runs, &first, s, opts.folds, opts.step_iter),
        })
        .collect();
    let chosen = with_chosen(&spec, &choices);
    let best = if chosen == spec {
        first
    } else {
        let mut start = first.clone();
        // carry the chosen forms' all-runs values into the start
        carry_laws(&mut start.result.shared, &choices);
        let refit = fit_group(runs, &chosen, Some(&start), opts.max_iter);
        if refit.cost() <= first.cost() + 50.0 || !first.converged() {
            refit
        } else {
            notes.push("the refit with the chosen laws did not reach the first fit's deviance; the first fit is kept".into());
            first
        }
    };
    let mut best = best;
    let (mut profile, mut lowest) = profile_and_lowest(runs, &best, &opts.grid, opts.step_iter);
    // a fit with μ_pp held ended below the joint fit, which frees it: the joint fit stopped at a
    // local optimum (under a 2 mm waviness the whole-run model leaves out, 440c's ended at μ_pp
    // 0.61 with the profile's fit at 1.58 lower by 300,234, and its table printed 0.61 as the
    // best fit)
    if let Some(low) = lowest
        .as_ref()
        .filter(|l| l.cost() < best.cost() - RESTART_GAIN)
    {
        let again = fit_group(runs, &best.spec, Some(low), opts.max_iter);
        if again.cost() < best.cost() {
            notes.push(format!(
                "the joint fit first ended at a local optimum (μ_pp = {:.3}, deviance {:.1} above the fit with μ_pp held at {:.3}); started again from that fit it reached μ_pp = {:.3}, which the table and the profile use",
                best.result.shared[MU_PP],
                best.cost() - low.cost(),
                low.result.shared[MU_PP],
                again.result.shared[MU_PP]
            ));
            best = again;
            (profile, lowest) = profile_and_lowest(runs, &best, &opts.grid, opts.step_iter);
        }
    }
    // once only: a fit still lower (the restart did not gain, or the new profile found another)
    // is said, and the profile's estimate is that fit's μ_pp, not the table's
    if let Some(low) = lowest.filter(|l| l.cost() < best.cost() - RESTART_GAIN) {
        notes.push(format!(
            "the fit with μ_pp held at {:.3} ends {:.1} below the joint fit's deviance (μ_pp = {:.3}): the joint fit is a local optimum, and the profile's estimate is the lower fit's μ_pp",
            low.result.shared[MU_PP],
            best.cost() - low.cost(),
            best.result.shared[MU_PP]
        ));
    }
    if best.result.termination == Termination::MaxIterations {
        notes.push(format!(
            "the joint fit stopped at its iteration limit ({}); raise whole_run.max_iter",
            opts.max_iter
        ));
    }
    if let Some(note) = unconverged_profile_note(&profile, opts.step_iter) {
        notes.push(note);
    }
    // discovery's laws at the values the fit gave them (a map's refitted nodes)
    let mut choices = choices;
    for c in choices.iter_mut().filter(|c| c.discovered.is_some()) {
        c.discovered = Some(best.spec.law_at(&best.result.shared, c.setup));
    }
    let n_points: usize = runs.iter().map(PairRun::n_samples).sum();
    let whole_runs = runs
        .iter()
        .zip(best.result.own.iter().zip(&best.result.own_se))
        .map(|(r, (own, se))| describe_run(r, &best, own, se))
        .collect();
    MaterialWholeRun {
        material: material.to_string(),
        n_runs: runs.len(),
        status: best.result.termination,
        iterations: best.result.iterations,
        max_iter: opts.max_iter,
        drag: match best.spec.drag {
            DragSpec::Saturating | DragSpec::SaturatingWith(_) => "saturating".into(),
            DragSpec::Linear => "linear".into(),
            DragSpec::Held(_) => "held".into(),
        },
        mu_pg: est(&best, MU_PG),
        t0_s: Estimate::new(
            best.result.shared[LN_T0].exp(),
            best.result.shared[LN_T0].exp() * best.result.shared_se(LN_T0),
        ),
        tp_s_per_mps: est(&best, TP),
        mu_pp: est(&best, MU_PP),
        mu_pp_slip: best.spec.slip,
        profile,
        restitution: choices,
        deviance: best.cost(),
        rms_noise: (best.cost() / n_points.max(1) as f64).sqrt(),
        runs: whole_runs,
        notes,
    }
}

/// What the spec carries from discovery's impact laws, in words (none for the chapter's model):
/// a map's node values are refitted, a named form is held, and μ_pp with a slip-speed dependence
/// is its value at the reference slip speed.
fn carried_notes(spec: &FitSpec) -> Vec<String> {
    let mut out = Vec::new();
    for (setup, name) in [(Setup::Rolling, "rolling"), (Setup::Contact, "contact")] {
        match spec.held_law(setup) {
            Some(Restitution::Map(m)) => out.push(format!(
                "the {name} setup's restitution law is the map discovery accepted, its values at the {} nodes refitted here from discovery's (the nodes' speeds held; C held at the end values beyond them)",
                m.len()
            )),
            Some(_) => out.push(format!(
                "the {name} setup's restitution law is the named form discovery accepted, held as it gave it from the impacts' own C (not refitted, so its uncertainty is not in the other parameters' errors)"
            )),
            None => {}
        }
    }
    if let Some(s) = spec.slip {
        out.push(format!(
            "μ_pp depends on the slip speed u at the contact as discovery accepted (its shape held, normalised at u_ref = {:.1} mm/s): μ_pp and its profile are μ_pp at u_ref",
            1e3 * s.u_ref_mps
        ));
    }
    out
}

/// Words for profile fits that stopped at their iteration limit (None when every one
/// converged): where they are, and whether they lie beyond the 95 % level (then they only draw
/// the curve) or could move the interval.
pub fn unconverged_profile_note(profile: &MuPpProfile, step_iter: usize) -> Option<String> {
    let bad: Vec<_> = profile.points.iter().filter(|p| !p.converged).collect();
    if bad.is_empty() {
        return None;
    }
    let at: Vec<String> = bad
        .iter()
        .map(|p| format!("μ_pp = {:.3} (deviance {:.3e})", p.mu_pp, p.deviance))
        .collect();
    // harmless when a converged fit above the 95 % level lies between the estimate and it: the
    // verdict takes the first crossing on each side
    let centre = match profile.verdict {
        ProfileVerdict::Interval { estimate, .. } => Some(estimate),
        _ => None,
    };
    let far = centre.is_some_and(|c| {
        bad.iter().all(|b| {
            profile.points.iter().any(|q| {
                q.converged
                    && q.deviance > profile.threshold
                    && (q.mu_pp - c) * (b.mu_pp - q.mu_pp) > 0.0
            })
        })
    });
    Some(format!(
        "{} of {} profile fits stopped at their iteration limit ({step_iter}): {}; {}",
        bad.len(),
        profile.points.len(),
        at.join(", "),
        if far {
            "each lies beyond a converged fit above the 95 % level, so it only draws the curve (its deviance is an upper bound) and does not move the interval"
        } else {
            "not all lie beyond a converged fit above the 95 % level: the verdict may move with more iterations (raise whole_run.step_iter)"
        }
    ))
}

/// The label of the bin of time since the last impact (the compare stage's bins).
fn time_bin(dt: Option<f64>) -> &'static str {
    const LABELS: [&str; 4] = ["0-1ms", "1-5ms", "5-20ms", ">20ms"];
    match dt {
        None => "before",
        Some(d) => {
            LABELS[SINCE_IMPACT_EDGES_S
                .iter()
                .position(|&e| d < e)
                .unwrap_or(SINCE_IMPACT_EDGES_S.len())]
        }
    }
}

/// One run at the fit: impacts, residuals by phase and by time since the last impact.
fn describe_run(run: &PairRun, fit: &GroupFit, own: &[f64], se: &[f64]) -> WholeRun {
    let (rel, traj) = simulate_run(run, &fit.spec, &fit.result.shared, own);
    let mut by_phase: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    let mut by_time: BTreeMap<String, (f64, usize)> = BTreeMap::new();
    let (mut ss, mut n) = (0.0, 0usize);
    for p in 0..2 {
        for &(i, zd) in &run.samples[p] {
            let zm = traj.particles[p].z_m[i];
            let r = zm - zd;
            let u = (r / run.sigma_m).powi(2);
            ss += r * r;
            n += 1;
            let phase = match traj.particles[p].phase[i] {
                Phase::Sliding => "sliding",
                Phase::Rolling => "rolling",
                Phase::Rest => "rest",
            };
            let e = by_phase.entry(phase.to_string()).or_default();
            e.0 += u;
            e.1 += 1;
            let last = traj
                .impacts
                .iter()
                .rev()
                .find(|im| im.t_s <= rel[i])
                .map(|im| rel[i] - im.t_s);
            let e = by_time.entry(time_bin(last).to_string()).or_default();
            e.0 += u;
            e.1 += 1;
        }
    }
    let rms = |m: BTreeMap<String, (f64, usize)>| -> BTreeMap<String, f64> {
        m.into_iter()
            .map(|(k, (s, n))| (k, (s / n.max(1) as f64).sqrt()))
            .collect()
    };
    let real: Vec<_> = traj.impacts.iter().filter(|im| !im.joined).collect();
    WholeRun {
        run: run.run.clone(),
        setup: run.setup,
        v0_mps: Estimate::new(own[V0], se[V0]),
        t_kick_s: own[T_KICK],
        rms_m: (ss / n.max(1) as f64).sqrt(),
        noise_m: run.sigma_m,
        n_points: n,
        n_impacts: traj.impacts.len(),
        n_slip: real.iter().filter(|im| im.slip).count(),
        first_impact_speed_mps: traj.impacts.first().map(|im| im.v_impact_mps),
        first_impact_restitution: traj.impacts.first().map(|im| im.restitution),
        residual_by_phase: rms(by_phase),
        residual_by_time_since_impact: rms(by_time),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::collision_summary::ProfilePoint;
    use crate::fit::collision::profile::DELTA_95;

    fn profile(points: &[(f64, f64, bool)]) -> MuPpProfile {
        MuPpProfile {
            points: points
                .iter()
                .map(|&(mu_pp, deviance, converged)| ProfilePoint {
                    mu_pp,
                    deviance,
                    converged,
                })
                .collect(),
            not_fitted: Vec::new(),
            verdict: ProfileVerdict::Interval {
                estimate: 1.4,
                lo: 1.39,
                hi: 1.41,
            },
            threshold: DELTA_95,
            dispersion: 1.0,
            lag1_autocorrelation: 0.0,
            score_lag1_autocorrelation: 0.0,
            serial_factor: 1.0,
            scale_factor: 1.0,
            inflation: 1.0,
        }
    }

    #[test]
    fn a_profile_fit_at_its_iteration_limit_is_said_with_whether_it_matters() {
        let all = profile(&[(0.5, 1e5, true), (1.4, 0.0, true), (2.0, 1e4, true)]);
        assert_eq!(unconverged_profile_note(&all, 25), None);
        // beyond a converged crossing: only draws the curve
        let far = profile(&[(0.34, 3e6, false), (0.5, 1e5, true), (1.4, 0.0, true)]);
        let words = unconverged_profile_note(&far, 25).unwrap();
        assert!(
            words.starts_with(
                "1 of 3 profile fits stopped at their iteration limit (25): μ_pp = 0.340"
            ) && words.contains("does not move the interval"),
            "{words}"
        );
        // nearer than any converged crossing: it may
        let near = profile(&[(0.5, 1e5, true), (1.38, 5.0, false), (1.4, 0.0, true)]);
        let words = unconverged_profile_note(&near, 25).unwrap();
        assert!(words.contains("may move"), "{words}");
    }
}
