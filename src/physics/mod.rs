//! The physics of spheres in a v-groove: one particle (closed-form baseline and event-driven
//! integrator for any extra physics) and two colliding particles. Knows nothing of files.
//!
//! Files of this folder:
//!
//! - `advance.rs`: Adaptive integration of one smooth piece of motion up to a time or an event
//! - `baseline.rs`: The closed-form baseline
//! - `constants.rs`: Physical constants used throughout the physics module
//! - `friction.rs`: Particle–groove friction
//! - `friction_variation.rs`: How μ varies by direction, position and slip speed beyond its law
//! - `groove.rs`: The groove geometry
//! - `hermite.rs`: Interpolation inside one integration step
//! - `impulse.rs`: The collision impulse between two equal spheres in the groove
//! - `ln_map.rs`: A law given by its values at a few speeds, piecewise linear in the logarithm of the speed
//! - `mode.rs`: The motion modes of one particle
//! - `model.rs`: A one-particle model (groove, friction law, extra terms) and the particle state
//! - `pair.rs`: Two equal particles in one groove
//! - `pair_force.rs`: A force between the two particles of a pair that acts before they touch
//! - `phase.rs`: The three motion phases of a particle in the groove
//! - `restitution.rs`: The coefficient of restitution C as a function of the impact speed
//! - `rk.rs`: One Dormand–Prince 5(4) step for an autonomous ODE
//! - `simulate.rs`: Event-driven simulation of one particle under any `Model`
//! - `slip_friction.rs`: μ_pp depending on the slip speed at the contact
//! - `spline.rs`: A smooth force given by a cubic B-spline in one variable
//! - `terms.rs`: Composable extra physics along the groove
//! - `trajectory.rs`: The sampled result of a one-particle simulation, with its phase switches
//!
//! Notation (the model in full below): `v` is the velocity along the groove, `va = R ω_x` the surface
//! speed of the spin, `s = sin(θ/2)`, `k = m R² / I`. Sliding while `v ≠ s·va`, rolling (the
//! constrained Filippov motion) while `v = s·va`, and rest. Motion may go either way along z.
//!
//! # The model
//!
//! One sphere of radius R (about 150 µm) moves along a v-groove of opening angle θ = 70.6°. Write
//! `z`, `v` for its position and velocity along the groove, `va = R ω_x` for the surface speed of its
//! spin, `s = sin(θ/2)` ≈ 0.5779 for the groove's geometric factor and `k = m R²/I` (5/2 for a
//! solid sphere; ks² ≈ 0.8348). μ is the particle–groove Coulomb friction (the chapter measured
//! 0.337 for 316 steel and 0.293 for 440c), `T` a drag time (linear drag v/T), g = 9.81 m/s².
//! Let a(z, v, t) collect every acceleration along z other than the groove's friction: the drag and
//! any extra physics.
//!
//! While the sphere slides (v ≠ s·va), with d the sign of v − s·va:
//!
//! ```text
//! dv/dt  = −d g μ / s + a
//! dva/dt =  d k g μ
//! ```
//!
//! While it rolls (v = s·va) the friction takes whatever value keeps the contact from slipping. The
//! chapter writes this with sign(0) = 0 (Eq. 4.5), which taken literally chatters between the two
//! branches; the consistent limit is the constrained motion
//!
//! ```text
//! dv/dt = ks²/(1 + ks²) · a,   va = v/s
//! ```
//!
//! valid while the friction it needs, |s a/(1 + ks²)|, does not exceed g μ; beyond that the sphere
//! slips again. A sphere at rest stays there until a force that does not dissipate outgrows what
//! holds it. Motion towards −z mirrors motion towards +z, and both are handled.
//!
//! **Closed form of the baseline.** With a = −v/T, no initial spin and v0 > 0, put A = g μ T/s.
//! Sliding: v(t) = (v0 + A) e^(−t/T) − A, z(t) = T (v0 + A)(1 − e^(−t/T)) − A t, va(t) = k g μ t,
//! until the time t1 where (v0 + A) e^(−t1/T) − A = s k g μ t1. Rolling after t1:
//! v = v1 e^(−(t − t1)/Te), z = z1 + v1 Te (1 − e^(−(t − t1)/Te)), with Te = T (1 + ks²)/ks² ≈ 2.2 T.
//! A recording begins a fraction of a frame after the kick at an unknown place, so a fit of one run
//! also has z0 and t0 (and v0) as nuisance parameters. Without drag (T → ∞) the steady state and
//! the distance and time to reach it are the chapter's Eqs. 4.3–4.4.
//!
//! **Two spheres of equal size and mass** touch when their centres are 2R apart. An impact is an
//! impulse: with J = (1 + C)/2 · (v1 − v2), v1' = v1 − J and v2' = v2 + J. If
//! |va1 + va2| ≥ 2 μ_pp k J the contact slips and each spin changes by μ_pp k J against the sliding
//! (va_i' = va_i − sign(va1 + va2) μ_pp k J); otherwise it sticks and va1' = (va1 − va2)/2,
//! va2' = (va2 − va1)/2. Between impacts each sphere follows the one-particle motion. For two rolling
//! spheres an impact and the re-acceleration after it scale their velocity difference by
//! (1 − ks²)/(1 + ks²) ≈ 0.090, so secondary impacts follow (forever, ideally) whenever θ < 78.5°,
//! and the pair ends rolling about 2R apart. The restitution measured from the velocities is
//! C = (v2' − v1')/(v1 − v2) (Eq. 4.20). The slope of Δva against Δv of the target is μ_pp k only
//! for slipping impacts, so μ_pp is estimated from those, or from a fit of the whole impulse model.
//!
//! # What the chapter gets wrong, corrected here
//!
//! The report's equation audit (`report::audit`) checks each with numbers from this module:
//!
//! 1. Eq. 4.6's second branch, as printed, is v(t1) e^(−(t−t1)/T), a velocity rather than a
//!    position, and it decays with T where constrained rolling decays with Te ≈ 2.2 T.
//! 2. The expansion v/T0 − v²/L of Eqs. 4.7–4.8 makes the dissipation change sign at
//!    v = L/T0 ≈ 48 mm/s, inside the measured range (up to 0.1 m/s); groove uses forms that stay
//!    physical, such as the saturating v/(T0 + T'|v|) or a fitted quadratic term.
//! 3. The Stokes time m/(6π η R) for R = 150 µm, steel (7,900 kg/m³) and air (1.81e-5 Pa·s) is
//!    about 2.2 s, not 0.074 s (which is what the chapter's T = 0.052 + 1.10 v0 gives at
//!    v0 = 0.02 m/s). The measured ~0.05 s is about 40× faster than free-air drag, so the loss
//!    comes from the support (contact, rolling losses, air squeezed at the walls). A fitted T that
//!    grows with v0 is also what a constant rolling resistance produces, not only a quadratic drag:
//!    which one it is must be decided by evidence (discovery does).
//! 4. Eqs. 4.15 and 4.17 print u1 in both terms; the second multiplies u2.
//! 5. After Eq. 4.16 the stick/slip test is cited as Eq. 4.9; it is Eq. 4.13.
//! 6. The caption of Fig. 4.2 gives μ = 0.296 for 440c; the text and Eq. 4.8 give 0.293.
//!
//! # Where missing physics enters
//!
//! A baseline fit leaves out whatever the experiment has and the model lacks. It can enter as a
//! force a(z_lab, v, t) (felt while sliding, and at ks²/(1 + ks²) while rolling; a force fixed in
//! the lab acts at the same lab z in every run); as a friction μ(z_lab, u, direction, material)
//! (changing the sliding phase, not pure rolling); in the measurement (length scale, distortion,
//! time base, tracker noise: no change of the dynamics); as differences between particles (per-run
//! values scattering beyond their errors); or between two particles (a force depending on their
//! separation, C(v), μ_pp(u)). A physical term keeps its physical sign: a drag that accelerates is
//! not one. The extra terms of `terms.rs` are the ways discovery adds such physics.
//!
//! # Integration
//!
//! `mode.rs`: sliding, rolling and rest, each mode ending at an
//!   event; with a rolling resistance a sign term is taken in the mode's direction even past v = 0,
//!   so the integrator reaches the event instead of stepping ever smaller across the jump, and a
//!   slide stopped with both ways barred (the resistance holds more than the spin's friction
//!   drives) rests (2026-11-26: a per-run fit of a slow run with μ at its floor ground at v = ±1e-11
//!   for 8.5 s, and the discovery of a rolling resistance took 14 s, now 3.7 s). A slide whose
//!   velocity-dependent friction holds the slip off zero (a force pushing it away, a tilt
//!   downhill) creeps once the slip's relaxation time τ is below 20 µs and its transient is over:
//!   the slip is put on its quasi-static value and v moves by the exact share of the slip's
//!   change, `v' = (ks² a + τ ȧ)/(1 + ks²)`, so the explicit integrator no longer steps at τ for
//!   the whole run (z within 2·10⁻¹² m of a stiff RK4 reference, `tests/physics.rs`; a fit of μ(v)
//!   with a tilt wandering to v_c ≈ 20 µm/s took 22 s and its cross-validation 11 s; the
//!   cross-validation now takes 0.7 s; `cargo bench --bench physics`: 215 → 64 µs a trajectory).
//!   Rest lasts to the end only under forces that do not depend on time (z is fixed, so nothing
//!   that holds the particle changes: `Mode::absorbing`); under a force in time (a vibration, a
//!   spline in t) rest ends where that force outgrows the hold, for one particle and for each of a
//!   pair (until 2026-11-26 a particle at rest stayed there; `tests/physics.rs` checks the start
//!   time to 1e-9 s and the roll from rest against its closed form to 1e-12 m). At rest nothing
//!   moves, so the error control lets steps grow; there no step spans a 32nd of the shortest time
//!   scale of the forces in time (`Mode::step_cap`: at 1 ms steps a vibration 2 % above the hold at
//!   900 Hz started the particle 3.3 ms late).

mod advance;
mod baseline;
mod constants;
mod friction;
mod friction_variation;
mod groove;
mod hermite;
pub mod impulse;
mod ln_map;
mod mode;
mod model;
mod pair;
mod pair_force;
mod phase;
mod restitution;
mod rk;
mod simulate;
mod slip_friction;
mod spline;
mod terms;
mod trajectory;

pub use advance::budget_stops;
pub use baseline::Baseline;
pub use constants::G_MPS2;
pub use friction::Friction;
pub use friction_variation::FrictionVariation;
pub use groove::Groove;
pub use ln_map::{LnMap, MAX_NODES as MAX_MAP_NODES};
pub use model::{Model, State};
pub use pair::{simulate_pair, Impact, PairParams, PairTrajectory, V_TOGETHER_MPS};
pub use pair_force::PairForce;
pub use phase::Phase;
pub use restitution::Restitution;
pub use simulate::simulate;
pub use slip_friction::{SlipFriction, SlipShape};
pub use spline::{basis as spline_basis, n_basis as spline_n_basis, SplineForce, Variable};
pub use terms::{step_shape, Term};
pub use trajectory::{SwitchEvent, Trajectory};
