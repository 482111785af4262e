//! Serde helper for an `f64` that may be NaN: defined with the artifact types (`crate::artifacts::nan_null`).

pub use crate::artifacts::nan_null::{deserialize, serialize};
