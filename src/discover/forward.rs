//! Forward selection: test every candidate term against the current model, accept the strongest
//! (likelihood ratio less ln(n) per extra parameter) one that passes both the bootstrap
//! likelihood-ratio test (Holm-corrected) and leave-runs-out cross-validation, refit, repeat;
//! then ask the drift probes whether a mismatch is left unexplained. The model and its starts are
//! in `model.rs`, the parameters as reported in `estimates.rs`.

use super::admissible::refusal;
use super::candidate::prepare;
use super::candidate::{Extra, N_LOCAL};
use super::cv::{folds, paired_t, signed_rank_p, CvResult};
use super::data::RunData;
use super::detection::detection_limit;
use super::estimates::{held_back, reported_parameters, scale_at_bound};
use super::holm::holm;
use super::model::{data_starts, Model};
use super::null_distribution::{empirical_p, NullFit};
use super::proposal::{needs_proposal, propose, wanted_for};
use super::ranges::{Proposals, Ranges};
use super::screen::{screen, Control, Screened, REPLICATES};
use super::Options;
use crate::artifacts::diagnosis::{CandidateRow, Evidence, Finding, ModelScore};
use crate::stats::dist::t_upper_quantile;
use rayon::prelude::*;
use std::cell::OnceCell;
use std::collections::BTreeMap;

/// Significant candidates fitted in full per round (strongest first, until one passes).
pub const FULL_TRIES: usize = 3;
/// Iterations of a full fit started from the screen's linear estimate.
pub const FULL_ITERATIONS: usize = 40;

/// Level of the one-sided paired test that held-out runs improve.
pub const CV_LEVEL: f64 = 0.05;

/// One-sided level of the signed-rank test that confirms a term the paired t does not: either
/// test passing confirms, so together they pass a term that does not help at up to 6 %, not 10.
pub const SIGNED_RANK_LEVEL: f64 = 0.01;

/// A pair of named forms is fitted beside a searched form that passed alone only if its two
/// first-order likelihood ratios sum to more than the form's divided by this. Where a pair was
/// the right answer (a rolling resistance and a quadratic drag mistaken for a wave) the sum was
/// 1.2× the wave's; beside a true wave and a tilt it was 0.3–0.55×.
const PAIR_GAIN_RATIO: f64 = 1.5;

/// With GROOVE_DISCOVER_TRACE set, print how long `what` took (stderr only, never in outputs).
pub(super) fn trace_took(start: std::time::Instant, what: impl FnOnce() -> String) {
    if std::env::var_os("GROOVE_DISCOVER_TRACE").is_some() {
        eprintln!(
            "discover: {} took {:.2} s",
            what(),
            start.elapsed().as_secs_f64()
        );
    }
}

/// The model a candidate would give to first order: the current fit with the screen's linear
/// estimates of the term (not refitted; χ² lowered by the screen's statistic).
fn pseudo(current: &Model, e: &Extra, s: Option<&Screened>, materials: &[String]) -> Model {
    let spec = current.spec.with(e.clone());
    let params = spec.global_params(materials);
    let mut fit = current.fit.clone();
    match s {
        Some(s) => {
            fit.global.extend(clamp_to(e, &s.estimate));
            fit.global_se.extend(s.se.iter().copied());
            fit.chi2 -= s.lr;
        }
        None => {
            fit.global.extend(e.params().iter().map(|p| p.start));
            fit.global_se.extend(e.params().iter().map(|_| f64::NAN));
        }
    }
    fit.iterations = 0;
    fit.converged = false;
    Model { spec, params, fit }
}

/// Values of a term's parameters held inside their bounds.
fn clamp_to(e: &Extra, v: &[f64]) -> Vec<f64> {
    v.iter()
        .zip(e.params())
        .map(|(x, q)| {
            if x.is_finite() {
                x.clamp(q.lo, q.hi)
            } else {
                q.start
            }
        })
        .collect()
}

/// Result of one round of tests against the current model.
pub struct Round {
    pub rows: Vec<CandidateRow>,
    /// (index into rows, extended model, its CV) of the accepted term, if any.
    pub accepted: Option<(usize, Model, CvResult)>,
    /// The row of a second term accepted with it (both in the extended model), if any.
    pub partner: Option<usize>,
    /// The bootstrap null of each candidate (same order as `rows`).
    pub nulls: Vec<NullFit>,
    /// Probe rows significant after Holm over the probes.
    pub flagged_probes: Vec<CandidateRow>,
    pub probe_rows: Vec<CandidateRow>,
    /// The forms tied with the accepted term, to be decided again beside later terms.
    pub tied: Vec<Tie>,
}

/// A form that held-out runs could not tell from the accepted term in its round (`tied`).
pub struct Tie {
    /// Its row (index into `Round::rows`).
    pub row: usize,
    /// Its parameters, fitted in full in the round.
    pub start: Vec<f64>,
    /// The round's model with it in place of the accepted term, scored.
    pub after: ModelScore,
}

/// One side of [`preferred`]: a form's parameter count, held-out error, and whether it is held
/// back (`estimates::held_back`: a parameter other than its scale at a bound of its search, or
/// a term physical only over the speeds the runs reach).
pub struct Side<'a> {
    pub n: usize,
    pub cv: &'a CvResult,
    pub pinned: bool,
}

