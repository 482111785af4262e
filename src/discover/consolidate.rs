//! One cause, one term: the named forces of one variable that a force map in it outpredicts
//! are replaced by the map.
//!
//! Forward selection adds named forms one at a time, so a force along the groove with no named
//! shape (a field of several wavelengths, a step) comes out as a tilt, a wave and a bump
//! together, and a force that rises and falls with speed as a drag. After the selection, for z
//! and for v in turn, the accepted forces of that variable (`Form::map_variable`: forces fixed
//! in the lab and the tilt, their mean, for z; drags and a resistance for v) are set aside with
//! any fallback map of the same variable; the force map of what is left is fitted in their place
//! as a spline and screened and cross-validated like any candidate. It replaces them when it
//! predicts held-out runs better than they do, by a paired t over the runs above its one-sided
//! 1 % critical value (a term is added at 5 %: the map has more freedom, and the forms it would
//! replace passed every test); where the named forms predict as well the simpler stay, and the
//! forms say the tie. Without a fallback map beside them, the map of what the model with the
//! forms leaves in that variable is screened first: when it is not significant even at 5 %, the
//! map in their place (to first order, the forms plus that map) could not predict better, and
//! it is not fitted (the forms say so). When a fallback map of that variable stood beside them,
//! the map alone replaces the two when it predicts held-out runs as well as both (paired t of
//! both over it within its 5 % critical value); otherwise, in z, the forms and the map are one
//! force along the groove (a wave shorter than the map's knots can follow, say, beside it) and
//! are reported so: one finding whose size is their sum's where the runs go, the forms its parts
//! (in the model, not findings). Held-out runs judge the map against the model with the forms;
//! only beside a fallback map is the model without them cross-validated. The map's fit in full starts from the force the forms give (on its basis)
//! plus what they leave, not from the map linearized about trajectories without them.

use super::candidate::Extra;
use super::cv::paired_t;
use super::data::RunData;
use super::forcemap::ForceMap;
use super::forms;
use super::forward::{run_round, screen_p, LazyProposals, CV_LEVEL};
use super::model::Model;
use super::selection::{Accepted, Ctx, Selection};
use crate::artifacts::diagnosis::Estimate;
use crate::physics::{Term, Variable};
use crate::stats::dist::t_upper_quantile;
use std::collections::BTreeMap;

/// One-sided level of the paired t at which a map replaces named forms that passed.
pub const REPLACE_LEVEL: f64 = 0.01;

/// Tries, for z and then v, the map in place of the accepted forces of that variable; returns
/// the map accepted last (or the fallback, unchanged) and the force maps of the final model.
pub(super) fn consolidate(
    sel: &mut Selection,
    fallback: Option<Accepted>,
    maps: Vec<ForceMap>,
    ctx: &Ctx,
) -> (Option<Accepted>, Vec<ForceMap>) {
    if !ctx.opts.nonparametric {
        return (fallback, maps);
    }
    let (mut fallback, mut changed) = (fallback, false);
    for var in [Variable::Z, Variable::V] {
        let group: Vec<usize> = (0..sel.accepted.len())
            .filter(|&a| sel.accepted[a].extra.map_variable() == Some(var))
            .collect();
        if group.is_empty() {
            continue;
        }
        let beside = fallback
            .as_ref()
            .is_some_and(|f| f.extra.map_variable() == Some(var));
        // the force maps of the current model, while no replacement has changed it
        let now = (!changed).then_some(maps.as_slice());
        let replaced = replace(
            sel,
            &group,
            fallback.as_ref().filter(|_| beside),
            var,
            now,
            ctx,
        );
        if replaced.is_none() && beside && var == Variable::Z {
            let map = fallback.as_mut().expect("the fallback beside the forms");
            absorb(sel, &group, map);
            continue;
        }
        if let Some(map) = replaced {
            if beside {
                let mut gone = fallback.take().expect("the fallback beside the forms");
                gone.row.accepted = false;
                gone.row.evidence.decision = format!(
                    "replaced by the map in {} fitted in place of it and the named forms beside it",
                    var_name(var)
                );
                sel.removed.push(gone);
            } else if let Some(f) = fallback.take() {
                // a map of another variable stays: it is in the current model
                sel.accepted.push(f);
            }
            fallback = Some(map);
            changed = true;
        }
    }
    if !changed {
        return (fallback, maps);
    }
    let after = ctx.force_maps(&sel.current).maps;
    (fallback, after)
}

