//! The chapter's numbers under the physics discovery accepted: the single runs' μ_pg and drag line
//! from discovery's joint fit (which carries every accepted term), and the whole-run pair fits
//! made again with the accepted terms other than drag held (μ_pg, the saturating drag, μ_pp and
//! the restitution laws refitted, the μ_pp profile redone), a force between the particles that
//! the pairs of a material were found to feel carried into that material's fits, and the impact
//! laws discovery accepted (`refit_impact`): a restitution law of a material and setup used in
//! that setup's fits in place of the candidates (the named form, held as discovery gave it from
//! the impacts' own C; else discovery's map, its nodes' speeds held and its values refitted from
//! discovery's), and μ_pp depending on the slip speed
//! carried as its shape, μ_pp(u) = μ_pp · s(u)/s(u_ref), u_ref the map's median node, so that
//! the fitted μ_pp and its profile are μ_pp at u_ref. Those fits start from the baseline's
//! (summary.json's `collisions.whole_run`: its shared values, chosen laws and each run's kick;
//! `collision::warm_start`), not from the defaults.

use super::collision::warm_start::from_summary;
use super::collision::whole_summary::{analyze_material_from, WholeRunOptions};
use super::collision::wholerun::{DragSpec, FitSpec, PairRun};
use super::refit_impact::{accepted_impact_laws, Carried, ImpactLaw};
use crate::artifacts::diagnosis::{Diagnosis, Finding};
use crate::artifacts::summary::{MaterialWholeRun, WholeRunSummary};
use crate::artifacts::under_accepted::{
    CarriedTerm, CollisionsUnder, DragTimeLine, SingleMaterial, SingleUnder, UnderAccepted,
};
use crate::artifacts::Estimate;
use crate::discover::candidate::OwnValues;
use crate::discover::forms;
use crate::discover::pair_force::carried_from;
use crate::discover::pairs::single_run_physics;
use crate::physics::{Groove, Restitution, Term};
use crate::recording::{Experiment, Recording};
use std::collections::BTreeMap;

/// The accepted single-run findings: the physics a refit carries, the findings a form of
/// discovery wrote (collision findings and the particle check name no term of the one-particle
/// model).
pub fn accepted_terms(d: &Diagnosis) -> Vec<&Finding> {
    d.findings
        .iter()
        .filter(|f| f.accepted && forms::read(f).is_some())
        .collect()
}

/// The single runs of each material under the accepted physics: μ and the drag of discovery's
/// final joint model (every accepted term fitted jointly over all single runs).
fn single_under(d: &Diagnosis) -> SingleUnder {
    let lab = forms::in_the_lab(accepted_terms(d));
    // beside a quadratic drag T is no line in |v|
    let quadratic = lab
        .forces
        .iter()
        .any(|t| matches!(t, Ok(Term::QuadraticDrag { .. })));
    let materials = d
        .materials
        .iter()
        .filter_map(|m| {
            let own = OwnValues::of(&d.model_parameters, m).ok()?;
            // a linear drag's line is flat
            let t_line = (!quadratic).then(|| DragTimeLine {
                intercept_s: own.t_s,
                slope_s_per_mps: lab.drag_slope.unwrap_or(Estimate::new(0.0, 0.0)),
            });
            Some((m.clone(), SingleMaterial { mu: own.mu, t_line }))
        })
        .collect();
    SingleUnder {
        source: "discovery's joint fit of every single run, with every accepted term fitted jointly (μ and the drag time per material, the terms shared)".into(),
        materials,
    }
}

/// The collision runs of `recordings` that read as pair runs, by material.
fn pair_runs(recordings: &[Recording]) -> BTreeMap<String, Vec<PairRun>> {
    let mut out: BTreeMap<String, Vec<PairRun>> = BTreeMap::new();
    for rec in recordings
        .iter()
        .filter(|r| r.info.experiment == Experiment::Collision)
    {
        if let Ok(run) = PairRun::from_recording(rec, rec.info.setup) {
            out.entry(rec.info.material.clone()).or_default().push(run);
        }
    }
    out
}