/// Whether form `new` is preferred to `old` (paired t over the runs against `t_cv`): a richer
/// form where held-out runs prefer it, a simpler one where they cannot tell the two apart. Of
/// two as simple, one held back is named only where held-out runs prefer it (a bump whose
/// centre ran to the end of the groove, 4 mm wide, is a step seen from one side: the data do
/// not place it; a quadratic drag with c < 0 beside a saturating one pushes the particle above
/// some speed: the two had come out a hair apart either way between builds), else the one with
/// the lower held-out error.
pub fn preferred(new: Side, old: Side, t_cv: f64) -> bool {
    match new.n.cmp(&old.n) {
        std::cmp::Ordering::Greater => paired_t(old.cv, new.cv) > t_cv,
        std::cmp::Ordering::Less => paired_t(new.cv, old.cv) <= t_cv,
        std::cmp::Ordering::Equal => match (new.pinned, old.pinned) {
            (false, true) => paired_t(new.cv, old.cv) <= t_cv,
            (true, false) => paired_t(old.cv, new.cv) > t_cv,
            _ => new.cv.cv_rms_m < old.cv.cv_rms_m,
        },
    }
}

fn row(
    round: usize,
    e: &Extra,
    m: &Model,
    materials: &[String],
    runs: &[RunData],
    ev: Evidence,
) -> CandidateRow {
    CandidateRow {
        round,
        effect: e.effect().unwrap_or("probe").to_string(),
        form: e.form(),
        accepted: false,
        parameters: reported_parameters(m, m.spec.extras.len() - 1, materials, runs),
        evidence: ev,
    }
}

/// The data and settings every round reads.
pub struct Setting<'a> {
    pub materials: &'a [String],
    pub runs: &'a [RunData],
    pub opts: &'a Options,
    /// Fold of each run (leave-runs-out cross-validation).
    pub fold: &'a [usize],
    pub rg: &'a Ranges,
    /// Where the step under way is said (the stage's progress line).
    pub say: &'a (dyn Fn(&str) + Sync),
    /// Whether two terms may be accepted together (room for two more under `max_terms`).
    pub pairs_allowed: bool,
}

/// The proposals of a round's residuals, made when first asked for: only a proposed form fitted
/// in full needs them, so a round whose screen finds nothing of that kind never makes them.
pub struct LazyProposals<'a> {
    cell: OnceCell<Proposals>,
    make: Box<dyn Fn() -> Proposals + 'a>,
}

impl<'a> LazyProposals<'a> {
    pub fn new(make: impl Fn() -> Proposals + 'a) -> LazyProposals<'a> {
        LazyProposals {
            cell: OnceCell::new(),
            make: Box::new(make),
        }
    }

    /// Proposals already made.
    pub fn ready(p: Proposals) -> LazyProposals<'a> {
        LazyProposals {
            cell: OnceCell::from(p),
            make: Box::new(Proposals::default),
        }
    }

    pub fn get(&self) -> &Proposals {
        self.cell.get_or_init(|| (self.make)())
    }
}

/// The screen of a round: every candidate's (and probe's) first-order statistic, its bootstrap
/// null, p-value and the linear model it stands for.
struct Screens {
    screens: Vec<Option<Screened>>,
    lr: Vec<f64>,
    reps: Vec<Vec<f64>>,
    nulls: Vec<NullFit>,
    p: Vec<f64>,
    linear: Vec<Model>,
}

fn screen_round(round: usize, current: &Model, all: &[&Extra], set: &Setting) -> Screens {
    let prep = prepare(
        &current.spec,
        &current.params,
        &current.fit.global,
        &current.fit.local,
        set.runs,
    );
    let say = |what: &str| (set.say)(&format!("round {round}: {what}"));
    let screens = screen(
        all,
        current,
        set.runs,
        &prep,
        set.rg,
        &Control {
            replicates: REPLICATES.max(set.opts.bootstrap),
            seed: set.opts.seed ^ (round as u64).wrapping_mul(0xD1B5_4A32_D192_ED03),
            alpha: set.opts.alpha,
            say: &say,
        },
    );
    drop(prep);
    let lr: Vec<f64> = screens
        .iter()
        .map(|s| s.as_ref().map(|s| s.lr).unwrap_or(0.0))
        .collect();
    let reps: Vec<Vec<f64>> = screens
        .iter()
        .map(|s| s.as_ref().map(|s| s.replicates.clone()).unwrap_or_default())
        .collect();
    // a named term's law is computed; a searched form's is fitted to its replicates
    let nulls: Vec<NullFit> = all
        .iter()
        .zip(&reps)
        .zip(&screens)
        .map(
            |((e, r), s)| match s.as_ref().and_then(|s| s.exact.as_ref()) {
                Some(x) => NullFit::exact(x, r.len()),
                None => NullFit::from_replicates(r, e.null_df(set.runs.len())),
            },
        )
        .collect();
    let p: Vec<f64> = nulls.iter().zip(&lr).map(|(n, l)| n.p_value(*l)).collect();
    // the linear estimates stand for every candidate; only the significant ones are fitted in
    // full (from the screen's estimate and the residuals' proposals)
    let linear: Vec<Model> = all
        .iter()
        .zip(&screens)
        .map(|(e, s)| pseudo(current, e, s.as_ref(), set.materials))
        .collect();
    Screens {
        screens,
        lr,
        reps,
        nulls,
        p,
        linear,
    }
}

