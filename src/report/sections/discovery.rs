//! Section 4: discovery — where the mismatch is, the candidates and their evidence, the accepted
//! physics, before/after figures, and a comparison with the chapter's own correction (Eq. 4.8).

use super::params::{at_bound, params_text};
use super::{Block, Table};
use crate::artifacts::diagnosis::{
    CandidateRow, Diagnosis, Effect, Estimate, Evidence, Finding, Structure,
};
use crate::artifacts::validation::Validation;
use crate::report::chapter as ch;
use crate::report::inputs::ReportData;
use crate::report::value::{as_num, sig};
use serde::Deserialize;
use serde_json::Value;
use std::collections::BTreeMap;

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// A compact one-line rendering of a JSON value: `a = 1.2; b.c = yes` (at most `max` entries).
pub fn short(v: &Value, max: usize) -> String {
    let mut parts = Vec::new();
    flatten(v, String::new(), &mut parts);
    let more = parts.len().saturating_sub(max);
    parts.truncate(max);
    let mut s = parts.join("; ");
    if more > 0 {
        s.push_str(&format!("; … {more} more"));
    }
    if s.is_empty() {
        "—".into()
    } else {
        s
    }
}

fn flatten(v: &Value, path: String, out: &mut Vec<String>) {
    let name = |p: &str| {
        if p.is_empty() {
            "value".to_string()
        } else {
            p.replace('_', " ")
        }
    };
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                flatten(x, p, out);
            }
        }
        Value::Array(a) if a.iter().all(|x| x.is_number()) && a.len() <= 4 => {
            let xs: Vec<String> = a.iter().filter_map(as_num).map(|x| sig(x, 3)).collect();
            out.push(format!("{} = [{}]", name(&path), xs.join(", ")));
        }
        Value::Array(a) => out.push(format!("{}: {} entries", name(&path), a.len())),
        Value::Number(_) => out.push(format!(
            "{} = {}",
            name(&path),
            as_num(v).map_or("—".into(), |x| sig(x, 4))
        )),
        Value::Bool(b) => out.push(format!(
            "{} = {}",
            name(&path),
            if *b { "yes" } else { "no" }
        )),
        Value::String(s) => out.push(format!("{} = {s}", name(&path))),
        Value::Null => {}
    }
}

/// What the truth file of a synthetic dataset says about the concealed physics (validation.json
/// `effects`), and each accepted parameter beside the truth term's parameter of the same name.
fn truth_block(b: &mut Block, d: &ReportData, diag: &Diagnosis, validation: &Validation) {
    let Some(effects) = &validation.effects else {
        return;
    };
    let names = |list: &[Effect]| -> Vec<String> {
        list.iter().map(|e| e.id().replace('_', " ")).collect()
    };
    let truth_names: Vec<String> = effects
        .truth
        .iter()
        .map(|t| {
            format!(
                "{} ({})",
                t.effect.id().replace('_', " "),
                short(&t.term, 6)
            )
        })
        .collect();
    let list = |v: Vec<String>| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.join(", ")
        }
    };
    b.para(format!(
        "Against the truth (this dataset is synthetic): concealed physics {}; accepted {}; missed {}; spurious {}.",
        list(truth_names),
        list(names(effects.accepted.as_slice())),
        list(names(effects.missed.as_slice())),
        list(names(effects.spurious.as_slice()))
    ));
    let mut t = Table::new(
        "Accepted parameters beside the truth",
        &["effect", "parameter", "ours", "truth"],
    );
    for f in diag.findings.iter().filter(|f| f.accepted) {
        let term = effects
            .truth
            .iter()
            .find(|t| t.effect.id() == f.effect)
            .map(|t| &t.term);
        for (name, p) in &f.parameters {
            let ours = match (
                finite(p.value),
                p.se.and_then(finite).filter(|se| *se > 0.0),
            ) {
                (Some(v), Some(se)) => format!("{} ± {}", sig(v, 4), sig(se, 2)),
                (Some(v), None) => sig(v, 4),
                _ => "—".into(),
            };
            // per-material parameters (`t0_s_316`) compare with the truth term's `t0_s`
            let base = d
                .materials()
                .iter()
                .find_map(|m| name.strip_suffix(&format!("_{m}")).map(str::to_string))
                .unwrap_or_else(|| name.clone());
            let truth = term
                .and_then(|t| {
                    [name, &base]
                        .into_iter()
                        .find_map(|k| t.get(k.as_str()).filter(|v| !v.is_null()))
                })
                .and_then(as_num)
                .map_or("—".into(), |x| sig(x, 4));
            t.push(vec![f.effect.replace('_', " "), name.clone(), ours, truth]);
        }
    }
    if !t.rows.is_empty() {
        b.table(t);
    }
}

