//! A tie decided again once the later terms are in the model.
//!
//! Two forms that held-out runs cannot tell apart in their round (a quadratic and a saturating
//! drag, say) are told apart by what is still missing then: a vibration not yet modelled adds
//! to every run's misfit alike and hides the small difference between the two shapes. After
//! the selection, each tied form is put in place of the accepted term it tied with, in the
//! final model, refitted and cross-validated; it is named instead where held-out runs prefer it
//! by the rule of its round (`forward::preferred`: a richer form only on a paired t above its
//! critical value, a simpler one where they cannot tell; of two as simple, one placed at a bound
//! only on such a t, else the one of lower held-out error). Both rows say what was
//! decided again and how, and a tie that stays is still said as one. A term accepted in the last
//! round was decided beside every other term already, and keeps its round's decision.

use super::admissible::refusal;
use super::cv::{paired_t, CvResult};
use super::estimates::{held_back, placed_at_bound};
use super::forward::{preferred, Side, CV_LEVEL, FULL_ITERATIONS};
use super::model::Model;
use super::selection::{Ctx, Selection, Tied};
use crate::stats::dist::t_upper_quantile;

/// Decide each tie of an earlier round again beside the terms accepted after it.
pub(super) fn redecide(sel: &mut Selection, ctx: &Ctx) {
    let ties = std::mem::take(&mut sel.ties);
    let Some(last_round) = sel.accepted.last().map(|a| a.row.evidence.round) else {
        return;
    };
    let t_cv = t_upper_quantile(CV_LEVEL, ctx.runs.len().saturating_sub(1) as f64);
    let mut by_term: Vec<(usize, Vec<Tied>)> = Vec::new();
    for t in ties {
        let Some(a) = sel.accepted.iter().position(|a| a.extra == t.with) else {
            // its term was removed by backward elimination: nothing to decide
            continue;
        };
        if sel.accepted[a].row.evidence.round == last_round {
            continue;
        }
        match by_term.iter_mut().find(|(b, _)| *b == a) {
            Some((_, v)) => v.push(t),
            None => by_term.push((a, vec![t])),
        }
    }
    for (a, tied) in by_term {
        decide(sel, a, tied, t_cv, ctx);
    }
}

