//! Physical constants used throughout the physics module.

/// Gravitational acceleration (m/s²), the value the chapter uses.
pub const G_MPS2: f64 = 9.81;
