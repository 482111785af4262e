//! Section 3.8: the chapter's numbers under the physics discovery accepted (`refit`), beside the
//! baseline's, with which the report trusts and why; and the helpers by which the summary's key
//! parameters and 3.5.1 take the trusted column.

use super::{Block, Table};
use crate::artifacts::summary::{MaterialWholeRun, ProfileVerdict};
use crate::artifacts::under_accepted::UnderAccepted;
use crate::artifacts::Estimate;
use crate::report::inputs::ReportData;
use crate::report::summary::{mu_all, t_line, Agg};
use crate::report::value::{pm, serde_name, sig};
use std::collections::BTreeMap;

/// The refit, when discovery accepted single-run physics: its column is the one trusted.
pub fn trusted(d: &ReportData) -> Option<&UnderAccepted> {
    d.under_accepted.as_ref().filter(|u| u.accepted)
}

/// The whole-run fit of `material` made again under the accepted physics (None when the refit
/// did not make it again: nothing accepted, not carried, or the baseline's fit carried it all).
pub fn whole_run_of<'a>(d: &'a ReportData, material: &str) -> Option<&'a MaterialWholeRun> {
    let c = trusted(d)?.collisions.as_ref()?;
    c.whole_run
        .materials
        .iter()
        .find(|m| m.material == material && !c.unchanged.contains(&m.material))
}

/// `value ± se [lo, hi]` with a 95 % normal interval from the standard error.
pub fn est_text(e: &Estimate) -> String {
    match e.se {
        Some(se) if se > 0.0 => format!(
            "{} [{}, {}]",
            pm(*e),
            sig(e.value - 1.96 * se, 4),
            sig(e.value + 1.96 * se, 4)
        ),
        _ => pm(*e),
    }
}

/// `value [lo, hi]` of a baseline aggregate (its bootstrap interval).
fn agg_cell(a: &Agg) -> String {
    match a.interval {
        Some((lo, hi)) => format!("{} [{}, {}]", pm(a.est), sig(lo, 4), sig(hi, 4)),
        None => pm(a.est),
    }
}

/// The profile's verdict in a table cell.
pub fn verdict_text(v: &ProfileVerdict) -> String {
    match *v {
        ProfileVerdict::Interval { estimate, lo, hi } => {
            format!("{estimate:.3} [{lo:.3}, {hi:.3}]")
        }
        ProfileVerdict::LowerBound { lo } => format!("> {lo:.2}"),
        ProfileVerdict::UpperBound { hi } => format!("< {hi:.2}"),
        ProfileVerdict::Unconstrained => "not constrained".into(),
    }
}