/// Decide accepted term `a` against the forms it tied with, in the current model.
fn decide(sel: &mut Selection, a: usize, tied: Vec<Tied>, t_cv: f64, ctx: &Ctx) {
    let Some(i) = sel
        .current
        .spec
        .extras
        .iter()
        .position(|e| *e == sel.accepted[a].extra)
    else {
        return;
    };
    (ctx.say)(&format!(
        "deciding the tie of {} again beside the later terms",
        sel.accepted[a].extra.form()
    ));
    let old_cv = sel.current_cv.clone();
    let n_old = sel.accepted[a].extra.params().len();
    let old_pinned = held_back(&sel.current, i);
    // each tied form's paired t against the accepted term beside the later terms (None: refused)
    let mut outcome: Vec<Option<f64>> = vec![None; tied.len()];
    // (index into tied, model, its CV) of the form preferred so far; None: the accepted term
    let mut best: Option<(usize, Model, CvResult)> = None;
    for (k, t) in tied.iter().enumerate() {
        let m = sel.current.replaced(
            i,
            &t.alt.extra,
            &t.start,
            ctx.materials,
            ctx.runs,
            FULL_ITERATIONS,
        );
        if refusal(&m).is_some() {
            continue;
        }
        let cv = ctx.cross_validate(&m);
        outcome[k] = Some(paired_t(&old_cv, &cv));
        let kept = match &best {
            Some((b, bm, b_cv)) => Side {
                n: tied[*b].alt.extra.params().len(),
                cv: b_cv,
                pinned: held_back(bm, i),
            },
            None => Side {
                n: n_old,
                cv: &old_cv,
                pinned: old_pinned,
            },
        };
        let new = Side {
            n: t.alt.extra.params().len(),
            cv: &cv,
            pinned: held_back(&m, i),
        };
        if preferred(new, kept, t_cv) {
            best = Some((k, m, cv));
        }
    }
    let round = sel.accepted[a].row.evidence.round;
    let flagged = flagged_suffix(&sel.accepted[a].row.evidence.decision);
    for (k, t) in tied.iter().enumerate() {
        if best.as_ref().is_some_and(|b| b.0 == k) {
            continue;
        }
        let note = match outcome[k] {
            None => "; decided again beside the later terms: refused there".to_string(),
            Some(t) if t.abs() <= t_cv => format!("; decided again beside the later terms: still a tie (paired t = {t:.2})"),
            Some(t) => format!("; decided again beside the later terms: held-out runs tell the two apart there (paired t = {t:.2})"),
        };
        let mut row = t.alt.row.clone();
        row.evidence.decision.push_str(&note);
        set_row(sel, &row);
    }
    let Some((k, model, cv)) = best else {
        let still: Vec<String> = tied
            .iter()
            .zip(&outcome)
            .filter(|(_, o)| o.is_some_and(|t| t.abs() <= t_cv))
            .map(|(t, _)| t.alt.extra.form())
            .collect();
        let row = &mut sel.accepted[a].row;
        let head = row
            .evidence
            .decision
            .split("; tied with ")
            .next()
            .unwrap_or_default()
            .to_string();
        row.evidence.decision = if still.is_empty() {
            format!("{head}; tied in its round, and told apart beside the later terms: held-out runs tell it from the forms it tied with there, or those are refused there (each one's row says which){flagged}")
        } else {
            format!("{head}; tied with {}: these data cannot tell them apart, beside the later terms too, and this one (simpler, stronger, inside its bounds, physical at every speed or of lower held-out error) is in the model{flagged}", still.join(" and "))
        };
        let row = row.clone();
        set_row(sel, &row);
        return;
    };
    let new = tied.into_iter().nth(k).expect("a tied form");
    let t_new = outcome[k].unwrap_or(f64::NAN);
    let old_form = sel.accepted[a].extra.form();
    let new_form = new.alt.extra.form();
    let why = match new.alt.extra.params().len().cmp(&n_old) {
        std::cmp::Ordering::Less => "simpler",
        _ if old_pinned && placed_at_bound(&sel.current, i) && !held_back(&model, i) => {
            "as simple and inside its bounds where the other ran to one"
        }
        _ if old_pinned && !held_back(&model, i) => {
            "as simple and physical at every speed where the other is only over the runs' speeds"
        }
        _ => "as simple and of lower held-out error",
    };
    let mut alt = new.alt;
    alt.row.accepted = true;
    let mut old = std::mem::replace(&mut sel.accepted[a], alt);
    old.row.accepted = false;
    let (acc, rej) = swap_words(round, &old_form, &new_form, t_new, t_cv, why, &flagged);
    sel.accepted[a].row.evidence.decision = acc;
    old.row.evidence.decision = rej;
    let row = sel.accepted[a].row.clone();
    set_row(sel, &row);
    set_row(sel, &old.row);
    sel.current = model;
    sel.current_cv = cv;
}

/// The decisions of a tied form named in place of the term accepted in `round` (the new term's,
/// the old one's), with the new form's paired t `t` over the old beside the later terms: a tie
/// that stays is said with "tied with" (which the report reads), one told apart is not.
fn swap_words(
    round: usize,
    old_form: &str,
    new_form: &str,
    t: f64,
    t_cv: f64,
    why: &str,
    flagged: &str,
) -> (String, String) {
    if t > t_cv {
        (
            format!("accepted: in round {round} held-out runs could not tell it from {old_form}, which was named; beside the later terms it predicts them better (paired t = {t:.2}) and is named instead{flagged}"),
            format!("rejected: accepted in round {round}, but beside the later terms {new_form} in its place predicts held-out runs better (paired t = {t:.2}) and is named instead"),
        )
    } else {
        (
            format!("accepted: decided again beside the later terms; tied with {old_form}: these data cannot tell them apart (paired t = {t:.2}, within its critical value {t_cv:.2}), and this one ({why}) is in the model{flagged}"),
            format!("tie: accepted in round {round}; beside the later terms {new_form} in its place predicts held-out runs as well (paired t = {t:.2}, within its critical value {t_cv:.2}): these data cannot tell the two apart, and {new_form} ({why}) is in the model"),
        )
    }
}

/// The " (flagged by N probe(s))" an accepted decision ends with, or nothing.
fn flagged_suffix(decision: &str) -> String {
    decision
        .rfind(" (flagged by ")
        .map(|at| decision[at..].to_string())
        .unwrap_or_default()
}

/// Write `row` over its entry in the candidate table.
fn set_row(sel: &mut Selection, row: &crate::artifacts::diagnosis::CandidateRow) {
    if let Some(r) = find(sel, row) {
        *r = row.clone();
    }
}

