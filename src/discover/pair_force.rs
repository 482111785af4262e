//! The test for a force between the two particles of a pair (adhesion, a liquid bridge,
//! magnetization, charge), which acts before they touch and so bends both tracks in the last
//! and first few hundred micrometres of separation around each impact.
//!
//! With the single runs' physics held (the pair check's held fit: μ_pp, the restitution laws and
//! every run's kick free), a force `a(s)` of the separation s = centre distance − 2R is added in
//! each named shape of `physics::PairForce` (exponential, power law) and fitted: the exponential
//! from a scan's best starts (`scan_starts`), and when it finds a force, again from about it and
//! from the scan's best of its sign (`found_starts`); the power law from the exponential. The
//! decision:
//! - the deviance gain over the held fit, divided by the inflation of the pairs' residuals
//!   (their correlation over the milliseconds a force acts, `pair_noise`, or the pair check's
//!   lag-1 inflation and any misfit the fit leaves, the larger), is a χ² with the shape's free
//!   parameters (2 or 3), Holm over materials at `ALPHA`;
//! - confirmed on held-out runs: fitted on every other run, the force must lower the χ² of the
//!   runs it did not see, each of the two halves (their kicks refitted, the physics held), by
//!   more than its parameters gain by chance 1 % of the time;
//! - physically possible: an amplitude or a range at its bound is a fit that went nowhere;
//! - the power law is chosen only when it beats the exponential by more than its one extra
//!   parameter is worth (χ²₁ at 0.99 after inflation); otherwise the two are a tie and the
//!   exponential, the simpler, is the model.
//!
//! The size reported: the amplitude at contact A, the range λ, and the work per unit mass over
//! the whole range W = ∫a ds, which the data fix best when the range is short.

use super::pair_held_out as held_out;
use super::pair_noise::long_run_factor;
use super::pair_range::{share_range, Member, SharedRange};
use super::pairs_impact::{ALPHA, IMPACT_WINDOW_S};
use crate::artifacts::diagnosis::{Effect, Estimate as Value, Evidence, Finding, ModelScore};
use crate::fit::collision::wholerun::{
    fit_group_with, residuals, FitSpec, GroupFit, PairForceShape, PairRun, PAIR_FORCE_START,
    PF_AMP, PF_EXPONENT, PF_LN_RANGE,
};
use crate::lsq::block::huber_rho;
use crate::lsq::Termination;
use crate::stats::dist::chi2_sf;
use std::collections::BTreeMap;

/// The scan that starts the fit: ranges (m) and amplitudes (m/s², both signs) of the
/// exponential on a grid, each scored by the held fit's loss with the force added (nothing
/// refitted); the fit starts from the best point, and the power law from the exponential's
/// optimum. From no force at all (A = 0, one start) the fit of a screened attraction found it as
/// well on rolling pairs; the scan costs about a tenth of one fit. (Refitting the runs' kicks at
/// each point of the scan, tried on touching pairs that an attraction holds together, cost 5× the
/// whole test and found nothing the plain scan missed.)
const SCAN_RANGES_M: [f64; 4] = [10e-6, 30e-6, 100e-6, 300e-6];
const SCAN_AMPS_MPS2: [f64; 4] = [0.3, 1.0, 3.0, 10.0];

/// The held fit's spec and shared values with a force of `shape` at `start` (A, ln λ, n) added.
fn with_force(held: &GroupFit, shape: PairForceShape, start: [f64; 3]) -> (FitSpec, Vec<f64>) {
    let spec = FitSpec {
        pair_force: Some((shape, start)),
        ..held.spec.clone()
    };
    let mut shared = held.result.shared.clone();
    shared[PF_AMP] = start[0];
    shared[PF_LN_RANGE] = start[1];
    shared[PF_EXPONENT] = start[2];
    (spec, shared)
}

/// A shared slot of the force.
fn force_slot(i: usize) -> bool {
    i == PF_AMP || i == PF_LN_RANGE || i == PF_EXPONENT
}

