//! The physics of spheres in a v-groove: one particle (closed-form baseline and event-driven
//! integrator for any extra physics) and two colliding particles. Knows nothing of files.
//!
//! Notation follows `physics.md`: `v` is the velocity along the groove, `va = R ω_x` the surface
//! speed of the spin, `s = sin(θ/2)`, `k = m R² / I`. Sliding while `v ≠ s·va`, rolling (the
//! constrained Filippov motion) while `v = s·va`, and rest. Motion may go either way along z.

mod advance;
mod baseline;
mod constants;
mod friction;
mod friction_variation;
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
pub use friction_variation::FrictionVariation;
pub use groove::Groove;
pub use model::{Model, State};
pub use pair::{simulate_pair, Impact, PairParams, PairTrajectory, V_TOGETHER_MPS};
pub use phase::Phase;
pub use restitution::Restitution;
pub use simulate::simulate;
pub use spline::{basis as spline_basis, n_basis as spline_n_basis, SplineForce, Variable};
pub use terms::Term;
pub use trajectory::{SwitchEvent, Trajectory};
