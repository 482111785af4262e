//! Section 3, single runs: Figs. 4.2b–d, each with our values beside the chapter's (and the truth).

use super::summary::agg_text;
use super::{Block, Table};
use crate::report::chapter as ch;
use crate::report::figures::fig_4_2b;
use crate::report::inputs::ReportData;
use crate::report::summary::{mu_all, mu_fast, t_line};
use crate::report::truth;
use crate::report::value::{pm, sig};
use std::collections::BTreeMap;

/// Headers of a comparison table: the truth column only when a truth file was validated.
pub fn headers(d: &ReportData, first: &[&str]) -> Vec<String> {
    let mut h: Vec<String> = first.iter().map(|s| s.to_string()).collect();
    h.extend(["ours".to_string(), "chapter".to_string()]);
    if d.validation.is_some() {
        h.push("truth".into());
    }
    h
}

/// A comparison row: label cells, ours, chapter, and the truth found under `tokens`.
pub fn row(
    d: &ReportData,
    labels: Vec<String>,
    ours: String,
    chapter: String,
    tokens: &[&str],
) -> Vec<String> {
    let mut r = labels;
    r.extend([ours, chapter]);
    if let Some(v) = &d.validation {
        let rows = truth::rows(v);
        r.push(truth::lookup(&rows, tokens).map_or("—".into(), |t| sig(t, 4)));
    }
    r
}

fn table(d: &ReportData, caption: &str, first: &[&str]) -> Table {
    let mut t = Table::new(caption, &[]);
    t.headers = headers(d, first);
    t
}

/// The run id a figure's caption names after `prefix` (up to the next " (").
pub fn caption_run(svg: &str, prefix: &str) -> Option<String> {
    let rest = &svg[svg.find(prefix)? + prefix.len()..];
    Some(rest[..rest.find(" (")?].to_string())
}

fn fig_4_2b_block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new(
        "fig-4-2b",
        "3.1 Fig. 4.2b: one trajectory, sliding then rolling",
    );
    // the run the figures stage drew (its caption names it), else the default choice
    let drawn = figs
        .get("fig_4_2b.svg")
        .and_then(|svg| caption_run(svg, "Fig. 4.2b: run "));
    let Some(fit) =
        fig_4_2b::choose(d, drawn.as_deref()).filter(|_| figs.contains_key("fig_4_2b.svg"))
    else {
        b.missing = Some("no single runs with a converged fit in this dataset".into());
        return b;
    };
    b.lead = Some(super::leads::trajectory(d, fit));
    let under_accepted = figs
        .get("fig_4_2b.svg")
        .is_some_and(|svg| svg.contains(fig_4_2b::ACCEPTED_LABEL));
    let caption = if under_accepted {
        "Fig. 4.2b: observed positions (green sliding, magenta rolling), the fitted baseline (black) and the run fitted under the physics discovery accepted (orange, dashed: the material's μ and drag from section 3.8, every accepted term carried, the run's own start fitted); the grey dashed line marks the baseline's switch to rolling. Below, on the same time axis, the residuals of the model the report trusts: data − the fit under the accepted physics, in µm."
    } else {
        "Fig. 4.2b: observed positions (green sliding, magenta rolling) and the fitted baseline (black); the dashed line marks the switch to rolling. Below, on the same time axis, the residuals: data − fitted baseline in µm."
    };
    b.figure(figs, "fig_4_2b.svg", caption);
    b.para(format!(
        "Run {} ({}) is the run whose |v0| is closest to the chapter's example of 0.025 m/s. The particle slides (its spin builds up under Coulomb friction) until v = s·v_a at t1, then rolls without sliding, decaying with $T_e = T(1 + ks^2)/ks^2 \\approx 2.2\\,T$.",
        fit.run, fit.material
    ));
    let mut t = table(d, "Fig. 4.2b: the example run", &["quantity"]);
    t.push(row(
        d,
        vec!["v0 (m/s)".into()],
        pm(fit.v0_mps),
        "0.025".into(),
        &[fit.run.as_str(), "v0_mps"],
    ));
    t.push(row(
        d,
        vec!["μ_pg".into()],
        pm(fit.mu),
        "—".into(),
        &[fit.run.as_str(), "mu"],
    ));
    t.push(row(
        d,
        vec!["T (s)".into()],
        pm(fit.t_drag_s),
        format!("{:.3} (its T line at 0.025 m/s)", ch::t_line_s(0.025)),
        &[fit.run.as_str(), "T_s"],
    ));
    t.push(row(
        d,
        vec!["t1 (ms)".into()],
        fit.t1_s.map_or("—".into(), |x| format!("{:.2}", x * 1e3)),
        "—".into(),
        &[fit.run.as_str(), "t1_s"],
    ));
    t.push(row(
        d,
        vec!["residual RMS (µm)".into()],
        fit.rms_m.map_or("—".into(), |x| format!("{:.2}", x * 1e6)),
        "—".into(),
        &["__none__"],
    ));
    b.table(t);
    b
}