/// The held fit's loss (the whole-run fits' Huber deviance at 3) with an exponential force at
/// `start` added, nothing refitted.
fn scan_cost(runs: &[PairRun], held: &GroupFit, start: [f64; 3]) -> f64 {
    let (spec, shared) = with_force(held, PairForceShape::Exponential, start);
    let mut cost = 0.0;
    for (run, own) in runs.iter().zip(&held.result.own) {
        let mut r = vec![0.0; run.n_samples()];
        residuals(run, &spec, &shared, own, &mut r);
        cost += r.iter().map(|&x| huber_rho(x, 3.0)).sum::<f64>();
    }
    cost
}

/// The scan's best point of each range among amplitudes `amps`, the ranges in the order of their
/// best points.
fn scan_ranges(runs: &[PairRun], held: &GroupFit, amps: &[f64]) -> Vec<(f64, [f64; 3])> {
    let mut best: Vec<(f64, [f64; 3])> = SCAN_RANGES_M
        .iter()
        .filter_map(|&l| {
            amps.iter()
                .map(|&a| [a, l.ln(), PAIR_FORCE_START[2]])
                .map(|s| (scan_cost(runs, held, s), s))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        })
        .collect();
    best.sort_by(|a, b| a.0.total_cmp(&b.0));
    best
}

/// The scan's starts: the best point of each range, the ranges in the order of their best
/// points, at most `STARTS`.
fn scan_starts(runs: &[PairRun], held: &GroupFit) -> Vec<[f64; 3]> {
    let amps: Vec<f64> = SCAN_AMPS_MPS2.iter().flat_map(|&a| [a, -a]).collect();
    let mut best = scan_ranges(runs, held, &amps);
    // where no point of the scan does better than no force at all, the fit starts there (the held
    // fit's optimum): from the best point it walked back to nothing in 20–30 iterations
    let none = [0.0, PAIR_FORCE_START[1], PAIR_FORCE_START[2]];
    let none_cost = scan_cost(runs, held, none);
    if best.first().is_some_and(|b| b.0 >= none_cost) {
        best.insert(0, (none_cost, none));
    }
    let starts: Vec<[f64; 3]> = best.into_iter().take(STARTS).map(|(_, s)| s).collect();
    if starts.is_empty() {
        vec![PAIR_FORCE_START]
    } else {
        starts
    }
}

/// The starts of a force found at (A, λ): 3A at λ/1.5 and A/3 at 1.5λ, and the scan's best
/// `STARTS` ranges among amplitudes of A's sign. From no force, a screened attraction of 3 m/s²
/// over 50 µm between rolling pairs was fitted at 1.1 m/s² over 77 µm (its work 44 % short), and
/// from 3A at λ/1.5 at the truth; a bench attraction of 0.63 m/s² over 143 µm in drifting noise
/// was fitted from no force at 0.0005 m/s², whose multiples are no start either.
fn found_starts(runs: &[PairRun], held: &GroupFit, fit: &GroupFit) -> Vec<[f64; 3]> {
    let (a, ln_l) = (fit.result.shared[PF_AMP], fit.result.shared[PF_LN_RANGE]);
    let n = PAIR_FORCE_START[2];
    let signed: Vec<f64> = SCAN_AMPS_MPS2.iter().map(|&x| x.copysign(a)).collect();
    let mut starts = vec![
        [3.0 * a, ln_l - 1.5f64.ln(), n],
        [a / 3.0, ln_l + 1.5f64.ln(), n],
    ];
    starts.extend(
        scan_ranges(runs, held, &signed)
            .into_iter()
            .take(STARTS)
            .map(|(_, s)| s),
    );
    starts
}

/// The scan's best ranges the exponential's fit may start from: the loss along the range is rough
/// (an attraction that recaptures the particles after an impact, or not, switches the whole run),
/// and from the best point alone the fit ended at a bound of the range on one material in seven
/// of the bench's seventeen pair datasets; the next start is tried only then.
const STARTS: usize = 2;

/// Iterations of each fit of this test: it starts from the held fit and the scan, near its
/// optimum, and on pairs under a carried waviness (slow to simulate) each of its fits at the
/// pair check's 80 made the check several times slower.
const FORCE_ITER: usize = 30;

/// χ²₁'s 0.99 quantile: what the power law's one parameter beyond the exponential must gain.
const ONE_PARAM_CHI2: f64 = 6.635;

