//! Section 4: discovery — where the mismatch is, the candidates and their evidence, the accepted
//! physics, before/after figures, and a comparison with the chapter's own correction (Eq. 4.8).

use super::{Block, Table};
use crate::report::chapter as ch;
use crate::report::inputs::ReportData;
use crate::report::value::{as_num, num, sig, text};
use serde_json::Value;
use std::collections::BTreeMap;

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
fn truth_block(b: &mut Block, d: &ReportData, diag: &Value, validation: &Value) {
    let Some(effects) = validation.get("effects") else {
        return;
    };
    let names = |k: &str| -> Vec<String> {
        effects
            .get(k)
            .and_then(Value::as_array)
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(|s| s.replace('_', " ")))
                    .collect()
            })
            .unwrap_or_default()
    };
    let truth_terms: Vec<&Value> = effects
        .get("truth")
        .and_then(Value::as_array)
        .map(|a| a.iter().collect())
        .unwrap_or_default();
    let truth_names: Vec<String> = truth_terms
        .iter()
        .map(|t| {
            format!(
                "{} ({})",
                text(t, &["effect"]).unwrap_or("?").replace('_', " "),
                t.get("term").map_or("—".into(), |x| short(x, 6))
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
        list(names("accepted")),
        list(names("missed")),
        list(names("spurious"))
    ));
    let mut t = Table::new(
        "Accepted parameters beside the truth",
        &["effect", "parameter", "ours", "truth"],
    );
    let findings = diag
        .get("findings")
        .and_then(Value::as_array)
        .map(|a| a.as_slice())
        .unwrap_or(&[]);
    for f in findings
        .iter()
        .filter(|f| f.get("accepted").and_then(Value::as_bool) == Some(true))
    {
        let effect = text(f, &["effect"]).unwrap_or("");
        let Some(Value::Object(ps)) = f.get("parameters") else {
            continue;
        };
        let term = truth_terms
            .iter()
            .find(|t| text(t, &["effect"]) == Some(effect))
            .and_then(|t| t.get("term"));
        for (name, p) in ps {
            let ours = match (as_num(p), num(p, &["stderr", "se"])) {
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
                .and_then(|t| num(t, &[name, &base]))
                .map_or("—".into(), |x| sig(x, 4));
            t.push(vec![effect.replace('_', " "), name.clone(), ours, truth]);
        }
    }
    if !t.rows.is_empty() {
        b.table(t);
    }
}

/// The decisive statistics of a candidate's evidence (LR, p-values, CV), else a compact dump.
pub fn evidence_text(e: &Value) -> String {
    let keys = [
        ("lr", "LR"),
        ("p_value", "p"),
        ("p_empirical", "p (empirical)"),
        ("p_holm", "p (Holm)"),
        ("cv_paired_t", "CV paired t"),
        ("decision", "decision"),
    ];
    let parts: Vec<String> = keys
        .iter()
        .filter_map(|(k, label)| match e.get(*k)? {
            Value::String(s) => Some(format!("{label}: {s}")),
            v => as_num(v).map(|x| format!("{label} = {}", sig(x, 3))),
        })
        .collect();
    if parts.is_empty() {
        short(e, 6)
    } else {
        parts.join("; ")
    }
}

/// Residual RMS before and after by phase, speed, position, direction and material
/// (diagnosis.json `residuals_before` / `residuals_after`).
fn structure_table(diag: &Value) -> Option<Table> {
    let before = diag.get("residuals_before").filter(|v| v.is_object())?;
    let after = diag.get("residuals_after").filter(|v| v.is_object());
    let mut t = Table::new(
        "Residuals before and after, pooled over runs (RMS in µm; RMS/noise in brackets)",
        &["by", "bin", "samples", "before", "after"],
    );
    let cell = |bin: Option<&Value>| {
        let Some(bin) = bin else {
            return "—".to_string();
        };
        match (num(bin, &["rms_m"]), num(bin, &["rms_over_noise"])) {
            (Some(r), Some(q)) => format!("{:.3} ({:.2})", r * 1e6, q),
            (Some(r), None) => format!("{:.3}", r * 1e6),
            _ => "—".into(),
        }
    };
    for (key, label) in [
        ("by_phase", "phase"),
        ("by_speed", "speed"),
        ("by_position", "position"),
        ("by_direction", "direction"),
        ("by_material", "material"),
    ] {
        let Some(Value::Object(bins)) = before.get(key) else {
            continue;
        };
        for (name, bin) in bins {
            // bins are matched by name, else by their index prefix (`2: …`), as edges may shift
            let a = after.and_then(|a| a.get(key)).and_then(|m| {
                m.get(name).or_else(|| {
                    let idx = name.split(':').next()?;
                    m.as_object()?
                        .iter()
                        .find(|(k, _)| k.split(':').next() == Some(idx))
                        .map(|(_, v)| v)
                })
            });
            t.push(vec![
                label.into(),
                name.clone(),
                num(bin, &["n"]).map_or("—".into(), |n| format!("{n:.0}")),
                cell(Some(bin)),
                cell(a),
            ]);
        }
    }
    for (key, label) in [
        ("runs_test_z", "runs test z"),
        ("lag1_autocorrelation", "lag-1 autocorrelation"),
    ] {
        if let Some(x) = num(before, &[key]) {
            let y = after.and_then(|a| num(a, &[key]));
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
fn drift_table(diag: &Value) -> Option<Table> {
    let drift = diag.get("drift").filter(|v| v.is_object())?;
    let (Some(Value::Object(before)), after) =
        (drift.get("lines_before"), drift.get("lines_after"))
    else {
        return None;
    };
    let mut t = Table::new(
        "Drift of per-run parameters: regression slopes before and after (t = slope/se)",
        &["line", "slope before", "t before", "slope after", "t after"],
    );
    let fmt = |l: Option<&Value>| -> (String, String) {
        let Some(l) = l else {
            return ("—".into(), "—".into());
        };
        let slope = match (num(l, &["slope"]), num(l, &["slope_se"])) {
            (Some(s), Some(se)) => format!("{} ± {}", sig(s, 3), sig(se, 2)),
            (Some(s), None) => sig(s, 3),
            _ => "—".into(),
        };
        (
            slope,
            num(l, &["t"]).map_or("—".into(), |x| format!("{x:.1}")),
        )
    };
    for (name, l) in before {
        let (sb, tb) = fmt(Some(l));
        let (sa, ta) = fmt(after.and_then(|a| a.get(name)));
        t.push(vec![name.clone(), sb, tb, sa, ta]);
    }
    if let Some(note) = drift
        .get("note")
        .and_then(Value::as_str)
        .filter(|n| !n.is_empty())
    {
        t.caption.push_str(&format!(" — {note}"));
    }
    (!t.rows.is_empty()).then_some(t)
}

/// `name = value ± stderr` for each parameter of a finding.
pub fn params_text(f: &Value) -> String {
    let Some(Value::Object(ps)) = f.get("parameters") else {
        return "—".into();
    };
    let parts: Vec<String> = ps
        .iter()
        .map(|(k, p)| {
            let v = as_num(p).map_or("—".into(), |x| sig(x, 4));
            match num(p, &["stderr", "se"]) {
                Some(se) => format!("{k} = {v} ± {}", sig(se, 2)),
                None => format!("{k} = {v}"),
            }
        })
        .collect();
    if parts.is_empty() {
        "—".into()
    } else {
        parts.join(", ")
    }
}

fn param(f: &Value, names: &[&str]) -> Option<f64> {
    f.get("parameters").and_then(|p| num(p, names))
}

/// A parameter that may be fitted per material (`t0_s`, or `t0_s_316`, `t0_s_440c`), as text with
/// `unit`, e.g. "0.0540 s (316), 0.0540 s (440c)".
fn param_text(f: &Value, name: &str, unit: &str) -> Option<String> {
    let Some(Value::Object(ps)) = f.get("parameters") else {
        return None;
    };
    let parts: Vec<String> = ps
        .iter()
        .filter_map(|(k, v)| {
            let x = as_num(v)?;
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

/// Where discovery located the mismatch, in words: the worst residual bins, the residual structure,
/// and the drift probes before and after (falls back to a compact dump for other layouts).
fn where_text(w: &Value) -> String {
    let mut parts = Vec::new();
    if let Some(r) = w.get("residuals_before") {
        if let Some(bins) = r.get("largest_residuals").and_then(Value::as_array) {
            let list: Vec<String> = bins
                .iter()
                .filter_map(|b| {
                    Some(format!(
                        "{} ({:.1}× noise)",
                        text(b, &["bin"])?,
                        num(b, &["rms_over_noise"])?
                    ))
                })
                .collect();
            if !list.is_empty() {
                parts.push(format!("largest baseline residuals in {}", list.join(", ")));
            }
        }
        if let (Some(z), Some(a)) = (num(r, &["runs_test_z"]), num(r, &["lag1_autocorrelation"])) {
            parts.push(format!("residuals correlated within runs (runs test z = {z:.0}, lag-1 autocorrelation {a:.2})"));
        }
    }
    for (key, when) in [
        ("drift_probes_before", "before"),
        ("drift_probes_after", "after"),
    ] {
        let Some(list) = w.get(key).and_then(Value::as_array) else {
            continue;
        };
        let probes: Vec<String> = list
            .iter()
            .filter_map(|p| {
                let name = text(p, &["probe"])?
                    .trim_start_matches("probe: ")
                    .to_string();
                let params = params_text(p);
                let ph = num(p, &["p_holm"])
                    .map_or(String::new(), |x| format!(", p (Holm) = {}", sig(x, 2)));
                Some(format!("{name} [{params}{ph}]"))
            })
            .collect();
        if !probes.is_empty() {
            parts.push(format!(
                "drift probes {when} the accepted physics: {}",
                probes.join("; ")
            ));
        }
    }
    if parts.is_empty() {
        short(w, 8)
    } else {
        parts.join("; ")
    }
}

/// How an accepted finding relates to the chapter's Eq. 4.8 correction, in words and numbers.
fn compare_with_eq_4_8(d: &ReportData, f: &Value) -> String {
    let effect = text(f, &["effect"]).unwrap_or("");
    let form = text(f, &["form"]).unwrap_or("").to_ascii_lowercase();
    let v_star = ch::L_M / ch::T0_S * 1e3;
    match effect {
        "velocity_dependent_drag" if form.contains("satur") => {
            let t0 = param_text(f, "t0_s", "s");
            let tp = param_text(f, "tp_s_per_mps", "s per m/s");
            let per_run = crate::report::summary::t_line(d, None)
                .map(|(_, b)| format!(" The per-run linear-drag fits average T0 + T'|v| over a run whose speed decays from v0, so their T rises with v0 with a smaller slope ({} s per m/s here, 1.10 in the chapter) than the T' of the law itself.", sig(b.est.value, 3)))
                .unwrap_or_default();
            format!(
                "The accepted drag v/(T0 + T'|v|) is the form the chapter's line T = T0 + T'·v0 suggests before Eq. 4.7 truncates it. Ours: T0 = {}, T' = {} (chapter 0.052 s and 1.10 s per m/s).{per_run} Unlike Eq. 4.8's v/T0 − v²/L, it stays dissipative at every speed; Eq. 4.8 turns into propulsion above L/T0 = {v_star:.0} mm/s.",
                t0.unwrap_or_else(|| "—".into()),
                tp.unwrap_or_else(|| "—".into())
            )
        }
        "velocity_dependent_drag" => {
            let c = param_text(f, "c_per_m", "per m").or_else(|| param_text(f, "c", "per m"));
            format!(
                "The accepted quadratic drag c·v|v| has c = {} (Eq. 4.8's −v²/L corresponds to c = −1/L = −400 per m). A fitted sign and size, unlike Eq. 4.8's, is what the data support; Eq. 4.8 with L = 2.5 mm changes sign at {v_star:.0} mm/s.",
                c.unwrap_or_else(|| "—".into())
            )
        }
        "rolling_resistance" => format!(
            "A constant resistance c·g opposing motion also makes the fitted linear-drag T grow with v0, the signature the chapter read as a quadratic drag term (Eq. 4.8). Discovery tested both as candidates and the evidence selects rolling resistance (deceleration {}); Eq. 4.8's v/T0 − v²/L would in addition change sign at {v_star:.0} mm/s.",
            param(f, &["deceleration_mps2", "c_g_mps2", "a_mps2", "decel_mps2"])
                .or_else(|| param(f, &["c"]).map(|c| c * crate::physics::G_MPS2))
                .map_or("see the table".into(), |x| format!("{} m/s²", sig(x, 3)))
        ),
        _ => format!(
            "Eq. 4.8 corrects only the drag (v/T0 − v²/L); the accepted {} is a different physical effect that the chapter's model does not contain.",
            effect.replace('_', " ")
        ),
    }
}

pub fn block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new("discovery", "4. Discovery");
    let Some(diag) = &d.diagnosis else {
        b.missing = Some("discovery did not run for this report (no diagnosis.json)".into());
        return b;
    };
    let mismatch = diag
        .get("mismatch")
        .and_then(Value::as_bool)
        .unwrap_or(false);
    let findings: Vec<&Value> = diag
        .get("findings")
        .and_then(Value::as_array)
        .map(|a| a.iter().collect())
        .unwrap_or_default();
    let accepted: Vec<&&Value> = findings
        .iter()
        .filter(|f| f.get("accepted").and_then(Value::as_bool) == Some(true))
        .collect();
    b.para(if mismatch {
        "The baseline misses systematically: the per-run fits and residuals, pooled over runs, show structure beyond the noise."
    } else {
        "No systematic mismatch: the pooled residuals and the per-run parameters show no structure beyond the noise, so nothing is missing from the baseline."
    });
    for f in &findings {
        if let Some(w) = f
            .get("where")
            .filter(|w| !w.is_null() && w.as_object().is_none_or(|o| !o.is_empty()))
        {
            let effect = text(f, &["effect"]).unwrap_or("?").replace('_', " ");
            b.para(format!("Where ({effect}): {}.", where_text(w)));
            break;
        }
    }
    // every candidate tested (diagnosis.candidates, by round), else the findings
    let rows: Vec<&Value> = match diag.get("candidates").and_then(Value::as_array) {
        Some(c) if !c.is_empty() => c.iter().collect(),
        _ => findings.clone(),
    };
    let baseline_cv = diag
        .get("baseline_model")
        .and_then(|m| num(m, &["cv_rms_m"]))
        .or_else(|| {
            findings
                .iter()
                .find_map(|f| f.get("baseline").and_then(|m| num(m, &["cv_rms_m"])))
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
            .get("extended")
            .and_then(|x| num(x, &["cv_rms_m"]))
            .or_else(|| f.get("evidence").and_then(|e| num(e, &["cv_rms_m"])));
        t.push(vec![
            num(f, &["round"])
                .or_else(|| f.get("evidence").and_then(|e| num(e, &["round"])))
                .map_or("—".into(), |r| format!("{r:.0}")),
            text(f, &["effect"]).unwrap_or("?").replace('_', " "),
            text(f, &["form"]).unwrap_or("—").to_string(),
            (if f.get("accepted").and_then(Value::as_bool) == Some(true) {
                "yes"
            } else {
                "no"
            })
            .into(),
            params_text(f),
            f.get("evidence").map_or("—".into(), evidence_text),
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
            .map(|f| text(f, &["effect"]).unwrap_or("?").replace('_', " "))
            .collect();
        b.para(format!("Accepted physics: {}.", names.join(", ")));
    }
    if !t.rows.is_empty() {
        b.table(t);
    }
    b.figure(figs, "fig_discovery_cv.svg", "Held-out (leave-runs-out) RMS of the simulated trajectories: baseline against each candidate's extended model.");
    if let Some(t) = structure_table(diag) {
        b.table(t);
    }
    b.figure(figs, "fig_discovery_drift.svg", "The drift that flagged the mismatch: fitted T against |v0| for the baseline (grey) and for the extended model (green), with regression lines.");
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
    b
}
