//! The coefficient of restitution C as a function of the impact speed.

use serde::{Deserialize, Serialize};

/// Restitution law. `SpeedDependent`: `C(v) = c0 + (1 − c0) e^{−|v|/v_ref}`, 1 for a gentle
/// touch and falling towards `c0` for hard impacts (the chapter's Fig. 4.4b–c trend).
/// `Linear`: `C(v) = c0 − slope·|v|`, kept within [0, 1].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Restitution {
    Constant(f64),
    SpeedDependent { c0: f64, v_ref_mps: f64 },
    Linear { c0: f64, slope_per_mps: f64 },
}

impl Restitution {
    /// C at impact speed `v_impact_mps` (relative approach speed).
    pub fn at(&self, v_impact_mps: f64) -> f64 {
        match *self {
            Restitution::Constant(c) => c,
            Restitution::SpeedDependent { c0, v_ref_mps } => {
                c0 + (1.0 - c0) * (-v_impact_mps.abs() / v_ref_mps).exp()
            }
            Restitution::Linear { c0, slope_per_mps } => {
                (c0 - slope_per_mps * v_impact_mps.abs()).clamp(0.0, 1.0)
            }
        }
    }
}
