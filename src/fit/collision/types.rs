//! The per-run result of a collision fit: the types live with the other stage contracts in
//! `crate::artifacts::collision_fit`.

pub use crate::artifacts::collision_fit::*;
pub use crate::artifacts::nan_null as nan_as_null;
