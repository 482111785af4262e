//! Discovery stays silent on recordings of the independent simulator (tests/support/indsim) with
//! nothing missing, whatever the tracker noise does: correlated over frames (AR(1) with lag-1
//! correlation 0.5-0.9 beside a white part), drifting over 5-30 ms (an Ornstein-Uhlenbeck
//! wander of 0.5-1.5 σ), growing with speed (motion blur) and locked to a sub-pixel grid. Each
//! noise model is drawn afresh (its parameters and the dataset) for every seed; a single
//! acceptance is a failure, and the message lists every one. Before discovery read a white part
//! beside a correlated one and a noise growing with speed, 2 and 3 of these 20 accepted physics
//! (mostly differences between particles).

#[allow(dead_code)]
#[path = "support/indsim/mod.rs"]
mod indsim;

#[allow(dead_code)]
#[path = "support/bed/mod.rs"]
mod bed;

use bed::draw::{case, Size};
use bed::in_process::discover_case;
use bed::score::accepted;

/// 12 single runs per material of 50 ms.
const SIZE: Size = Size {
    singles_per_material: 12,
    duration_s: 0.05,
};

/// What discovery accepts on the null drawn with `seed` in `noise` (place/effect: form).
fn accepted_on_null(seed: u64, noise: &str) -> Vec<String> {
    let c = case(seed, SIZE, noise, &[], false);
    assert!(c.truths.is_empty(), "a case drawn with no shapes is a null");
    let d = discover_case(&c, seed);
    let said = |a: &bed::score::Accepted| {
        // the particle check's own words (its ratio and p), for the failure message
        let why = d
            .findings
            .iter()
            .find(|f| f.accepted && f.effect == a.effect && f.form == a.form)
            .map(|f| f.evidence.decision.clone())
            .unwrap_or_default();
        format!("{}/{}: {} ({why})", a.place, a.effect, a.form)
    };
    accepted(&serde_json::to_string(&d).unwrap())
        .unwrap()
        .iter()
        .map(said)
        .collect()
}

/// Every seed of `seeds` silent in `noise`.
fn silent(noise: &str, seeds: std::ops::Range<u64>) {
    let loud: Vec<String> = seeds
        .clone()
        .filter_map(|s| {
            let a = accepted_on_null(s, noise);
            (!a.is_empty()).then(|| format!("seed {s}: {a:?}"))
        })
        .collect();
    assert!(
        loud.is_empty(),
        "{noise} noise: {} of {} nulls accepted physics: {loud:#?}",
        loud.len(),
        seeds.end - seeds.start
    );
}

/// Seeds per noise model: 20 (`GROOVE_NULL_SEEDS` sets fewer for a quick look).
fn seeds() -> std::ops::Range<u64> {
    let n = std::env::var("GROOVE_NULL_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20);
    1000..1000 + n
}

#[test]
fn correlated_noise_nulls_are_silent() {
    silent("ar1", seeds());
}

#[test]
fn drifting_noise_nulls_are_silent() {
    silent("drift", seeds());
}

#[test]
fn speed_dependent_noise_nulls_are_silent() {
    silent("blur", seeds());
}

#[test]
fn quantized_noise_nulls_are_silent() {
    silent("locked", seeds());
}

/// The noise's growth with speed is measured, not only tolerated: on six blur nulls (white
/// noise σ plus σ|v|/v_ref, so c = σ/v_ref) discovery keeps the blur in at least five, each kept
/// c within 25 % of the truth and their mean within 10 %. (Measured at this test's writing:
/// 0.88–1.04 of the truth; on 60 ms runs in mixed noise 0.79–1.05, one of six not kept.)
#[test]
fn the_blur_is_measured_near_its_truth() {
    let mut ratios = Vec::new();
    let mut lines = Vec::new();
    for seed in 500..506u64 {
        let c = case(seed, SIZE, "blur", &[], false);
        let (sigma, v_ref) = c.spec.noise.blur.expect("a blur noise");
        let truth = sigma / v_ref;
        let d = discover_case(&c, seed);
        let read = d.tracking_blur.as_ref().map(|b| b.noise_per_speed_s);
        lines.push(format!("seed {seed}: c {truth:.3e}, read {read:?}"));
        if let Some(r) = read {
            ratios.push(r / truth);
        }
    }
    let text = lines.join("\n");
    eprintln!("{text}");
    assert!(
        ratios.len() >= 5,
        "blur kept in {}/6:\n{text}",
        ratios.len()
    );
    assert!(
        ratios.iter().all(|r| (0.75..=1.25).contains(r)),
        "{ratios:?}\n{text}"
    );
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!((mean - 1.0).abs() <= 0.1, "mean {mean}\n{text}");
}
