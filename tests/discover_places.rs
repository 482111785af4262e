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
/// what it accepted (place/effect: form, and its parameters), whether that names the truth alone,
/// and the worst relative error of the sizes it gives for the truth's (per material, say).
fn discovered(seed: u64, noise: &str, name: &str, multiple: f64) -> (bool, f64, Vec<String>) {
    discovered_at(SIZE, seed, noise, name, multiple)
}

/// `discovered` on datasets of `size`.
fn discovered_at(
    size: Size,
    seed: u64,
    noise: &str,
    name: &str,
    multiple: f64,
) -> (bool, f64, Vec<String>) {
    let c = case(seed, size, noise, &[(shape(name), multiple)], false);
    let d = discover_case(&c, seed);
    let found = accepted(&serde_json::to_string(&d).unwrap()).unwrap();
    let mut said: Vec<String> = found
        .iter()
        .map(|a| format!("{}/{}: {} {:?}", a.place, a.effect, a.form, a.parameters))
        .collect();
    // what the particle check said, for the failure message
    said.extend(
        d.findings
            .iter()
            .filter(|f| f.effect == "particle_differences" && !f.accepted)
            .map(|f| format!("(particle check: {})", f.evidence.decision)),
    );
    let s = score(&found, &c.truths);
    said.push(format!("(truth: {:?})", c.truths[0].sizes));
    assert_eq!(s.named, found.len() == 1 && names(&found[0], &c.truths[0]));
    let worst = c.truths[0]
        .sizes
        .iter()
        .flat_map(|(size, truth)| {
            found
                .iter()
                .flat_map(|a| a.parameters.iter())
                .filter(move |p| p.0.starts_with(size.as_str()))
                .map(move |p| (p.1 / truth - 1.0).abs())
        })
        .fold(f64::NAN, f64::max);
    (s.named, worst, said)
}

fn assert_named(seed: u64, noise: &str, name: &str) {
    let (named, _, said) = discovered(seed, noise, name, 8.0);
    assert!(
        named,
        "{name} in {noise} noise (seed {seed}): accepted {said:?}"
    );
}

