//! Section 3, collisions: Figs. 4.3c–d, 4.4a–c and the secondary-collision factor with its bound.

use super::chapter::{headers, row};
use super::summary::agg_text;
use super::{Block, Table};
use crate::physics::Groove;
use crate::physics::Restitution;
use crate::report::chapter as ch;
use crate::report::figures::{fig_4_3, fig_4_4, restitution_name, secondary};
use crate::report::inputs::ReportData;
use crate::report::summary::mu_pp;
use crate::report::value::sig;
use std::collections::BTreeMap;

const NO_COLLISIONS: &str = "no collision runs in this dataset";

fn fig_4_3_block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new(
        "fig-4-3",
        "3.4 Figs. 4.3c–d: a collision, and the striker's four segments",
    );
    let drawn = figs
        .get("fig_4_3c.svg")
        .and_then(|svg| super::chapter::caption_run(svg, "Fig. 4.3c: collision run "));
    let Some(c) =
        fig_4_3::choose(d, drawn.as_deref()).filter(|_| figs.contains_key("fig_4_3c.svg"))
    else {
        b.missing = Some(NO_COLLISIONS.into());
        return b;
    };
    b.lead = Some(super::leads::collision(d, c));
    b.figure(figs, "fig_4_3c.svg", "Fig. 4.3c: striker (grey) and target (teal) positions with the fitted segments (dark lines); dashed lines mark the fitted impacts. Below, on the same time axis, each particle's residuals: data − fitted segments in µm, where a segment is fitted.");
    b.figure(figs, "fig_4_3d.svg", "Fig. 4.3d: the striker's samples by segment: sliding (green) and rolling (magenta), before (circles) and after (triangles) the impact; the black line is the fitted motion.");
    b.para(format!(
        "Run {} ({}, {} setup). After the impact the striker's spin exceeds v/s, so friction pushes it forward again (v − s·v_a < 0): it catches up with the target and the pair ends up rolling about 2R apart, as secondary collisions predict.",
        c.run,
        c.material,
        if c.contact { "contact" } else { "rolling" }
    ));
    let mut t = Table::new(
        "Fig. 4.3c–d: impacts of this run",
        &["impact", "t (ms)", "impact speed (m/s)", "C", "regime"],
    );
    for (i, im) in c.impacts.iter().enumerate() {
        t.push(vec![
            (i + 1).to_string(),
            im.t_s.map_or("—".into(), |x| format!("{:.2}", x * 1e3)),
            format!("{:.4}", im.speed_mps),
            im.restitution.map_or("—".into(), |x| format!("{x:.3}")),
            match im.slip {
                Some(true) => "slip".into(),
                Some(false) => "stick".into(),
                None => "—".into(),
            },
        ]);
    }
    if !t.rows.is_empty() {
        b.table(t);
    }
    if c.segments.iter().filter(|s| s.particle == 0).count() == 0 {
        b.para("The collision fit of this run lists no motion segments, so Fig. 4.3d separates the striker's samples only at the impact.");
    }
    b
}

