//! synth (being built)
