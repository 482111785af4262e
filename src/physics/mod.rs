//! physics (being built)
