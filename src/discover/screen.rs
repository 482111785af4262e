//! The screen: every candidate's likelihood-ratio statistic and its parametric-bootstrap null,
//! from the linear response of the current joint model, with no refits.
//!
//! Around the fitted model a small extra term moves the predicted positions linearly: along the
//! model's secant for a named term (each parameter stepped from where the term vanishes), along
//! the response to the force's basis functions for a form with a scale to search (`response.rs`: a
//! periodic force in z at each trial wavenumber, a bump at each trial centre and width, a force
//! periodic in time at each trial frequency with a phase per run, a spline). Each run's z0, t0, v0
//! are projected out and the shared parameters (μ, T, accepted terms) profiled, so the statistic
//! is the drop in χ² a refit would give to first order. The same statistic, maximised over the
//! same trials, is computed on replicates of each run's measured noise (Gaussian, as
//! `noise_model.rs` draws it: σ, the fast part's shape and growth with speed, and the dataset's
//! slow drift) pushed through the same projections: the null of a searched form carries
//! its look-elsewhere effect, for a few dot products per trial instead of a nonlinear refit per
//! replicate. Only the candidates the screen finds significant are fitted in full.
//!
//! A searched form's replicates come in two batches (sequential testing): the first
//! `FIRST_BATCH`, and the rest only when those leave its decision open (`clearly_null`). The
//! named terms cost a few dot products and always take every replicate.

use super::candidate::{predict, Extra, N_LOCAL};
use super::data::RunData;
use super::forms::Search;
use super::model::Model;
use super::null_distribution::{ExactNull, NullFit};
use super::ranges::Ranges;
use super::response::Prepared;
pub use super::screen_sums::Typical;
use super::screen_sums::{best_of, coherent_sums, one_sided, Trial, Vectors};
use super::time_scan::TimeMemo;
use rayon::prelude::*;
use std::ops::Range;

/// Noise replicates drawn for each screen (the data is replicate 0).
pub const REPLICATES: usize = 60;

/// Replicates of a searched form's first batch (sequential testing).
pub const FIRST_BATCH: usize = 20;

/// Chance, were a form's true p-value below α, that its first batch stops it as clearly null.
pub const STOP_ERROR: f64 = 1e-3;

/// The fewest of `b` replicates reaching the data's statistic that a true p-value below `alpha`
/// gives with probability at most `STOP_ERROR` (binomial tail); `b + 1` when no count does.
pub fn stop_count(b: usize, alpha: f64) -> usize {
    // P(X = j) for X ~ Bin(b, alpha), summed from the top
    let mut pmf = vec![0.0f64; b + 1];
    pmf[0] = (1.0 - alpha).powi(b as i32);
    for j in 1..=b {
        pmf[j] = pmf[j - 1] * (b - j + 1) as f64 / j as f64 * alpha / (1.0 - alpha);
    }
    let mut tail = 0.0;
    let mut k = b + 1;
    for j in (0..=b).rev() {
        tail += pmf[j];
        if tail > STOP_ERROR {
            break;
        }
        k = j;
    }
    k
}

/// True when the first replicates settle a form's decision: at least `stop_count` of them reach
/// the data's statistic (`lr[0]`) and the p-value of their gamma law is at least `alpha`, so the
/// form is not significant whatever Holm's step; its null is then those replicates.
pub fn clearly_null(lr: &[f64], df: f64, alpha: f64) -> bool {
    let Some((&data, reps)) = lr.split_first() else {
        return false;
    };
    let reached = reps.iter().filter(|x| **x >= data).count();
    reached >= stop_count(reps.len(), alpha)
        && NullFit::from_replicates(reps, df).p_value(data) >= alpha
}

/// What the screen found for one candidate.
#[derive(Clone, Debug)]
pub struct Screened {
    /// First-order χ² drop on the data, maximised over the form's trials.
    pub lr: f64,
    /// The same statistic on each noise replicate.
    pub replicates: Vec<f64>,
    /// Linear estimates of the term's parameters (in its own parameterization) and their
    /// standard errors (NaN where the trial grid, not a fit, set the value).
    pub estimate: Vec<f64>,
    pub se: Vec<f64>,
    /// A searched form's information about its size at its most sensitive trial (for its
    /// detection limit, `detection.rs`); None for a named term.
    pub typical: Option<Typical>,
    /// The statistic's law under the noise model, computed rather than sampled: for a named
    /// term with one secant (`secant`), whose statistic is a quadratic form in the Gaussian
    /// noise; None for a searched form or a maximum over trial scales.
    pub exact: Option<ExactNull>,
}

