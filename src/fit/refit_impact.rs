//! The impact laws discovery accepted (`discover::impact`), read back from their findings as the
//! whole-run fits carry them: a restitution law per material and setup, used in that setup's
//! fits (the named form when discovery named one, else its map), and μ_pp's dependence on the
//! slip speed per material, carried as its shape normalised at the map's median node.

use crate::artifacts::diagnosis::{Diagnosis, Effect, Finding};
use crate::discover::impact::POWER_LAW_REFERENCE;
use crate::physics::{LnMap, Restitution, SlipFriction, SlipShape};
use crate::recording::Setup;

/// One accepted impact law, as carried.
#[derive(Debug, Clone, PartialEq)]
pub enum ImpactLaw {
    /// The restitution law of one setup of the material's pairs.
    Restitution(Setup, Restitution),
    /// μ_pp(u) = μ_pp · s(u)/s(u_ref).
    SlipFriction(SlipFriction),
}

/// An accepted impact law and the finding it came from.
#[derive(Debug, Clone)]
pub struct Carried<'a> {
    pub material: String,
    pub law: ImpactLaw,
    pub finding: &'a Finding,
}

/// The finding's map, {speeds_mps, values}.
fn map_of(f: &Finding) -> Result<LnMap, String> {
    let m = f
        .where_
        .get("map")
        .ok_or("its finding has no map (where.map)")?;
    let read = |k: &str| -> Result<Vec<f64>, String> {
        serde_json::from_value(m.get(k).cloned().unwrap_or_default())
            .map_err(|e| format!("its map's {k} do not read as numbers ({e})"))
    };
    LnMap::new(&read("speeds_mps")?, &read("values")?).map_err(|e| format!("its map: {e}"))
}

fn param(f: &Finding, name: &str) -> Option<f64> {
    f.parameters
        .get(name)
        .map(|e| e.value)
        .filter(|v| v.is_finite())
}

/// The restitution law of an accepted `restitution_law` finding: the named form when its
/// parameters name one (a power law also needs its reference speed), else the map.
fn restitution_of(f: &Finding) -> Result<(Setup, Restitution), String> {
    let setup: Setup = f
        .where_
        .get("setup")
        .and_then(|s| serde_json::from_value(s.clone()).ok())
        .ok_or("its finding names no setup (where.setup)")?;
    let p = |n: &str| param(f, &format!("restitution_{n}"));
    let named = if let (Some(c_elastic), Some(v_stick_mps), Some(v_yield_mps)) =
        (p("c_elastic"), p("v_stick_mps"), p("v_yield_mps"))
    {
        Some(Restitution::AdhesiveYield {
            c_elastic,
            v_stick_mps,
            v_yield_mps,
        })
    } else if let (Some(c_elastic), Some(v_stick_mps)) = (p("c_elastic"), p("v_stick_mps")) {
        Some(Restitution::Adhesive {
            c_elastic,
            v_stick_mps,
        })
    } else if let Some(a) = p("viscous_coefficient") {
        Some(Restitution::Viscoelastic { a })
    } else if let (Some(c_ref), Some(exponent), Some(v_ref_mps)) = (
        p("c_at_mean_speed"),
        p("exponent"),
        f.where_.get(POWER_LAW_REFERENCE).and_then(|v| v.as_f64()),
    ) {
        Some(Restitution::PowerLaw {
            c_ref,
            v_ref_mps,
            exponent,
        })
    } else {
        None
    };
    match named {
        Some(law) => Ok((setup, law)),
        None => Ok((setup, Restitution::Map(map_of(f)?))),
    }
}

/// μ_pp's slip-speed dependence of an accepted `pair_friction_slip_speed` finding: the named
/// shape (linear, weakening) or the map, normalised at the map's median node.
fn slip_of(f: &Finding) -> Result<SlipFriction, String> {
    let map = map_of(f)?;
    let p = |n: &str| param(f, &format!("mu_pp_{n}"));
    let shape =
        if let (Some(at_zero_slip), Some(fall_per_mps)) = (p("at_zero_slip"), p("fall_per_mps")) {
            SlipShape::Linear {
                at_zero_slip,
                fall_per_mps,
            }
        } else if let Some(slip_scale_mps) = p("slip_scale_mps") {
            SlipShape::Weakening { slip_scale_mps }
        } else {
            SlipShape::Map(map)
        };
    let s = SlipFriction {
        shape,
        u_ref_mps: map.median_speed_mps(),
    };
    if s.factor(s.u_ref_mps).is_nan() {
        return Err(format!(
            "μ_pp's shape is not positive at its reference slip speed ({:.1} mm/s)",
            1e3 * s.u_ref_mps
        ));
    }
    Ok(s)
}