fn fig_4_2c_block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new("fig-4-2c", "3.2 Fig. 4.2c: drag time T against v0");
    if !b.figure(figs, "fig_4_2c.svg", "Fig. 4.2c: fitted T per run against |v0| (log scale), our regression line per material (solid), the chapter's line (dashed) and the Stokes time of free air (grey dashed).") {
        b.missing = Some("no single runs with a converged fit in this dataset".into());
        return b;
    }
    let stokes = ch::stokes_time_s(ch::RADIUS_M, ch::DENSITY_KG_M3, ch::AIR_VISCOSITY_PA_S);
    if let Some((a, s)) = t_line(d, None) {
        let trend = if s.est.value > 0.0 { "rises" } else { "falls" };
        b.lead = Some(format!(
            "The drag time T {trend} with |v0|: T = {} s + {} s per m/s · |v0| over all runs, against the chapter's 0.052 + 1.10·v0{}.",
            crate::report::value::pm(a.est),
            crate::report::value::pm(s.est),
            if a.est.value * 10.0 < stokes {
                format!("; far below the {stokes:.1} s of drag in free air")
            } else {
                String::new()
            }
        ));
    }
    b.para(format!(
        "The Stokes time of a 150 µm steel sphere in free air is $m/(6\\pi\\eta R)$ = {stokes:.1} s (ρ = 7900 kg/m³, η = 1.81e-5 Pa·s). The chapter's 0.074 s is wrong: it is what its own line $T = 0.052 + 1.10\\,v_0$ gives at v0 = 0.02 m/s. The measured T is some 40× shorter, so the dissipation is not free-air drag."
    ));
    let mut t = table(
        d,
        "Fig. 4.2c: the $T = T_0 + T'\\lvert v_0\\rvert$ line",
        &["material", "quantity"],
    );
    let mut mats: Vec<Option<String>> = d
        .materials()
        .into_iter()
        .filter(|m| d.singles_of(m).next().is_some())
        .map(Some)
        .collect();
    mats.push(None);
    for m in &mats {
        if let Some((a, s)) = t_line(d, m.as_deref()) {
            let name = m.clone().unwrap_or_else(|| "all".into());
            let tok = m.as_deref().unwrap_or("pooled");
            t.push(row(
                d,
                vec![name.clone(), "T0 (s)".into()],
                agg_text(&a),
                "0.052".into(),
                &[tok, "intercept_s"],
            ));
            t.push(row(
                d,
                vec![name, "T' (s per m/s)".into()],
                agg_text(&s),
                "1.10".into(),
                &[tok, "slope_s_per_mps"],
            ));
        }
    }
    t.push(row(
        d,
        vec!["—".into(), "Stokes time, free air (s)".into()],
        format!("{stokes:.2}"),
        "0.074 (wrong)".into(),
        &["__none__"],
    ));
    b.table(t);
    b
}

fn fig_4_2d_block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new("fig-4-2d", "3.3 Fig. 4.2d: friction μ_pg against v0");
    if !b.figure(figs, "fig_4_2d.svg", "Fig. 4.2d: fitted μ_pg per run against |v0|; solid lines our means for |v0| > 0.03 m/s (dotted vertical line), dashed lines the chapter's.") {
        b.missing = Some("no single runs with a converged fit in this dataset".into());
        return b;
    }
    let fast: Vec<String> = d
        .materials()
        .iter()
        .filter_map(|m| {
            let a = mu_fast(d, m)?;
            let chv = ch::mu_for(m).map_or(String::new(), |v| format!(" (chapter {v:.3})"));
            Some(format!("{m} {}{chv}", crate::report::value::pm(a.est)))
        })
        .collect();
    if !fast.is_empty() {
        b.lead = Some(format!(
            "The friction coefficient μ_pg of the runs faster than 0.03 m/s: {}.",
            fast.join(", ")
        ));
    }
    let mut t = table(d, "Fig. 4.2d: μ_pg per material", &["material", "quantity"]);
    for m in d.materials() {
        if d.singles_of(&m).next().is_none() {
            continue;
        }
        let chv = ch::mu_for(&m).map_or("—".into(), |v| format!("{v:.3}"));
        if let Some(a) = mu_fast(d, &m) {
            t.push(row(
                d,
                vec![m.clone(), "mean for |v0| > 0.03 m/s".into()],
                agg_text(&a),
                chv.clone(),
                &[&m, "mu_fast"],
            ));
        }
        if let Some(a) = mu_all(d, &m) {
            t.push(row(
                d,
                vec![m.clone(), "weighted mean, all runs".into()],
                agg_text(&a),
                "—".into(),
                &[&m, "mu_weighted"],
            ));
        }
        let n = d.singles_of(&m).count();
        t.push(row(
            d,
            vec![m.clone(), "runs".into()],
            n.to_string(),
            "—".into(),
            &["__none__"],
        ));
    }
    b.table(t);
    b.para("The caption of Fig. 4.2 prints 0.296 for 440c where the text and Eq. 4.8 give 0.293; the table uses 0.293 (see the equation audit).");
    b
}

/// The blocks of Figs. 4.2b–d.
pub fn blocks(d: &ReportData, figs: &BTreeMap<String, String>) -> Vec<Block> {
    vec![
        fig_4_2b_block(d, figs),
        fig_4_2c_block(d, figs),
        fig_4_2d_block(d, figs),
    ]
}
