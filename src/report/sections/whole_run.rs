//! The whole-run collision fits in the report (beside Fig. 4.4a): the μ_pp profile per
//! material with what it says in words, the restitution law chosen by held-out error, and the
//! fits' status (summary.json → collisions.whole_run).

use super::{Block, Table};
use crate::report::inputs::ReportData;
use serde_json::Value;
use std::collections::BTreeMap;

fn num(v: &Value, k: &str) -> Option<f64> {
    v.get(k)?.as_f64()
}

/// The sentence about μ_pp of one material's profile verdict (`profile.verdict`).
pub fn mu_pp_words(material: &str, verdict: &Value) -> String {
    let kind = verdict.get("kind").and_then(Value::as_str).unwrap_or("");
    match kind {
        "interval" => {
            let (e, lo, hi) = (
                num(verdict, "estimate").unwrap_or(f64::NAN),
                num(verdict, "lo").unwrap_or(f64::NAN),
                num(verdict, "hi").unwrap_or(f64::NAN),
            );
            format!(
                "{material}: the profile has a minimum: μ_pp = {e:.3}, 95 % interval {lo:.3}–{hi:.3}; the chapter's 1.4 is {} it.",
                if lo <= 1.4 && 1.4 <= hi { "inside" } else { "outside" }
            )
        }
        "lower_bound" => format!(
            "{material}: the profile is flat above: the recordings bound μ_pp from below at {:.2} (95 %), and the chapter's 1.4 is {}.",
            num(verdict, "lo").unwrap_or(f64::NAN),
            if num(verdict, "lo").unwrap_or(f64::NAN) <= 1.4 { "allowed but not measured" } else { "excluded" }
        ),
        "upper_bound" => format!(
            "{material}: the profile is flat below: the recordings bound μ_pp from above at {:.2} (95 %).",
            num(verdict, "hi").unwrap_or(f64::NAN)
        ),
        _ => format!("{material}: the profile is flat: the recordings do not constrain μ_pp over the range profiled."),
    }
}

fn fmt_param(p: &Value) -> String {
    format!(
        "{} = {:.4} [{:.4}, {:.4}]",
        p.get("name").and_then(Value::as_str).unwrap_or("?"),
        num(p, "value").unwrap_or(f64::NAN),
        num(p, "lo").unwrap_or(f64::NAN),
        num(p, "hi").unwrap_or(f64::NAN)
    )
}

/// How the profile's deviance was scaled: by the residuals' serial correlation, by the runs'
/// dispersion, or not at all.
fn inflation_words(p: &Value) -> String {
    let rho = num(p, "score_lag1_autocorrelation").unwrap_or(f64::NAN);
    let rho_r = num(p, "lag1_autocorrelation").unwrap_or(f64::NAN);
    let serial = num(p, "serial_factor").unwrap_or(1.0);
    let disp = num(p, "dispersion").unwrap_or(1.0);
    if serial <= 1.0 && disp <= 1.0 {
        format!("the profile interval is not widened: the μ_pp score's lag-1 autocorrelation is ρ = {rho:.2} (residuals' {rho_r:.2}) and the run dispersion {disp:.2}")
    } else if serial >= disp {
        format!("the profile interval is widened by the residuals' serial correlation: the μ_pp score's lag-1 autocorrelation is ρ = {rho:.2} (residuals' {rho_r:.2}), so the deviance is divided by (1 + ρ)/(1 − ρ) = {serial:.2} (run dispersion {disp:.2})")
    } else {
        format!("the profile interval is widened by the runs' dispersion: the deviance is divided by {disp:.2} (the μ_pp score's lag-1 autocorrelation ρ = {rho:.2}, residuals' {rho_r:.2}, factor {serial:.2})")
    }
}