/// Every accepted impact law of `d` as carried, and notes for those that cannot be (a finding
/// without its setup or a readable map), each saying why.
pub fn accepted_impact_laws(d: &Diagnosis) -> (Vec<Carried<'_>>, Vec<String>) {
    let (mut carried, mut notes) = (Vec::new(), Vec::new());
    for f in d.findings.iter().filter(|f| f.accepted) {
        let Some(m) = f.where_.get("material").and_then(|m| m.as_str()) else {
            continue;
        };
        let (law, what) = match Effect::from_id(&f.effect) {
            Some(Effect::RestitutionLaw) => {
                let setup = f
                    .where_
                    .get("setup")
                    .and_then(|s| s.as_str())
                    .unwrap_or("?");
                (
                    restitution_of(f).map(|(s, r)| ImpactLaw::Restitution(s, r)),
                    format!("restitution law of the {m} pairs ({setup} setup)"),
                )
            }
            Some(Effect::PairFrictionSlipSpeed) => (
                slip_of(f).map(ImpactLaw::SlipFriction),
                format!("dependence of the {m} pairs' μ_pp on the slip speed"),
            ),
            _ => continue,
        };
        match law {
            Ok(law) => carried.push(Carried {
                material: m.to_string(),
                law,
                finding: f,
            }),
            Err(why) => notes.push(format!(
                "the {what} that discovery accepted is not carried: {why}"
            )),
        }
    }
    (carried, notes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::diagnosis::Estimate as Value;

    /// The shipped diagnosis' 316 rolling restitution test, made accepted with `parameters`.
    fn restitution_finding(parameters: &[(&str, f64)]) -> Finding {
        let d = crate::artifacts::diagnosis::shipped();
        let mut f = d
            .findings
            .into_iter()
            .find(|f| {
                f.effect == "restitution_law"
                    && f.where_["material"] == "316"
                    && f.where_["setup"] == "rolling"
            })
            .unwrap();
        f.accepted = true;
        f.parameters = parameters
            .iter()
            .map(|(k, v)| (k.to_string(), Value::new(*v, 0.01)))
            .collect();
        f
    }

    #[test]
    fn a_restitution_law_is_its_named_form_else_its_map() {
        let f = restitution_finding(&[]);
        let (setup, law) = restitution_of(&f).unwrap();
        assert_eq!(setup, Setup::Rolling);
        let Restitution::Map(m) = law else {
            panic!("{law:?}")
        };
        let want: Vec<f64> = serde_json::from_value(f.where_["map"]["values"].clone()).unwrap();
        assert_eq!(m.values(), want.as_slice());
        let f = restitution_finding(&[
            ("restitution_c_elastic", 0.9),
            ("restitution_v_stick_mps", 0.01),
        ]);
        assert_eq!(
            restitution_of(&f).unwrap().1,
            Restitution::Adhesive {
                c_elastic: 0.9,
                v_stick_mps: 0.01
            }
        );
        // a power law without its reference speed: the map
        let mut f = restitution_finding(&[
            ("restitution_c_at_mean_speed", 0.7),
            ("restitution_exponent", 0.25),
        ]);
        assert!(matches!(restitution_of(&f).unwrap().1, Restitution::Map(_)));
        f.where_
            .insert(POWER_LAW_REFERENCE.into(), serde_json::json!(0.05));
        assert_eq!(
            restitution_of(&f).unwrap().1,
            Restitution::PowerLaw {
                c_ref: 0.7,
                v_ref_mps: 0.05,
                exponent: 0.25
            }
        );
        f.where_.remove("setup");
        assert!(restitution_of(&f).unwrap_err().contains("no setup"));
    }

    #[test]
    fn mu_pp_against_slip_speed_is_normalised_at_the_median_node() {
        let d = crate::artifacts::diagnosis::shipped();
        let mut f = d
            .findings
            .into_iter()
            .find(|f| f.effect == "pair_friction_slip_speed")
            .unwrap();
        f.accepted = true;
        f.where_.insert(
            "map".into(),
            serde_json::json!({"speeds_mps": [0.02, 0.05, 0.1], "values": [0.3, 0.2, 0.15]}),
        );
        let s = slip_of(&f).unwrap();
        assert!((s.u_ref_mps - 0.05).abs() < 1e-15);
        assert!((s.factor(0.02) - 1.5).abs() < 1e-12);
        f.parameters
            .insert("mu_pp_at_zero_slip".into(), Value::new(0.3, 0.01));
        f.parameters
            .insert("mu_pp_slip_scale_mps".into(), Value::new(0.05, 0.01));
        let s = slip_of(&f).unwrap();
        assert_eq!(
            s.shape,
            SlipShape::Weakening {
                slip_scale_mps: 0.05
            }
        );
        assert!((s.factor(0.0) - 2.0).abs() < 1e-12);
        f.where_.remove("map");
        assert!(slip_of(&f).unwrap_err().contains("no map"));
    }
}