/// What each half of the runs must gain held out: the χ² that the shape's free parameters (2 or
/// 3) gain by chance 1 % of the time. A positive gain alone let nulls through: on 160 material
/// tests of nulls in white, correlated, drifting and mixed noise, three forces were confirmed
/// with halves gaining 5.5–32, where the forces simulated gained 67 and more on each half.
fn held_out_floor(shape: PairForceShape) -> f64 {
    match shape {
        PairForceShape::Exponential => 9.210,
        PairForceShape::PowerLaw => 11.345,
    }
}

/// A parameter within this fraction of its interval's width from a bound is at the bound.
const AT_BOUND: f64 = 1e-3;

/// The shape's name in diagnosis.json.
fn shape_name(shape: PairForceShape) -> &'static str {
    match shape {
        PairForceShape::Exponential => "exponential",
        PairForceShape::PowerLaw => "power law",
    }
}

/// The force an accepted finding of this test names, to carry in a pair fit: its shape and
/// (A, ln λ, n) read back from its parameters. None for any other finding.
pub fn carried_from(f: &Finding) -> Option<(PairForceShape, [f64; 3])> {
    if f.effect != Effect::ForceBetweenParticles.id() || !f.accepted {
        return None;
    }
    let get = |k: &str| f.parameters.get(k).map(|e| e.value);
    let (a, range) = (get("pair_amplitude_mps2")?, get("pair_range_m")?);
    let (shape, n) = match get("pair_exponent") {
        Some(n) => (PairForceShape::PowerLaw, n),
        None => (PairForceShape::Exponential, PAIR_FORCE_START[2]),
    };
    Some((shape, [a, range.ln(), n]))
}

/// One shape's fit over all runs.
#[derive(Clone, Debug)]
pub struct ShapeFit {
    pub shape: PairForceShape,
    pub fit: GroupFit,
}

impl ShapeFit {
    /// The spec that carries this force at its fitted values (as start values of its slots).
    pub fn carried(&self) -> (PairForceShape, [f64; 3]) {
        let sh = &self.fit.result.shared;
        (self.shape, [sh[PF_AMP], sh[PF_LN_RANGE], sh[PF_EXPONENT]])
    }
}

/// The test of one material's pairs.
#[derive(Clone, Debug)]
pub struct ForceTest {
    pub material: String,
    /// The chosen shape's fit, and the other shape's.
    pub chosen: ShapeFit,
    pub other: ShapeFit,
    /// The two shapes cannot be told apart (the exponential chosen).
    pub tie: bool,
    /// Deviance gain over the held fit over the inflation, its χ² p-value.
    pub lr: f64,
    pub p: f64,
    /// The held-out χ² gains (over the inflation) of the two halves of the runs; None when the
    /// runs are too few to split (fewer than 4).
    pub held_out: Option<[f64; 2]>,
    /// A parameter of the chosen fit at its bound, named.
    pub at_bound: Option<&'static str>,
    pub held_cost: f64,
    pub inflate: f64,
    /// One range shared with the other materials' forces (`pair_range`), the chosen fit then
    /// being the one at that range.
    pub shared_range: Option<SharedRange>,
}

/// Fits the force of `shape` to `runs` from `start` (A, ln λ, n) with the physics of `held`
/// (the held fit) held.
fn fit_shape(
    runs: &[PairRun],
    held: &GroupFit,
    shape: PairForceShape,
    start: [f64; 3],
    free: &dyn Fn(usize) -> bool,
    max_iter: usize,
) -> GroupFit {
    let (spec, shared) = with_force(held, shape, start);
    fit_group_with(
        runs,
        &spec,
        &shared,
        Some(held.result.own.as_slice()),
        &|i| free(i) || force_slot(i),
        max_iter,
    )
}

/// How a force fit ranks among fits from other starts (lower is better): one that ends at a
/// bound of its range last, then by cost.
fn rank(fit: &GroupFit) -> (bool, f64) {
    (at_bound(fit).is_some(), fit.cost())
}

