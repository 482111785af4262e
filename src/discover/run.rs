//! The whole discovery on a set of recordings: measure, fit the joint baseline, select terms, report.

use super::candidate::{Extra, Spec, N_LOCAL};
use super::cv::{cross_validate, CvResult};
use super::data::{prepare_runs, RunData};
use super::diagnosis::{
    CandidateRow, Diagnosis, Drift, DriftPoint, Estimate, Finding, ModelScore, Settings,
};
use super::drift::line;
use super::forward::{finding, fold_of, median_speed, run_round, Model};
use super::locate::locate;
use super::perrun::{fit_each_run, measure_noise, PerRunFit};
use super::residual_structure::Structure;
use super::Options;
use crate::artifacts::estimate::stderr;
use crate::recording::Recording;
use serde_json::json;
use std::collections::BTreeMap;

fn median(mut v: Vec<f64>) -> f64 {
    crate::stats::upper_median(&mut v)
}

fn library(
    opts: &Options,
    n_materials: usize,
    z_min_m: f64,
    span_m: f64,
    harmonics: usize,
) -> Vec<Extra> {
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
            "position_dependent_force" => out.push(Extra::PositionForce {
                harmonics,
                z_min_m,
                span_m,
            }),
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

/// Choose the Fourier basis size of the position-dependent force by cross-validation against `current`.
fn position_harmonics(
    current: &Model,
    opts: &Options,
    materials: &[String],
    runs: &[RunData],
    fold: &[usize],
    z_min_m: f64,
    span_m: f64,
) -> usize {
    let mut best = (opts.position_harmonics[0], f64::INFINITY);
    if opts.position_harmonics.len() == 1 {
        return best.0;
    }
    for &h in &opts.position_harmonics {
        let m = current.extend(
            &Extra::PositionForce {
                harmonics: h,
                z_min_m,
                span_m,
            },
            materials,
            runs,
            40,
        );
        let cv = cross_validate(&m.spec, &m.params, runs, &m.fit, fold, opts.folds);
        if cv.cv_rms_m < best.1 {
            best = (h, cv.cv_rms_m);
        }
    }
    best.0
}

/// Start values of the joint globals: per material the median per-run μ, then the median T.
fn global_start(runs: &[RunData], per_run: &[PerRunFit], n_materials: usize) -> Vec<f64> {
    let of_material = |m: usize, pick: fn(&PerRunFit) -> f64| -> Vec<f64> {
        runs.iter()
            .zip(per_run)
            .filter(|(r, _)| r.material == m)
            .map(|(_, f)| pick(f))
            .collect()
    };
    let mut g0: Vec<f64> = (0..n_materials)
        .map(|m| median(of_material(m, |f| f.mu)))
        .collect();
    g0.extend((0..n_materials).map(|m| median(of_material(m, |f| f.t_s))));
    g0
}

/// Lowest kept position and the span of kept positions over all runs (at least 1 µm).
fn kept_extent(runs: &[RunData]) -> (f64, f64) {
    let (zmin, zmax) = runs
        .iter()
        .flat_map(|r| {
            r.z_m
                .iter()
                .zip(&r.keep)
                .filter(|(_, k)| **k)
                .map(|(z, _)| *z)
        })
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
            (a.min(z), b.max(z))
        });
    (zmin, (zmax - zmin).max(1e-6))
}

/// An accepted term: its row, the scores before and after it, and the probes of the next round.
type Accepted = (CandidateRow, ModelScore, ModelScore, Vec<CandidateRow>);

/// What the forward selection found: the final model and every row it tested.
struct Selection {
    current: Model,
    current_cv: CvResult,
    accepted: Vec<Accepted>,
    table: Vec<CandidateRow>,
    /// The rows of the round that accepted nothing (or hit the term limit).
    last_rows: Vec<CandidateRow>,
    last_probes: Vec<CandidateRow>,
    /// Probes flagged in the last round with no term to explain them.
    unexplained: Vec<CandidateRow>,
}

