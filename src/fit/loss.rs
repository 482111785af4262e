//! The robust losses of the per-run fits: the shared [`crate::lsq::loss`].

pub use crate::lsq::loss::{Loss, HUBER_K};
