//! What a finished term selection reports: its findings (with where the model missed and what
//! the drift probes said), the per-run drift before and after, and the parameters by name.

use super::candidate::Spec;
use super::data::RunData;
use super::drift::line;
use super::estimates::{bound_notes, reported_parameters};
use super::forward::finding;
use super::model::Model;
use super::perrun::{fit_each_run, PerRunFit};
use super::residual_structure::Structure;
use super::selection::{Accepted, Ctx, Selection};
use crate::artifacts::diagnosis::{CandidateRow, Drift, DriftPoint, Estimate, Finding, ModelScore};
use crate::artifacts::estimate::stderr;
use serde_json::json;
use std::collections::BTreeMap;

fn drift_points(runs: &[RunData], fits: &[PerRunFit], materials: &[String]) -> Vec<DriftPoint> {
    runs.iter()
        .zip(fits)
        .map(|(r, f)| DriftPoint {
            run: r.run.clone(),
            material: materials[r.material].clone(),
            v0_mps: f.local[2],
            t_s: f.t_s,
            mu: f.mu,
            z0_m: f.local[0],
        })
        .collect()
}

fn drift_lines(
    points: &[DriftPoint],
    materials: &[String],
) -> BTreeMap<String, super::drift::Line> {
    let mut out = BTreeMap::new();
    for m in materials {
        let p: Vec<&DriftPoint> = points.iter().filter(|p| &p.material == m).collect();
        let v: Vec<f64> = p.iter().map(|p| p.v0_mps.abs()).collect();
        let dir: Vec<f64> = p.iter().map(|p| p.v0_mps.signum()).collect();
        let z0: Vec<f64> = p.iter().map(|p| p.z0_m).collect();
        let t: Vec<f64> = p.iter().map(|p| p.t_s).collect();
        let mu: Vec<f64> = p.iter().map(|p| p.mu).collect();
        for (name, x, y) in [
            ("t_s vs |v0|", &v, &t),
            ("mu vs |v0|", &v, &mu),
            ("t_s vs direction", &dir, &t),
            ("mu vs direction", &dir, &mu),
            ("t_s vs z0", &z0, &t),
            ("mu vs z0", &z0, &mu),
        ] {
            if let Some(l) = line(x, y) {
                out.insert(format!("{name} ({m})"), l);
            }
        }
    }
    out
}

/// A bin names where the model misses only if it holds at least this share of its group's
/// samples: a position bin the runs cross in a handful of frames (6 of 57,000 on the shipped
/// data, 14× noise) says where a fit's tail wanders, not where physics is missing.
const MIN_BIN_SHARE: f64 = 0.01;

/// The bins where the model misses most (largest RMS over noise; with their mean residual z),
/// among bins holding at least `MIN_BIN_SHARE` of their group's samples.
fn worst_bins(s: &Structure) -> serde_json::Value {
    let mut all: Vec<(String, f64, f64)> = Vec::new();
    for (group, bins) in [
        ("phase", &s.by_phase),
        ("speed", &s.by_speed),
        ("position", &s.by_position),
        ("direction", &s.by_direction),
        ("material", &s.by_material),
    ] {
        let total: usize = bins.values().map(|b| b.n).sum();
        for (k, b) in bins {
            if (b.n as f64) < MIN_BIN_SHARE * total as f64 {
                continue;
            }
            all.push((format!("{group} {k}"), b.mean_z, b.rms_over_noise));
        }
    }
    all.sort_by(|a, b| b.2.total_cmp(&a.2).then(a.0.cmp(&b.0)));
    let top: Vec<serde_json::Value> = all
        .iter()
        .take(4)
        .map(|(k, z, r)| json!({"bin": k, "mean_z": z, "rms_over_noise": r}))
        .collect();
    json!({"largest_residuals": top, "runs_test_z": s.runs_test_z, "lag1_autocorrelation": s.lag1_autocorrelation})
}

fn probes_json(rows: &[CandidateRow]) -> serde_json::Value {
    let v: Vec<serde_json::Value> = rows
        .iter()
        .map(|r| json!({"probe": r.form, "p_holm": r.evidence.p_holm, "lr": r.evidence.lr, "parameters": stderr::map::shaped(&r.parameters)}))
        .collect();
    serde_json::Value::Array(v)
}