/// The first parameter of `fit`'s force at its bound, by name.
pub(super) fn at_bound(fit: &GroupFit) -> Option<&'static str> {
    let specs = fit.spec.shared_specs(Some(&fit.result.shared), &[]);
    [
        (PF_AMP, "amplitude"),
        (PF_LN_RANGE, "range"),
        (PF_EXPONENT, "exponent"),
    ]
    .into_iter()
    .find(|&(i, _)| {
        let s = &specs[i];
        let w = s.upper - s.lower;
        w > 0.0
            && (fit.result.shared[i] - s.lower < AT_BOUND * w
                || s.upper - fit.result.shared[i] < AT_BOUND * w)
    })
    .map(|(_, name)| name)
}

/// Test one material's `runs` for a force between the particles, from the pair check's held fit
/// `held`; `free` picks the shared slots the held fit frees; `inflate` is the pairs' residual
/// inflation (the pair check's).
pub fn test_force(
    material: &str,
    runs: &[PairRun],
    held: &GroupFit,
    free: &dyn Fn(usize) -> bool,
    inflate: f64,
    max_iter: usize,
) -> ForceTest {
    let max_iter = max_iter.min(FORCE_ITER);
    let exp_from = |start: [f64; 3]| {
        fit_shape(
            runs,
            held,
            PairForceShape::Exponential,
            start,
            free,
            max_iter,
        )
    };
    // from the scan's best range, and from the next only when that fit ends at a bound
    let mut exp: Option<ShapeFit> = None;
    for start in scan_starts(runs, held) {
        let fit = exp_from(start);
        if exp.as_ref().is_none_or(|e| rank(&fit) < rank(&e.fit)) {
            exp = Some(ShapeFit {
                shape: PairForceShape::Exponential,
                fit,
            });
        }
        if exp.as_ref().is_some_and(|e| at_bound(&e.fit).is_none()) {
            break;
        }
    }
    let mut exp = exp.expect("the scan gives at least one start");
    // a force found: the loss is rough along its size too (a recapture after an impact switches
    // whole runs), so the fit is tried again from about it and from the scan's best of its sign
    if chi2_sf((held.cost() - exp.fit.cost()) / inflate, 2.0) < ALPHA {
        for start in found_starts(runs, held, &exp.fit) {
            let fit = exp_from(start);
            if rank(&fit) < rank(&exp.fit) {
                exp.fit = fit;
            }
        }
    }
    // the power law from the exponential's optimum: the same slope at contact, n/λ = 1/λ_exp
    let n = PAIR_FORCE_START[2];
    let from_exp = [
        exp.fit.result.shared[PF_AMP],
        exp.fit.result.shared[PF_LN_RANGE] + n.ln(),
        n,
    ];
    let pow = ShapeFit {
        shape: PairForceShape::PowerLaw,
        fit: fit_shape(
            runs,
            held,
            PairForceShape::PowerLaw,
            from_exp,
            free,
            max_iter,
        ),
    };
    // a force is fitted to the residuals averaged over the milliseconds around impacts: its gain
    // varies with the noise's long-run variance there, which a slow drift raises far above what
    // the lag-1 correlation says
    let inflate = inflate.max(long_run_factor(runs, &exp.fit, IMPACT_WINDOW_S));
    // the power law holds the exponential only in a limit: it is chosen on a clear gain alone
    let extra = ONE_PARAM_CHI2;
    let pow_gain = (exp.fit.cost() - pow.fit.cost()) / inflate;
    let (chosen, other, tie) = if pow_gain > extra {
        (pow, exp, false)
    } else {
        let tie = pow_gain > -extra;
        (exp, pow, tie)
    };
    let k = match chosen.shape {
        PairForceShape::Exponential => 2.0,
        PairForceShape::PowerLaw => 3.0,
    };
    let lr = ((held.cost() - chosen.fit.cost()) / inflate).max(0.0);
    let p = chi2_sf(lr, k);
    // held-out runs confirm what is significant; below α before Holm nothing can be accepted
    let held_out = if p < ALPHA {
        let with_force = |i: usize| free(i) || force_slot(i);
        held_out::gains(
            runs,
            (&chosen.fit, &with_force),
            (held, free),
            inflate,
            max_iter,
        )
    } else {
        None
    };
    ForceTest {
        material: material.to_string(),
        at_bound: at_bound(&chosen.fit),
        chosen,
        other,
        tie,
        lr,
        p,
        held_out,
        held_cost: held.cost(),
        inflate,
        shared_range: None,
    }
}

