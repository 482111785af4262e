//! Scoring one diagnosis.json against a case's truth: named right (the accepted findings are
//! exactly the effects, each in its place with an acceptable form), sized within 15 %, and for a
//! null whether anything was accepted.

use super::shapes::Truth;
use serde_json::Value;

/// Relative tolerance on sizes.
pub const SIZE_TOLERANCE: f64 = 0.15;

/// One accepted finding as the bench sees it.
#[derive(Clone, Debug)]
pub struct Accepted {
    pub place: String,
    pub effect: String,
    pub form: String,
    pub parameters: Vec<(String, f64)>,
}

/// The place of a finding: its `where.place` (or a top-level `place`), else the place today's effect ids stand for.
pub fn place_of(finding: &Value) -> String {
    if let Some(p) = finding
        .get("where")
        .and_then(|w| w.get("place"))
        .or_else(|| finding.get("place"))
        .and_then(Value::as_str)
    {
        return p.to_string();
    }
    match finding.get("effect").and_then(Value::as_str).unwrap_or("") {
        "velocity_dependent_friction" => "friction",
        "velocity_dependent_drag"
        | "rolling_resistance"
        | "groove_tilt"
        | "position_dependent_force"
        | "time_dependent_force" => "force",
        "pair_physics_mismatch" | "impact_specific_mismatch" => "pair",
        "unexplained" => "unexplained",
        _ => "other",
    }
    .to_string()
}

/// The accepted findings of a diagnosis.json text. Findings of one effect made material by
/// material (the collision runs' tests) are one finding: the effect found, with every material's
/// sizes and forms.
pub fn accepted(diagnosis: &str) -> Result<Vec<Accepted>, String> {
    let mut out: Vec<Accepted> = Vec::new();
    for (per_material, a) in accepted_each(diagnosis)? {
        match out
            .iter_mut()
            .find(|o| per_material && o.place == a.place && o.effect == a.effect)
        {
            Some(o) => {
                if !o.form.contains(&a.form) {
                    o.form = format!("{} | {}", o.form, a.form);
                }
                o.parameters.extend(a.parameters);
            }
            None => out.push(a),
        }
    }
    Ok(out)
}

/// Each accepted finding, and whether it is one material's (`where.material`).
fn accepted_each(diagnosis: &str) -> Result<Vec<(bool, Accepted)>, String> {
    let d: Value = serde_json::from_str(diagnosis)
        .map_err(|e| format!("diagnosis.json does not parse: {e}"))?;
    let findings = d
        .get("findings")
        .and_then(Value::as_array)
        .ok_or("diagnosis.json has no findings array")?;
    Ok(findings
        .iter()
        .filter(|f| f.get("accepted").and_then(Value::as_bool) == Some(true))
        .map(|f| {
            let per_material = f.get("where").and_then(|w| w.get("material")).is_some();
            (
                per_material,
                Accepted {
                    place: place_of(f),
                    effect: f
                        .get("effect")
                        .and_then(Value::as_str)
                        .unwrap_or("")
                        .to_string(),
                    form: f
                        .get("form")
                        .and_then(Value::as_str)
                        .unwrap_or("")
                        .to_string(),
                    parameters: f
                        .get("parameters")
                        .and_then(Value::as_object)
                        .map(|m| {
                            m.iter()
                                .filter_map(|(k, v)| {
                                    Some((
                                        k.clone(),
                                        v.get("value").and_then(Value::as_f64).or(v.as_f64())?,
                                    ))
                                })
                                .collect()
                        })
                        .unwrap_or_default(),
                },
            )
        })
        .collect())
}

/// Whether finding `a` names `t`: the same place and an acceptable form.
pub fn names(a: &Accepted, t: &Truth) -> bool {
    let form = a.form.to_lowercase();
    a.place == t.place && t.forms.iter().any(|f| form.contains(f.as_str()))
}

/// Whether finding `a` reports every size of `t` within the tolerance (at least one parameter
/// per size; signs compared only for the tilt).
pub fn sizes(a: &Accepted, t: &Truth) -> bool {
    t.sizes.iter().all(|(name, truth)| {
        let got: Vec<f64> = a
            .parameters
            .iter()
            .filter(|(k, _)| k.starts_with(name.as_str()))
            .map(|p| p.1)
            .collect();
        !got.is_empty()
            && got.iter().all(|&g| {
                let (g, w) = if name == "alpha_deg" {
                    (g, *truth)
                } else {
                    (g.abs(), truth.abs())
                };
                (g - w).abs() <= SIZE_TOLERANCE * w.abs()
            })
    })
}

/// The score of one dataset.
#[derive(Clone, Debug, PartialEq)]
pub struct Score {
    /// Every effect named by exactly one accepted finding and nothing else accepted.
    pub named: bool,
    /// Named, and every size within the tolerance.
    pub sized: bool,
    /// For a null: something was accepted.
    pub false_accept: bool,
}

/// Scores the accepted findings against the truths (empty: a null).
pub fn score(found: &[Accepted], truths: &[Truth]) -> Score {
    if truths.is_empty() {
        return Score {
            named: false,
            sized: false,
            false_accept: !found.is_empty(),
        };
    }
    // each truth takes a distinct finding that names it; the assignment is tried both ways for two
    let mut best = (false, false);
    let n = truths.len();
    if found.len() == n {
        let orders: Vec<Vec<usize>> = if n == 2 {
            vec![vec![0, 1], vec![1, 0]]
        } else {
            vec![(0..n).collect()]
        };
        for order in orders {
            let pairs: Vec<(&Accepted, &Truth)> =
                order.iter().map(|&i| &found[i]).zip(truths).collect();
            if pairs.iter().all(|(a, t)| names(a, t)) {
                let sized = pairs.iter().all(|(a, t)| sizes(a, t));
                best = (true, best.1 || sized);
            }
        }
    }
    Score {
        named: best.0,
        sized: best.1,
        false_accept: false,
    }
}