/// Per-run fits before and after: each run's own μ and T, with the final model's extra terms
/// held at their joint values in `after`.
pub(super) fn drift_of(current: &Model, per_run: &[PerRunFit], ctx: &Ctx) -> Drift {
    let (runs, materials) = (ctx.runs, ctx.materials);
    let extra_values: Vec<f64> = current.fit.global[2 * materials.len()..].to_vec();
    let after_fits = fit_each_run(
        runs,
        &current.spec,
        &current.params,
        &extra_values,
        Some(per_run),
    );
    let before_pts = drift_points(runs, per_run, materials);
    let after_pts = drift_points(runs, &after_fits, materials);
    Drift {
        lines_before: drift_lines(&before_pts, materials),
        lines_after: drift_lines(&after_pts, materials),
        before: before_pts,
        after: after_pts,
        note: "per-run fits (own mu and T; extra terms held at the joint values in `after`); the fitted |v0| shares errors with T and mu, so the probes fitted inside the joint model carry the decision".into(),
    }
}

/// The findings: the accepted terms (and the fallback), a mismatch left unexplained, the terms
/// removed by backward elimination, and the candidates of the last round. An accepted term's
/// parameters are those of the final model, where every accepted term is fitted jointly (the
/// round that accepted it fitted it without the terms accepted later, which may share its
/// signature: a rolling resistance accepted before a quadratic drag reads 40 % low there).
pub(super) fn findings_of(
    sel: &Selection,
    fallback: Option<&Accepted>,
    residuals: [&Structure; 2],
    final_score: &ModelScore,
    ctx: &Ctx,
) -> Vec<Finding> {
    let [residuals_before, residuals_after] = residuals;
    let mut findings: Vec<Finding> = Vec::new();
    for acc in sel.accepted.iter().chain(fallback) {
        let mut row = acc.row.clone();
        let mut w = BTreeMap::new();
        if let Some(i) = sel.current.spec.extras.iter().position(|e| *e == acc.extra) {
            row.parameters = reported_parameters(&sel.current, i, ctx.materials, ctx.runs);
            super::consolidate::field_size(sel, &acc.extra, ctx.runs, &mut row.parameters);
            let notes = bound_notes(&sel.current, i, ctx.materials);
            if !notes.is_empty() {
                w.insert("at_bound".to_string(), serde_json::json!(notes));
            }
        }
        let flagged: Vec<CandidateRow> = sel
            .table
            .iter()
            .filter(|t| t.round == acc.row.evidence.round && t.effect == "probe")
            .cloned()
            .collect();
        w.insert("drift_probes_before".to_string(), probes_json(&flagged));
        w.insert(
            "drift_probes_after".to_string(),
            probes_json(&acc.probes_after),
        );
        w.insert("residuals_before".to_string(), worst_bins(residuals_before));
        findings.push(finding(&row, acc.before.clone(), acc.after.clone(), w));
    }
    if !sel.unexplained.is_empty() && fallback.is_none() {
        findings.push(unexplained_finding(
            &sel.unexplained,
            residuals_after,
            final_score,
        ));
    }
    for acc in &sel.parts {
        // a part of a field is still in the model: its values are the final fit's
        let mut row = acc.row.clone();
        if let Some(i) = sel.current.spec.extras.iter().position(|e| *e == acc.extra) {
            row.parameters = reported_parameters(&sel.current, i, ctx.materials, ctx.runs);
        }
        let mut w = BTreeMap::new();
        w.insert("part_of".to_string(), serde_json::json!("field in z"));
        findings.push(finding(&row, acc.before.clone(), acc.after.clone(), w));
    }
    for acc in &sel.removed {
        let mut w = BTreeMap::new();
        w.insert("drift_probes".to_string(), probes_json(&acc.probes_after));
        findings.push(finding(&acc.row, acc.before.clone(), acc.after.clone(), w));
    }
    for row in &sel.last_rows {
        let mut w = BTreeMap::new();
        w.insert("drift_probes".to_string(), probes_json(&sel.last_probes));
        findings.push(finding(
            row,
            final_score.clone(),
            ModelScore {
                cv_rms_m: row.evidence.cv_rms_m.unwrap_or(f64::NAN),
                ..Default::default()
            },
            w,
        ));
    }
    findings
}

