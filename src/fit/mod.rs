//! fit (being built)

pub mod collision;