/// What decided a finding when no bootstrap null was simulated (`bootstrap_replicates` = 0): the
/// collision-run tests of `discover/pairs.rs`, decided by a χ², a Student's t over runs or an F
/// test over impacts. The statistic's
/// name and the law, or None for a bootstrap-decided candidate.
fn closed_form_test(effect: &str, e: &Evidence) -> Option<String> {
    if e.bootstrap_replicates > 0 {
        return None;
    }
    let stat = finite(e.lr).map_or("—".into(), |x| sig(x, 3));
    Some(match Effect::from_id(effect) {
        Some(Effect::ImpactSpecificMismatch) => format!(
            "t test over runs: mean-square residual within 5 ms of an impact over what the tracking noise gives there, typical run = {stat}"
        ),
        Some(Effect::RestitutionLaw | Effect::PairFrictionSlipSpeed) if !e.lr.is_finite() => {
            "not tested".into()
        }
        Some(Effect::RestitutionLaw | Effect::PairFrictionSlipSpeed) => format!(
            "F test over the impacts' own values: a map in ln speed against the candidate law, {} more parameters, F = {stat}",
            e.extra_params
        ),
        _ => format!("χ² test: χ²({}) = {stat}", e.extra_params),
    })
}

/// The decisive statistics of a candidate's evidence: LR, p-values, CV, decision. A finding
/// decided by a χ² or t test (no bootstrap) names that test and shows no empirical p.
pub fn evidence_text(effect: &str, e: &Evidence) -> String {
    let closed = closed_form_test(effect, e);
    let bootstrap = closed.is_none();
    let mut parts: Vec<String> = closed.into_iter().collect();
    parts.extend(
        [
            (bootstrap.then_some(e.lr), "LR"),
            (Some(e.p_value), "p"),
            (bootstrap.then_some(e.p_empirical), "p (empirical)"),
            (Some(e.p_holm), "p (Holm)"),
            (e.cv_paired_t, "CV paired t"),
        ]
        .into_iter()
        .filter_map(|(x, label)| Some(format!("{label} = {}", sig(finite(x?)?, 3)))),
    );
    parts.push(format!("decision: {}", e.decision));
    parts.join("; ")
}

/// The collision-run findings (`where.experiment` = `collision`), one row per material and test.
fn collision_table(diag: &Diagnosis) -> Option<Table> {
    let mut t = Table::new(
        "Collision runs: do the pairs move under the single runs' physics, and do their impacts follow the chapter's laws? (whole-run pair fits per material; the impacts' own C per material and setup, μ_pp per material; Holm within each test, α = 0.01)",
        &["material", "test", "evidence", "accepted"],
    );
    for f in &diag.findings {
        if f.where_.get("experiment").and_then(Value::as_str) != Some("collision") {
            continue;
        }
        let material = f
            .where_
            .get("material")
            .and_then(Value::as_str)
            .unwrap_or("?");
        let material = match f.where_.get("setup").and_then(Value::as_str) {
            Some(setup) => format!("{material} ({setup})"),
            None => material.to_string(),
        };
        t.push(vec![
            material,
            f.effect.replace('_', " "),
            evidence_text(&f.effect, &f.evidence),
            (if f.accepted { "yes" } else { "no" }).into(),
        ]);
    }
    (!t.rows.is_empty()).then_some(t)
}

