//! Discovery on recordings of the independent simulator (tests/support/indsim): an effect in each
//! place where physics enters (a force, the friction, the measurement, differences between
//! particles), two shapes per place where two are detectable, at 8× its detection limit in the
//! tracker noise it is drawn with, must be named in its place with an acceptable form and nothing
//! beside it. The rates over randomized datasets, sizes and noises are the bench's
//! (`tests/bench/discovery_bed.rs`); these fix one seed each so a regression shows here first.

#[allow(dead_code)]
#[path = "support/indsim/mod.rs"]
mod indsim;

#[allow(dead_code)]
#[path = "support/bed/mod.rs"]
mod bed;

use bed::draw::{case, Size};
use bed::in_process::discover_case;
use bed::score::{accepted, names, score};
use bed::shapes::SHAPES;

/// 12 single runs per material of 50 ms.
const SIZE: Size = Size {
    singles_per_material: 12,
    duration_s: 0.05,
};

fn shape(name: &str) -> usize {
    SHAPES
        .iter()
        .position(|s| s.1 == name)
        .unwrap_or_else(|| panic!("no shape {name}"))
}

/// Draws `name` at `multiple`× its limit in `noise`, runs discovery through ingest, and returns
/// what it accepted (place/effect: form) and whether that names the truth alone.
fn discovered(seed: u64, noise: &str, name: &str, multiple: f64) -> (bool, Vec<String>) {
    let c = case(seed, SIZE, noise, &[(shape(name), multiple)], false);
    let d = discover_case(&c, seed);
    let found = accepted(&serde_json::to_string(&d).unwrap()).unwrap();
    let mut said: Vec<String> = found
        .iter()
        .map(|a| format!("{}/{}: {}", a.place, a.effect, a.form))
        .collect();
    // what the particle check said, for the failure message
    said.extend(
        d.findings
            .iter()
            .filter(|f| f.effect == "particle_differences" && !f.accepted)
            .map(|f| format!("(particle check: {})", f.evidence.decision)),
    );
    let s = score(&found, &c.truths);
    assert_eq!(s.named, found.len() == 1 && names(&found[0], &c.truths[0]));
    (s.named, said)
}

fn assert_named(seed: u64, noise: &str, name: &str) {
    let (named, said) = discovered(seed, noise, name, 8.0);
    assert!(
        named,
        "{name} in {noise} noise (seed {seed}): accepted {said:?}"
    );
}

#[test]
fn a_force_is_named_a_force_tilt() {
    assert_named(1, "white", "tilt");
}

#[test]
fn a_force_is_named_a_force_resistance() {
    assert_named(2, "ar1", "resistance");
}

#[test]
fn a_friction_is_named_a_friction_rising_with_slip() {
    assert_named(3, "white", "mu_slip_rising");
}

#[test]
fn a_friction_is_named_a_friction_by_direction() {
    assert_named(4, "blur", "mu_direction");
}

#[test]
fn a_measurement_is_named_a_measurement_distortion() {
    assert_named(5, "white", "distortion");
}

#[test]
#[ignore = "a known miss: at 8x its limit a spread of mu leaves 5.5x the noise's energy in slow shapes a run's own linearized mu and T cannot make, so the particle check reads it as a wandering tracker and a force in time with a phase per run takes the misfit; the check needs each run refitted with its own mu and T"]
fn particles_that_differ_are_named_so_mu() {
    assert_named(6, "white", "mu_spread");
}

#[test]
fn particles_that_differ_are_named_so_size() {
    assert_named(7, "ar1", "size_spread");
}
