//! The sampled result of a one-particle simulation, with its phase switches.

use super::Phase;
use serde::{Deserialize, Serialize};

/// A change of motion phase (or of slip direction) at time `t_s`, with the state there.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SwitchEvent {
    pub t_s: f64,
    pub from: Phase,
    pub to: Phase,
    pub z_m: f64,
    pub v_mps: f64,
    pub va_mps: f64,
}

/// State and phase at each requested time, plus every switch that happened before the last one,
/// and whether the simulation stopped at its step budget before the last time (`stalled`: every
/// later sample then holds the state reached, a misfit that is the integrator's, not the physics').
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Trajectory {
    pub t_s: Vec<f64>,
    pub z_m: Vec<f64>,
    pub v_mps: Vec<f64>,
    pub va_mps: Vec<f64>,
    pub phase: Vec<Phase>,
    pub events: Vec<SwitchEvent>,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub stalled: bool,
}

impl Trajectory {
    pub(crate) fn with_capacity(n: usize) -> Trajectory {
        Trajectory {
            t_s: Vec::with_capacity(n),
            z_m: Vec::with_capacity(n),
            v_mps: Vec::with_capacity(n),
            va_mps: Vec::with_capacity(n),
            phase: Vec::with_capacity(n),
            events: Vec::new(),
            stalled: false,
        }
    }

    pub(crate) fn push(&mut self, t_s: f64, y: &[f64], phase: Phase) {
        self.t_s.push(t_s);
        self.z_m.push(y[0]);
        self.v_mps.push(y[1]);
        self.va_mps.push(y[2]);
        self.phase.push(phase);
    }
}