fn var_name(var: Variable) -> &'static str {
    match var {
        Variable::Z => "z",
        Variable::V => "v",
        Variable::T => "t",
    }
}

/// The current model without the extras `drop` (refitted after each removal, from the values
/// before it).
fn without_all(current: &Model, drop: &[&Extra], ctx: &Ctx) -> Model {
    let mut m = current.clone();
    for e in drop {
        if let Some(i) = m.spec.extras.iter().position(|x| x == *e) {
            m = m.without(i, ctx.materials, ctx.runs, 40);
        }
    }
    m
}

/// The map in `var` fitted in place of accepted terms `group` (and of `beside`, a fallback map
/// of the same variable): when it replaces them, they move to the removed terms, the model
/// becomes the map's, and the map's accepted term is returned.
fn replace(
    sel: &mut Selection,
    group: &[usize],
    beside: Option<&Accepted>,
    var: Variable,
    maps_now: Option<&[ForceMap]>,
    ctx: &Ctx,
) -> Option<Accepted> {
    let fresh;
    let now = match maps_now {
        Some(m) => m,
        None => {
            fresh = ctx.force_maps(&sel.current).maps;
            &fresh
        }
    };
    // the round's number (its replicates' seed) is taken whether or not the map is fitted
    sel.round += 1;
    if beside.is_none() {
        let left = now
            .iter()
            .find(|m| m.variable == var_name(var))
            .and_then(|m| forms::Spline::on(m, var));
        if let Some(left) = left {
            let p = screen_p(sel.round, &sel.current, &Extra::from(left), &ctx.setting());
            if p >= CV_LEVEL {
                say_nothing_left(sel, group, var, p);
                return None;
            }
        }
    }
    let mut drop: Vec<&Extra> = group.iter().map(|&a| &sel.accepted[a].extra).collect();
    drop.extend(beside.map(|b| &b.extra));
    let base = without_all(&sel.current, &drop, ctx);
    let mut props = ctx.force_maps(&base);
    let map = props
        .maps
        .iter_mut()
        .find(|m| m.variable == var_name(var) && m.spline.is_some())?;
    let form = forms::Spline::on(map, var)?;
    if let (Some(start), Some(sp)) = (
        start_in_place(&form, &sel.current, &base, now, var, ctx),
        map.spline.as_mut(),
    ) {
        sp.3 = start;
    }
    let spline = Extra::from(form);
    // held-out runs judge the map against the model with the forms it would replace; beside a
    // fallback map of its variable, against the model without either (the map alone must then
    // predict as well as both), the only case that cross-validates that model
    let judge_cv = match beside {
        Some(_) => ctx.cross_validate(&base),
        None => sel.current_cv.clone(),
    };
    let r = run_round(
        sel.round,
        &base,
        &judge_cv,
        std::slice::from_ref(&spline),
        &[],
        &LazyProposals::ready(props),
        &ctx.setting(),
    );
    let names: Vec<String> = drop.iter().map(|e| e.form()).collect();
    let names = names.join("; ");
    let mut rows = r.rows.clone();
    let df = ctx.runs.len().saturating_sub(1) as f64;
    let (crit5, crit1) = (
        t_upper_quantile(CV_LEVEL, df),
        t_upper_quantile(REPLACE_LEVEL, df),
    );
    let place = format!("a map in {} fitted in place of {names}", var_name(var));
    // held-out runs judged the map against the model with the forms (`run_round`'s 5 % test)
    let Some((i, model, cv)) = r.accepted else {
        let t = rows.first().and_then(|row| row.evidence.cv_paired_t);
        for row in &mut rows {
            row.evidence.decision = format!("{} — tried as {place}", row.evidence.decision);
        }
        sel.table.extend(rows);
        if let (None, Some(t)) = (beside, t) {
            if t.abs() <= crit5 {
                // neither predicts held-out runs better: a tie, said on the forms that stay
                for &a in group {
                    sel.accepted[a].row.evidence.decision.push_str(&format!(
                        "; tied with a map in {v} of no named shape: {place} predicts held-out runs as well (paired t {t:.2}, within {crit5:.2}), so these data cannot tell the named form{} from a force of {v} with no named shape, and the named, simpler, is kept",
                        if group.len() > 1 { "s" } else { "" },
                        v = var_name(var)
                    ));
                }
            }
        }
        return None;
    };
    let t_gain = paired_t(&sel.current_cv, &cv);
    let (replaces, why) = if beside.is_some() {
        let t_loss = paired_t(&cv, &sel.current_cv);
        (
            t_loss <= crit5,
            format!(
                "the map alone predicts held-out runs as well as the map and the named forms together (paired t of both over the map {t_loss:.2}, within {crit5:.2})"
            ),
        )
    } else {
        (
            t_gain > crit1,
            format!(
                "the map predicts held-out runs better than the named forms (paired t {t_gain:.2}, above its 1 % critical value {crit1:.2})"
            ),
        )
    };
    if !replaces {
        rows[i].accepted = false;
        rows[i].evidence.decision = match beside {
            Some(_) => format!(
                "not kept: {place} and the map beside them predicts held-out runs worse alone than they do together (paired t {:.2}, above {crit5:.2}); they stay",
                paired_t(&cv, &sel.current_cv)
            ),
            None => format!(
                "not kept: {place} predicts held-out runs better than they do (paired t {t_gain:.2}), but not beyond the 1 % critical value {crit1:.2} a map needs to replace named forms that passed; the named forms, simpler, stand"
            ),
        };
        sel.table.extend(rows);
        return None;
    }
    rows[i].evidence.decision =
        format!("accepted in place of {names}: {why}; no named form has this shape");
    sel.table.extend(rows.iter().cloned());
    let before = sel.current.score(ctx.runs, Some(&sel.current_cv));
    let after = model.score(ctx.runs, Some(&cv));
    for &a in group.iter().rev() {
        let mut gone = sel.accepted.remove(a);
        gone.row.accepted = false;
        gone.row.evidence.decision = format!("replaced by a map in {}: {why}", var_name(var));
        sel.removed.push(gone);
    }
    sel.current = model;
    sel.current_cv = cv;
    Some(Accepted {
        row: rows[i].clone(),
        before,
        after,
        probes_after: vec![],
        null: r.nulls[i].clone(),
        extra: spline,
    })
}