/// One range for every material whose pairs accept an exponential force at Holm p-values
/// `p_holm` (`pair_range`; `runs` each test's runs, `free` the shared slots the held fit
/// frees): when it is a tie with the ranges apart and no amplitude ends at its bound, each such
/// test keeps its fit at the shared range.
pub fn share_ranges(
    tests: &mut [ForceTest],
    p_holm: &[f64],
    runs: &[&[PairRun]],
    free: &(dyn Fn(usize) -> bool + Sync),
    max_iter: usize,
) {
    let picked: Vec<usize> = (0..tests.len())
        .filter(|&k| {
            tests[k].chosen.shape == PairForceShape::Exponential && tests[k].decision(p_holm[k]).0
        })
        .collect();
    let members: Vec<Member> = picked
        .iter()
        .map(|&k| Member {
            material: &tests[k].material,
            fit: &tests[k].chosen.fit,
            inflate: tests[k].inflate,
            runs: runs[k],
        })
        .collect();
    let Some(shared) = share_range(&members, free, max_iter.min(FORCE_ITER)) else {
        return;
    };
    if shared.iter().any(|(_, fit)| at_bound(fit).is_some()) {
        return;
    }
    for (&k, (range, fit)) in picked.iter().zip(shared) {
        tests[k].shared_range = Some(range);
        tests[k].chosen.fit = fit;
    }
}

/// The decision's clause for a range shared with the other materials.
fn shared_words(r: &SharedRange) -> String {
    let apart: Vec<String> = r
        .apart_m
        .iter()
        .map(|(m, l)| format!("{:.0} µm ({m})", l * 1e6))
        .collect();
    let range = r.ln_range.exp() * 1e6;
    let cost = if r.chi2 < -1.0 {
        format!(
            "one range of {range:.0} µm fits better (χ² lower by {:.1}: a fit apart had stopped in a worse minimum)",
            -r.chi2
        )
    } else {
        format!(
            "one range of {range:.0} µm costs χ²({}) = {:.1} (p {:.2}), which chance explains",
            r.dof,
            r.chi2.max(0.0),
            r.p
        )
    };
    format!(
        "; one range for every material's pairs: fitted apart the ranges were {}, and {cost}, so the range is shared and this material's amplitude fitted at it",
        apart.join(" and "),
    )
}

impl ForceTest {
    /// The force as fitted.
    pub fn force(&self) -> crate::physics::PairForce {
        self.chosen
            .fit
            .spec
            .force(&self.chosen.fit.result.shared)
            .expect("a shape fit carries a force")
    }

    /// The work's standard error from the fit's covariance (inflated): W = Aλ, or Aλ/(n − 1).
    fn work_se(&self) -> f64 {
        let r = &self.chosen.fit.result;
        let w = self.force().work_m2ps2();
        let (range, n) = (r.shared[PF_LN_RANGE].exp(), r.shared[PF_EXPONENT]);
        let grad: Vec<(usize, f64)> = match self.chosen.shape {
            PairForceShape::Exponential => vec![(PF_AMP, range), (PF_LN_RANGE, w)],
            PairForceShape::PowerLaw => vec![
                (PF_AMP, range / (n - 1.0)),
                (PF_LN_RANGE, w),
                (PF_EXPONENT, -w / (n - 1.0)),
            ],
        };
        let mut var = 0.0;
        for &(i, gi) in &grad {
            for &(j, gj) in &grad {
                var += gi * r.shared_cov[i][j] * gj;
            }
        }
        (var.max(0.0) * self.inflate).sqrt()
    }

    /// Accepted at Holm p-value `p_holm`, and the decision in words, with the force fit's end
    /// when it stopped at its iteration limit rather than converging.
    pub fn decision(&self, p_holm: f64) -> (bool, String) {
        let (accepted, words) = self.verdict(p_holm);
        if self.chosen.fit.result.termination == Termination::MaxIterations {
            return (
                accepted,
                format!("{words} (the force fit stopped at its iteration limit, not converged)"),
            );
        }
        (accepted, words)
    }