/// The block, or None when the summary has no whole-run fits.
pub fn block(d: &ReportData, figs: &BTreeMap<String, String>) -> Option<Block> {
    let whole = d.whole_run_json()?;
    let mats = whole.get("materials")?.as_array()?;
    let mut b = Block::new("whole-run", "3.5.1 μ_pp and restitution from whole runs");
    b.para(
        "Each material's collision runs are fitted together, every run over its whole recording: the event-driven two-particle model (every impact, first and secondary, and the sliding and rolling of both particles between them) with shared μ_pg, drag v/(T0 + T'|v|), μ_pp and one restitution law per setup, and per run the kick speed, kick time, start position and gap. The secondary impacts slip, so the whole runs say what the first (stick) impacts cannot. The profile holds μ_pp at each value and refits everything else; its deviance is divided by the larger of the runs' dispersion (how much more the runs disagree than their noise says) and the serial-correlation factor (1 + ρ)/(1 − ρ), ρ the pooled lag-1 autocorrelation of the best fit's residuals weighted by their sensitivity to μ_pp (the μ_pp score): successive positions of a sliding sphere miss the model together, so the samples carry less independent information than their number says.",
    );
    b.figure(
        figs,
        "fig_mu_pp_profile.svg",
        "μ_pp profile: square root of the whole-run fit's deviance above its best (divided by the larger of the run dispersion and the serial-correlation factor), μ_pp held at each value (clipped at 12); dashed: the 95 % level and the chapter's 1.4.",
    );
    let mut t = Table::new(
        "Whole-run fits per material",
        &[
            "material",
            "runs",
            "status (iterations)",
            "μ_pp (best fit)",
            "μ_pg",
            "T0 (s)",
            "T' (s per m/s)",
            "RMS / noise",
            "run dispersion",
        ],
    );
    for m in mats {
        let name = m.get("material").and_then(Value::as_str).unwrap_or("?");
        let est = |k: &str| {
            m.get(k)
                .map(|e| {
                    let v = num(e, "value").unwrap_or(f64::NAN);
                    match num(e, "se") {
                        Some(se) => format!("{v:.4} ± {se:.4}"),
                        None => format!("{v:.4}"),
                    }
                })
                .unwrap_or_default()
        };
        t.push(vec![
            name.to_string(),
            m.get("n_runs")
                .and_then(Value::as_u64)
                .unwrap_or(0)
                .to_string(),
            format!(
                "{} ({})",
                m.get("status")
                    .and_then(Value::as_str)
                    .unwrap_or("?")
                    .replace('_', " "),
                m.get("iterations").and_then(Value::as_u64).unwrap_or(0)
            ),
            est("mu_pp"),
            est("mu_pg"),
            est("t0_s"),
            est("tp_s_per_mps"),
            format!("{:.3}", num(m, "rms_noise").unwrap_or(f64::NAN)),
            format!(
                "{:.2}",
                m.get("profile")
                    .and_then(|p| num(p, "dispersion"))
                    .unwrap_or(f64::NAN)
            ),
        ]);
        if let Some(v) = m.get("profile").and_then(|p| p.get("verdict")) {
            b.para(mu_pp_words(name, v));
        }
        if let Some(p) = m.get("profile") {
            b.para(format!("{name}: {}.", inflation_words(p)));
        }
        for n in m
            .get("notes")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            if let Some(n) = n.as_str() {
                b.para(format!("{name}: {n}."));
            }
        }
    }
    b.table(t);
    let mut laws = Table::new(
        "Restitution law per material and setup, chosen by held-out error (k-fold over runs); parameters with 95 % intervals",
        &["material", "setup", "runs", "form", "parameters", "held-out RMS / noise"],
    );
    for m in mats {
        let name = m.get("material").and_then(Value::as_str).unwrap_or("?");
        for c in m
            .get("restitution")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            let chosen = c.get("chosen").and_then(Value::as_str).unwrap_or("");
            for cand in c
                .get("candidates")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                let form = cand.get("form").and_then(Value::as_str).unwrap_or("?");
                let params: Vec<String> = cand
                    .get("parameters")
                    .and_then(Value::as_array)
                    .into_iter()
                    .flatten()
                    .map(fmt_param)
                    .collect();
                laws.push(vec![
                    name.to_string(),
                    c.get("setup")
                        .and_then(Value::as_str)
                        .unwrap_or("?")
                        .to_string(),
                    c.get("n_runs")
                        .and_then(Value::as_u64)
                        .unwrap_or(0)
                        .to_string(),
                    if form == chosen {
                        format!("**{form}** (chosen)")
                    } else {
                        form.to_string()
                    },
                    params.join("; "),
                    format!("{:.4}", num(cand, "heldout_rms_noise").unwrap_or(f64::NAN)),
                ]);
            }
        }
    }
    b.table(laws);
    let mut res = Table::new(
        "Pair residuals of the whole-run fits, RMS in units of the noise (mean over runs), by phase of the particle and by time since the last impact",
        &["material", "phase or time since impact", "RMS / noise", "runs"],
    );
    for m in mats {
        let name = m.get("material").and_then(Value::as_str).unwrap_or("?");
        for key in ["residual_by_phase", "residual_by_time_since_impact"] {
            let mut acc: BTreeMap<String, (f64, usize)> = BTreeMap::new();
            for r in m
                .get("runs")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
            {
                for (k, v) in r.get(key).and_then(Value::as_object).into_iter().flatten() {
                    if let Some(x) = v.as_f64() {
                        let e = acc.entry(k.clone()).or_default();
                        e.0 += x;
                        e.1 += 1;
                    }
                }
            }
            for (k, (sum, n)) in acc {
                res.push(vec![
                    name.to_string(),
                    k,
                    format!("{:.3}", sum / n.max(1) as f64),
                    n.to_string(),
                ]);
            }
        }
    }
    b.table(res);
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn words_say_bound_or_interval_and_compare_with_the_chapter() {
        let lb = mu_pp_words("316", &json!({"kind": "lower_bound", "lo": 0.81}));
        assert!(
            lb.contains("bound μ_pp from below at 0.81") && lb.contains("allowed but not measured")
        );
        let iv = mu_pp_words(
            "440c",
            &json!({"kind": "interval", "estimate": 1.39, "lo": 1.35, "hi": 1.43}),
        );
        assert!(
            iv.contains("μ_pp = 1.390") && iv.contains("1.4 is inside"),
            "{iv}"
        );
        let out = mu_pp_words(
            "440c",
            &json!({"kind": "interval", "estimate": 0.3, "lo": 0.29, "hi": 0.31}),
        );
        assert!(out.contains("outside"), "{out}");
    }
}