/// The map in `var` is not fitted in place of the forms `group` when the map of what the model
/// with them leaves in `var`, screened as a candidate, is not significant even at `CV_LEVEL`
/// (p-value `p`): to first order the map in their place is the forms plus that map, so it could
/// not predict held-out runs better than they do at the 1 % a map needs to replace named forms.
/// Said on each form.
fn say_nothing_left(sel: &mut Selection, group: &[usize], var: Variable, p: f64) {
    for &a in group {
        sel.accepted[a].row.evidence.decision.push_str(&format!(
            "; no map in {v} was fitted in its place: a map in {v} of what the model leaves is not significant (p = {p:.2}), so to first order a map in place of the named form{s} could predict held-out runs no better",
            v = var_name(var),
            s = if group.len() > 1 { "s" } else { "" }
        ));
    }
}

/// Where a fit in full of the map in place of named forms starts: the force those forms give
/// beyond what the model without them keeps (the two models' accelerations apart, on the map's
/// basis), plus the map of what the model with them leaves (`maps_now`). The map of the model
/// without them is the same force linearized about trajectories without it: for a strong
/// force (a drag that halves the speeds) it starts far off, and the fit took tens of
/// iterations. None when the two cannot be evaluated on the map's basis.
fn start_in_place(
    form: &forms::Spline,
    with: &Model,
    without: &Model,
    maps_now: &[ForceMap],
    var: Variable,
    ctx: &Ctx,
) -> Option<Vec<f64>> {
    let v0 = super::forward::median_speed(&with.fit.local);
    let z_mid = 0.5 * (ctx.rg.z_lo + ctx.rg.z_hi);
    let physics = |m: &Model| m.spec.sim_model(&m.fit.global, 0, v0).to_physics();
    let (a, b) = (physics(with), physics(without));
    let at = |m: &crate::physics::Model, x: f64| match var {
        Variable::Z => m.accel(x, 0.0, 0.0),
        Variable::V => m.accel(z_mid, x, 0.0),
        Variable::T => m.accel(z_mid, 0.0, x),
    };
    let mut start = form.projected(&|x| at(&a, x) - at(&b, x), form.segments)?;
    let left = maps_now
        .iter()
        .find(|m| m.variable == var_name(var))
        .and_then(|m| m.spline.as_ref())
        .and_then(|(lo, dx, segments, coefs, _)| form.resampled(*lo, *dx, *segments, coefs));
    if let Some(left) = left {
        start.iter_mut().zip(&left).for_each(|(s, l)| *s += l);
    }
    start.iter().all(|c| c.is_finite()).then_some(start)
}

