//! Discovery beyond the fixed list, on datasets made by `groove synth` from the truth files in
//! tests/fixtures/truths/ (lab coordinates: each run starts 0.5–1.5 mm inside either end of a
//! 12 mm field of view, both directions, 316 and 440c, 1 µm noise on a sub-pixel grid, dropped
//! frames and outliers), read back through ingest.
//!
//! Each concealed effect must be named with the right effect and form, its magnitudes within
//! 15 % of the truth, and no other term accepted; nulls must accept nothing and carry detection
//! limits. These tests use one seed per case; the sweeps over seeds of the same fixtures are a
//! benchmark, `tests/bench/discovery_power.sh` (e.g. `SEEDS="2 3 4 5 6" EFFECTS="waviness_5mm"
//! NULLS="" bash tests/bench/discovery_power.sh`), and their results are in
//! tests/bench/DISCOVERY.md.

#[path = "support/noise.rs"]
mod noise;

use groove::discover::{discover, Diagnosis, Options};
use groove::ingest::{ingest, IngestParams};
use groove::physics::Term;
use groove::recording::Recording;
use groove::synth::{synth_tables, Truth};
use std::collections::BTreeMap;
use std::path::Path;

fn truth(name: &str, seed: Option<u64>) -> Truth {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/truths")
        .join(format!("{name}.toml"));
    let mut t = Truth::parse(&std::fs::read_to_string(&path).unwrap()).unwrap();
    if let Some(s) = seed {
        t.seed = s;
    }
    t
}

fn recordings(truth: &Truth) -> Vec<Recording> {
    let tables = synth_tables(truth);
    let mut files = BTreeMap::new();
    files.insert("runs.csv".to_string(), tables.runs_csv.into_bytes());
    files.insert(
        "trajectories.csv".to_string(),
        tables.trajectories_csv.into_bytes(),
    );
    ingest(&files, &IngestParams::default())
        .expect("a synthesized dataset ingests")
        .recordings
}

fn options(seed: u64) -> Options {
    Options {
        bootstrap: 12,
        bootstrap_iterations: 5,
        folds: 4,
        max_terms: 3,
        seed,
        ..Options::default()
    }
}

fn run(name: &str, seed: Option<u64>) -> Diagnosis {
    let t = truth(name, seed);
    discover(&recordings(&t), &options(seed.unwrap_or(t.seed)))
}

fn accepted(d: &Diagnosis) -> Vec<(String, String)> {
    d.findings
        .iter()
        .filter(|f| f.accepted)
        .map(|f| (f.effect.clone(), f.form.clone()))
        .collect()
}

fn param(d: &Diagnosis, effect: &str, form: &str, name: &str) -> f64 {
    let f = d
        .findings
        .iter()
        .find(|f| f.accepted && f.effect == effect && f.form.contains(form))
        .unwrap_or_else(|| panic!("no accepted {effect} ({form}): {:?}", accepted(d)));
    f.parameters
        .get(name)
        .unwrap_or_else(|| panic!("no {name} in {:?}", f.parameters))
        .value
}

/// Asserts `got` within 15 % of `want`; the found value and its error, for the sweeps' lines.
fn within(got: f64, want: f64, what: &str) -> String {
    assert!(
        (got - want).abs() <= 0.15 * want.abs(),
        "{what}: found {got}, truth {want}"
    );
    format!("{what} {got:.4e} ({:+.1} %)", 100.0 * (got / want - 1.0))
}