fn fig_4_4a_block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new(
        "fig-4-4a",
        "3.5 Fig. 4.4a: spin change against velocity change, μ_pp",
    );
    if !b.figure(figs, "fig_4_4a.svg", "Fig. 4.4a: target's Δv_a against Δv_z; filled markers slip collisions, open markers stick; lines through the origin with slope μ_pp·k.") {
        b.missing = Some(if d.collisions.is_empty() { NO_COLLISIONS.into() } else { "no impact carries the target's velocity and spin changes".into() });
        return b;
    }
    b.lead = super::leads::mu_pp(d);
    let k = d.groove.k;
    let impacts: Vec<_> = d.collisions.iter().flat_map(|c| &c.impacts).collect();
    let slip = impacts.iter().filter(|i| i.slip == Some(true)).count();
    let stick = impacts.iter().filter(|i| i.slip == Some(false)).count();
    b.para(format!(
        "The slope of Δv_a against Δv_z of the target is μ_pp·k only for slip collisions ({slip} here); in stick collisions ({stick}) the spins equalise and the slope says nothing about μ_pp, so those are left out of the estimate."
    ));
    let mut t = Table::new("Fig. 4.4a: particle–particle friction", &[]);
    t.headers = headers(d, &["quantity"]);
    let lower = crate::report::summary::mu_pp_stick_lower_bound(d);
    if let Some(lb) = lower {
        t.push(row(
            d,
            vec!["μ_pp lower bound from stick impacts".into()],
            format!("> {lb:.2}"),
            "—".into(),
            &["mu_pp"],
        ));
    }
    if let Some(a) = mu_pp(d, k) {
        t.push(row(
            d,
            vec![format!("μ_pp ({})", a.source)],
            agg_text(&a),
            "1.4".into(),
            &["mu_pp"],
        ));
        t.push(row(
            d,
            vec!["slope μ_pp·k".into()],
            format!("{:.2}", a.est.value * k),
            format!("{:.2}", ch::MU_PP * k),
            &["__none__"],
        ));
    }
    b.table(t);
    b
}

/// The truth file's restitution law of a material and setup (validation.json), compactly.
fn truth_law(d: &ReportData, material: &str, setup: &str) -> Option<String> {
    let list = d.validation.as_ref()?.parameters.as_ref()?;
    let q = format!("restitution_{setup}");
    let law = list.iter().find_map(|r| match r {
        crate::artifacts::validation::ParameterCheck::Law {
            material: m,
            quantity,
            truth_law,
        } if m == material && *quantity == q => Some(truth_law),
        _ => None,
    })?;
    Some(match serde_json::from_str::<Restitution>(law) {
        Ok(r) => law_words(&r),
        // a law this build does not know: its JSON, flattened
        Err(_) => super::discovery::short(&serde_json::from_str(law).ok()?, 4),
    })
}

/// A truth law in the words and parameter names of the fitted laws (the whole-run table's
/// `constant`, `linear`, `saturating`), so the two can be read side by side.
fn law_words(r: &Restitution) -> String {
    match *r {
        Restitution::Constant(c) => format!("constant: c = {}", sig(c, 4)),
        Restitution::SpeedDependent { c0, v_ref_mps } => format!(
            "saturating: c_inf = {}; v_ref_mps = {}",
            sig(c0, 4),
            sig(v_ref_mps, 4)
        ),
        Restitution::Linear { c0, slope_per_mps } => format!(
            "linear: c0 = {}; slope_per_mps = {}",
            sig(c0, 4),
            sig(slope_per_mps, 4)
        ),
        // laws beyond the candidates, in the words of the laws carried from discovery
        other => crate::report::impact_laws::discovered_law(&other)
            .replace(", held from discovery", "")
            .replace("discovery's map, its values refitted: ", "map: "),
    }
}