/// Secant columns of a named term: each parameter stepped from where the term vanishes; with
/// the statistic's law under the noise model (`ExactNull`).
fn secant(
    current: &Model,
    extra: &Extra,
    theta0: &[f64],
    steps: &[(usize, f64)],
    runs: &[RunData],
    prep: &[Prepared],
    null_pred: &[Vec<f64>],
    v: &Vectors,
) -> Option<(Trial, Option<ExactNull>)> {
    let spec = current.spec.with(extra.clone());
    let q = steps.len();
    // each run's columns (an integration per parameter) in parallel, summed in run order
    let cols: Vec<Vec<Vec<f64>>> = prep
        .par_iter()
        .map(|p| {
            let run = &runs[p.run];
            let l: &[f64; N_LOCAL] = &current.fit.local[p.run];
            steps
                .iter()
                .map(|&(j, to)| {
                    let mut g = current.fit.global.clone();
                    g.extend_from_slice(theta0);
                    let n0 = current.fit.global.len();
                    let d = to - theta0[j];
                    g[n0 + j] = to;
                    let mut z = vec![0.0; run.t_s.len()];
                    predict(&spec, &g, l, run, &mut z);
                    let kept: Vec<f64> = (0..run.t_s.len())
                        .filter(|&i| run.keep[i])
                        .map(|i| (z[i] - null_pred[p.run][i]) / d)
                        .collect();
                    p.column(kept)
                })
                .collect()
        })
        .collect();
    // a parameter starting at its bound may only move into its range
    let ps = extra.params();
    let sign: Vec<f64> = steps
        .iter()
        .map(|&(j, _)| {
            if theta0[j] <= ps[j].lo {
                1.0
            } else if theta0[j] >= ps[j].hi {
                -1.0
            } else {
                0.0
            }
        })
        .collect();
    let sums = coherent_sums(prep, v, q, 0..v.n_rep(), |p| Some(cols[p.run].clone()));
    let (lr, beta, var) = sums.solve(v, &sign)?;
    let exact = sums
        .null_moments(v, prep, runs, |p| Some(cols[p.run].as_slice()))
        .map(|(mean, var)| ExactNull {
            mean,
            var,
            one_sided: one_sided(q, &sign).is_some(),
        });
    let mut est = theta0.to_vec();
    let mut se = vec![f64::NAN; theta0.len()];
    for (a, &(j, _)) in steps.iter().enumerate() {
        est[j] = theta0[j] + beta[a];
        se[j] = var[a].sqrt();
    }
    Some(((lr, est, se), exact))
}

/// How a screen runs: the replicates drawn, their seed, the level of the decisions the first
/// batch may settle, and where progress is said.
pub struct Control<'a> {
    pub replicates: usize,
    pub seed: u64,
    pub alpha: f64,
    pub say: &'a (dyn Fn(&str) + Sync),
}

/// A named term's statistic on every replicate: along its secant, with its law under the noise
/// model (the friction law at a few trial scales, the best kept: a maximum, whose law is left to
/// the replicates).
fn named_trial(
    e: &Extra,
    current: &Model,
    runs: &[RunData],
    prep: &[Prepared],
    null_pred: &[Vec<f64>],
    v: &Vectors,
) -> (Option<Trial>, Option<ExactNull>) {
    if let Some(trials) = e.scale_trials() {
        let trials: Vec<Option<Trial>> = trials
            .par_iter()
            .map(|(theta0, steps)| {
                secant(current, e, theta0, steps, runs, prep, null_pred, v).map(
                    |((lr, _, se), _)| {
                        let mut est = theta0.clone();
                        for &(j, to) in steps {
                            est[j] = to;
                        }
                        (lr, est, vec![f64::NAN; se.len()])
                    },
                )
            })
            .collect();
        return (best_of(trials, v.n_rep()), None);
    }
    let ps = e.params();
    let theta0: Vec<f64> = ps.iter().map(|p| p.start).collect();
    let steps: Vec<(usize, f64)> = ps
        .iter()
        .enumerate()
        .map(|(j, p)| {
            let up = p.start + 100.0 * p.step;
            (
                j,
                if up <= p.hi {
                    up
                } else {
                    p.start - 100.0 * p.step
                },
            )
        })
        .collect();
    match secant(current, e, &theta0, &steps, runs, prep, null_pred, v) {
        Some((trial, exact)) => (Some(trial), exact),
        None => (None, None),
    }
}

/// A form's short name for the progress line (its form up to the formula).
fn short(e: &Extra) -> String {
    let f = e.form();
    f.split(':').next().unwrap_or(&f).to_string()
}