    fn verdict(&self, p_holm: f64) -> (bool, String) {
        if p_holm >= ALPHA {
            return (
                false,
                format!("no force between the particles is needed (p Holm {p_holm:.2})"),
            );
        }
        if let Some(name) = self.at_bound {
            return (
                false,
                format!("a force between the particles lowers χ² but its {name} ends at its bound: a fit that went nowhere, not physics"),
            );
        }
        match self.held_out {
            None => (
                false,
                format!("significant in the runs fitted (p Holm {p_holm:.1e}), but too few runs ({}) to confirm it on held-out runs", self.chosen.fit.result.own.len()),
            ),
            Some([a, b]) if a.min(b) <= held_out_floor(self.chosen.shape) => (
                false,
                format!("significant in the runs fitted (p Holm {p_holm:.1e}), but not confirmed on held-out runs (χ² gains {a:.1} and {b:.1} on the two halves; each must exceed {:.1}, what its parameters gain by chance 1 % of the time)", held_out_floor(self.chosen.shape)),
            ),
            Some([a, b]) => {
                let f = self.force();
                let kind = if f.amplitude_mps2() < 0.0 { "an attraction" } else { "a repulsion" };
                let tie = if self.tie {
                    format!("; tied with {}: these data cannot tell them apart, and this one, the simpler, is in the model", shape_name(self.other.shape))
                } else {
                    String::new()
                };
                let shared = self.shared_range.as_ref().map_or(String::new(), shared_words);
                (
                    true,
                    format!("{kind} between the particles before they touch: confirmed on held-out runs (χ² gains {a:.1} and {b:.1} on the two halves){tie}{shared}"),
                )
            }
        }
    }