/// Residual RMS before and after by phase, speed, position, direction and material
/// (diagnosis.json `residuals_before` / `residuals_after`).
fn structure_table(diag: &Diagnosis) -> Option<Table> {
    let before = diag.residuals_before.as_ref()?;
    let after = diag.residuals_after.as_ref();
    let mut t = Table::new(
        "Residuals before and after, pooled over runs (RMS in µm; RMS/noise in brackets)",
        &["by", "bin", "samples", "before", "after"],
    );
    let cell = |bin: Option<&crate::artifacts::diagnosis::Bin>| {
        let Some(bin) = bin else {
            return "—".to_string();
        };
        match (finite(bin.rms_m), finite(bin.rms_over_noise)) {
            (Some(r), Some(q)) => format!("{:.3} ({:.2})", r * 1e6, q),
            (Some(r), None) => format!("{:.3}", r * 1e6),
            _ => "—".into(),
        }
    };
    type Bins = BTreeMap<String, crate::artifacts::diagnosis::Bin>;
    let groups: [(fn(&Structure) -> &Bins, &str); 5] = [
        (|s| &s.by_phase, "phase"),
        (|s| &s.by_speed, "speed"),
        (|s| &s.by_position, "position"),
        (|s| &s.by_direction, "direction"),
        (|s| &s.by_material, "material"),
    ];
    for (get, label) in groups {
        for (name, bin) in get(before) {
            // bins are matched by name, else by their index prefix (`2: …`), as edges may shift
            let a = after.map(get).and_then(|m| {
                m.get(name).or_else(|| {
                    let idx = name.split(':').next()?;
                    m.iter()
                        .find(|(k, _)| k.split(':').next() == Some(idx))
                        .map(|(_, v)| v)
                })
            });
            t.push(vec![
                label.into(),
                name.clone(),
                bin.n.to_string(),
                cell(Some(bin)),
                cell(a),
            ]);
        }
    }
    let scalars: [(fn(&Structure) -> f64, &str); 2] = [
        (|s| s.runs_test_z, "runs test z"),
        (|s| s.lag1_autocorrelation, "lag-1 autocorrelation"),
    ];
    for (get, label) in scalars {
        if let Some(x) = finite(get(before)) {
            let y = after.map(get).and_then(finite);
            t.push(vec![
                "structure".into(),
                label.into(),
                "—".into(),
                sig(x, 3),
                y.map_or("—".into(), |y| sig(y, 3)),
            ]);
        }
    }
    (!t.rows.is_empty()).then_some(t)
}

/// The drift lines (e.g. "t_s vs |v0| (316)") before and after: slope ± se and its t.
fn drift_table(diag: &Diagnosis) -> Option<Table> {
    let drift = diag.drift.as_ref()?;
    let mut t = Table::new(
        "Drift of per-run parameters: regression slopes before and after (t = slope/se)",
        &["line", "slope before", "t before", "slope after", "t after"],
    );
    let fmt = |l: Option<&crate::artifacts::diagnosis::Line>| -> (String, String) {
        let Some(l) = l else {
            return ("—".into(), "—".into());
        };
        let slope = match (finite(l.slope), finite(l.slope_se)) {
            (Some(s), Some(se)) => format!("{} ± {}", sig(s, 3), sig(se, 2)),
            (Some(s), None) => sig(s, 3),
            _ => "—".into(),
        };
        (slope, finite(l.t).map_or("—".into(), |x| format!("{x:.1}")))
    };
    for (name, l) in &drift.lines_before {
        let (sb, tb) = fmt(Some(l));
        let (sa, ta) = fmt(drift.lines_after.get(name));
        t.push(vec![name.clone(), sb, tb, sa, ta]);
    }
    if !drift.note.is_empty() {
        t.caption.push_str(&format!(" — {}", drift.note));
    }
    (!t.rows.is_empty()).then_some(t)
}

fn param(f: &Finding, name: &str) -> Option<f64> {
    f.parameters.get(name).and_then(|p| finite(p.value))
}