/// Named, and each material's spread (relative to its μ, or the radii's) within 40 % of the
/// spread its 12 particles were given (their sample standard deviation, not the law's width):
/// each run's μ and T carry their own noise, which the estimate removes only on average.
fn assert_named_and_sized(seed: u64, noise: &str, name: &str) {
    let (named, worst, said) = discovered(seed, noise, name, 8.0);
    assert!(
        named && worst < 0.4,
        "{name} in {noise} noise (seed {seed}): named {named}, worst size error {worst:.2}: {said:?}"
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
fn particles_that_differ_are_named_so_mu() {
    // before each run was refitted with its own μ and T, the first order left 5.5× the noise's
    // energy in slow shapes here, read as a wandering tracker
    assert_named_and_sized(6, "white", "mu_spread");
}

#[test]
fn particles_that_differ_are_named_so_size() {
    assert_named_and_sized(7, "ar1", "size_spread");
}

/// μ periodic along the groove (a texture of 1–8 mm wavelength, the simulator's own law), six
/// datasets at 5× its limit over six noises: a friction along z is accepted in at least four;
/// where the periodic form is the one chosen (in at least two), its relative amplitude is within
/// 15 % in at least half. Not yet asserted, because not so: nothing else beside it (a particle
/// spread or a second friction form came with it in two of six at this test's writing) and the
/// periodic form over μ's gradient and curvature (P1 + P2 bent to 80 % of μ took two). Before
/// the friction place had a periodic form, the bench named this shape 0/5.
#[test]
fn a_friction_along_the_groove_is_named_a_friction() {
    let noises = ["white", "ar1", "blur", "locked", "outliers", "mixture"];
    let (mut place, mut periodic, mut sized, mut said) = (0, 0, 0, Vec::new());
    for (k, noise) in noises.into_iter().enumerate() {
        let (alone, worst, s) = discovered(40 + k as u64, noise, "mu_position", 5.0);
        said.push(format!(
            "{noise}: alone {alone}, size error {worst:.2}: {s:?}"
        ));
        if s.iter()
            .any(|a| a.starts_with("friction/position_dependent_friction"))
        {
            place += 1;
        }
        // the size error is that of the periodic form's amplitude `delta_mu_rel`; the form in
        // μ's gradient and curvature reports half its range over the stretch under that name,
        // which understates a texture of a wavelength or less (0.81 and 0.72 of the truth here
        // in locked and outlier noise): it sizes the quadratic, not the wave
        let wave = s
            .iter()
            .any(|a| a.contains("periodic mu(z) along the groove"));
        if wave && worst.is_finite() {
            periodic += 1;
            if worst < 0.15 {
                sized += 1;
            }
        }
    }
    let text = said.join("\n");
    eprintln!("{text}");
    assert!(
        place >= 4 && periodic >= 2 && 2 * sized >= periodic,
        "friction along z in {place}/6, periodic form in {periodic}, sized {sized}:\n{text}"
    );
}

/// A force along the groove with no named shape (the simulator's sum of five waves of 1–10 mm
/// with random amplitudes), four datasets of the bench's size (60 runs) at 6× its limit over
/// four noises: named as one finding — a map in z, with any named forms in z as its parts — in
/// at least two. Before the map could stand in for the named forms or take them as parts, the
/// bench named this shape 0/4 at 3× or more: a tilt, a wave and a bump came out as three
/// findings. Not yet more: on 24 runs of this file's size it is named in 1 of 4, and where no
/// map passes, the named forms stand (a wave of 0.9 mm with a bump of −4 m/s² where no run went
/// came out on one).
#[test]
fn a_force_field_along_the_groove_is_one_finding() {
    let noises = ["white", "ar1", "blur", "locked"];
    let (mut named, mut said) = (0, Vec::new());
    for (k, noise) in noises.into_iter().enumerate() {
        let (alone, _, s) =
            discovered_at(bed::draw::FULL_SIZE, 60 + k as u64, noise, "field_z", 6.0);
        said.push(format!("{noise}: named {alone}: {s:?}"));
        named += usize::from(alone);
    }
    let text = said.join("\n");
    eprintln!("{text}");
    assert!(named >= 2, "a field in z named in {named}/4:\n{text}");
}

/// Over four noises (seeds from `seed`), how often `name` at `multiple`× its limit is named
/// alone and how often its sizes are within 15 % as well, with what was said.
fn named_and_sized(name: &str, seed: u64, multiple: f64) -> (usize, usize, String) {
    named_and_sized_at(SIZE, name, seed, multiple)
}

/// `named_and_sized` on datasets of `size`.
fn named_and_sized_at(size: Size, name: &str, seed: u64, multiple: f64) -> (usize, usize, String) {
    let noises = ["white", "ar1", "drift", "blur"];
    let (mut named, mut sized, mut said) = (0, 0, Vec::new());
    for (k, noise) in noises.into_iter().enumerate() {
        let (alone, worst, s) = discovered_at(size, seed + k as u64, noise, name, multiple);
        said.push(format!(
            "{noise}: named {alone}, size error {worst:.2}: {s:?}"
        ));
        named += usize::from(alone);
        sized += usize::from(alone && worst < 0.15);
    }
    let text = said.join("\n");
    eprintln!("{text}");
    (named, sized, text)
}

/// A force periodic in time with one phase for every run (a vibration locked to the kick, the
/// simulator's own, at 20–200 Hz), four datasets at 6× its limit over four noises, slow drift
/// among them: named as a force in time and nothing else, its amplitude and frequency within
/// 15 %, in at least three (4/4 at this test's writing, within 5 %). Before the form with one
/// phase for every run, a 29 Hz vibration in drifting noise came out as a spline in time (the
/// form with a phase per run then searched from three periods in the longest run).
#[test]
fn a_vibration_locked_to_the_kick_is_a_force_in_time() {
    let (named, sized, text) = named_and_sized("time_common_phase", 80, 6.0);
    assert!(
        named >= 3 && sized >= 3,
        "a vibration locked to the kick named in {named}/4, sized in {sized}:\n{text}"
    );
}

/// A force periodic in time with its own phase in each run (the simulator's own, at 20–200 Hz:
/// one to twelve periods in a run of 60 ms), four datasets of the bench's size at 6× its limit
/// over four noises: named as a force in time with a phase per run and nothing else, its
/// amplitude and frequency within 15 %, in at least three (at this test's writing: 58 and 70 Hz,
/// and 23.5 Hz in blur, within 6 %; the fourth, 23.6 Hz in white noise, nothing found). While
/// the search started at three periods in the longest run (50 Hz here), the 23.5 Hz one was out
/// of its reach, and the bench named 3 of its 6 such datasets at 3× and more (misses at 26 and
/// 37 Hz among them).
#[test]
fn a_vibration_with_a_phase_per_run_is_a_force_in_time() {
    let (named, sized, text) = named_and_sized_at(bed::draw::FULL_SIZE, "time_run_phase", 110, 6.0);
    assert!(
        named >= 3 && sized >= 3,
        "a vibration with a phase per run named in {named}/4, sized in {sized}:\n{text}"
    );
}

/// A step in the force along the groove (the simulator's own, 0.1 mm wide at 3–9 mm), four
/// datasets at 8× its limit over four noises: named (a step, or a map in z) and nothing else,
/// its height within 15 %, in at least three. Before the step form, the bench named this shape
/// 0/5: a Gaussian bump centred at the end of the observed stretch stood for it.
#[test]
fn a_step_along_the_groove_is_named_a_step() {
    let (named, sized, text) = named_and_sized("step_z", 90, 8.0);
    assert!(
        named >= 3 && sized >= 3,
        "a step along the groove named in {named}/4, sized in {sized}:\n{text}"
    );
}

/// A friction falling with the slip speed from a static value (a Stribeck curve, the
/// simulator's own: μ (1 + δ e^(−u/v_c)), v_c 5–30 mm/s), four datasets of the bench's size at
/// 6× its limit over four noises: named as a friction of the slip speed and nothing else, its
/// excess δ within 15 %, in at least three. Before the Stribeck form, the bench's one such
/// dataset was named by the linear law in the slip speed, whose slope is no size of this curve.
/// On the small datasets of the tests above (12 runs a material), before the richer form of an
/// effect was fitted beside the first to pass, the line was named in three of four.
#[test]
fn a_friction_falling_with_slip_is_a_stribeck_curve() {
    let (named, sized, text) =
        named_and_sized_at(bed::draw::FULL_SIZE, "mu_slip_falling", 100, 6.0);
    assert!(
        named >= 3 && sized >= 3,
        "a friction falling with slip named in {named}/4, sized in {sized}:\n{text}"
    );
}