/// The whole-run fits under the accepted physics; `baseline` (summary.json's
/// `collisions.whole_run`) gives the materials whose fits already carry it.
fn collisions_under(
    d: &Diagnosis,
    laws: &[Carried],
    recordings: &[Recording],
    baseline: Option<&WholeRunSummary>,
    groove: Groove,
    opts: &WholeRunOptions,
    notes: &mut Vec<String>,
) -> Option<CollisionsUnder> {
    let by_material = pair_runs(recordings);
    if by_material.is_empty() {
        return None;
    }
    let lab = forms::in_the_lab(accepted_terms(d));
    let mut materials: Vec<MaterialWholeRun> = Vec::new();
    let mut unchanged = Vec::new();
    for (m, runs) in &by_material {
        let own = OwnValues::of(&d.model_parameters, m);
        let model = match own.and_then(|own| single_run_physics(&own, &lab, groove)) {
            Ok(model) => model,
            Err(why) => {
                notes.push(format!("the whole-run fits of {m} are not refitted: {why}"));
                continue;
            }
        };
        // the pairs' own friction and drag stay free, as in the baseline: what is carried is
        // every other accepted force, and the friction's accepted variation
        let others: Vec<Term> = model
            .terms
            .into_iter()
            .filter(|t| !matches!(t, Term::LinearDrag { .. } | Term::SaturatingDrag { .. }))
            .collect();
        // an accepted force between this material's particles is carried too, from its values
        let force = d
            .findings
            .iter()
            .filter(|f| f.where_.get("material").and_then(|v| v.as_str()) == Some(m.as_str()))
            .find_map(carried_from);
        let kept = baseline.and_then(|b| b.materials.iter().find(|w| &w.material == m));
        let own_laws: Vec<&ImpactLaw> = laws
            .iter()
            .filter(|c| &c.material == m)
            .map(|c| &c.law)
            .collect();
        if let (true, None, true, Some(kept)) = (
            others.is_empty() && model.variation.is_none(),
            force,
            own_laws.is_empty(),
            kept,
        ) {
            // nothing beyond the drag: the baseline's fit is this very fit
            materials.push(kept.clone());
            unchanged.push(m.clone());
            continue;
        }
        let mut spec = FitSpec {
            drag: DragSpec::SaturatingWith(others),
            pair_force: force,
            variation: model.variation,
            ..FitSpec::new(groove)
        };
        // the impact laws discovery accepted for these pairs
        for law in own_laws {
            match law {
                ImpactLaw::Restitution(setup, r) => spec.hold_law(*setup, *r),
                ImpactLaw::SlipFriction(s) => spec.slip = Some(*s),
            }
        }
        // the baseline's fit of these runs is the start: the accepted terms move it little
        let start = kept.map(|k| from_summary(k, runs, &spec));
        materials.push(analyze_material_from(m, runs, &spec, opts, start.as_ref()));
    }
    Some(CollisionsUnder {
        whole_run: WholeRunSummary {
            materials,
            notes: Vec::new(),
        },
        unchanged,
    })
}

