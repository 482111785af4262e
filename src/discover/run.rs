//! The whole discovery on a set of recordings: measure, fit the joint baseline, select terms, report.

use super::candidate::{Extra, Spec, N_LOCAL};
use super::cv::{cross_validate, CvResult};
use super::data::{prepare_runs, RunData};
use super::diagnosis::{
    CandidateRow, Diagnosis, Drift, DriftPoint, Estimate, Finding, ForceMaps, ModelScore, Settings,
};
use super::drift::line;
use super::forcemap::ForceMap;
use super::forward::{finding, fold_of, median_speed, run_round, Model};
use super::locate::locate;
use super::null_distribution::NullFit;
use super::perrun::{fit_each_run, measure_noise, PerRunFit};
use super::proposal::{propose, wanted_for, Ranges, Wanted};
use super::residual_structure::Structure;
use super::spectral::Spectrum;
use super::Options;
use crate::artifacts::estimate::stderr;
use crate::physics::Variable;
use crate::recording::Recording;
use serde_json::json;
use std::collections::BTreeMap;

fn median(mut v: Vec<f64>) -> f64 {
    crate::stats::upper_median(&mut v)
}

fn library(opts: &Options, n_materials: usize, rg: &Ranges) -> Vec<Extra> {
    let mut out = Vec::new();
    for c in &opts.candidates {
        match c.as_str() {
            "velocity_dependent_drag" => {
                out.push(Extra::QuadraticDrag);
                out.push(Extra::SaturatingDrag);
            }
            "rolling_resistance" => out.push(Extra::RollingResistance),
            "groove_tilt" => out.push(Extra::GrooveTilt),
            "velocity_dependent_friction" => out.push(Extra::VelocityFriction {
                materials: n_materials,
            }),
            "position_dependent_force" => {
                out.push(rg.periodic_z());
                out.push(rg.localized());
            }
            "time_dependent_force" => out.push(rg.time_periodic()),
            _ => {}
        }
    }
    out
}

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