/// A parameter that may be fitted per material (`t0_s`, or `t0_s_316`, `t0_s_440c`), as text with
/// `unit`, e.g. "0.0540 s (316), 0.0540 s (440c)".
fn param_text(f: &Finding, name: &str, unit: &str) -> Option<String> {
    let parts: Vec<String> = f
        .parameters
        .iter()
        .filter_map(|(k, v)| {
            let x = finite(v.value)?;
            if k == name {
                Some(format!("{} {unit}", sig(x, 3)))
            } else {
                let m = k.strip_prefix(name)?.strip_prefix('_')?;
                Some(format!("{} {unit} ({m})", sig(x, 3)))
            }
        })
        .collect();
    (!parts.is_empty()).then(|| parts.join(", "))
}

/// `where.residuals_before` of a finding: the worst bins and the structure of the baseline residuals.
#[derive(Deserialize)]
struct WhereResiduals {
    #[serde(default)]
    largest_residuals: Vec<LargeBin>,
    runs_test_z: Option<f64>,
    lag1_autocorrelation: Option<f64>,
}

#[derive(Deserialize)]
struct LargeBin {
    bin: String,
    rms_over_noise: Option<f64>,
}

/// One drift probe of `where.drift_probes_before` / `_after`.
#[derive(Deserialize)]
struct Probe {
    probe: String,
    #[serde(default, with = "crate::artifacts::estimate::stderr::map")]
    parameters: BTreeMap<String, Estimate>,
    p_holm: Option<f64>,
}

/// Where discovery located the mismatch, in words: the worst residual bins, the residual structure,
/// and the drift probes before and after (a compact dump of `where` when it has none of them).
fn where_text(w: &BTreeMap<String, Value>) -> String {
    let mut parts = Vec::new();
    let residuals = w
        .get("residuals_before")
        .and_then(|r| WhereResiduals::deserialize(r).ok());
    if let Some(r) = residuals {
        let list: Vec<String> = r
            .largest_residuals
            .iter()
            .filter_map(|b| {
                Some(format!(
                    "{} ({:.1}× noise)",
                    b.bin,
                    b.rms_over_noise.and_then(finite)?
                ))
            })
            .collect();
        if !list.is_empty() {
            parts.push(format!("largest baseline residuals in {}", list.join(", ")));
        }
        if let (Some(z), Some(a)) = (
            r.runs_test_z.and_then(finite),
            r.lag1_autocorrelation.and_then(finite),
        ) {
            parts.push(format!("residuals correlated within runs (runs test z = {z:.0}, lag-1 autocorrelation {a:.2})"));
        }
    }
    for (key, when) in [
        ("drift_probes", ""),
        ("drift_probes_before", " before the accepted physics"),
        ("drift_probes_after", " after the accepted physics"),
    ] {
        let Some(list) = w.get(key).and_then(|l| Vec::<Probe>::deserialize(l).ok()) else {
            continue;
        };
        let probes: Vec<String> = list
            .iter()
            .map(|p| {
                let name = p.probe.trim_start_matches("probe: ");
                let params = params_text(&p.parameters);
                let ph = p
                    .p_holm
                    .and_then(finite)
                    .map_or(String::new(), |x| format!(", p (Holm) = {}", sig(x, 2)));
                format!("{name} [{params}{ph}]")
            })
            .collect();
        if !probes.is_empty() {
            parts.push(format!("drift probes{when}: {}", probes.join("; ")));
        }
    }
    let bounds = at_bound(w);
    if !bounds.is_empty() {
        parts.push(format!("the fit ended at a bound: {}", bounds.join("; ")));
    }
    if parts.is_empty() {
        short(&serde_json::to_value(w).unwrap_or(Value::Null), 8)
    } else {
        parts.join("; ")
    }
}