/// Screen `extras` against `current` (prepared in `prep`). A searched form first gets
/// `FIRST_BATCH` replicates and the rest only when `clearly_null` does not settle it; a named
/// term gets every replicate. Each candidate and batch is said through `ctl.say`.
pub fn screen(
    extras: &[&Extra],
    current: &Model,
    runs: &[RunData],
    prep: &[Prepared],
    rg: &Ranges,
    ctl: &Control,
) -> Vec<Option<Screened>> {
    let v = Vectors::new(prep, runs, ctl.replicates, ctl.seed);
    let nrep = v.n_rep();
    let null_pred: Vec<Vec<f64>> = runs
        .par_iter()
        .zip(&current.fit.local)
        .map(|(run, l)| {
            let mut z = vec![0.0; run.t_s.len()];
            predict(&current.spec, &current.fit.global, l, run, &mut z);
            z
        })
        .collect();
    let first = 0..(FIRST_BATCH + 1).min(nrep);
    let n = extras.len();
    let time = TimeMemo::default();
    extras
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let name = short(e);
            let clock = std::time::Instant::now();
            let (t, typical, exact) = if e.searched() {
                (ctl.say)(&format!(
                    "candidate {}/{n} {name}: replicates 0/{} done",
                    i + 1,
                    nrep - 1
                ));
                let search = |reps: Range<usize>| {
                    e.search(&Search {
                        prep,
                        v: &v,
                        rg,
                        reps,
                        time: &time,
                    })
                };
                let (t, typical) = search(first.clone());
                let t = t.map(|(mut lr, est, se)| {
                    let df = e.null_df(runs.len());
                    if first.end < nrep && !clearly_null(&lr, df, ctl.alpha) {
                        (ctl.say)(&format!(
                            "candidate {}/{n} {name}: replicates {}/{} done, not yet decided",
                            i + 1,
                            first.end - 1,
                            nrep - 1
                        ));
                        if let (Some((more, _, _)), _) = search(first.end..nrep) {
                            lr.extend(more);
                        }
                    }
                    (lr, est, se)
                });
                (t, typical, None)
            } else {
                (ctl.say)(&format!(
                    "candidate {}/{n} {name}: {} replicates",
                    i + 1,
                    nrep - 1
                ));
                let (t, exact) = named_trial(e, current, runs, prep, &null_pred, &v);
                (t, None, exact)
            };
            if std::env::var_os("GROOVE_DISCOVER_TRACE").is_some() {
                eprintln!("screen: {name} took {:.2} s", clock.elapsed().as_secs_f64());
            }
            t.map(|(lr, estimate, se)| Screened {
                lr: lr[0],
                replicates: lr[1..].to_vec(),
                estimate,
                se,
                typical,
                exact,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Binomial tail P(X ≥ k), X ~ Bin(b, p), summed term by term from the definition.
    fn tail(b: usize, p: f64, k: usize) -> f64 {
        let choose = |n: usize, r: usize| -> f64 {
            (0..r).map(|i| (n - i) as f64 / (i + 1) as f64).product()
        };
        (k..=b)
            .map(|j| choose(b, j) * p.powi(j as i32) * (1.0 - p).powi((b - j) as i32))
            .sum()
    }

    #[test]
    fn the_stop_count_is_the_smallest_with_a_tail_below_the_stated_error() {
        for (b, alpha) in [(20, 0.01), (20, 0.05), (30, 0.01), (12, 0.2)] {
            let k = stop_count(b, alpha);
            assert!(k <= b, "b {b} alpha {alpha}: some count must stop");
            assert!(tail(b, alpha, k) <= STOP_ERROR, "b {b} alpha {alpha} k {k}");
            assert!(
                tail(b, alpha, k - 1) > STOP_ERROR,
                "b {b} alpha {alpha} k {k}"
            );
        }
        // four of twenty at α = 0.01 (P(X ≥ 3) = 0.0010 is just above 0.1 %)
        assert_eq!(stop_count(20, 0.01), 4);
        // too few replicates for a lax level: never stop early
        assert_eq!(stop_count(5, 0.45), 6);
    }

    #[test]
    fn only_a_statistic_inside_its_null_stops_early() {
        // twenty replicates spread like a χ²₂ (quantiles at (i + 0.5)/20)
        let reps: Vec<f64> = (0..20)
            .map(|i| -2.0 * (1.0 - (i as f64 + 0.5) / 20.0).ln())
            .collect();
        let with = |data: f64| {
            let mut lr = vec![data];
            lr.extend(&reps);
            lr
        };
        // at the null's median: half the replicates reach it
        assert!(clearly_null(&with(1.4), 2.0, 0.01));
        // beyond all but three replicates: open, the second batch is drawn
        let third_largest = reps[17];
        assert!(!clearly_null(&with(third_largest + 1e-9), 2.0, 0.01));
        // far beyond every replicate
        assert!(!clearly_null(&with(40.0), 2.0, 0.01));
    }
}