/// The bins where the model misses most (largest |mean residual| z and RMS over noise).
fn worst_bins(s: &Structure) -> serde_json::Value {
    let mut all: Vec<(String, f64, f64)> = Vec::new();
    for (group, bins) in [
        ("phase", &s.by_phase),
        ("speed", &s.by_speed),
        ("position", &s.by_position),
        ("direction", &s.by_direction),
        ("material", &s.by_material),
    ] {
        for (k, b) in bins {
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

fn empty(opts: &Options, runs_used: usize, materials: Vec<String>, note: &str) -> Diagnosis {
    Diagnosis {
        mismatch: false,
        findings: vec![],
        candidates: vec![],
        model: ModelScore::default(),
        model_parameters: BTreeMap::new(),
        baseline_model: ModelScore::default(),
        residuals_before: None,
        residuals_after: None,
        drift: None,
        force_maps: None,
        spectra: vec![],
        runs_used,
        materials,
        settings: settings(opts),
        note: note.into(),
    }
}

fn settings(opts: &Options) -> Settings {
    Settings {
        bootstrap: opts.bootstrap,
        alpha: opts.alpha,
        folds: opts.folds,
        seed: opts.seed,
        candidates: opts.candidates.clone(),
    }
}

/// An accepted term with what the report shows about it.
struct Accepted {
    row: CandidateRow,
    before: ModelScore,
    after: ModelScore,
    probes_after: Vec<CandidateRow>,
    null: NullFit,
    extra: Extra,
}

/// The baseline joint model with its starting values from the per-run fits.
fn fit_baseline(
    runs: &mut [RunData],
    materials: &[String],
    opts: &Options,
) -> (Model, Vec<PerRunFit>) {
    let s = (opts.groove_angle_deg.to_radians() / 2.0).sin();
    let base_spec = Spec {
        n_materials: materials.len(),
        s,
        k: opts.k,
        extras: vec![],
    };
    let base_params = base_spec.global_params(materials);
    let per_run = measure_noise(runs, &base_spec, &base_params);
    let mut g0 = Vec::new();
    for m in 0..materials.len() {
        g0.push(median(
            runs.iter()
                .zip(&per_run)
                .filter(|(r, _)| r.material == m)
                .map(|(_, f)| f.mu)
                .collect(),
        ));
    }
    for m in 0..materials.len() {
        g0.push(median(
            runs.iter()
                .zip(&per_run)
                .filter(|(r, _)| r.material == m)
                .map(|(_, f)| f.t_s)
                .collect(),
        ));
    }
    let l0: Vec<[f64; N_LOCAL]> = per_run.iter().map(|f| f.local).collect();
    let baseline = Model::fit(base_spec, materials, runs, &g0, &l0, 80);
    (baseline, per_run)
}

/// Backward elimination: drop the weakest earlier term whose likelihood ratio, given the others,
/// is within its own bootstrap null; repeat until every term is needed.
fn eliminate(
    current: &mut Model,
    current_cv: &mut CvResult,
    accepted: &mut Vec<Accepted>,
    removed: &mut Vec<Accepted>,
    materials: &[String],
    runs: &[RunData],
    fold: &[usize],
    opts: &Options,
) {
    loop {
        if accepted.len() < 2 {
            return;
        }
        let last = accepted.len() - 1;
        let mut weakest: Option<(usize, f64, f64, Model)> = None;
        for (a, acc) in accepted.iter().enumerate().take(last) {
            let Some(i) = current.spec.extras.iter().position(|e| *e == acc.extra) else {
                continue;
            };
            let without = current.without(i, materials, runs, 40);
            let lr = (without.fit.chi2 - current.fit.chi2).max(0.0);
            let p = acc.null.p_value(lr);
            if p >= opts.alpha && weakest.as_ref().map(|w| p > w.2).unwrap_or(true) {
                weakest = Some((a, lr, p, without));
            }
        }
        let Some((a, lr, p, without)) = weakest else {
            return;
        };
        let mut gone = accepted.remove(a);
        gone.row.accepted = false;
        gone.row.evidence.decision = format!(
            "removed by backward elimination: with the later terms its likelihood ratio is {lr:.1} (p = {p:.3}), within its bootstrap null"
        );
        removed.push(gone);
        *current = without;
        *current_cv = cross_validate(
            &current.spec,
            &current.params,
            runs,
            &current.fit,
            fold,
            opts.folds,
        );
    }
}

/// Run the whole discovery on `recordings` (single runs are used; collision runs are skipped).
fn trace(t0: std::time::Instant, what: &str) {
    if std::env::var_os("GROOVE_DISCOVER_TRACE").is_some() {
        eprintln!("discover: {what} at {:.2} s", t0.elapsed().as_secs_f64());
    }
}

pub fn discover(recordings: &[Recording], opts: &Options) -> Diagnosis {
    let t0 = std::time::Instant::now();
    let (mut runs, materials) = prepare_runs(recordings, opts.min_frames);
    if runs.len() < 2 * opts.folds.max(2) {
        return empty(
            opts,
            runs.len(),
            materials,
            &format!(
                "discovery did not run: {} single runs with at least {} frames, fewer than the {} a joint model with {}-fold cross-validation needs; nothing was tested, so nothing can be said about missing physics",
                runs.len(),
                opts.min_frames,
                2 * opts.folds.max(2),
                opts.folds
            ),
        );
    }
    let (baseline, per_run) = fit_baseline(&mut runs, &materials, opts);
    trace(t0, "baseline fitted");
    let fold = fold_of(&runs, &baseline.fit.local, opts.folds);
    let base_cv = cross_validate(
        &baseline.spec,
        &baseline.params,
        &runs,
        &baseline.fit,
        &fold,
        opts.folds,
    );
    trace(t0, "baseline cross-validated");
    let rg = Ranges::of(&runs);
    let vref = median_speed(&baseline.fit.local);
    let probes = vec![
        Extra::SpeedDriftT { v_ref_mps: vref },
        Extra::SpeedDriftMu { v_ref_mps: vref },
        Extra::DirectionAsymmetry,
    ];
    let mut current = baseline.clone();
    let mut current_cv: CvResult = base_cv.clone();
    let mut accepted: Vec<Accepted> = Vec::new();
    let mut removed: Vec<Accepted> = Vec::new();
    let mut table: Vec<CandidateRow> = Vec::new();
    let mut last_rows: Vec<CandidateRow> = Vec::new();
    let mut last_probes: Vec<CandidateRow> = Vec::new();
    let mut unexplained: Vec<CandidateRow> = Vec::new();
    let mut maps_before: Vec<ForceMap> = Vec::new();
    let mut spectra: Vec<Spectrum> = Vec::new();
    let mut round = 0;
    loop {
        round += 1;
        // one cause, one term: a named effect is not added twice, except position forces of
        // another form (a waviness and a bump)
        let entries: Vec<Extra> = library(opts, materials.len(), &rg)
            .into_iter()
            .filter(|e| {
                !accepted.iter().any(|a| {
                    if e.effect() == Some("position_dependent_force") {
                        std::mem::discriminant(&a.extra) == std::mem::discriminant(e)
                    } else {
                        Some(a.row.effect.as_str()) == e.effect()
                    }
                })
            })
            .collect();
        if entries.is_empty() {
            break;
        }
        let refs: Vec<&Extra> = entries.iter().collect();
        let mut wanted = wanted_for(&refs);
        wanted.maps = round == 1;
        if std::env::var_os("GROOVE_DISCOVER_TRACE").is_some() {
            eprintln!("round {round} starts");
        }
        let props = propose(
            &current.spec,
            &current.params,
            &current.fit.global,
            &current.fit.local,
            &runs,
            &rg,
            wanted,
            Some((&fold, opts.folds)),
        );
        if round == 1 {
            maps_before = props.maps.clone();
            spectra = props.z.iter().chain(props.t.iter()).cloned().collect();
        }
        trace(t0, "proposed");
        let r = run_round(
            round,
            &current,
            &current_cv,
            &entries,
            &probes,
            &materials,
            &runs,
            opts,
            &fold,
            &props,
            &rg,
        );
        table.extend(r.rows.iter().cloned());
        table.extend(r.probe_rows.iter().cloned());
        if let Some(last) = accepted.last_mut() {
            last.probes_after = r.probe_rows.clone();
        }
        match r.accepted {
            Some((i, model, cv)) if accepted.len() < opts.max_terms => {
                let before = current.score(&runs, Some(&current_cv));
                let after = model.score(&runs, Some(&cv));
                let mut row = r.rows[i].clone();
                row.evidence.decision = format!(
                    "{} (flagged by {} probe(s))",
                    row.evidence.decision,
                    r.flagged_probes.len()
                );
                accepted.push(Accepted {
                    row,
                    before,
                    after,
                    probes_after: vec![],
                    null: r.nulls[i].clone(),
                    extra: entries[i].clone(),
                });
                current = model;
                current_cv = cv;
                last_probes = r.probe_rows;
                eliminate(
                    &mut current,
                    &mut current_cv,
                    &mut accepted,
                    &mut removed,
                    &materials,
                    &runs,
                    &fold,
                    opts,
                );
            }
            _ => {
                last_rows = r.rows;
                unexplained = r.flagged_probes;
                last_probes = r.probe_rows;
                break;
            }
        }
        if accepted.len() >= opts.max_terms {
            break;
        }
    }
    trace(t0, "rounds done");
    // the nonparametric fallback: structure in a force map that no named form explained
    let mut fallback: Option<Accepted> = None;
    let mut maps_after: Vec<ForceMap> = Vec::new();
    if opts.nonparametric {
        let props = propose(
            &current.spec,
            &current.params,
            &current.fit.global,
            &current.fit.local,
            &runs,
            &rg,
            Wanted {
                z: false,
                t: false,
                bump: false,
                maps: true,
            },
            Some((&fold, opts.folds)),
        );
        maps_after = props.maps.clone();
        let strongest = props
            .maps
            .iter()
            .filter(|m| m.spline.is_some() && m.cv_gain > 0.0)
            .max_by(|a, b| a.cv_gain.total_cmp(&b.cv_gain));
        let var = strongest.map(|m| match m.variable.as_str() {
            "z" => Variable::Z,
            "v" => Variable::V,
            _ => Variable::T,
        });
        if let (Some(map), Some(var)) = (strongest, var) {
            if let Some(spline) = rg.spline(map, var) {
                round += 1;
                let r = run_round(
                    round,
                    &current,
                    &current_cv,
                    std::slice::from_ref(&spline),
                    &[],
                    &materials,
                    &runs,
                    opts,
                    &fold,
                    &props,
                    &rg,
                );
                table.extend(r.rows.iter().cloned());
                if let Some((i, model, cv)) = r.accepted {
                    let before = current.score(&runs, Some(&current_cv));
                    let after = model.score(&runs, Some(&cv));
                    let mut row = r.rows[i].clone();
                    row.evidence.decision = format!(
                        "accepted as a model of what no named form explains: the force map in {} shows structure (held-out χ² drop {:.1})",
                        map.variable, map.cv_gain
                    );
                    fallback = Some(Accepted {
                        row,
                        before,
                        after,
                        probes_after: vec![],
                        null: r.nulls[i].clone(),
                        extra: spline,
                    });
                    current = model;
                    current_cv = cv;
                    maps_after = propose(
                        &current.spec,
                        &current.params,
                        &current.fit.global,
                        &current.fit.local,
                        &runs,
                        &rg,
                        Wanted {
                            z: false,
                            t: false,
                            bump: false,
                            maps: true,
                        },
                        Some((&fold, opts.folds)),
                    )
                    .maps;
                }
            }
        }
    }
    trace(t0, "fallback done");
    let residuals_before = locate(&baseline.spec, &baseline.fit, &runs, &materials);
    let residuals_after = locate(&current.spec, &current.fit, &runs, &materials);
    // per-run drift with the final model's extra terms held at their joint values
    let extra_values: Vec<f64> = current.fit.global[2 * materials.len()..].to_vec();
    let after_fits = fit_each_run(
        &runs,
        &current.spec,
        &current.params,
        &extra_values,
        Some(&per_run),
    );
    let before_pts = drift_points(&runs, &per_run, &materials);
    let after_pts = drift_points(&runs, &after_fits, &materials);
    let drift = Drift {
        lines_before: drift_lines(&before_pts, &materials),
        lines_after: drift_lines(&after_pts, &materials),
        before: before_pts,
        after: after_pts,
        note: "per-run fits (own mu and T; extra terms held at the joint values in `after`); the fitted |v0| shares errors with T and mu, so the probes fitted inside the joint model carry the decision".into(),
    };
    trace(t0, "drift done");
    let mut findings: Vec<Finding> = Vec::new();
    for acc in accepted.iter().chain(fallback.iter()) {
        let mut w = BTreeMap::new();
        let flagged: Vec<CandidateRow> = table
            .iter()
            .filter(|t| t.round == acc.row.evidence.round && t.effect == "probe")
            .cloned()
            .collect();
        w.insert("drift_probes_before".to_string(), probes_json(&flagged));
        w.insert(
            "drift_probes_after".to_string(),
            probes_json(&acc.probes_after),
        );
        w.insert(
            "residuals_before".to_string(),
            worst_bins(&residuals_before),
        );
        findings.push(finding(&acc.row, acc.before.clone(), acc.after.clone(), w));
    }
    let final_score = current.score(&runs, Some(&current_cv));
    if !unexplained.is_empty() && fallback.is_none() {
        let strongest = unexplained
            .iter()
            .max_by(|a, b| a.evidence.lr.total_cmp(&b.evidence.lr))
            .expect("non-empty");
        let mut w = BTreeMap::new();
        w.insert("drift_probes".to_string(), probes_json(&unexplained));
        w.insert("residuals".to_string(), worst_bins(&residuals_after));
        let mut parameters = BTreeMap::new();
        for r in &unexplained {
            for (k, v) in &r.parameters {
                parameters.insert(k.clone(), *v);
            }
        }
        findings.push(Finding {
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
        });
    }
    for acc in &removed {
        let mut w = BTreeMap::new();
        w.insert("drift_probes".to_string(), probes_json(&acc.probes_after));
        findings.push(finding(&acc.row, acc.before.clone(), acc.after.clone(), w));
    }
    for row in &last_rows {
        let mut w = BTreeMap::new();
        w.insert("drift_probes".to_string(), probes_json(&last_probes));
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
    let mut model_parameters = BTreeMap::new();
    for (p, (v, se)) in current
        .params
        .iter()
        .zip(current.fit.global.iter().zip(&current.fit.global_se))
    {
        model_parameters.insert(p.name.clone(), Estimate::new(*v, *se));
    }
    let any_accepted = findings.iter().any(|f| f.accepted);
    Diagnosis {
        mismatch: any_accepted || !unexplained.is_empty(),
        findings,
        candidates: table,
        model: final_score,
        model_parameters,
        baseline_model: baseline.score(&runs, Some(&base_cv)),
        residuals_before: Some(residuals_before),
        residuals_after: Some(residuals_after),
        drift: Some(drift),
        force_maps: Some(ForceMaps {
            before: maps_before,
            after: maps_after,
        }),
        spectra,
        runs_used: runs.len(),
        materials,
        settings: settings(opts),
        note: String::new(),
    }
}