/// How an accepted finding relates to the chapter's Eq. 4.8 correction, in words and numbers.
fn compare_with_eq_4_8(d: &ReportData, f: &Finding) -> String {
    let form = f.form.to_ascii_lowercase();
    let v_star = ch::L_M / ch::T0_S * 1e3;
    match f.effect.as_str() {
        "velocity_dependent_drag" if form.contains("satur") => {
            let t0 = param_text(f, "t0_s", "s");
            let tp = param_text(f, "tp_s_per_mps", "s per m/s");
            let per_run = crate::report::summary::t_line(d, None)
                .map(|(_, b)| format!(" The per-run linear-drag fits average $T_0 + T'\\lvert v\\rvert$ over a run whose speed decays from $v_0$, so their $T$ rises with $v_0$ with a smaller slope ({} s per m/s here, 1.10 in the chapter) than the T' of the law itself.", sig(b.est.value, 3)))
                .unwrap_or_default();
            format!(
                "The accepted drag $v/(T_0 + T'\\lvert v\\rvert)$ is the form the chapter's line $T = T_0 + T' v_0$ suggests before Eq. 4.7 truncates it. Ours: T0 = {}, T' = {} (chapter 0.052 s and 1.10 s per m/s).{per_run} Unlike Eq. 4.8's $v/T_0 - v^2/L$, it stays dissipative at every speed; Eq. 4.8 turns into propulsion above $L/T_0$ = {v_star:.0} mm/s.",
                t0.unwrap_or_else(|| "—".into()),
                tp.unwrap_or_else(|| "—".into())
            )
        }
        "velocity_dependent_drag" => {
            let c = param_text(f, "c_per_m", "per m");
            format!(
                "The accepted quadratic drag c·v|v| has c = {} (Eq. 4.8's −v²/L corresponds to c = −1/L = −400 per m). A fitted sign and size, unlike Eq. 4.8's, is what the data support; Eq. 4.8 with L = 2.5 mm changes sign at {v_star:.0} mm/s.",
                c.unwrap_or_else(|| "—".into())
            )
        }
        "rolling_resistance" => format!(
            "A constant resistance c·g opposing motion also makes the fitted linear-drag T grow with v0, the signature the chapter read as a quadratic drag term (Eq. 4.8). Discovery tested both as candidates and the evidence selects rolling resistance (deceleration {}); Eq. 4.8's v/T0 − v²/L would in addition change sign at {v_star:.0} mm/s.",
            param(f, "deceleration_mps2")
                .map_or("see the table".into(), |x| format!("{} m/s²", sig(x, 3)))
        ),
        effect => format!(
            "Eq. 4.8 corrects only the drag (v/T0 − v²/L); the accepted {} is a different physical effect that the chapter's model does not contain.",
            effect.replace('_', " ")
        ),
    }
}

/// One row of the table of candidates: a candidate of diagnosis.json, or a finding when there
/// is no candidate list.
struct CandidateView<'a> {
    round: usize,
    effect: &'a str,
    form: &'a str,
    accepted: bool,
    parameters: &'a BTreeMap<String, Estimate>,
    evidence: &'a Evidence,
    extended_cv_m: Option<f64>,
}

impl<'a> From<&'a CandidateRow> for CandidateView<'a> {
    fn from(c: &'a CandidateRow) -> Self {
        CandidateView {
            round: c.round,
            effect: &c.effect,
            form: &c.form,
            accepted: c.accepted,
            parameters: &c.parameters,
            evidence: &c.evidence,
            extended_cv_m: None,
        }
    }
}

impl<'a> From<&'a Finding> for CandidateView<'a> {
    fn from(f: &'a Finding) -> Self {
        CandidateView {
            round: f.evidence.round,
            effect: &f.effect,
            form: &f.form,
            accepted: f.accepted,
            parameters: &f.parameters,
            evidence: &f.evidence,
            extended_cv_m: finite(f.extended.cv_rms_m),
        }
    }
}