/// A mismatch the drift probes flag and no term explained: not modelled, so not accepted.
fn unexplained_finding(
    unexplained: &[CandidateRow],
    residuals_after: &Structure,
    final_score: &ModelScore,
) -> Finding {
    let strongest = unexplained
        .iter()
        .max_by(|a, b| a.evidence.lr.total_cmp(&b.evidence.lr))
        .expect("non-empty");
    let mut w = BTreeMap::new();
    w.insert("drift_probes".to_string(), probes_json(unexplained));
    w.insert("residuals".to_string(), worst_bins(residuals_after));
    let mut parameters = BTreeMap::new();
    for r in unexplained {
        for (k, v) in &r.parameters {
            parameters.insert(k.clone(), *v);
        }
    }
    Finding {
        effect: "unexplained".into(),
        accepted: false,
        form: unexplained
            .iter()
            .map(|r| r.form.clone())
            .collect::<Vec<_>>()
            .join("; "),
        parameters,
        evidence: strongest.evidence.clone(),
        where_: w,
        baseline: final_score.clone(),
        extended: ModelScore {
            cv_rms_m: f64::NAN,
            ..final_score.clone()
        },
    }
}

/// The final model's global parameters with their standard errors, by name. Two terms may
/// name a parameter alike (a bump's and a vibration's `amplitude_mps2`, two waves' `k_per_m`):
/// the first keeps the name, a later one is named `name.effect` (`name.effect.i` with the
/// term's index if that is taken too), so that no parameter is lost.
pub(super) fn model_parameters(current: &Model) -> BTreeMap<String, Estimate> {
    let names: Vec<&str> = current.params.iter().map(|p| p.name.as_str()).collect();
    unique_parameter_names(&current.spec, &names)
        .into_iter()
        .zip(current.fit.global.iter().zip(&current.fit.global_se))
        .map(|(name, (v, se))| (name, Estimate::new(*v, *se)))
        .collect()
}

/// `names` (the global parameters of `spec`, in layout order) made unique as
/// `model_parameters` says.
fn unique_parameter_names(spec: &Spec, names: &[&str]) -> Vec<String> {
    // which extra term each global parameter belongs to (None: μ and T of a material)
    let mut owner: Vec<Option<usize>> = vec![None; 2 * spec.n_materials];
    for (i, e) in spec.extras.iter().enumerate() {
        owner.extend(std::iter::repeat_n(Some(i), e.params().len()));
    }
    let mut taken = std::collections::BTreeSet::new();
    let mut out = Vec::with_capacity(names.len());
    for (j, base) in names.iter().enumerate() {
        let mut name = base.to_string();
        if taken.contains(&name) {
            let term = owner.get(j).copied().flatten();
            let effect = term.and_then(|i| spec.extras[i].effect()).unwrap_or("term");
            name = format!("{base}.{effect}");
            if taken.contains(&name) {
                name = format!("{base}.{effect}.{}", term.unwrap_or(j));
            }
        }
        taken.insert(name.clone());
        out.push(name);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discover::candidate::Extra;
    use crate::discover::forms::{Localized, TimePeriodic};

    /// A bump and a vibration both have `amplitude_mps2`, two bumps all three names: every
    /// parameter keeps a name of its own, the first the plain one.
    #[test]
    fn parameters_named_alike_by_two_terms_all_keep_a_name() {
        let bump: Extra = Localized {
            z_lo: 0.0,
            z_hi: 0.01,
            w_lo: 1e-4,
            w_hi: 1e-3,
        }
        .into();
        let spec = Spec {
            n_materials: 1,
            s: 1.0,
            k: 2.5,
            extras: vec![
                bump.clone(),
                TimePeriodic {
                    f_lo: 10.0,
                    f_hi: 500.0,
                }
                .into(),
                bump,
            ],
        };
        let params = spec.global_params(&["316".to_string()]);
        let names: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
        let unique = unique_parameter_names(&spec, &names);
        assert_eq!(
            unique,
            [
                "mu_316",
                "t_s_316",
                "amplitude_mps2",
                "centre_m",
                "width_m",
                "frequency_hz",
                "amplitude_mps2.time_dependent_force",
                "amplitude_mps2.position_dependent_force",
                "centre_m.position_dependent_force",
                "width_m.position_dependent_force",
            ]
        );
        // without a clash the names are the terms' own
        let one = Spec {
            extras: spec.extras[..2].to_vec(),
            ..spec.clone()
        };
        let params = one.global_params(&["316".to_string()]);
        let names: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(unique_parameter_names(&one, &names)[..6], names[..6]);
    }
}