/// The significant candidates (Holm-adjusted p below α), strongest first. "Strongest" is the
/// statistic's excess over its own null (what noise alone gives this form, its search included;
/// mean, and ln(n) per parameter) so that when a one-parameter term explains as much as a
/// six-parameter series (rolling resistance against a position force when each direction of
/// motion covers its own stretch of the groove), the simpler physics is named.
fn ranked(all: &[&Extra], sc: &Screens, p_holm: &[f64], set: &Setting) -> Vec<usize> {
    let n_obs: usize = set
        .runs
        .iter()
        .map(|r| r.keep.iter().filter(|k| **k).count())
        .sum();
    let penalty = (n_obs.max(2) as f64).ln();
    let strength: Vec<f64> = (0..p_holm.len())
        .map(|i| {
            let df = all[i].params().len() as f64;
            sc.lr[i] - sc.nulls[i].mean.max(df) - penalty * df
        })
        .collect();
    let mut order: Vec<usize> = (0..p_holm.len())
        .filter(|i| p_holm[*i] < set.opts.alpha)
        .collect();
    order.sort_by(|a, b| strength[*b].total_cmp(&strength[*a]).then(a.cmp(b)));
    order
}

/// The candidates fitted in full and cross-validated so far, and the one that passes both tests.
struct Trials<'r> {
    round: usize,
    current: &'r Model,
    current_cv: &'r CvResult,
    all: &'r [&'r Extra],
    props: &'r LazyProposals<'r>,
    set: &'r Setting<'r>,
    /// Critical value of the one-sided paired t over the runs.
    t_cv: f64,
    /// Each candidate's model: its linear estimate until it is fitted in full.
    fitted: Vec<Model>,
    cv_of: Vec<Option<(CvResult, f64)>>,
    /// Why a candidate fitted in full is no finding although it predicts held-out runs better.
    refused: Vec<Option<String>>,
    /// What the runs' own μ and T explain of the current model's misfit beyond the noise when
    /// the particles differ (`particle_excess`), checked once a round when a term with a phase
    /// per run is fitted.
    particle_check: Option<Option<f64>>,
    /// Each candidate's first-order statistic less its null's mean.
    excess: Vec<f64>,
    best: Option<(usize, CvResult)>,
    /// A second term accepted with `best`: neither alone passed the held-out check, both did.
    pair: Option<(usize, Model, f64)>,
    /// A searched form that passed alone and gave way to the pair.
    displaced: Option<usize>,
    /// A form with a phase per run whose phases gather about one value, and the chance of
    /// that under phases of their own (`prefer_locked`): its form with one phase is named.
    locked: Option<(usize, f64)>,
    /// The pair is a named term and a searched form that passed alone, started again beside it.
    beside_form: bool,
}