pub fn block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new("discovery", "4. Discovery");
    let Some(diag) = &d.diagnosis else {
        b.missing = Some("discovery did not run for this report (no diagnosis.json)".into());
        return b;
    };
    let mismatch = diag.mismatch;
    let accepted: Vec<&Finding> = diag.findings.iter().filter(|f| f.accepted).collect();
    if diag.candidates.is_empty() && diag.findings.is_empty() {
        b.lead = Some(if diag.note.is_empty() {
            "Discovery tested nothing on this dataset, so nothing can be said about missing physics.".to_string()
        } else {
            format!("{}.", capitalize(diag.note.trim_end_matches('.')))
        });
        return b;
    }
    b.lead = super::verdict::verdict(diag);
    b.para(if mismatch {
        "The baseline misses systematically: the per-run fits and residuals, pooled over runs, show structure beyond the noise."
    } else {
        "No systematic mismatch was found: the pooled residuals and the per-run parameters show no structure beyond the noise. That is a statement at the detection limits below, not a proof that nothing is missing."
    });
    if let Some(t) = &diag.tracking_drift {
        b.para(tracking_drift_text(t));
    }
    if let Some(t) = &diag.tracking_blur {
        b.para(tracking_blur_text(t));
    }
    let limits = detection_limits(diag);
    if !limits.is_empty() {
        b.para(format!(
            "Detection limits on this dataset (90 % power at the first Holm level, from the bootstrap null of the last round that tested each form): {}.",
            limits.join("; ")
        ));
    }
    if let Some(f) = diag.findings.iter().find(|f| !f.where_.is_empty()) {
        if mismatch {
            let effect = f.effect.replace('_', " ");
            b.para(format!("Where ({effect}): {}.", where_text(&f.where_)));
        } else {
            // no mismatch: `where` holds only the drift probes, which flagged nothing
            b.para(format!("{}.", capitalize(&where_text(&f.where_))));
        }
    }
    // every candidate tested (diagnosis.candidates, by round), else the findings
    let rows: Vec<CandidateView> = if diag.candidates.is_empty() {
        diag.findings.iter().map(CandidateView::from).collect()
    } else {
        diag.candidates.iter().map(CandidateView::from).collect()
    };
    let baseline_cv = finite(diag.baseline_model.cv_rms_m).or_else(|| {
        diag.findings
            .iter()
            .find_map(|f| finite(f.baseline.cv_rms_m))
    });
    let caption = match baseline_cv {
        Some(cv) => format!(
            "Every candidate tested: evidence and fitted size (baseline held-out RMS {:.3} µm)",
            cv * 1e6
        ),
        None => "Every candidate tested: evidence and fitted size".to_string(),
    };
    let mut t = Table::new(
        &caption,
        &[
            "round",
            "effect",
            "form",
            "accepted",
            "parameters",
            "evidence",
            "held-out RMS (µm)",
        ],
    );
    for f in &rows {
        let cv = f
            .extended_cv_m
            .or_else(|| f.evidence.cv_rms_m.and_then(finite));
        t.push(vec![
            f.round.to_string(),
            f.effect.replace('_', " "),
            crate::report::formula::form(f.form),
            (if f.accepted { "yes" } else { "no" }).into(),
            params_text(f.parameters),
            evidence_text(f.effect, f.evidence),
            cv.map_or("—".into(), |x| format!("{:.3}", x * 1e6)),
        ]);
    }
    if accepted.is_empty() {
        b.para(if mismatch {
            "No candidate explains the mismatch well enough to be accepted (see the unexplained finding, if any, for where it is)."
        } else {
            "No candidate term was accepted."
        });
    } else {
        let names: Vec<String> = accepted
            .iter()
            .map(|f| f.effect.replace('_', " "))
            .collect();
        b.para(format!("Accepted physics: {}.", names.join(", ")));
    }
    if !t.rows.is_empty() {
        b.table(t);
    }
    if let Some(t) = collision_table(diag) {
        b.table(t);
    }
    if !diag.note.is_empty() {
        // e.g. collision runs left untested because the pair fit cannot carry an accepted term
        b.para(format!(
            "Notes of the discover stage: {}.",
            diag.note.trim_end_matches('.')
        ));
    }
    b.figure(figs, "fig_discovery_cv.svg", "Held-out (leave-runs-out) RMS of the simulated trajectories: baseline against each candidate's extended model.");
    if let Some(t) = structure_table(diag) {
        b.table(t);
    }
    b.figure(figs, "fig_discovery_drift.svg", "The drift that flagged the mismatch: fitted T against |v0| for the baseline (grey) and for the extended model (green), with regression lines.");
    for (v, what) in [
        ("z", "the position in the lab"),
        ("v", "the signed velocity"),
        ("t", "the time since the kick"),
    ] {
        b.figure(
            figs,
            &format!("fig_discovery_forcemap_{v}.svg"),
            &format!("Force map: the missing acceleration as a smooth function of {what} (penalized spline over every run, smoothness by leave-runs-out cross-validation, 95 % band), for the baseline (grey) and with the accepted physics (green). A band that holds zero is the picture of nothing missing in that variable."),
        );
    }
    if let Some(t) = drift_table(diag) {
        b.table(t);
    }
    if let Some(v) = &d.validation {
        truth_block(&mut b, d, diag, v);
    }
    b.para(match accepted.first() {
        Some(f) => format!("Comparison with the chapter's correction (Eq. 4.8): {}", compare_with_eq_4_8(d, f)),
        None => "Comparison with the chapter's correction (Eq. 4.8): with nothing accepted there is no extended model to compare; Eq. 4.8's v/T0 − v²/L is in any case unphysical above L/T0 ≈ 48 mm/s (see the audit).".into(),
    });
    // the statistics behind the verdict, in full in report.md and diagnosis.json
    b.fold_tables();
    b
}