/// The common inputs of every selection round.
struct Ground<'a> {
    opts: &'a Options,
    materials: &'a [String],
    runs: &'a [RunData],
    fold: &'a [usize],
    probes: &'a [Extra],
    z_min_m: f64,
    span_m: f64,
}

/// Forward selection: each round tests the library's remaining terms against the current model
/// and accepts the strongest passing one, until none passes or `max_terms` are in.
fn select_terms(gr: &Ground, baseline: &Model, base_cv: &CvResult) -> Selection {
    let (opts, runs) = (gr.opts, gr.runs);
    let mut sel = Selection {
        current: baseline.clone(),
        current_cv: base_cv.clone(),
        accepted: Vec::new(),
        table: Vec::new(),
        last_rows: Vec::new(),
        last_probes: Vec::new(),
        unexplained: Vec::new(),
    };
    let mut accepted_effects: Vec<String> = Vec::new();
    let mut round = 0;
    loop {
        round += 1;
        let uses_position = opts
            .candidates
            .iter()
            .any(|c| c == "position_dependent_force")
            && !accepted_effects
                .iter()
                .any(|e| e == "position_dependent_force");
        let harmonics = if uses_position {
            position_harmonics(
                &sel.current,
                opts,
                gr.materials,
                runs,
                gr.fold,
                gr.z_min_m,
                gr.span_m,
            )
        } else {
            1
        };
        let entries: Vec<Extra> =
            library(opts, gr.materials.len(), gr.z_min_m, gr.span_m, harmonics)
                .into_iter()
                .filter(|e| {
                    !accepted_effects
                        .iter()
                        .any(|a| Some(a.as_str()) == e.effect())
                })
                .collect();
        if entries.is_empty() {
            break;
        }
        let r = run_round(
            round,
            &sel.current,
            &sel.current_cv,
            &entries,
            gr.probes,
            gr.materials,
            runs,
            opts,
            gr.fold,
        );
        sel.table.extend(r.rows.iter().cloned());
        sel.table.extend(r.probe_rows.iter().cloned());
        if let Some(last) = sel.accepted.last_mut() {
            last.3 = r.probe_rows.clone();
        }
        match r.accepted {
            Some((i, model, cv)) if sel.accepted.len() < opts.max_terms => {
                let before = sel.current.score(runs, Some(&sel.current_cv));
                let after = model.score(runs, Some(&cv));
                let mut row = r.rows[i].clone();
                row.evidence.decision = format!(
                    "{} (flagged by {} probe(s))",
                    row.evidence.decision,
                    r.flagged_probes.len()
                );
                accepted_effects.push(row.effect.clone());
                sel.accepted.push((row, before, after, vec![]));
                sel.current = model;
                sel.current_cv = cv;
                sel.last_probes = r.probe_rows;
            }
            _ => {
                sel.last_rows = r.rows;
                sel.unexplained = r.flagged_probes;
                sel.last_probes = r.probe_rows;
                break;
            }
        }
        if sel.accepted.len() >= opts.max_terms {
            break;
        }
    }
    sel
}

