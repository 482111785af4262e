//! μ_pp depending on the slip speed at the contact, u = |v_a1 + v_a2| before the impact (the
//! dependence discovery can accept, `pair_friction_slip_speed`), carried as a shape normalised
//! at a reference slip speed: μ_pp(u) = μ_pp · s(u)/s(u_ref), so that the one fitted μ_pp (and
//! its profile) keeps its meaning, μ_pp at u_ref.

use super::ln_map::LnMap;
use serde::{Deserialize, Serialize};

/// The shape s(u) of μ_pp against the slip speed u, as discovery names it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SlipShape {
    /// Discovery's map of μ_pp, linear in ln u between its nodes, held beyond them.
    Map(LnMap),
    /// a − b·u.
    Linear {
        at_zero_slip: f64,
        fall_per_mps: f64,
    },
    /// 1/(1 + u/u0) (the amplitude cancels in the normalisation).
    Weakening { slip_scale_mps: f64 },
}

impl SlipShape {
    fn at(&self, u: f64) -> f64 {
        let u = u.abs();
        match *self {
            SlipShape::Map(m) => m.at(u),
            SlipShape::Linear {
                at_zero_slip,
                fall_per_mps,
            } => at_zero_slip - fall_per_mps * u,
            SlipShape::Weakening { slip_scale_mps } => 1.0 / (1.0 + u / slip_scale_mps),
        }
    }
}

/// μ_pp's dependence on the slip speed, normalised at `u_ref_mps`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SlipFriction {
    pub shape: SlipShape,
    /// The slip speed at which μ_pp(u) is the fitted μ_pp (m/s).
    pub u_ref_mps: f64,
}

impl SlipFriction {
    /// μ_pp(u)/μ_pp(u_ref) at slip speed `u_mps`, never below 0 (a linear fall does not turn
    /// the friction around). NaN when the shape is 0 or not finite at u_ref (no normalisation).
    pub fn factor(&self, u_mps: f64) -> f64 {
        let r = self.shape.at(self.u_ref_mps);
        if !(r.is_finite() && r > 0.0) {
            return f64::NAN;
        }
        (self.shape.at(u_mps) / r).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_factor_is_one_at_the_reference_and_follows_the_shape() {
        let w = SlipFriction {
            shape: SlipShape::Weakening {
                slip_scale_mps: 0.05,
            },
            u_ref_mps: 0.05,
        };
        assert_eq!(w.factor(0.05), 1.0);
        assert!((w.factor(0.0) - 2.0).abs() < 1e-15 && (w.factor(-0.15) - 0.5).abs() < 1e-15);
        let l = SlipFriction {
            shape: SlipShape::Linear {
                at_zero_slip: 0.4,
                fall_per_mps: 2.0,
            },
            u_ref_mps: 0.1,
        };
        assert!((l.factor(0.0) - 2.0).abs() < 1e-15);
        assert_eq!(l.factor(0.5), 0.0, "never below 0");
        let m = SlipFriction {
            shape: SlipShape::Map(LnMap::new(&[0.01, 0.1], &[0.4, 0.2]).unwrap()),
            u_ref_mps: 0.1,
        };
        assert!((m.factor(0.001) - 2.0).abs() < 1e-15 && (m.factor(1.0) - 1.0).abs() < 1e-15);
        let flat = SlipFriction {
            shape: SlipShape::Linear {
                at_zero_slip: 0.0,
                fall_per_mps: 0.0,
            },
            u_ref_mps: 0.1,
        };
        assert!(flat.factor(0.1).is_nan());
    }
}
