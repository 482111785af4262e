//! An independent simulator of the groove experiment, for tests and the discovery bench only.
//!
//! Written from the equations of motion, sharing no code with the analysis it tests:
//!
//! * one particle in a v-groove of half-angle sine `s` with `k = m R² / I`: while it slides
//!   (`u = v − s·v_a ≠ 0`, `d = sign u`) `dv/dt = −d g μ / s + a(z, v, t)` and
//!   `dv_a/dt = d k g μ`; while it rolls (`u = 0`) `dv/dt = ks²/(1 + ks²) · a` with `v_a = v/s`,
//!   which holds while `|s a / (1 + ks²)| ≤ g μ_static`; at rest it stays unless a force with the
//!   particle at rest would move it;
//! * `a` is the drag (linear `−v/T`, quadratic, saturating) plus any extra force of [`effects`];
//! * two particles of radius `R` collide when their centres are `2R` apart: with
//!   `J = (1 + C)/2 · (v1 − v2)` the velocities become `v1 − J`, `v2 + J`; the spins slip by
//!   `μ_pp k J` (against the sign of their sum) when `|v_a1 + v_a2| ≥ 2 μ_pp k J` and otherwise
//!   stick to `±(v_a1 − v_a2)/2`;
//! * the camera films at `fps` starting a random fraction of a frame after the kick, from a field
//!   of view fixed in the lab, with dropped frames, tracking outliers and the tracker's noise of
//!   [`noise`]; [`writer`] writes the interchange tables: `runs.csv` (`run, experiment, material,
//!   diameter_m, fps, setup`) and `trajectories.csv` (`run, particle, frame, t_s, z_m`; `t_s`
//!   counted from each run's first frame, gaps in `frame` for dropped frames).
//!
//! Integration is fixed-step RK4 (10 µs by default); slip ends, hold breaks and stops are found by
//! bisection inside the step, and frames are sampled from the fine trajectory by cubic Hermite
//! interpolation.

pub mod camera;
pub mod effects;
pub mod events;
pub mod integrator;
pub mod model;
pub mod noise;
pub mod pair;
pub mod run;
pub mod writer;
