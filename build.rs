//! Build script: computes each stage kind's code fingerprint (being built).

fn main() {}