/// "a groove tilt above 0.02 ° would have been found", one per form, from the last round that
/// tested it.
/// The slow drift of the tracking noise in words: a measurement, not physics, and what it costs.
fn tracking_drift_text(t: &crate::artifacts::diagnosis::TrackingDrift) -> String {
    let on = if t.runs_left_out == 0 {
        "the runs' own fits".to_string()
    } else {
        format!(
            "the own fits of {} of the {} runs (the other {} wander beyond what a drift shared by the runs explains, so their wander is not read as the tracker's; they carry the drift measured on the others)",
            t.runs - t.runs_left_out.min(t.runs),
            t.runs,
            t.runs_left_out
        )
    };
    let line = if t.line_hz.1 > 0.0 {
        format!(
            " It was measured without the frequencies from {:.1} to {:.1} Hz: there the runs share a line that no drift's spectrum has, which no term of the final model takes up; it is left out of the noise, not explained.",
            t.line_hz.0, t.line_hz.1
        )
    } else {
        String::new()
    };
    format!(
        "The tracking noise also drifts slowly: a part of {:.2}× the variance of each run's frame-scale noise, correlated over {:.1} ms, measured on {on} under the final model. Every test's null carries it, so it is reported as noise, not physics, and it raises the detection limits of slow shapes (drags, a distortion, differences between particles).{line}",
        t.variance_ratio,
        1e3 * t.time_constant_s
    )
}

/// The tracking noise's growth with speed in words: a measurement, not physics.
fn tracking_blur_text(t: &crate::artifacts::diagnosis::TrackingBlur) -> String {
    format!(
        "The tracking noise grows with the particle's speed, as motion blur makes it: its variance is that at rest plus ({:.2} µm per m/s × speed)², the same for every run. Every test's null carries it, so it is reported as noise, not physics; it weighs most on what acts while the particles are fast (the sliding friction, differences between particles).",
        1e6 * t.noise_per_speed_s
    )
}

pub fn detection_limits(diag: &Diagnosis) -> Vec<String> {
    let mut by_form: BTreeMap<String, String> = BTreeMap::new();
    let mut order: Vec<String> = Vec::new();
    for c in &diag.candidates {
        let Some(l) = &c.evidence.detection_limit else {
            continue;
        };
        if !by_form.contains_key(&c.form) {
            order.push(c.form.clone());
        }
        by_form.insert(c.form.clone(), l.text.clone());
    }
    order
        .into_iter()
        .filter_map(|f| by_form.remove(&f))
        .collect()
}

