//! discover (being built)