/// Reports accepted terms `group` (forces of z) as parts of one field in z with `map`, the map
/// in z accepted beside them: they stay in the model and leave the findings.
fn absorb(sel: &mut Selection, group: &[usize], map: &mut Accepted) {
    let names: Vec<String> = group
        .iter()
        .map(|&a| sel.accepted[a].extra.form())
        .collect();
    let names = names.join("; ");
    for &a in group.iter().rev() {
        let mut part = sel.accepted.remove(a);
        part.row.accepted = false;
        part.row.evidence.decision = format!(
            "{}; part of one field in z: a map in z then took up what the named forms left, so the force along the groove has no single named shape and is reported once, as the field",
            part.row.evidence.decision
        );
        sel.parts.push(part);
    }
    map.row.form = format!("{}; with {names}: one field in z, their sum", map.row.form);
    map.row.evidence.decision = format!(
        "{}; the named forms in z accepted before it are its parts: one force along the groove with no single named shape, sized as their sum",
        map.row.evidence.decision
    );
}

/// The whole field in z of `model` at `z`: the tilt, the waves, bumps and map in z.
fn field_in_z(m: &super::sim::SimModel, z: f64) -> f64 {
    let waves: f64 = m
        .position
        .iter()
        .map(|(a, k, ph)| a * (k * z + ph).sin())
        .sum();
    let terms: f64 = m
        .terms
        .iter()
        .filter(|t| match t {
            Term::LocalizedForce { .. } | Term::PositionForce { .. } | Term::StepForce { .. } => {
                true
            }
            Term::Spline(s) => s.variable == Variable::Z,
            _ => false,
        })
        .map(|t| t.accel(z, 0.0, 0.0))
        .sum();
    m.tilt_mps2 + waves + terms
}

/// The size of the field in z where the runs go (peak, where, RMS, covered fraction), replacing
/// the map's own in `out`, when `map` is a map in z with parts.
pub(super) fn field_size(
    sel: &Selection,
    map: &Extra,
    runs: &[RunData],
    out: &mut BTreeMap<String, Estimate>,
) {
    let Extra::Spline(sp) = map else {
        return;
    };
    if sp.variable != Variable::Z || sel.parts.is_empty() {
        return;
    }
    let m = &sel.current;
    let sim = m.spec.sim_model(&m.fit.global, 0, 0.0);
    // the field's gradient in every global, by central differences a thousandth of each
    // global's standard error wide (the field is linear in its amplitudes, smooth in the rest)
    let shifted: Vec<Option<(super::sim::SimModel, super::sim::SimModel, f64)>> =
        (0..m.fit.global.len())
            .map(|i| {
                let h = 1e-3 * m.fit.global_se.get(i).copied().unwrap_or(0.0);
                (h.is_finite() && h > 0.0).then(|| {
                    let mut g = m.fit.global.clone();
                    g[i] += h;
                    let up = m.spec.sim_model(&g, 0, 0.0);
                    g[i] -= 2.0 * h;
                    (up, m.spec.sim_model(&g, 0, 0.0), h)
                })
            })
            .collect();
    let grad = |z: f64| -> Vec<f64> {
        shifted
            .iter()
            .map(|s| {
                s.as_ref().map_or(0.0, |(up, down, h)| {
                    (field_in_z(up, z) - field_in_z(down, z)) / (2.0 * h)
                })
            })
            .collect()
    };
    sp.size_over_runs(
        &|z| field_in_z(&sim, z),
        &grad,
        &m.fit.global_cov,
        runs,
        out,
    );
}
