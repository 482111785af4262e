//! The three motion phases of a particle in the groove.

use serde::{Deserialize, Serialize};

/// Sliding (`v ≠ s·va`), rolling without sliding (`v = s·va`), or at rest.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Phase {
    Sliding,
    Rolling,
    Rest,
}