/// `row`'s entry in the candidate table: its round, effect and form.
fn find<'a>(
    sel: &'a mut Selection,
    row: &crate::artifacts::diagnosis::CandidateRow,
) -> Option<&'a mut crate::artifacts::diagnosis::CandidateRow> {
    sel.table.iter_mut().find(|r| {
        r.evidence.round == row.evidence.round && r.effect == row.effect && r.form == row.form
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cv(per_run: &[f64]) -> CvResult {
        CvResult {
            cv_rms_m: per_run.iter().sum::<f64>() / per_run.len() as f64,
            per_run_msn: per_run.to_vec(),
        }
    }

    /// The rule a tie is decided by: a richer form only where held-out runs prefer it beyond
    /// the critical value, a simpler one unless they prefer the richer so, of two as simple the
    /// lower held-out error however small the difference.
    #[test]
    fn a_richer_form_needs_the_runs_a_simpler_one_a_tie_an_equal_one_the_lower_error() {
        let t_cv = 1.7;
        let old = cv(&[1.0, 1.1, 0.9, 1.05, 0.95, 1.0]);
        // a little better in every run but one: paired t well above 1.7
        let clearly = cv(&[0.9, 1.0, 0.8, 0.95, 0.85, 1.01]);
        // better on average by a hair, worse in half the runs: paired t below 1.7
        let hair = cv(&[0.99, 1.12, 0.88, 1.06, 0.94, 0.99]);
        assert!(paired_t(&old, &clearly) > t_cv && paired_t(&old, &hair).abs() < t_cv);
        assert!(hair.cv_rms_m < old.cv_rms_m);
        let side = |n: usize, cv, pinned: bool| Side { n, cv, pinned };
        let free = |n: usize, cv| side(n, cv, false);
        assert!(preferred(free(3, &clearly), free(2, &old), t_cv));
        assert!(!preferred(free(3, &hair), free(2, &old), t_cv));
        assert!(preferred(free(1, &hair), free(2, &old), t_cv));
        assert!(!preferred(free(1, &old), free(2, &clearly), t_cv));
        assert!(preferred(free(2, &hair), free(2, &old), t_cv));
        assert!(!preferred(free(2, &old), free(2, &hair), t_cv));
        // of two as simple, one with a parameter at a bound needs the runs, and the other is
        // named unless the runs prefer the pinned one: a hair's lower error does not decide
        assert!(!preferred(side(2, &hair, true), free(2, &old), t_cv));
        assert!(preferred(free(2, &old), side(2, &hair, true), t_cv));
        assert!(preferred(side(2, &clearly, true), free(2, &old), t_cv));
        assert!(!preferred(free(2, &old), side(2, &clearly, true), t_cv));
        // both pinned: the lower error, as between two free ones
        assert!(preferred(side(2, &hair, true), side(2, &old, true), t_cv));
    }

    /// A tie that stays is said so that the report names the form it tied with; one told apart
    /// is said without "tied with", so the report says no tie.
    #[test]
    fn a_swap_within_the_critical_value_is_still_said_as_a_tie() {
        let (old, new) = (
            "quadratic: a = -v/T - c v|v|",
            "saturating: a = -v/(T0 + T'|v|)",
        );
        let (acc, rej) = swap_words(
            1,
            old,
            new,
            0.4,
            1.67,
            "as simple",
            " (flagged by 2 probe(s))",
        );
        let named = acc
            .split("tied with ")
            .nth(1)
            .and_then(|r| r.split(':').next());
        assert_eq!(named, Some("quadratic"), "{acc}");
        assert!(
            acc.contains("cannot tell") && acc.ends_with("(flagged by 2 probe(s))"),
            "{acc}"
        );
        assert!(
            rej.starts_with("tie:") && rej.contains("cannot tell"),
            "{rej}"
        );
        let (acc, rej) = swap_words(1, old, new, 2.5, 1.67, "as simple", "");
        assert!(
            !acc.contains("tied with ") && acc.contains("predicts them better"),
            "{acc}"
        );
        assert!(
            rej.starts_with("rejected:") && !rej.contains("cannot tell"),
            "{rej}"
        );
    }

    #[test]
    fn the_flagged_probes_are_carried_over() {
        assert_eq!(
            flagged_suffix("accepted: x; tied with y: z (flagged by 3 probe(s))"),
            " (flagged by 3 probe(s))"
        );
        assert_eq!(flagged_suffix("accepted: x"), "");
    }
}
