//! A force between the two particles of a collision run, on recordings of the independent
//! simulator (tests/support/indsim): attractive and repulsive, of three shapes (screened, an
//! inverse power, a liquid bridge that ruptures) and ranges between 20 and 200 µm, must be named
//! as a force between the particles (`force_between_particles`, place `pair`) with its work
//! within 25 %; pairs with no such force stay silent on 10 seeds. The pair check is given the
//! single runs' physics as the single runs' analysis would hand it over (μ and the linear drag of
//! each material, here those the recordings were simulated with).

#[allow(dead_code)]
#[path = "support/indsim/mod.rs"]
mod indsim;

#[allow(dead_code)]
#[path = "support/bed/mod.rs"]
mod bed;

use bed::draw::{case, Case, Size};
use bed::in_process::ingest_case;
use groove::artifacts::diagnosis::Finding;
use groove::discover::pairs::check_pairs;
use groove::physics::{Friction, Groove, Model, Term};
use indsim::effects::Drag;
use indsim::pair::Between;
use std::collections::BTreeMap;

/// The single runs hardly matter here: a few, short.
const SIZE: Size = Size {
    singles_per_material: 2,
    duration_s: 0.04,
};

/// A case with collision runs (six rolling pairs of 316, six touching pairs of 440c) in
/// `noise`, with `force` between the particles.
fn pairs_case(seed: u64, noise: &str, force: Option<Between>) -> Case {
    let mut c = case(seed, SIZE, noise, &[], true);
    c.spec.pair_force = force;
    c
}

/// Each material's single-run physics as the pair check takes it: μ and the linear drag.
fn single_physics(c: &Case) -> BTreeMap<String, (Model, [f64; 3])> {
    let mut out = BTreeMap::new();
    for run in &c.spec.runs {
        let p = &run.physics[0];
        let Drag::Linear { t_s } = p.drag else {
            panic!("a baseline drag")
        };
        let model = Model {
            groove: Groove::CHAPTER,
            friction: Friction::Constant { mu: p.mu },
            variation: Default::default(),
            terms: vec![Term::LinearDrag { t_s }],
        };
        let name = c.spec.materials[run.material].name.to_string();
        out.insert(name, (model, [0.002 * p.mu, 0.01 * t_s, 0.0]));
    }
    out
}

fn pair_findings(c: &Case) -> Vec<Finding> {
    let recs = ingest_case(c);
    check_pairs(&recs, &single_physics(c), Groove::CHAPTER, 80).0
}