/// Per-run drift of μ and T before (the baseline per-run fits) and after (the final model's extra
/// terms held at their joint values).
fn per_run_drift(
    runs: &[RunData],
    per_run: &[PerRunFit],
    current: &Model,
    materials: &[String],
) -> Drift {
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

/// The findings: each accepted term, then the unexplained flagged probes (if any), then the
/// rejected terms of the last round.
fn findings(
    sel: &Selection,
    final_score: &ModelScore,
    residuals_before: &Structure,
    residuals_after: &Structure,
) -> Vec<Finding> {
    let mut findings: Vec<Finding> = Vec::new();
    for (row, before, after, probes_after) in &sel.accepted {
        let mut w = BTreeMap::new();
        let flagged: Vec<CandidateRow> = sel
            .table
            .iter()
            .filter(|t| t.round == row.evidence.round && t.effect == "probe")
            .cloned()
            .collect();
        w.insert("drift_probes_before".to_string(), probes_json(&flagged));
        w.insert("drift_probes_after".to_string(), probes_json(probes_after));
        w.insert("residuals_before".to_string(), worst_bins(residuals_before));
        findings.push(finding(row, before.clone(), after.clone(), w));
    }
    if !sel.unexplained.is_empty() {
        findings.push(unexplained_finding(
            &sel.unexplained,
            final_score,
            residuals_after,
        ));
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

/// A finding for flagged probes that no term explains, with the strongest probe's evidence.
fn unexplained_finding(
    unexplained: &[CandidateRow],
    final_score: &ModelScore,
    residuals_after: &Structure,
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

/// The final model's global parameters by name, with their standard errors.
fn model_parameters(current: &Model) -> BTreeMap<String, Estimate> {
    current
        .params
        .iter()
        .zip(current.fit.global.iter().zip(&current.fit.global_se))
        .map(|(p, (v, se))| (p.name.clone(), Estimate::new(*v, *se)))
        .collect()
}

/// Run the whole discovery on `recordings` (single runs are used; collision runs are skipped):
/// measure each run's noise, fit the joint baseline, select terms, then describe the result.
pub fn discover(recordings: &[Recording], opts: &Options) -> Diagnosis {
    let (mut runs, materials) = prepare_runs(recordings, opts.min_frames);
    if runs.len() < 2 * opts.folds.max(2) {
        return empty(
            opts,
            runs.len(),
            materials,
            "too few single runs for a joint model and cross-validation: nothing tested",
        );
    }
    let s = (opts.groove_angle_deg.to_radians() / 2.0).sin();
    let base_spec = Spec {
        n_materials: materials.len(),
        s,
        k: opts.k,
        extras: vec![],
    };
    let base_params = base_spec.global_params(&materials);
    let per_run = measure_noise(&mut runs, &base_spec, &base_params);
    let g0 = global_start(&runs, &per_run, materials.len());
    let l0: Vec<[f64; N_LOCAL]> = per_run.iter().map(|f| f.local).collect();
    let baseline = Model::fit(base_spec.clone(), &materials, &runs, &g0, &l0, 80);
    let fold = fold_of(&runs, &baseline.fit.local, opts.folds);
    let base_cv = cross_validate(
        &baseline.spec,
        &baseline.params,
        &runs,
        &baseline.fit,
        &fold,
        opts.folds,
    );
    let vref = median_speed(&baseline.fit.local);
    let (z_min_m, span_m) = kept_extent(&runs);
    let probes = vec![
        Extra::SpeedDriftT { v_ref_mps: vref },
        Extra::SpeedDriftMu { v_ref_mps: vref },
        Extra::DirectionAsymmetry,
    ];
    let ground = Ground {
        opts,
        materials: &materials,
        runs: &runs,
        fold: &fold,
        probes: &probes,
        z_min_m,
        span_m,
    };
    let sel = select_terms(&ground, &baseline, &base_cv);
    let residuals_before = locate(&baseline.spec, &baseline.fit, &runs, &materials);
    let residuals_after = locate(&sel.current.spec, &sel.current.fit, &runs, &materials);
    let drift = per_run_drift(&runs, &per_run, &sel.current, &materials);
    let final_score = sel.current.score(&runs, Some(&sel.current_cv));
    let findings = findings(&sel, &final_score, &residuals_before, &residuals_after);
    Diagnosis {
        mismatch: !sel.accepted.is_empty() || !sel.unexplained.is_empty(),
        findings,
        candidates: sel.table.clone(),
        model: final_score,
        model_parameters: model_parameters(&sel.current),
        baseline_model: baseline.score(&runs, Some(&base_cv)),
        residuals_before: Some(residuals_before),
        residuals_after: Some(residuals_after),
        drift: Some(drift),
        runs_used: runs.len(),
        materials,
        settings: settings(opts),
        note: String::new(),
    }
}