impl Trials<'_> {
    /// Candidate `i` fitted in full from the screen's estimate and the residuals' proposals.
    fn full(&self, i: usize) -> Model {
        self.current.extend(
            self.all[i],
            &self.starts(i),
            self.set.materials,
            self.set.runs,
            FULL_ITERATIONS,
        )
    }

    /// Starting values of candidate `i`'s parameters: the screen's estimate, then the data's.
    fn starts(&self, i: usize) -> Vec<Vec<f64>> {
        let e = self.all[i];
        let n = e.params().len();
        let fitted = &self.fitted[i].fit.global;
        if e.proposal_supersedes_screen() {
            let proposed = data_starts(e, self.props.get());
            if !proposed.is_empty() {
                return proposed;
            }
        }
        let mut starts = vec![clamp_to(e, &fitted[fitted.len() - n..])];
        if e.searched() {
            starts.extend(data_starts(e, self.props.get()));
        } else {
            starts.extend(data_starts(e, &Proposals::default()));
        }
        starts.dedup();
        starts
    }

    /// Cross-validate `m` against the current model: (held-out RMS better and paired t above
    /// its critical value, the CV, the paired t).
    fn held_out(&self, m: &Model) -> (bool, CvResult, f64) {
        let cv = m.held_out(
            self.set.runs,
            self.set.fold,
            self.set.opts.folds,
            self.set.opts.seed,
        );
        let t = paired_t(self.current_cv, &cv);
        (self.improves(&cv, t), cv, t)
    }

    /// Whether a model of held-out error `cv`, paired t `t` against the current model, predicts
    /// held-out runs better: a lower RMS, and t above its critical value or, for a first term
    /// whose gain sits in few runs (which swells the paired t's spread), Wilcoxon's signed-rank
    /// test over the runs at `SIGNED_RANK_LEVEL` (`by_ranks`).
    fn improves(&self, cv: &CvResult, t: f64) -> bool {
        cv.cv_rms_m < self.current_cv.cv_rms_m && (t > self.t_cv || self.by_ranks(cv))
    }

    /// Whether the signed-rank test confirms `cv` against the current model. Only a first term
    /// is confirmed so: beside an accepted term, a second one that bends it a little gains a
    /// little in nearly every run, which ranks count as much as a large gain and the paired t
    /// weighs by size (a μ by direction beside a periodic μ in mixed noise: gains 32, 6.5, 1.5,
    /// 1.1 and about zero in the other runs, paired t 1.35, signed-rank p 1.4e-4; the periodic
    /// μ then read 0.51 against 0.39, and 0.36 without it).
    fn by_ranks(&self, cv: &CvResult) -> bool {
        self.current.spec.extras.is_empty()
            && signed_rank_p(self.current_cv, cv) < SIGNED_RANK_LEVEL
    }

    /// Whether candidate `i`, fitted in full (once), predicts held-out runs better than the
    /// current model, with its CV.
    fn check(&mut self, i: usize) -> (bool, CvResult) {
        if self.cv_of[i].is_none() {
            (self.set.say)(&format!(
                "round {}: fitting {} in full and cross-validating it",
                self.round,
                self.all[i].effect().unwrap_or("probe")
            ));
            let start = std::time::Instant::now();
            // a phase per run whose screen peaks at the slowest frequency searched is one free
            // push per run there, refused after a full fit as well (`Form::scale_at_end`):
            // refused before it (on the shipped data, the drag's misfit took 4 s to fit so)
            let unfitted = self.all[i].run_phase() && scale_at_bound(&self.fitted[i]).is_some();
            if !unfitted {
                self.fitted[i] = self.full(i);
                trace_took(start, || format!("round {}: the full fit", self.round));
            }
            self.refused[i] = refusal(&self.fitted[i]).map(|why| {
                if unfitted {
                    // its parameters are the screen's linear estimate: say so
                    format!("{why}; at the screen, not fitted in full")
                } else {
                    why
                }
            });
            let particles = if self.refused[i].is_none() && self.all[i].run_phase() {
                self.particle_excess()
            } else {
                None
            };
            if particles.is_some_and(|p| p >= self.excess[i]) {
                // a phase per run fits whatever misfit a run has of its own; when each run's own
                // μ and T take up that misfit as well as the term does (each statistic beyond
                // what the noise gives it), it is a difference between particles, said by the
                // particle check on the final model. A vibration with a phase per run also
                // shifts each run's own μ and T, so particles "differ" beside it too, but by far
                // less than it explains (bench: 0.35 m/s² at 186 Hz, its statistic 1030 and
                // the runs' own μ and T 1.6× their noise's)
                self.refused[i] = Some(
                    "refused: each run's own mu and T take up the misfit it fits as well as it does (differences between particles), and a phase per run fits any run's own misfit".into(),
                );
            }
            if self.refused[i].is_some() {
                // a refused term cannot pass whatever held-out runs say: not cross-validated
                // (its paired t is NaN and its row gives none)
                self.cv_of[i] = Some((self.current_cv.clone(), f64::NAN));
                return (false, self.current_cv.clone());
            }
            let (_, cv, t) = self.held_out(&self.fitted[i]);
            self.cv_of[i] = Some((cv, t));
            trace_took(start, || {
                format!(
                    "round {}: {} fitted in full and cross-validated",
                    self.round,
                    self.all[i].form()
                )
            });
        }
        let (cv, t) = self.cv_of[i].clone().expect("just set");
        let passes = self.improves(&cv, t) && self.refused[i].is_none();
        (passes, cv)
    }

    /// What the runs' own μ and T take up of the current model's misfit beyond what the noise
    /// gives them (the particle check's statistic less its null mean), when the check says the
    /// particles differ; None when they agree (checked once a round).
    fn particle_excess(&mut self) -> Option<f64> {
        if self.particle_check.is_none() {
            let c = super::particles::check(
                self.current,
                self.set.runs,
                self.set.materials,
                self.set.opts.alpha,
                self.set.opts.seed ^ 0x005E_ED0F_9A27,
            );
            self.particle_check = Some(c.filter(|c| c.differ).map(|c| c.lr - c.lr_null_mean));
        }
        self.particle_check.flatten()
    }

    /// When no significant candidate passes the held-out check alone, two of the strongest
    /// (of different effects) fitted together may: two speed effects at once (a rolling
    /// resistance and a quadratic drag) each misdescribe the other's share alone. The first
    /// pair, strongest first, whose joint fit predicts held-out runs better is accepted;
    /// backward elimination then re-tests each of the two given the other.
    ///
    /// A searched form that passed alone (a wave, a bump, a force in time) is no reason to stop:
    /// a wave whose wells trap a particle as a rolling resistance stops it can stand in for a
    /// resistance and a drag together. A pair of named terms that predicts held-out runs as well
    /// (paired t of the form over the pair within its critical value) is named instead: fewer
    /// parameters, fixed shapes. `lr` are the screen's first-order likelihood ratios.
    fn pairs(&mut self, order: &[usize], lr: &[f64]) {
        let incumbent = self.best.clone();
        if incumbent
            .as_ref()
            .is_some_and(|(b, _)| !needs_proposal(self.all[*b]))
        {
            return;
        }
        // the searched forms are flexible enough to absorb part of anything: pairs are of the
        // named forms with fixed shapes only, every form of the three strongest significant
        // effects (alone, a quadratic drag beside a missing resistance may fit with the wrong
        // sign and rank below the saturating form of the same effect)
        // and of the incumbent's place: a searched force stands in for named forces, not for a
        // friction law or a distortion (those compete with it in the screen on their own)
        let place = |e: &Extra| (e.effect().is_some()).then(|| e.place());
        let incumbent_place = incumbent.as_ref().and_then(|(b, _)| place(self.all[*b]));
        let named: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&i| {
                !self.all[i].searched()
                    && incumbent_place.is_none_or(|p| place(self.all[i]) == Some(p))
            })
            .collect();
        let mut effects: Vec<Option<&str>> = Vec::new();
        for &i in &named {
            let e = self.all[i].effect();
            if !effects.contains(&e) && effects.len() < FULL_TRIES {
                effects.push(e);
            }
        }
        let top: Vec<usize> = named
            .into_iter()
            .filter(|&i| effects.contains(&self.all[i].effect()))
            .collect();
        if incumbent.is_none() {
            for &i in &top {
                let (passes, cv) = self.check(i);
                if passes {
                    self.best = Some((i, cv));
                    return;
                }
            }
        }
        for (n, &a) in top.iter().enumerate() {
            for &b in &top[n + 1..] {
                let (ea, eb) = (self.all[a], self.all[b]);
                if ea.effect() == eb.effect() {
                    continue;
                }
                // a pair whose first-order gains add up to well below the searched form's
                // cannot predict as well (their joint gain is about their sum less their
                // overlap): not fitted (on a tilt beside a wave, 25–44 thousand against 80)
                if incumbent
                    .as_ref()
                    .is_some_and(|(i, _)| (lr[a] + lr[b]) * PAIR_GAIN_RATIO < lr[*i])
                {
                    continue;
                }
                (self.set.say)(&format!(
                    "round {}: fitting {} and {} together and cross-validating them",
                    self.round,
                    ea.effect().unwrap_or("probe"),
                    eb.effect().unwrap_or("probe")
                ));
                let start = std::time::Instant::now();
                let m = self.fitted[a].extend(
                    eb,
                    &self.starts(b),
                    self.set.materials,
                    self.set.runs,
                    FULL_ITERATIONS,
                );
                trace_took(start, || {
                    format!("round {}: {} + {} fitted", self.round, ea.form(), eb.form())
                });
                if refusal(&m).is_some() {
                    continue;
                }
                let (passes, cv, t) = self.held_out(&m);
                let as_good = incumbent
                    .as_ref()
                    .is_none_or(|(_, inc)| paired_t(&cv, inc) <= self.t_cv);
                if passes && as_good {
                    self.displaced = incumbent.map(|(i, _)| i);
                    self.best = Some((a, cv));
                    self.pair = Some((b, m, t));
                    return;
                }
            }
        }
        if let Some((s, s_cv)) = incumbent {
            if self.drift_beside(s) {
                self.mixed_pairs(s, &s_cv, &top);
            }
        }
    }

    /// Whether the probes (T or μ drifting with |v0|, a difference by direction) still flag a
    /// mismatch against the model with searched form `s` fitted alone (Holm over the probes at
    /// α): the sign of a form that bent to stand in for speed physics too. Beside a true wave
    /// alone they fell within their nulls (Holm p ≥ 0.06 on the 0.5–5 mm fixtures); beside a
    /// wave bent by a rolling resistance or a saturating drag they flagged at p < 0.001.
    fn drift_beside(&self, s: usize) -> bool {
        let probes: Vec<&Extra> = self.all[self.cv_of.len()..].to_vec();
        if probes.is_empty() {
            return false;
        }
        (self.set.say)(&format!(
            "round {}: probing the {} alone for drift left",
            self.round,
            self.all[s].effect().unwrap_or("probe")
        ));
        let runs_s = runs_under(&self.fitted[s], self.set.runs);
        let set_s = Setting {
            runs: runs_s.as_deref().unwrap_or(self.set.runs),
            ..*self.set
        };
        let sc = screen_round(self.round, &self.fitted[s], &probes, &set_s);
        holm(&sc.p).iter().any(|p| *p < self.set.opts.alpha)
    }

    /// A searched form `s` that passed alone beside a significant named term may be bending to
    /// stand in for both: a wave of 3 mm beside a rolling resistance was fitted as one of 4.9 mm
    /// and 1.5–1.8× the amplitude, after which the resistance scored nothing (its first-order
    /// statistic is taken at the bent wave) and a bump and a spline took the rest. So each named
    /// term of the strongest significant effects is fitted in full alone, the form is started again
    /// from the proposals of that model's residuals and fitted with it, and of the pairs that
    /// predict held-out runs better than the form alone (paired t above its critical value) the one
    /// with the least held-out error is accepted together (the first that passed, a saturating drag
    /// with T' ≈ 0.02 s²/m beside a wave still bent, was not the answer: the resistance came later
    /// in the order); backward elimination then re-tests each given the other. Only when drift is
    /// left beside the form alone (`drift_beside`): each try is a few full fits and a cross-
    /// validation.
    fn mixed_pairs(&mut self, s: usize, s_cv: &CvResult, top: &[usize]) {
        let form = self.all[s];
        let mut best: Option<(usize, CvResult, Model, f64)> = None;
        for &t in top {
            self.check(t);
            (self.set.say)(&format!(
                "round {}: fitting {} with the {} started again beside it",
                self.round,
                self.all[t].effect().unwrap_or("probe"),
                form.effect().unwrap_or("probe")
            ));
            let beside = &self.fitted[t];
            let props = propose(
                &beside.spec,
                &beside.params,
                &beside.fit.global,
                &beside.fit.local,
                self.set.runs,
                self.set.rg,
                wanted_for(&[form]),
                Some((self.set.fold, self.set.opts.folds)),
            );
            // the proposals of the new residuals only: the form's own starts (its screen's
            // estimate, the proposals of the residuals before) are those it bent from
            let starts = data_starts(form, &props);
            let m = beside.extend(
                form,
                &starts,
                self.set.materials,
                self.set.runs,
                FULL_ITERATIONS,
            );
            if refusal(&m).is_some() {
                continue;
            }
            let (passes, cv, t_stat) = self.held_out(&m);
            let better = best
                .as_ref()
                .is_none_or(|(_, b, _, _)| cv.cv_rms_m < b.cv_rms_m);
            if passes && paired_t(s_cv, &cv) > self.t_cv && better {
                best = Some((t, cv, m, t_stat));
            }
        }
        if let Some((t, cv, m, t_stat)) = best {
            self.best = Some((t, cv));
            self.pair = Some((s, m, t_stat));
            self.beside_form = true;
        }
    }

    /// Fit in full and cross-validate the significant candidates strongest first (at most
    /// FULL_TRIES of them); the first that also predicts held-out runs better is the best.
    fn strongest(&mut self, order: &[usize]) {
        for &i in order.iter().take(FULL_TRIES) {
            let (passes, cv) = self.check(i);
            if passes {
                self.best = Some((i, cv));
                return;
            }
        }
    }

    /// Of two forms of one effect, the richer is named only where held-out runs prefer it: each
    /// form of the accepted term's effect with more parameters and a comparable statistic (as
    /// `prefer_simpler` reads it) is fitted in full, and named instead when it predicts held-out
    /// runs better (paired t above its critical value). The order charges each parameter, so a
    /// curve with one parameter more ranks below a line it explains more than (a Stribeck
    /// friction behind the line in the slip speed, whose slope is no size of it) and was
    /// otherwise never fitted.
    ///
    /// A form of the same effect with as many parameters and a comparable statistic is fitted
    /// too: two such forms often screen alike (a quadratic and a saturating drag at one LR), and
    /// which ranks first is then the noise's choice. Neither is simpler, so the one with the
    /// lower held-out error is named; where held-out runs cannot tell them apart (paired t
    /// within its critical value), `tied` says so.
    fn prefer_richer(&mut self, order: &[usize], lr: &[f64]) {
        let Some((b, _)) = self.best.clone() else {
            return;
        };
        if self.pair.is_some() {
            // accepted together with a term beside it: the two stand or fall as a pair
            return;
        }
        let (effect, nb) = (self.all[b].effect(), self.all[b].params().len());
        let alike = |j: usize| {
            j != b
                && self.all[j].effect() == effect
                && self.all[j].params().len() >= nb
                && lr[j] >= 0.5 * lr[b]
        };
        let others: Vec<usize> = order.iter().copied().filter(|&j| alike(j)).collect();
        for j in others {
            let (passes, cv) = self.check(j);
            let Some((k, k_cv)) = self.best.as_ref() else {
                return;
            };
            let side = |i: usize, cv| Side {
                n: self.all[i].params().len(),
                cv,
                pinned: self.pinned(i),
            };
            if passes && preferred(side(j, &cv), side(*k, k_cv), self.t_cv) {
                self.best = Some((j, cv));
            }
        }
    }

    /// Whether candidate `i`, fitted in full, is held back in a tie (`estimates::held_back`).
    fn pinned(&self, i: usize) -> bool {
        let m = &self.fitted[i];
        !m.spec.extras.is_empty() && held_back(m, m.spec.extras.len() - 1)
    }

    /// A force with a phase per run whose fitted phases gather about one value (Rayleigh's test
    /// beyond α) is locked to the kick: its form with one phase for every run is named where that
    /// passes both tests. Each run's phase absorbs the error of its own kick time (t0), which a
    /// sliding run's parabola hardly fixes, so held-out runs may prefer the phases per run
    /// though they are one cause; phases of their own in every run gather beyond chance at
    /// rate α only, and then the one-phase form must still pass both tests.
    fn prefer_locked(&mut self, order: &[usize]) {
        let Some((b, _)) = self.best.clone() else {
            return;
        };
        if self.pair.is_some() || !self.all[b].run_phase() {
            return;
        }
        let m = &self.fitted[b];
        let phases: Vec<f64> = self
            .set
            .runs
            .par_iter()
            .enumerate()
            .filter_map(|(r, run)| {
                let sim = m
                    .spec
                    .sim_model(&m.fit.global, run.material, m.fit.local[r][2]);
                let (idx, amp, _) = super::timeforce::time_term(&sim)?;
                (amp != 0.0).then(|| {
                    super::timeforce::best_phase(&super::timeforce::run_sums(
                        &sim,
                        idx,
                        &m.fit.local[r],
                        run,
                    ))
                })
            })
            .collect();
        let p = super::timeforce::phases_uniform_p(&phases);
        if p >= self.set.opts.alpha {
            return;
        }
        let effect = self.all[b].effect();
        for &j in order {
            if j == b {
                continue;
            }
            if self.all[j].effect() == effect && !self.all[j].run_phase() {
                let (passes, cv) = self.check(j);
                if passes {
                    self.best = Some((j, cv));
                    self.locked = Some((b, p));
                    return;
                }
            }
        }
    }

    /// Of two representations that predict held-out runs equally well, the simpler is named; a
    /// representation explains as much only if its statistic is comparable.
    fn prefer_simpler(&mut self, order: &[usize], lr: &[f64]) {
        let Some((b, b_cv)) = self.best.clone() else {
            return;
        };
        let nb = self.all[b].params().len();
        let mut simpler: Vec<usize> = order
            .iter()
            .copied()
            .filter(|&j| self.all[j].params().len() < nb && lr[j] >= 0.5 * lr[b])
            .collect();
        simpler.sort_by_key(|&j| (self.all[j].params().len(), j));
        for j in simpler {
            let (passes, cv) = self.check(j);
            if passes && paired_t(&cv, &b_cv) <= self.t_cv {
                self.best = Some((j, cv));
                return;
            }
        }
    }
}