/// The chosen restitution law of each setup, in words.
fn laws_text(m: &MaterialWholeRun) -> String {
    m.restitution
        .iter()
        .map(|c| {
            if let Some(law) = &c.discovered {
                return format!(
                    "{}: {}",
                    serde_name(&c.setup),
                    crate::report::impact_laws::discovered_law(law)
                );
            }
            let params: Vec<String> = c
                .chosen_candidate()
                .map(|cand| {
                    cand.ordered()
                        .into_iter()
                        .map(|(n, e)| format!("{n} = {}", sig(e.value, 3)))
                        .collect()
                })
                .unwrap_or_default();
            format!(
                "{}: {} ({})",
                serde_name(&c.setup),
                serde_name(&c.chosen),
                params.join(", ")
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// The block, or None when the pipeline has no refit stage.
pub fn block(d: &ReportData, figs: &BTreeMap<String, String>) -> Option<Block> {
    let u = d.under_accepted.as_ref()?;
    let mut b = Block::new(
        "under-accepted",
        "3.8 The chapter's numbers under the physics discovery accepted",
    );
    if !u.accepted {
        b.para("Discovery accepted no single-run physics, so nothing was refitted: the baseline's numbers above are the analysis' numbers.");
        return Some(b);
    }
    let terms: Vec<String> = u
        .terms
        .iter()
        .map(|t| {
            format!(
                "{} ({})",
                t.effect.replace('_', " "),
                crate::report::formula::form(&t.form)
            )
        })
        .collect();
    b.para(format!(
        "Discovery accepted {}. The single runs' μ_pg and drag come from its joint fit of every single run with these terms fitted jointly; the whole-run pair fits are made again with every accepted force other than the drag held at its fitted values (μ_pg, the saturating drag, μ_pp and the restitution laws refitted, the μ_pp profile redone). The report trusts this column: discovery accepted each term by its likelihood ratio against a null from the runs' own noise and by better predictions of held-out runs, so the baseline leaves out physics the recordings show, and its numbers can be biased by it. The baseline column is kept for comparison with the chapter.",
        terms.join("; ")
    ));
    let carried = |effect: &str| u.terms.iter().any(|t| t.effect == effect);
    if carried("restitution_law") {
        b.para("A restitution law discovery accepted outside the candidates is used in the whole-run fits of its material and setup instead of a candidate: its named form held as discovery gave it from the impacts' own C, else its map, the nodes' speeds held and their values refitted with the runs; the other setups still choose among the candidates.");
    }
    if carried("pair_friction_slip_speed") {
        b.para("μ_pp depending on the slip speed, which discovery accepted, is carried as its shape s(u), normalised at a reference slip speed: μ_pp(u) = μ_pp · s(u)/s(u_ref), so that the μ_pp below and its profile are μ_pp at u_ref (each material's note gives it).");
    }
    for n in &u.notes {
        b.para(format!(
            "{n}; for this material the baseline's numbers stand."
        ));
    }
    if let Some(s) = &u.single {
        let mut t = Table::new(
            "μ_pg per material: baseline (weighted mean of the per-run fits, [bootstrap 95 %]) and under the accepted physics (joint fit, ± standard error [95 %])",
            &["material", "baseline", "under the accepted physics", "trusted"],
        );
        let mut lines = Table::new(
            "Drag time: the baseline's T-vs-|v0| line over the runs (linear drag per run) and, under the accepted physics, the drag's own $T(\\lvert v\\rvert) = T_0 + T'\\lvert v\\rvert$ (a different quantity: the drag time at the particle's speed)",
            &[
                "material",
                "baseline T0 (s)",
                "baseline slope (s per m/s)",
                "accepted T0 (s)",
                "accepted T' (s per m/s)",
            ],
        );
        for (m, sm) in &s.materials {
            let base = mu_all(d, m).map_or("—".into(), |a| agg_cell(&a));
            t.push(vec![
                m.clone(),
                base,
                est_text(&sm.mu),
                "under the accepted physics".into(),
            ]);
            let (bi, bs) = t_line(d, Some(m)).map_or(("—".into(), "—".into()), |(a, s)| {
                (agg_cell(&a), agg_cell(&s))
            });
            let (ai, asl) = sm.t_line.map_or(
                ("no line (a quadratic drag)".to_string(), "—".to_string()),
                |l| (est_text(&l.intercept_s), est_text(&l.slope_s_per_mps)),
            );
            lines.push(vec![m.clone(), bi, bs, ai, asl]);
        }
        b.table(t);
        b.table(lines);
    }
    if let Some(c) = &u.collisions {
        let mut t = Table::new(
            "Whole-run pair fits per material: μ_pp (profile, 95 %), μ_pg and the chosen restitution laws, baseline and under the accepted physics",
            &[
                "material",
                "μ_pp baseline",
                "μ_pp under the accepted physics",
                "μ_pg baseline",
                "μ_pg under the accepted physics",
                "restitution under the accepted physics",
                "RMS / noise (baseline → accepted)",
            ],
        );
        for m in &c.whole_run.materials {
            let base = d
                .whole_run()
                .and_then(|w| w.materials.iter().find(|x| x.material == m.material));
            t.push(vec![
                m.material.clone(),
                base.map_or("—".into(), |x| verdict_text(&x.profile.verdict)),
                verdict_text(&m.profile.verdict),
                base.map_or("—".into(), |x| pm(x.mu_pg)),
                pm(m.mu_pg),
                laws_text(m),
                format!(
                    "{} → {:.3}",
                    base.map_or("—".into(), |x| format!("{:.3}", x.rms_noise)),
                    m.rms_noise
                ),
            ]);
            if c.unchanged.contains(&m.material) {
                b.para(format!("{}: the whole-run fits already carry every accepted term (a saturating drag is their own), so their numbers are the baseline's.", m.material));
            } else {
                b.para(format!(
                    "{}: under the accepted physics the μ_pp profile gives {} (95 %); the chapter's 1.4 is {}.",
                    m.material,
                    verdict_text(&m.profile.verdict),
                    if holds_1_4(&m.profile.verdict) { "allowed" } else { "excluded" }
                ));
                for n in &m.notes {
                    b.para(format!("{}: {n}.", m.material));
                }
            }
        }
        b.table(t);
        b.figure(
            figs,
            "fig_mu_pp_profile_accepted.svg",
            "μ_pp profile of the whole-run fits made again under the accepted physics (as the figure of 3.5.1).",
        );
    }
    if c_refitted(u) {
        b.para("Figs. 4.4b–c add, dashed, each setup's whole-run restitution law under the accepted physics. Fig. 4.2b's fitted curve is still the baseline's.");
    }
    Some(b)
}

/// Whether some whole-run fit was made again (not only kept from the baseline).
fn c_refitted(u: &UnderAccepted) -> bool {
    u.collisions.as_ref().is_some_and(|c| {
        c.whole_run
            .materials
            .iter()
            .any(|m| !c.unchanged.contains(&m.material))
    })
}

/// Whether the profile's verdict allows the chapter's 1.4.
fn holds_1_4(v: &ProfileVerdict) -> bool {
    match *v {
        ProfileVerdict::Interval { lo, hi, .. } => lo <= 1.4 && 1.4 <= hi,
        ProfileVerdict::LowerBound { lo } => lo <= 1.4,
        ProfileVerdict::UpperBound { hi } => 1.4 <= hi,
        ProfileVerdict::Unconstrained => true,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::collision_summary::LawForm;
    use crate::artifacts::under_accepted::CarriedTerm;
    use crate::physics::{LnMap, Restitution};

    /// The shipped report's inputs with the 316 pairs refitted with a map in the rolling setup:
    /// the section says the law in words and with its numbers.
    #[test]
    fn a_law_from_discovery_is_said_in_words() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("reports");
        let read = |f: &str| std::fs::read(root.join(f)).unwrap();
        let mut u: UnderAccepted =
            serde_json::from_slice(&read("under_accepted_physics.json")).unwrap();
        let c = u
            .collisions
            .as_mut()
            .expect("the shipped refit has the pairs");
        c.unchanged.clear();
        let m = c
            .whole_run
            .materials
            .iter_mut()
            .find(|m| m.material == "316")
            .unwrap();
        let rolling = m
            .restitution
            .iter_mut()
            .find(|c| c.setup == crate::recording::Setup::Rolling)
            .unwrap();
        rolling.chosen = LawForm::FromDiscovery;
        rolling.candidates.clear();
        rolling.discovered = Some(Restitution::Map(
            LnMap::new(&[0.01, 0.03, 0.07], &[0.99, 0.79, 0.61]).unwrap(),
        ));
        u.terms.push(CarriedTerm {
            effect: "restitution_law".into(),
            form: "C depends on the impact speed".into(),
            parameters: BTreeMap::new(),
        });
        let d = ReportData {
            summary: Some(serde_json::from_slice(&read("summary.json")).unwrap()),
            under_accepted: Some(u),
            ..ReportData::default()
        };
        let text = format!("{:?}", block(&d, &BTreeMap::new()).unwrap());
        assert!(
            text.contains("rolling: discovery's map, its values refitted: C = 0.990 at 10.0 mm/s, 0.790 at 30.0 mm/s, 0.610 at 70.0 mm/s"),
            "{text}"
        );
        assert!(text.contains("is used in the whole-run fits of its material and setup"));
    }
}