    /// The finding at Holm p-value `p_holm`.
    pub fn finding(&self, p_holm: f64, n_pts: usize, sigma: f64) -> Finding {
        let (accepted, decision) = self.decision(p_holm);
        let f = self.force();
        let sh = &self.chosen.fit.result.shared;
        let se = |i: usize| self.chosen.fit.result.shared_se(i) * self.inflate.sqrt();
        let range = sh[PF_LN_RANGE].exp();
        // at a shared range, the range's own error moves the amplitude along the profile
        let (amp_se, range_se, work_se) = match &self.shared_range {
            None => (se(PF_AMP), range * se(PF_LN_RANGE), self.work_se()),
            Some(s) => {
                let along = s.amp_slope * s.ln_range_se;
                let work_along = (s.amp_slope + sh[PF_AMP]) * range * s.ln_range_se;
                (
                    se(PF_AMP).hypot(along),
                    range * s.ln_range_se,
                    self.work_se().hypot(work_along),
                )
            }
        };
        let mut parameters = BTreeMap::new();
        parameters.insert("pair_amplitude_mps2".into(), Value::new(sh[PF_AMP], amp_se));
        parameters.insert("pair_range_m".into(), Value::new(range, range_se));
        if self.chosen.shape == PairForceShape::PowerLaw {
            parameters.insert(
                "pair_exponent".into(),
                Value::new(sh[PF_EXPONENT], se(PF_EXPONENT)),
            );
        }
        parameters.insert(
            "pair_work_m2ps2".into(),
            Value::new(f.work_m2ps2(), work_se),
        );
        let form = match self.chosen.shape {
            PairForceShape::Exponential => {
                "force between the particles, exponential in their separation: A e^(−s/λ)"
            }
            PairForceShape::PowerLaw => {
                "force between the particles, a power law in their separation: A (1 + s/λ)^(−n)"
            }
        };
        let mut where_ = BTreeMap::new();
        where_.insert("experiment".into(), serde_json::json!("collision"));
        where_.insert("material".into(), serde_json::json!(self.material));
        where_.insert(
            "variable".into(),
            serde_json::json!("separation (centre distance − 2R)"),
        );
        where_.insert("reach_m".into(), serde_json::json!(f.reach_m()));
        if self.tie {
            where_.insert(
                "tie".into(),
                serde_json::json!("exponential or power law: these data cannot tell them apart; the exponential, the simpler, is the one reported"),
            );
        }
        if let Some([a, b]) = self.held_out {
            where_.insert("held_out_chi2_gain".into(), serde_json::json!([a, b]));
        }
        if let Some(r) = &self.shared_range {
            let apart: BTreeMap<&str, f64> =
                r.apart_m.iter().map(|(m, l)| (m.as_str(), *l)).collect();
            where_.insert(
                "shared_range".into(),
                serde_json::json!({
                    "range_m": r.ln_range.exp(),
                    "ranges_apart_m": apart,
                    "chi2_of_sharing": r.chi2,
                    "degrees_of_freedom": r.dof,
                    "p": r.p,
                }),
            );
        }
        where_.insert(
            "other_shape_chi2".into(),
            serde_json::json!({
                "shape": shape_name(self.other.shape),
                "chi2": self.other.fit.cost(),
                "chi2_chosen": self.chosen.fit.cost(),
            }),
        );
        let score = |f: &GroupFit, n: usize, terms: &str| ModelScore {
            cv_rms_m: f64::NAN,
            rms_m: (f.cost() / n_pts.max(1) as f64).sqrt() * sigma,
            chi2: f.cost(),
            n_global_params: n,
            terms: vec![terms.to_string()],
        };
        let k = if self.chosen.shape == PairForceShape::PowerLaw {
            3
        } else {
            2
        };
        Finding {
            effect: Effect::ForceBetweenParticles.id().into(),
            accepted,
            form: form.into(),
            parameters,
            evidence: Evidence {
                lr: self.lr,
                extra_params: k,
                p_value: self.p,
                p_holm,
                decision,
                ..Evidence::default()
            },
            where_,
            baseline: ModelScore {
                cv_rms_m: f64::NAN,
                rms_m: (self.held_cost / n_pts.max(1) as f64).sqrt() * sigma,
                chi2: self.held_cost,
                n_global_params: 0,
                terms: vec!["single runs' physics held".into()],
            },
            extended: score(&self.chosen.fit, k, form),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn finding(accepted: bool, exponent: Option<f64>) -> Finding {
        let mut parameters = BTreeMap::new();
        parameters.insert("pair_amplitude_mps2".into(), Value::new(-2.5, 0.1));
        parameters.insert("pair_range_m".into(), Value::new(40e-6, 1e-6));
        if let Some(n) = exponent {
            parameters.insert("pair_exponent".into(), Value::new(n, 0.1));
        }
        Finding {
            effect: Effect::ForceBetweenParticles.id().into(),
            accepted,
            form: String::new(),
            parameters,
            evidence: Evidence::default(),
            where_: BTreeMap::new(),
            baseline: ModelScore::default(),
            extended: ModelScore::default(),
        }
    }

    #[test]
    fn an_accepted_force_is_read_back_in_its_shape_and_nothing_else_is() {
        let (shape, p) = carried_from(&finding(true, None)).expect("accepted");
        assert_eq!(shape, PairForceShape::Exponential);
        assert_eq!(p[0], -2.5);
        assert!((p[1].exp() - 40e-6).abs() < 1e-18);
        let (shape, p) = carried_from(&finding(true, Some(4.0))).expect("accepted");
        assert_eq!((shape, p[2]), (PairForceShape::PowerLaw, 4.0));
        assert!(carried_from(&finding(false, None)).is_none());
        let mut other = finding(true, None);
        other.effect = Effect::PairPhysicsMismatch.id().into();
        assert!(carried_from(&other).is_none());
    }

    #[test]
    fn a_fit_parameter_at_its_bound_is_named() {
        let spec = FitSpec {
            pair_force: Some((PairForceShape::Exponential, PAIR_FORCE_START)),
            ..FitSpec::new(crate::physics::Groove::CHAPTER)
        };
        let specs = spec.shared_specs(None, &[]);
        let mut shared: Vec<f64> = specs.iter().map(|s| s.start).collect();
        shared[PF_AMP] = -1.0;
        let fit = |shared: Vec<f64>| GroupFit {
            spec: spec.clone(),
            result: crate::lsq::block::BlockResult {
                shared,
                own: Vec::new(),
                shared_cov: Vec::new(),
                own_se: Vec::new(),
                block_cost: Vec::new(),
                termination: crate::lsq::Termination::SmallStep,
                iterations: 0,
            },
        };
        assert_eq!(at_bound(&fit(shared.clone())), None);
        shared[PF_LN_RANGE] = specs[PF_LN_RANGE].lower;
        assert_eq!(at_bound(&fit(shared)), Some("range"));
    }
}