/// `text` with its first letter upper case (a sentence made of a clause).
fn capitalize(text: &str) -> String {
    let mut c = text.chars();
    match c.next() {
        Some(first) => first.to_uppercase().chain(c).collect(),
        None => String::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_noise_growing_with_speed_is_said_as_noise_with_its_size() {
        let t = crate::artifacts::diagnosis::TrackingBlur {
            noise_per_speed_s: 4.96e-6,
        };
        let text = super::tracking_blur_text(&t);
        assert!(text.contains("4.96 µm per m/s"), "{text}");
        assert!(text.contains("noise, not physics"), "{text}");
    }

    #[test]
    fn a_slow_drift_of_the_tracking_noise_is_said_as_noise_with_its_size() {
        let mut t = crate::artifacts::diagnosis::TrackingDrift {
            variance_ratio: 1.2197,
            time_constant_s: 0.0128,
            runs: 60,
            runs_left_out: 0,
            line_hz: (0.0, 0.0),
        };
        let text = super::tracking_drift_text(&t);
        assert!(text.contains("1.22×") && text.contains("12.8 ms"), "{text}");
        assert!(text.contains("noise, not physics"), "{text}");
        assert!(text.contains("the runs' own fits"), "{text}");
        // runs left out of the estimate are said, with how many it was measured on
        t.runs_left_out = 4;
        let text = super::tracking_drift_text(&t);
        assert!(text.contains("56 of the 60 runs"), "{text}");
        assert!(text.contains("the other 4 wander"), "{text}");
        assert!(!text.contains("Hz"), "{text}");
        // a line left out of the estimate is said, as left out, not explained
        t.line_hz = (25.04, 41.66);
        let text = super::tracking_drift_text(&t);
        assert!(text.contains("from 25.0 to 41.7 Hz"), "{text}");
        assert!(text.contains("not explained"), "{text}");
    }

    #[test]
    fn the_drift_probes_of_where_are_read_in_the_shape_discover_writes() {
        let w: BTreeMap<String, Value> = serde_json::from_str(
            r#"{"drift_probes_before": [{"probe": "probe: T drifts with |v0|", "p_holm": 3e-300,
                "parameters": {"dT_dv_s_per_mps": {"stderr": 0.0024, "value": 1.101}}}]}"#,
        )
        .unwrap();
        let text = where_text(&w);
        assert!(text.contains("dT_dv_s_per_mps = 1.101 ± 0.0024"), "{text}");
    }

    #[test]
    fn without_a_mismatch_the_drift_probes_are_read_not_counted() {
        // discover writes `drift_probes` (no before/after) when nothing was accepted
        let w: BTreeMap<String, Value> = serde_json::from_str(
            r#"{"drift_probes": [{"probe": "probe: T drifts with |v0|", "p_holm": 1.0,
                "parameters": {"dT_dv_s_per_mps": {"stderr": 0.0098, "value": -0.0065}}}]}"#,
        )
        .unwrap();
        let text = where_text(&w);
        assert_eq!(
            text,
            "drift probes: T drifts with |v0| [dT_dv_s_per_mps = -0.006500 ± 0.0098, p (Holm) = 1.0]"
        );
        assert_eq!(capitalize(&text)[..12], *"Drift probes");
    }

    #[test]
    fn a_chi2_decided_finding_names_its_test_and_prints_no_bootstrap_zeros() {
        let pair = Evidence {
            lr: 0.7112,
            extra_params: 3,
            p_value: 0.8706,
            p_holm: 1.0,
            decision: "the single runs' physics explains the pair motion".into(),
            ..Evidence::default()
        };
        let text = evidence_text("pair_physics_mismatch", &pair);
        assert!(
            text.starts_with("χ² test: χ²(3) = 0.711; p = 0.871"),
            "{text}"
        );
        assert!(
            !text.contains("empirical") && !text.contains("LR"),
            "{text}"
        );
        let impact = Evidence {
            lr: 1.0737,
            p_value: 3.0e-4,
            ..Evidence::default()
        };
        let text = evidence_text("impact_specific_mismatch", &impact);
        assert!(
            text.starts_with("t test over runs: ") && text.contains("= 1.07"),
            "{text}"
        );
        assert!(!text.contains("empirical"), "{text}");
        // a bootstrap-decided candidate keeps its LR and empirical p
        let boot = Evidence {
            lr: 4.77,
            bootstrap_replicates: 24,
            p_value: 0.0773,
            p_empirical: 0.12,
            ..pair
        };
        let text = evidence_text("groove_tilt", &boot);
        assert!(
            text.starts_with("LR = 4.77; p = 0.0773; p (empirical) = 0.120"),
            "{text}"
        );
    }
}