fn fig_4_4bc_block(d: &ReportData, figs: &BTreeMap<String, String>) -> Block {
    let mut b = Block::new(
        "fig-4-4bc",
        "3.6 Figs. 4.4b–c: restitution against impact speed",
    );
    let mut mats: Vec<String> = d.collisions.iter().map(|c| c.material.clone()).collect();
    mats.sort();
    mats.dedup();
    let mut any = false;
    for m in &mats {
        let (name, fig) = restitution_name(m);
        any |= b.figure(figs, &name, &format!("Fig. {fig}: $C = (v_2' - v_1')/(v_1 - v_2)$ against impact speed for {m}, rolling pairs and pairs initially in contact; solid lines: the law each setup's whole-run fit chose (the table of 3.5.1), or $C = 1 - a v$ without a whole-run fit."));
    }
    if !any {
        b.missing = Some(NO_COLLISIONS.into());
        return b;
    }
    b.lead = super::leads::restitution(d);
    let mut t = Table::new(
        "Figs. 4.4b–c: restitution C = 1 − a·v per material and setup",
        &[
            "material",
            "setup",
            "impacts",
            "mean C",
            "a (s/m), ours",
            "chapter",
        ],
    );
    if d.validation.is_some() {
        t.headers.push("truth law".into());
    }
    for m in &mats {
        for contact in [false, true] {
            let p: Vec<(f64, f64)> = d
                .collisions
                .iter()
                .filter(|c| &c.material == m && c.contact == contact)
                .flat_map(|c| &c.impacts)
                .filter_map(|i| Some((i.speed_mps, i.restitution?)))
                .collect();
            if p.is_empty() {
                continue;
            }
            let mean = p.iter().map(|q| q.1).sum::<f64>() / p.len() as f64;
            t.push(vec![
                m.clone(),
                (if contact { "contact" } else { "rolling" }).into(),
                p.len().to_string(),
                format!("{mean:.3}"),
                match crate::report::summary::restitution_curve(d, m, contact) {
                    Some((a, _)) => agg_text(&a),
                    None => fig_4_4::restitution_slope(&p)
                        .map_or("—".into(), |a| format!("{a:.2} (least squares here)")),
                },
                (if contact {
                    "higher than rolling; → 1 at low speed"
                } else {
                    "falls with speed; → 1 at low speed"
                })
                .into(),
            ]);
            if d.validation.is_some() {
                let law = truth_law(d, m, if contact { "contact" } else { "rolling" });
                t.rows
                    .last_mut()
                    .expect("row just pushed")
                    .push(law.unwrap_or_else(|| "—".into()));
            }
        }
    }
    b.table(t);
    b.para("For pairs that start in contact the striker has no track before the impact; its pre-impact speed is estimated from momentum conservation with the post-impact velocities (the chapter used the laser's momentum calibration, 15 % scatter).");
    b
}

fn secondary_block(figs: &BTreeMap<String, String>, g: Groove) -> Block {
    let mut b = Block::new(
        "secondary",
        "3.7 Secondary collisions: the factor (1 − ks²)/(1 + ks²) and the 78.5° bound",
    );
    b.figure(figs, "fig_secondary.svg", "The velocity difference of two rolling particles is multiplied by $(1 - ks^2)/(1 + ks^2)$ per collision and re-acceleration; it stays positive (secondary collisions follow) below the bound.");
    let theta = 2.0 * g.s.asin().to_degrees();
    let f = g.collision_factor();
    let bound = secondary::bound_deg(g.k);
    let mut t = Table::new("Eq. 4.18, computed", &["quantity", "ours", "chapter"]);
    t.push(vec![
        "opening angle θ (°)".into(),
        format!("{theta:.1}"),
        "70.6".into(),
    ]);
    t.push(vec![
        "ks² = k·sin²(θ/2)".into(),
        format!("{:.4}", g.ks2()),
        "—".into(),
    ]);
    t.push(vec![
        "(1 − ks²)/(1 + ks²)".into(),
        format!("{f:.4}"),
        format!("{:.2}", ch::SECONDARY_FACTOR),
    ]);
    t.push(vec![
        "bound on θ: 2·asin(1/√k) (°)".into(),
        format!("{bound:.2}"),
        format!("{:.1}", ch::THETA_BOUND_DEG),
    ]);
    b.table(t);
    b.lead = Some(super::leads::secondary(g, theta, bound));
    b
}

/// The blocks of Figs. 4.3–4.4 and the secondary-collision factor.
pub fn blocks(d: &ReportData, figs: &BTreeMap<String, String>) -> Vec<Block> {
    let mut out = vec![fig_4_3_block(d, figs)];
    out.extend(super::compare::block(d));
    out.push(fig_4_4a_block(d, figs));
    out.extend(super::whole_run::block(d, figs));
    out.push(fig_4_4bc_block(d, figs));
    out.push(secondary_block(figs, d.groove));
    out
}
