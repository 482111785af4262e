//! The physics of spheres in a v-groove: one particle (closed-form baseline and event-driven
//! integrator for any extra physics) and two colliding particles. Knows nothing of files.
//!
//! Files of this folder:
//!
//! - `advance.rs`: Adaptive integration of one smooth piece of motion up to a time or an event
//! - `baseline.rs`: The closed-form baseline
//! - `constants.rs`: Physical constants used throughout the physics module
//! - `friction.rs`: Particle–groove friction
//! - `groove.rs`: The groove geometry
//! - `hermite.rs`: Interpolation inside one integration step
//! - `impulse.rs`: The collision impulse between two equal spheres in the groove
//! - `mode.rs`: The motion modes of one particle
//! - `model.rs`: A one-particle model (groove, friction law, extra terms) and the particle state
//! - `pair.rs`: Two equal particles in one groove
//! - `phase.rs`: The three motion phases of a particle in the groove
//! - `restitution.rs`: The coefficient of restitution C as a function of the impact speed
//! - `rk.rs`: One Dormand–Prince 5(4) step for an autonomous ODE
//! - `simulate.rs`: Event-driven simulation of one particle under any `Model`
//! - `spline.rs`: A smooth force given by a cubic B-spline in one variable
//! - `terms.rs`: Composable extra physics along the groove
//! - `trajectory.rs`: The sampled result of a one-particle simulation, with its phase switches
//!
//! Notation follows `physics.md`: `v` is the velocity along the groove, `va = R ω_x` the surface
//! speed of the spin, `s = sin(θ/2)`, `k = m R² / I`. Sliding while `v ≠ s·va`, rolling (the
//! constrained Filippov motion) while `v = s·va`, and rest. Motion may go either way along z.

mod advance;
mod baseline;
mod constants;
mod friction;
mod groove;
mod hermite;
pub mod impulse;
mod mode;
mod model;
mod pair;
mod phase;
mod restitution;
mod rk;
mod simulate;
mod spline;
mod terms;
mod trajectory;

pub use baseline::Baseline;
pub use constants::G_MPS2;
pub use friction::Friction;
pub use groove::Groove;
pub use model::{Model, State};
pub use pair::{simulate_pair, Impact, PairParams, PairTrajectory, V_TOGETHER_MPS};
pub use phase::Phase;
pub use restitution::Restitution;
pub use simulate::simulate;
pub use spline::{basis as spline_basis, n_basis as spline_n_basis, SplineForce, Variable};
pub use terms::Term;
pub use trajectory::{SwitchEvent, Trajectory};
