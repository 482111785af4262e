//! A one-particle model (groove, friction law, extra terms) and the particle state.

use super::{Friction, FrictionVariation, Groove, Term};
use serde::{Deserialize, Serialize};

/// Everything that sets the motion of one particle in the groove.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Model {
    pub groove: Groove,
    pub friction: Friction,
    /// How μ varies with direction, position and slip speed beyond its law (none by default).
    #[serde(default, skip_serializing_if = "FrictionVariation::is_none")]
    pub variation: FrictionVariation,
    pub terms: Vec<Term>,
}

/// Position, velocity and spin surface speed `va = R ω` of one particle.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct State {
    pub z_m: f64,
    pub v_mps: f64,
    pub va_mps: f64,
}

impl Model {
    /// The chapter's groove with constant μ and a linear drag T (the baseline as a model).
    pub fn baseline(mu: f64, t_drag_s: f64) -> Model {
        Model {
            groove: Groove::CHAPTER,
            friction: Friction::Constant { mu },
            variation: FrictionVariation::default(),
            terms: vec![Term::LinearDrag { t_s: t_drag_s }],
        }
    }

    /// Sum of the extra accelerations at (z, v) and time since the kick t.
    pub fn accel(&self, z_m: f64, v_mps: f64, t_s: f64) -> f64 {
        self.terms.iter().map(|t| t.accel(z_m, v_mps, t_s)).sum()
    }

    /// Some term jumps where v changes sign.
    pub fn has_sign_jump(&self) -> bool {
        self.terms.iter().any(Term::has_sign_jump)
    }

    /// Some term depends on the time since the kick (so a particle at rest may start again).
    pub fn time_dependent(&self) -> bool {
        self.terms.iter().any(Term::time_dependent)
    }

    /// The shortest time over which a term in time changes (s; infinite without one).
    pub fn shortest_time_scale_s(&self) -> f64 {
        self.terms
            .iter()
            .filter_map(Term::time_scale_s)
            .fold(f64::INFINITY, f64::min)
    }

    /// What the terms can hold at rest (m/s²).
    pub fn static_hold_mps2(&self) -> f64 {
        self.terms.iter().map(Term::static_hold_mps2).sum()
    }
}