fn summary(findings: &[Finding]) -> String {
    findings
        .iter()
        .map(|f| {
            format!(
                "{} {} {}: {} | {}",
                f.where_["material"],
                f.effect,
                if f.accepted { "ACCEPTED" } else { "no" },
                f.parameters
                    .iter()
                    .map(|(k, v)| format!("{k} = {:.4e}", v.value))
                    .collect::<Vec<_>>()
                    .join(", "),
                f.evidence.decision
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The accepted findings of `effect` by material, with their work (m²/s²).
fn accepted_work(findings: &[Finding], effect: &str) -> BTreeMap<String, f64> {
    findings
        .iter()
        .filter(|f| f.accepted && f.effect == effect)
        .map(|f| {
            let m = f.where_["material"].as_str().unwrap().to_string();
            let w = f
                .parameters
                .get("pair_work_m2ps2")
                .map_or(f64::NAN, |e| e.value);
            (m, w)
        })
        .collect()
}

/// Five forces (attractive and repulsive; screened, inverse-power and bridge shapes; ranges 20 to
/// 200 µm) in five tracker noises, each in rolling pairs of one material and touching pairs of
/// the other. Every force named has its work within 25 % where groove has its shape (the
/// screened force is its exponential, the inverse power its power law), and the liquid bridge,
/// a linear fall cut off at its rupture that neither shape holds, within 50 % (an exponential of
/// the bridge's work misfits the rolling pairs 8× worse than one of half that work: 0.54 of the
/// work measured); at least 7 of the 10 (force, material) pairs are named; a screened force
/// named in both materials (at least two of the three) is sized with one range for both,
/// within 15 % of the truth; no pair is said to move under friction or drag of its own. Known
/// miss: touching pairs under the strong screened attraction, where every start of the fit ends
/// at a weak force that held-out runs do not confirm (their misfit concentrates after impacts,
/// and the impact test says so).
#[test]
fn a_force_between_the_particles_is_named_with_its_work() {
    let cases = [
        (
            "white",
            Between::Screened {
                amp: -3.0,
                range: 50e-6,
            },
        ),
        (
            "ar1",
            Between::Screened {
                amp: 1.5,
                range: 150e-6,
            },
        ),
        (
            "blur",
            Between::InversePower {
                amp: -4.0,
                d: 30e-6,
                p: 3.0,
            },
        ),
        (
            "outliers",
            Between::Bridge {
                amp: -2.0,
                rupture: 100e-6,
            },
        ),
        (
            "mixture",
            Between::Screened {
                amp: 6.0,
                range: 20e-6,
            },
        ),
    ];
    let (mut named, mut shared, mut wrong, mut report) = (0, 0, Vec::new(), Vec::new());
    for (k, (noise, b)) in cases.into_iter().enumerate() {
        let c = pairs_case(100 + k as u64, noise, Some(b));
        let findings = pair_findings(&c);
        let truth = b.work();
        report.push(format!(
            "{b:?} in {noise} (work {truth:.3e}):\n{}",
            summary(&findings)
        ));
        let found = accepted_work(&findings, "force_between_particles");
        let tolerance = match b {
            Between::Bridge { .. } => 0.5,
            _ => 0.25,
        };
        for (m, w) in &found {
            if (w - truth).abs() > tolerance * truth.abs() {
                wrong.push(format!("{b:?}, {m}: work {w:.3e} against {truth:.3e}"));
            }
        }
        named += found.len();
        // a screened force named in both materials, in its own shape, is sized with one range
        if let (Between::Screened { range, .. }, 2) = (b, found.len()) {
            let ranges: Vec<f64> = findings
                .iter()
                .filter(|f| f.accepted && f.effect == "force_between_particles")
                .filter(|f| f.where_.contains_key("shared_range"))
                .map(|f| f.parameters["pair_range_m"].value)
                .collect();
            shared += 1;
            if ranges.len() != 2
                || ranges[0] != ranges[1]
                || (ranges[0] - range).abs() > 0.15 * range
            {
                wrong.push(format!(
                    "{b:?}: ranges {ranges:?}, not one range within 15 % of {range:e}"
                ));
            }
        }
        for m in accepted_work(&findings, "pair_physics_mismatch").keys() {
            wrong.push(format!(
                "{b:?}, {m}: said to move under friction or drag of its own"
            ));
        }
    }
    eprintln!("{}", report.join("\n"));
    assert!(wrong.is_empty(), "{wrong:#?}\n{}", report.join("\n"));
    assert!(named >= 7, "{named}/10 named:\n{}", report.join("\n"));
    assert!(
        shared >= 2,
        "{shared} screened forces named in both materials"
    );
}

/// Pairs with nothing between them, in ten seeds over the tracker noises (correlated, blurred,
/// locked to the pixel grid, with outliers, drifting, all at once): the pair check accepts
/// nothing (no force between the particles, no impact misfit, no pair physics, no impact law).
#[test]
fn pairs_with_nothing_between_them_stay_silent() {
    let noises = [
        "white", "ar1", "drift", "blur", "locked", "outliers", "mixture", "ar1", "blur", "mixture",
    ];
    let mut loud = Vec::new();
    for (k, noise) in noises.into_iter().enumerate() {
        let c = pairs_case(300 + k as u64, noise, None);
        let findings = pair_findings(&c);
        if findings.iter().any(|f| f.accepted) {
            loud.push(format!(
                "seed {} ({noise}):\n{}",
                300 + k,
                summary(&findings)
            ));
        }
    }
    assert!(
        loud.is_empty(),
        "{}/10 accepted something:\n{}",
        loud.len(),
        loud.join("\n")
    );
}

/// The pair check's false accepts as a rate: pairs with nothing between them, twenty seeds in
/// each of the seven tracker noises (140 datasets, 280 material tests of each kind). Each test
/// is at α = 0.01 with Holm over the two materials, and the check runs four kinds (pair physics,
/// impact misfit, force, impact laws), so a few accepts in a hundred datasets is its nominal
/// rate; at most 3 % of the datasets may accept anything.
#[test]
fn pair_nulls_accept_at_most_three_percent_over_every_noise() {
    let mut loud = Vec::new();
    let mut table = Vec::new();
    for noise in bed::draw::NOISES {
        let mut n_loud = 0;
        for seed in 400..420u64 {
            let findings = pair_findings(&pairs_case(seed, noise, None));
            if findings.iter().any(|f| f.accepted) {
                n_loud += 1;
                loud.push(format!("seed {seed} ({noise}):\n{}", summary(&findings)));
            }
        }
        table.push(format!("{noise}: {n_loud}/20"));
    }
    eprintln!("{}\n{}", table.join(", "), loud.join("\n"));
    assert!(
        loud.len() * 100 <= 3 * 140,
        "{}/140 nulls accepted something ({}):\n{}",
        loud.len(),
        table.join(", "),
        loud.join("\n")
    );
}