/// The chapter's numbers under `d`'s accepted physics. Nothing accepted: says so and refits
/// nothing. `baseline` is summary.json's `collisions.whole_run`, if any.
pub fn under_accepted(
    d: &Diagnosis,
    recordings: &[Recording],
    baseline: Option<&WholeRunSummary>,
    groove: Groove,
    opts: &WholeRunOptions,
) -> UnderAccepted {
    // the single runs' terms, then any force between the particles of a material's pairs, then
    // the impact laws
    let mut accepted = accepted_terms(d);
    accepted.extend(d.findings.iter().filter(|f| carried_from(f).is_some()));
    let (laws, not_carried) = accepted_impact_laws(d);
    accepted.extend(laws.iter().map(|c| c.finding));
    if accepted.is_empty() {
        let lead = if not_carried.is_empty() {
            "discovery accepted no physics: the baseline's numbers are the analysis' numbers, and nothing is refitted"
        } else {
            "discovery accepted no physics the refit carries: the baseline's numbers are the analysis' numbers, and nothing is refitted"
        };
        return UnderAccepted {
            accepted: false,
            terms: Vec::new(),
            single: None,
            collisions: None,
            notes: std::iter::once(lead.to_string())
                .chain(not_carried)
                .collect(),
        };
    }
    let terms = accepted
        .iter()
        .map(|f| {
            let mut parameters: BTreeMap<String, f64> = f
                .parameters
                .iter()
                .map(|(k, e)| (k.clone(), e.value))
                .collect();
            // a map is carried at its nodes' values (named as discovery names them), μ_pp against
            // the slip speed normalised at u_ref
            match laws
                .iter()
                .find(|c| std::ptr::eq(c.finding, *f))
                .map(|c| &c.law)
            {
                Some(ImpactLaw::Restitution(_, Restitution::Map(m))) => {
                    for (v, c) in m.speeds_mps().iter().zip(m.values()) {
                        let at = 1e3 * v;
                        parameters.insert(format!("restitution_map_at_{at:.0}_mmps"), *c);
                    }
                }
                Some(ImpactLaw::SlipFriction(s)) => {
                    parameters.insert("mu_pp_reference_slip_speed_mps".into(), s.u_ref_mps);
                }
                _ => {}
            }
            CarriedTerm {
                effect: f.effect.clone(),
                form: f.form.clone(),
                parameters,
            }
        })
        .collect();
    let mut notes = not_carried;
    let single = Some(single_under(d)).filter(|s| !s.materials.is_empty());
    let collisions = collisions_under(d, &laws, recordings, baseline, groove, opts, &mut notes);
    UnderAccepted {
        accepted: true,
        terms,
        single,
        collisions,
        notes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_accepted_says_so_and_copies_nothing() {
        let mut d = crate::artifacts::diagnosis::shipped();
        for f in &mut d.findings {
            f.accepted = false;
        }
        let u = under_accepted(&d, &[], None, Groove::CHAPTER, &WholeRunOptions::default());
        assert!(!u.accepted && u.terms.is_empty());
        assert!(u.single.is_none() && u.collisions.is_none());
        assert!(u.notes[0].contains("nothing is refitted"), "{:?}", u.notes);
    }

    #[test]
    fn accepted_impact_laws_are_carried_terms_not_notes() {
        let mut d = crate::artifacts::diagnosis::shipped();
        for f in &mut d.findings {
            f.accepted = f.effect == "restitution_law" && f.where_["material"] == "316";
        }
        let u = under_accepted(&d, &[], None, Groove::CHAPTER, &WholeRunOptions::default());
        assert!(u.accepted, "{:?}", u.notes);
        // one term per accepted group (316: rolling and contact), carried at the map's values
        let effects: Vec<&str> = u.terms.iter().map(|t| t.effect.as_str()).collect();
        assert_eq!(effects, ["restitution_law", "restitution_law"]);
        for (t, setup) in u.terms.iter().zip(["rolling", "contact"]) {
            let f = d
                .findings
                .iter()
                .find(|f| f.accepted && f.where_["setup"] == setup)
                .unwrap();
            let values: Vec<f64> =
                serde_json::from_value(f.where_["map"]["values"].clone()).unwrap();
            let carried: Vec<f64> = t.parameters.values().copied().collect();
            assert!(
                t.parameters
                    .keys()
                    .all(|k| k.starts_with("restitution_map_at_")),
                "{t:?}"
            );
            assert_eq!(carried.len(), values.len(), "{t:?}");
        }
        assert!(u.notes.is_empty(), "{:?}", u.notes);
        // a finding without its map cannot be carried: said, with why
        for f in &mut d.findings {
            f.where_.remove("map");
        }
        let u = under_accepted(&d, &[], None, Groove::CHAPTER, &WholeRunOptions::default());
        assert!(!u.accepted && u.terms.is_empty());
        assert!(
            u.notes[0].contains("no physics the refit carries"),
            "{:?}",
            u.notes
        );
        let why = u
            .notes
            .iter()
            .filter(|n| n.contains("is not carried: its finding has no map"));
        assert_eq!(why.count(), 2, "{:?}", u.notes);
    }

    #[test]
    fn a_saturating_drag_gives_the_drag_line_and_carries_its_term() {
        let d = crate::artifacts::diagnosis::shipped();
        let u = under_accepted(&d, &[], None, Groove::CHAPTER, &WholeRunOptions::default());
        assert!(u.accepted);
        let effects: Vec<&str> = u.terms.iter().map(|t| t.effect.as_str()).collect();
        assert_eq!(effects, ["velocity_dependent_drag"]);
        let s = u.single.unwrap();
        for m in ["316", "440c"] {
            let sm = &s.materials[m];
            assert_eq!(sm.mu.value, d.model_parameters[&format!("mu_{m}")].value);
            let line = sm.t_line.expect("a saturating drag has a line");
            assert_eq!(
                line.intercept_s.value,
                d.model_parameters[&format!("t0_s_{m}")].value
            );
            assert_eq!(
                line.slope_s_per_mps.value,
                d.model_parameters["tp_s_per_mps"].value
            );
        }
        // no recordings: no collision part
        assert!(u.collisions.is_none());
    }
}