/// The candidates fitted in full that pass both tests and that held-out runs cannot tell from
/// the accepted single term (paired t of the accepted over it within its critical value), with
/// that t; none beside a pair.
fn tied(tr: &Trials, ne: usize) -> Vec<(usize, f64)> {
    let Some((b, b_cv)) = tr.best.as_ref() else {
        return vec![];
    };
    if tr.pair.is_some() {
        return vec![];
    }
    (0..ne)
        .filter(|&j| j != *b && tr.refused[j].is_none())
        // the phases per run that gather about one value are said as such, not as a tie
        .filter(|&j| tr.locked.is_none_or(|l| l.0 != j))
        .filter_map(|j| {
            let (cv, t_base) = tr.cv_of[j].as_ref()?;
            let passes = tr.improves(cv, *t_base);
            let t = paired_t(cv, b_cv);
            (passes && t <= tr.t_cv).then_some((j, t))
        })
        .collect()
}

/// The decision of candidate or probe `i` in words (and its CV in `ev`).
fn decide(i: usize, ne: usize, p_holm: f64, ev: &mut Evidence, tr: &Trials, alpha: f64) -> String {
    if i >= ne {
        return if p_holm < alpha {
            "probe flags a mismatch"
        } else {
            "probe: no drift"
        }
        .into();
    }
    if p_holm >= alpha {
        return "rejected: likelihood ratio (first order) within its bootstrap null".into();
    }
    if let Some((cv, t)) = &tr.cv_of[i] {
        if let Some(why) = &tr.refused[i] {
            return format!("{why} (not cross-validated)");
        }
        ev.cv_paired_t = Some(*t);
        ev.cv_rms_m = Some(cv.cv_rms_m);
        if let Some((_, p)) = tr.locked.filter(|l| l.0 == i) {
            let one = tr.best.as_ref().map(|(b, _)| tr.all[*b].form());
            return format!(
                "passes both tests, but its phases gather about one value (p = {p:.2e} if each run's phase were its own): the force is locked to the kick, and {} is named instead",
                one.unwrap_or_default()
            );
        }
        if tr.displaced == Some(i) {
            return "passes both tests, but two named terms fitted together predict held-out runs as well with fixed shapes: they are named instead".into();
        }
        return match &tr.best {
            Some((b, _)) if *b == i && *t <= tr.t_cv => format!(
                "passes: bootstrap LR test and held-out runs, by the signed-rank test over the runs (p = {:.2e}): the gain sits in few runs, which swells the paired t's spread",
                signed_rank_p(tr.current_cv, cv)
            ),
            Some((b, _)) if *b == i => "passes: bootstrap LR test and held-out runs".into(),
            // it passed on its own, and another form was preferred by held-out runs (a richer
            // form of its effect, `prefer_richer`); a tie is said over this by `tied`
            Some((b, b_cv)) if tr.improves(cv, *t) => format!(
                "passes both tests, but {} predicts held-out runs better (paired t = {:.2}): it is named instead",
                tr.all[*b].form(),
                paired_t(cv, b_cv)
            ),
            _ => "rejected: held-out runs do not improve".into(),
        };
    }
    if tr.best.is_some() {
        "significant, not fitted in full: a stronger term passed both tests".into()
    } else {
        format!("significant, not fitted in full: only the {FULL_TRIES} strongest significant terms of a round are fitted in full and none of those passed the held-out check")
    }
}

