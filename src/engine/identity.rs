//! The code identity compiled into this binary: each built-in kind's fingerprint and the code commit.

include!(concat!(env!("OUT_DIR"), "/code_identity.rs"));

/// The groove version recorded in every stage key.
pub const GROOVE_VERSION: &str = env!("CARGO_PKG_VERSION");
