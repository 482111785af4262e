//! The types of summary.json (the output contract of the fits) live with the other stage contracts
//! in `crate::artifacts::summary`.

pub use crate::artifacts::summary::*;