/// The runs with the slow tracking noise read under `model` (None for the baseline, whose runs
/// carry it): a misfit that the model's terms explain no longer counts as noise, so each model
/// is judged against the noise its own fit leaves.
pub fn runs_under(model: &Model, runs: &[RunData]) -> Option<Vec<RunData>> {
    if model.spec.extras.is_empty() {
        return None;
    }
    let slow = super::perrun::slow_noise_under(
        runs,
        &model.spec,
        &model.params,
        &model.fit.global,
        &model.fit.local,
    );
    Some(runs.iter().map(|r| RunData { slow, ..r.clone() }).collect())
}

/// The screen's p-value of the one candidate `e` against `current`, as round `round` would read
/// it (the runs' slow noise under `current`, the round's replicates).
pub fn screen_p(round: usize, current: &Model, e: &Extra, set: &Setting) -> f64 {
    let runs_here = runs_under(current, set.runs);
    let set = &Setting {
        runs: runs_here.as_deref().unwrap_or(set.runs),
        ..*set
    };
    screen_round(round, current, &[e], set).p[0]
}

/// Test `entries` (candidate terms) and `probes` against `current`: screen all, fit the
/// strongest significant candidates in full, cross-validate, prefer the simpler of equals, and
/// write every row. `props` are the proposals of the current residuals (starts of the forms
/// that need them), made only if such a form is fitted in full.
pub fn run_round(
    round: usize,
    current: &Model,
    current_cv: &CvResult,
    entries: &[Extra],
    probes: &[Extra],
    props: &LazyProposals,
    set: &Setting,
) -> Round {
    let all: Vec<&Extra> = entries.iter().chain(probes).collect();
    let ne = entries.len();
    let clock = std::time::Instant::now();
    let runs_here = runs_under(current, set.runs);
    let set = &Setting {
        runs: runs_here.as_deref().unwrap_or(set.runs),
        ..*set
    };
    let trace = |what: &str| {
        if std::env::var_os("GROOVE_DISCOVER_TRACE").is_some() {
            eprintln!(
                "round {round}: {what} at {:.2} s",
                clock.elapsed().as_secs_f64()
            );
        }
    };
    let sc = screen_round(round, current, &all, set);
    trace("screened");
    let p_holm_e = holm(&sc.p[..ne]);
    let p_holm_p = holm(&sc.p[ne..]);
    let order = ranked(&all, &sc, &p_holm_e, set);
    let mut tr = Trials {
        round,
        current,
        current_cv,
        all: &all,
        props,
        set,
        // the held-out check confirms a term the LR test already found; one-sided 5 % on the
        // paired t over the runs: Student's t with (runs − 1) degrees of freedom
        t_cv: t_upper_quantile(CV_LEVEL, set.runs.len().saturating_sub(1) as f64),
        fitted: sc.linear.clone(),
        cv_of: vec![None; ne],
        refused: vec![None; ne],
        particle_check: None,
        excess: (0..ne).map(|i| sc.lr[i] - sc.nulls[i].mean).collect(),
        best: None,
        pair: None,
        displaced: None,
        locked: None,
        beside_form: false,
    };
    tr.strongest(&order);
    trace("fitted and cross-validated the strongest");
    tr.prefer_richer(&order, &sc.lr);
    tr.prefer_simpler(&order, &sc.lr);
    tr.prefer_locked(&order);
    trace("cross-validated");
    if set.pairs_allowed {
        tr.pairs(&order, &sc.lr);
        trace("pairs tried");
    }
    let opts = set.opts;
    let mut rows = Vec::new();
    for (i, e) in all.iter().enumerate() {
        let is_probe = i >= ne;
        let p_holm = if is_probe {
            p_holm_p[i - ne]
        } else {
            p_holm_e[i]
        };
        let mut ev = Evidence {
            round,
            lr: sc.lr[i],
            extra_params: e.params().len(),
            bootstrap_replicates: sc.reps[i].len(),
            null_mean_lr: sc.nulls[i].mean,
            p_value: sc.p[i],
            p_empirical: empirical_p(&sc.reps[i], sc.lr[i]),
            p_holm,
            cv_paired_t: None,
            cv_rms_m: None,
            decision: String::new(),
            detection_limit: if is_probe {
                None
            } else {
                detection_limit(
                    e,
                    &sc.linear[i],
                    sc.screens[i].as_ref().and_then(|s| s.typical.as_ref()),
                    &sc.nulls[i],
                    opts.alpha / ne.max(1) as f64,
                )
            },
        };
        ev.decision = decide(i, ne, p_holm, &mut ev, &tr, opts.alpha);
        rows.push(row(round, e, &tr.fitted[i], set.materials, set.runs, ev));
    }
    let partner = tr.pair.as_ref().map(|(b, _, _)| *b);
    let ties = tied(&tr, ne);
    let kept_ties = ties
        .iter()
        .filter_map(|&(j, _)| {
            let (cv, _) = tr.cv_of[j].as_ref()?;
            let n = all[j].params().len();
            let g = &tr.fitted[j].fit.global;
            Some(Tie {
                row: j,
                start: g[g.len() - n..].to_vec(),
                after: tr.fitted[j].score(set.runs, Some(cv)),
            })
        })
        .collect();
    for &(j, t) in &ties {
        rows[j].evidence.decision = format!(
            "tie: passes both tests and predicts held-out runs as well as the accepted term (paired t = {t:.2}, within its critical value {:.2}): these data cannot tell the two apart",
            tr.t_cv
        );
    }
    let accepted = tr.best.map(|(i, cv)| {
        rows[i].accepted = true;
        let Some((b, m, t)) = tr.pair else {
            rows[i].evidence.decision = "accepted: strongest term passing both tests".into();
            if paired_t(current_cv, &cv) <= tr.t_cv {
                rows[i].evidence.decision.push_str(&format!(
                    " (held-out runs by the signed-rank test over the runs, p = {:.2e}: the gain sits in few runs, which swells the paired t's spread)",
                    signed_rank_p(current_cv, &cv)
                ));
            }
            if !ties.is_empty() {
                let forms: Vec<String> = ties.iter().map(|&(j, _)| all[j].form()).collect();
                rows[i].evidence.decision.push_str(&format!(
                    "; tied with {}: these data cannot tell them apart, and this one (simpler, stronger, inside its bounds, physical at every speed or of lower held-out error) is in the model",
                    forms.join(" and ")
                ));
            }
            return (i, tr.fitted[i].clone(), cv);
        };
        let effect = |k: usize| all[k].effect().unwrap_or("probe").replace('_', " ");
        for (k, other) in [(i, b), (b, i)] {
            rows[k].accepted = true;
            rows[k].evidence.cv_paired_t = Some(t);
            rows[k].evidence.cv_rms_m = Some(cv.cv_rms_m);
            rows[k].evidence.decision = match tr.beside_form {
                false => format!(
                    "accepted together with {}: neither alone predicts held-out runs better, both fitted together do (paired t = {t:.2})",
                    effect(other)
                ),
                true => format!(
                    "accepted together with {}: the {} alone passed, but the drift probes still flagged a mismatch beside it; started again from the residuals beside the {} and fitted with it, the two predict held-out runs better than it alone (paired t against the current model = {t:.2})",
                    effect(other),
                    effect(b),
                    effect(i)
                ),
            };
        }
        (i, m, cv)
    });
    let probe_rows: Vec<CandidateRow> = rows[ne..].to_vec();
    let flagged_probes = probe_rows
        .iter()
        .filter(|r| r.evidence.p_holm < opts.alpha)
        .cloned()
        .collect();
    rows.truncate(ne);
    Round {
        nulls: sc.nulls[..ne].to_vec(),
        rows,
        accepted,
        partner,
        flagged_probes,
        probe_rows,
        tied: kept_ties,
    }
}

/// Build a finding from an accepted row.
pub fn finding(
    row: &CandidateRow,
    before: ModelScore,
    after: ModelScore,
    where_: BTreeMap<String, serde_json::Value>,
) -> Finding {
    Finding {
        effect: row.effect.clone(),
        accepted: row.accepted,
        form: row.form.clone(),
        parameters: row.parameters.clone(),
        evidence: row.evidence.clone(),
        where_,
        baseline: before,
        extended: after,
    }
}

/// Speed reference of the probes: the median |v0| of the runs.
pub fn median_speed(local: &[[f64; N_LOCAL]]) -> f64 {
    let mut v: Vec<f64> = local.iter().map(|l| l[2].abs()).collect();
    if v.is_empty() {
        return 0.0;
    }
    crate::stats::upper_median(&mut v)
}

/// Fold assignment for `runs` given per-run starting values.
pub fn fold_of(runs: &[RunData], local: &[[f64; N_LOCAL]], k: usize) -> Vec<usize> {
    folds(runs, local, k)
}
