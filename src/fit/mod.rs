//! fit (being built)
