//! The coefficient of restitution C as a function of the impact speed: the chapter's candidate
//! laws, and the laws discovery can accept beyond them (a map in ln speed, named forms).

use super::ln_map::LnMap;
use serde::{Deserialize, Serialize};

/// Restitution law. `SpeedDependent`: `C(v) = c0 + (1 − c0) e^{−|v|/v_ref}`, 1 for a gentle
/// touch and falling towards `c0` for hard impacts (the chapter's Fig. 4.4b–c trend).
/// `Linear`: `C(v) = c0 − slope·|v|`, kept within [0, 1]. The laws beyond the chapter's
/// candidates, as discovery names them (`discover::impact`), are kept within [0, 1]:
/// `Map`: piecewise linear in ln |v| through its nodes, the end values held beyond them (see
/// `LnMap`); `Viscoelastic`: `1 − a |v|^(1/5)`; `Adhesive`: `c (1 − (v_s/|v|)²)^(1/2)` above
/// `v_s`, 0 below (the contact sticks); `AdhesiveYield`: the adhesive law times
/// `e^{−|v|/v_y}`; `PowerLaw`: `c (|v|/v_ref)^(−n)`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Restitution {
    Constant(f64),
    SpeedDependent {
        c0: f64,
        v_ref_mps: f64,
    },
    Linear {
        c0: f64,
        slope_per_mps: f64,
    },
    Map(LnMap),
    Viscoelastic {
        a: f64,
    },
    Adhesive {
        c_elastic: f64,
        v_stick_mps: f64,
    },
    AdhesiveYield {
        c_elastic: f64,
        v_stick_mps: f64,
        v_yield_mps: f64,
    },
    PowerLaw {
        c_ref: f64,
        v_ref_mps: f64,
        exponent: f64,
    },
}

/// `(1 − (v_s/v)²)^(1/2)` above v_s, 0 at and below it.
fn adhesion(v: f64, v_stick_mps: f64) -> f64 {
    if v <= v_stick_mps {
        0.0
    } else {
        (1.0 - (v_stick_mps / v).powi(2)).sqrt()
    }
}

impl Restitution {
    /// C at impact speed `v_impact_mps` (relative approach speed).
    pub fn at(&self, v_impact_mps: f64) -> f64 {
        let v = v_impact_mps.abs();
        match *self {
            Restitution::Constant(c) => c,
            Restitution::SpeedDependent { c0, v_ref_mps } => {
                c0 + (1.0 - c0) * (-v / v_ref_mps).exp()
            }
            Restitution::Linear { c0, slope_per_mps } => (c0 - slope_per_mps * v).clamp(0.0, 1.0),
            Restitution::Map(m) => m.at(v).clamp(0.0, 1.0),
            Restitution::Viscoelastic { a } => (1.0 - a * v.powf(0.2)).clamp(0.0, 1.0),
            Restitution::Adhesive {
                c_elastic,
                v_stick_mps,
            } => (c_elastic * adhesion(v, v_stick_mps)).clamp(0.0, 1.0),
            Restitution::AdhesiveYield {
                c_elastic,
                v_stick_mps,
                v_yield_mps,
            } => (c_elastic * adhesion(v, v_stick_mps) * (-v / v_yield_mps).exp()).clamp(0.0, 1.0),
            Restitution::PowerLaw {
                c_ref,
                v_ref_mps,
                exponent,
            } => {
                if v == 0.0 {
                    // the limit: 1 for a falling law (n > 0), 0 for a rising one, c at n = 0
                    return if exponent > 0.0 {
                        1.0
                    } else if exponent < 0.0 {
                        0.0
                    } else {
                        c_ref.clamp(0.0, 1.0)
                    };
                }
                (c_ref * (v / v_ref_mps).powf(-exponent)).clamp(0.0, 1.0)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_law_follows_its_nodes_holds_its_ends_and_stays_within_0_and_1() {
        let m = LnMap::new(&[0.02, 0.05, 0.2], &[0.4, 0.9, 1.2]).unwrap();
        let c = Restitution::Map(m);
        assert!((c.at(0.02) - 0.4).abs() < 1e-12 && (c.at(-0.05) - 0.9).abs() < 1e-12);
        let mid = (0.02f64 * 0.05).sqrt();
        assert!((c.at(mid) - 0.65).abs() < 1e-12, "{}", c.at(mid));
        assert_eq!(
            (c.at(1e-4), c.at(0.0)),
            (0.4, 0.4),
            "the first node's value below it"
        );
        // above 1 at the last node: clamped there and beyond; between 0.05 and 0.2 it crosses 1
        assert_eq!((c.at(0.2), c.at(3.0)), (1.0, 1.0));
        assert!(c.at(0.1) <= 1.0 && c.at(0.1) > 0.9);
        let low = Restitution::Map(LnMap::new(&[0.01, 0.1], &[-0.2, 0.5]).unwrap());
        assert_eq!(low.at(0.005), 0.0);
    }

    #[test]
    fn the_named_laws_beyond_the_candidates_read_as_written() {
        let v = 0.1f64;
        let visco = Restitution::Viscoelastic { a: 0.3 };
        assert!((visco.at(v) - (1.0 - 0.3 * v.powf(0.2))).abs() < 1e-15);
        assert_eq!(visco.at(0.0), 1.0);
        let adh = Restitution::Adhesive {
            c_elastic: 0.9,
            v_stick_mps: 0.02,
        };
        assert_eq!((adh.at(0.01), adh.at(0.02)), (0.0, 0.0), "sticks below v_s");
        assert!((adh.at(v) - 0.9 * (1.0 - 0.04f64).sqrt()).abs() < 1e-15);
        let yield_ = Restitution::AdhesiveYield {
            c_elastic: 0.9,
            v_stick_mps: 0.02,
            v_yield_mps: 0.5,
        };
        assert!((yield_.at(v) - adh.at(v) * (-0.2f64).exp()).abs() < 1e-15);
        let pl = Restitution::PowerLaw {
            c_ref: 0.8,
            v_ref_mps: 0.05,
            exponent: 0.25,
        };
        assert!((pl.at(0.05) - 0.8).abs() < 1e-15);
        assert!((pl.at(0.8) - 0.4).abs() < 1e-12, "{}", pl.at(0.8));
        assert_eq!(
            (pl.at(1e-6), pl.at(0.0)),
            (1.0, 1.0),
            "clamped at 1 when slow"
        );
    }

    #[test]
    fn the_laws_beyond_the_candidates_are_written_by_name() {
        let m = Restitution::Map(LnMap::new(&[0.02, 0.05], &[0.5, 0.7]).unwrap());
        let j = serde_json::to_value(m).unwrap();
        assert_eq!(j["map"]["values"], serde_json::json!([0.5, 0.7]));
        assert_eq!(serde_json::from_value::<Restitution>(j).unwrap(), m);
        let a: Restitution =
            serde_json::from_str(r#"{"adhesive": {"c_elastic": 0.9, "v_stick_mps": 0.01}}"#)
                .unwrap();
        assert_eq!(
            a,
            Restitution::Adhesive {
                c_elastic: 0.9,
                v_stick_mps: 0.01
            }
        );
    }
}