/// Every candidate tested, one line each, for a failing assertion's message.
fn table(d: &Diagnosis) -> String {
    d.candidates
        .iter()
        .map(|c| {
            format!(
                "round {} {} [{}] lr {:.1} null mean {:.1} p_holm {:.2e} cv_t {:?}: {}",
                c.round,
                c.effect,
                c.form.chars().take(24).collect::<String>(),
                c.evidence.lr,
                c.evidence.null_mean_lr,
                c.evidence.p_holm,
                c.evidence.cv_paired_t,
                c.evidence.decision
            )
        })
        .chain(d.findings.iter().filter(|f| f.accepted).map(|f| {
            let ps: Vec<String> = f
                .parameters
                .iter()
                .map(|(k, v)| format!("{k} {:.4e}", v.value))
                .collect();
            format!("accepted {}: {}", f.effect, ps.join(", "))
        }))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The accepted findings are exactly `want` (effect, form fragment), in any order.
fn exactly(d: &Diagnosis, want: &[(&str, &str)]) {
    let got = accepted(d);
    assert_eq!(
        got.len(),
        want.len(),
        "accepted {got:?}, want {want:?}\n{}",
        table(d)
    );
    for (e, form) in want {
        assert!(
            got.iter().any(|(ge, gf)| ge == e && gf.contains(form)),
            "accepted {got:?}, want {e} ({form})"
        );
    }
    assert!(d.mismatch);
    for f in d.findings.iter().filter(|f| f.accepted) {
        assert!(
            f.extended.cv_rms_m < f.baseline.cv_rms_m,
            "{}: held-out error must fall",
            f.effect
        );
    }
}

fn check_waviness(name: &str, seed: Option<u64>) -> String {
    let Term::PositionForce {
        amp_mps2,
        wavelength_m,
        ..
    } = concealed(name)
    else {
        panic!("{name}.toml conceals a waviness");
    };
    let d = run(name, seed);
    exactly(&d, &[("position_dependent_force", "periodic in z")]);
    let p = |n| param(&d, "position_dependent_force", "periodic", n);
    [
        within(p("amplitude_mps2"), amp_mps2, "amplitude"),
        within(p("wavelength_m"), wavelength_m, "wavelength"),
    ]
    .join(", ")
}

/// The concealed term of a truth file (the first one that is not the baseline drag).
fn concealed(name: &str) -> Term {
    truth(name, None)
        .physics
        .terms
        .into_iter()
        .find(|t| !matches!(t, Term::LinearDrag { .. }))
        .unwrap_or_else(|| panic!("{name}: no concealed term"))
}

fn check_localized(seed: Option<u64>) -> String {
    let Term::LocalizedForce {
        amp_mps2,
        centre_m,
        width_m,
    } = concealed("localized_force")
    else {
        panic!("localized_force.toml conceals a localized force");
    };
    let d = run("localized_force", seed);
    exactly(&d, &[("position_dependent_force", "localized in z")]);
    let p = |n| param(&d, "position_dependent_force", "localized", n);
    [
        within(p("amplitude_mps2"), amp_mps2, "amplitude"),
        within(p("centre_m"), centre_m, "centre"),
        within(p("width_m"), width_m, "width"),
    ]
    .join(", ")
}

fn check_time(seed: Option<u64>) -> String {
    let Term::TimePeriodicForce {
        amp_mps2, freq_hz, ..
    } = concealed("time_force")
    else {
        panic!("time_force.toml conceals a time-periodic force");
    };
    let d = run("time_force", seed);
    exactly(&d, &[("time_dependent_force", "periodic in time")]);
    let p = |n| param(&d, "time_dependent_force", "periodic in time", n);
    [
        within(p("amplitude_mps2"), amp_mps2, "amplitude"),
        within(p("frequency_hz"), freq_hz, "frequency"),
    ]
    .join(", ")
}

fn check_two(seed: Option<u64>) -> String {
    let d = run("two_effects", seed);
    exactly(
        &d,
        &[
            ("groove_tilt", "tilt"),
            ("position_dependent_force", "periodic in z"),
        ],
    );
    let p = |n| param(&d, "position_dependent_force", "periodic", n);
    [
        within(param(&d, "groove_tilt", "tilt", "alpha_deg"), 0.05, "tilt"),
        within(p("amplitude_mps2"), 0.05, "amplitude"),
        within(p("wavelength_m"), 2e-3, "wavelength"),
    ]
    .join(", ")
}

/// A rolling resistance beside a 3 mm waviness: both named (the wave alone had bent to stand
/// in for both, and the resistance then scored nothing), each within 15 %.
fn check_resistance_and_wave(seed: Option<u64>) -> String {
    let d = run("resistance_and_waviness", seed);
    exactly(
        &d,
        &[
            ("rolling_resistance", "resistance"),
            ("position_dependent_force", "periodic in z"),
        ],
    );
    // accepted as a pair in one round, the wave started again beside the resistance (not the
    // wave alone first and the resistance never)
    for f in d.findings.iter().filter(|f| f.accepted) {
        let why = &f.evidence.decision;
        assert!(
            why.contains("accepted together with") && why.contains("drift probes still flagged"),
            "{}: {why}",
            f.effect
        );
    }
    let p = |n| param(&d, "position_dependent_force", "periodic", n);
    let c = param(&d, "rolling_resistance", "resistance", "coefficient");
    [
        within(c, 0.004, "resistance"),
        within(p("amplitude_mps2"), 0.05, "amplitude"),
        within(p("wavelength_m"), 3e-3, "wavelength"),
    ]
    .join(", ")
}

/// An effect of the fixed list (tests/fixtures/truths/<name>.toml, lab coordinates): named with
/// its form, nothing else accepted, and each of `sizes` (parameter, truth) within 15 %.
fn check_listed(
    name: &str,
    seed: Option<u64>,
    effect: &str,
    form: &str,
    sizes: &[(&str, f64)],
) -> String {
    let d = run(name, seed);
    exactly(&d, &[(effect, form)]);
    sizes
        .iter()
        .map(|(p, want)| within(param(&d, effect, form, p), *want, p))
        .collect::<Vec<_>>()
        .join(", ")
}

fn check_existing(name: &str, seed: Option<u64>) -> String {
    let g = groove::discover::G_MPS2;
    match name {
        "quadratic_drag" => check_listed(
            name,
            seed,
            "velocity_dependent_drag",
            "quadratic",
            &[("c_per_m", 40.0)],
        ),
        "saturating_drag" => check_listed(
            name,
            seed,
            "velocity_dependent_drag",
            "saturating",
            &[
                ("tp_s_per_mps", 1.1),
                ("t0_s_316", 0.052),
                ("t0_s_440c", 0.052),
            ],
        ),
        "rolling_resistance" => check_listed(
            name,
            seed,
            "rolling_resistance",
            "constant resistance",
            &[("deceleration_mps2", 0.004 * g)],
        ),
        "groove_tilt" => check_listed(name, seed, "groove_tilt", "tilt", &[("alpha_deg", 0.2)]),
        "velocity_dependent_friction" => check_listed(
            name,
            seed,
            "velocity_dependent_friction",
            "mu(u)",
            &[("v_c_mps_316", 0.004), ("v_c_mps_440c", 0.004)],
        ),
        "position_force" => check_waviness(name, seed),
        "runs_that_stop" => check_listed(
            name,
            seed,
            "rolling_resistance",
            "constant resistance",
            &[("coefficient", 0.004)],
        ),
        _ => panic!("no check for {name}"),
    }
}

/// A null accepts nothing, and every candidate carries its detection limit.
fn check_null(name: &str, seed: Option<u64>) -> bool {
    let d = run(name, seed);
    let limits = d
        .candidates
        .iter()
        .filter(|c| c.effect != "probe" && c.evidence.detection_limit.is_some())
        .count();
    assert!(limits >= 4, "detection limits on {limits} candidates");
    let tilt = d
        .candidates
        .iter()
        .find(|c| c.effect == "groove_tilt")
        .and_then(|c| c.evidence.detection_limit.clone())
        .expect("a tilt detection limit");
    assert!(
        tilt.value > 0.0 && tilt.value < 0.5 && tilt.text.contains("tilt above"),
        "{tilt:?}"
    );
    let found = accepted(&d);
    if !found.is_empty() {
        println!("{name} seed {seed:?}: accepted {found:?}\n{}", table(&d));
    }
    found.is_empty()
}

/// A null whose tracking noise is correlated in time (AR(1), lag-1 coefficient 0.6, 1 µm, over
/// 0.2 µm of white noise) accepts nothing. On this seed the largest of a force in time's
/// frequencies passed for a vibration (p Holm 6e-3, statistic 490 against a null mean of 399)
/// before its replicates were raised to the noise floor the data show around each frequency
/// (`discover::noise_floor`; the null mean is now 468). `GROOVE_AR_SEED=<n>` tries another.
#[test]
fn correlated_tracking_noise_is_not_a_vibration() {
    let seed: u64 = std::env::var("GROOVE_AR_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(AR_SEED);
    let mut t = truth("null", Some(1));
    t.camera.noise_m = 0.2e-6;
    let mut recs = recordings(&t);
    noise::with_correlated_noise(&mut recs, 0.6, 1e-6, seed);
    let d = discover(&recs, &options(1));
    let time = d
        .candidates
        .iter()
        .find(|c| c.effect == "time_dependent_force")
        .expect("a force in time is a candidate");
    println!(
        "seed {seed}: time force lr {:.0}, null mean {:.0}, p Holm {:.2e}",
        time.evidence.lr, time.evidence.null_mean_lr, time.evidence.p_holm
    );
    let found = accepted(&d);
    assert!(found.is_empty(), "accepted {found:?}\n{}", table(&d));
}

/// The seed of `correlated_tracking_noise_is_not_a_vibration`.
const AR_SEED: u64 = 10;

#[test]
fn waviness_of_0_8_mm_is_a_periodic_force_in_z() {
    check_waviness("waviness_0p8mm", None);
}

#[test]
fn waviness_of_3_mm_is_a_periodic_force_in_z() {
    check_waviness("waviness_3mm", None);
}

#[test]
fn a_bump_is_a_localized_force_and_no_tilt() {
    check_localized(None);
}

#[test]
fn a_vibration_is_a_force_periodic_in_time() {
    check_time(None);
}

#[test]
fn two_effects_at_once_are_both_named() {
    check_two(None);
}

#[test]
fn a_rolling_resistance_beside_a_waviness_are_both_named() {
    check_resistance_and_wave(None);
}

/// Slow runs (v0 3–20 mm/s, 0.25 s) that mostly come to rest within 0.15 s under a rolling
/// resistance: named alone, c within 15 %. While each run's noise was read from the rms of its
/// baseline fit, which cannot follow a stop, σ read 2.5× the camera's and c was named 30 % low
/// beside a spurious μ(v) (`discover::noise` now reads it from what a local cubic leaves).
#[test]
fn a_rolling_resistance_that_brings_runs_to_rest_is_named_alone() {
    println!("{}", check_existing("runs_that_stop", None));
}

/// Slow runs trapped in the wells of a 3 mm waviness: the wave named alone, amplitude and
/// wavelength within 15 %. With the noise read from the baseline's rms a tilt, the wave and an
/// unexplained spline were accepted.
#[test]
fn runs_trapped_in_a_waviness_name_the_wave_alone() {
    println!("{}", check_waviness("waviness_trapped", None));
}

#[test]
fn quantized_positions_with_outliers_give_no_finding() {
    assert!(check_null("null_quantized", None), "a finding on a null");
}

#[test]
fn a_small_set_gives_no_finding_and_states_its_limits() {
    assert!(check_null("null_small", None), "a finding on a null");
}
