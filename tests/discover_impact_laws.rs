//! Probe (temporary): the per-impact C and μ_pp of the collision fit on independent-simulator pairs.

#[allow(dead_code)]
#[path = "support/indsim/mod.rs"]
mod indsim;

#[allow(dead_code)]
#[path = "support/bed/mod.rs"]
mod bed;

use bed::dataset::RunSpec;
use bed::draw::{case, Case, Size};
use groove::artifacts::diagnosis::Finding;
use groove::discover::impact::test_impact_laws;
use groove::physics::Groove;
use groove::ingest::{ingest, IngestParams};
use groove::recording::Recording;
use indsim::pair::Law;
use indsim::writer::write_dataset;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

const SIZE: Size = Size {
    singles_per_material: 2,
    duration_s: 0.04,
};

/// A case whose collision runs are `n` pairs per material and setup (rolling in from a gap of
/// 0.6–1.5 mm, or touching), kicked over a wide range of speeds.
fn pairs_case(seed: u64, noise: &str, n: usize) -> Case {
    let mut c = case(seed, SIZE, noise, &[], true);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_1a75);
    let fov = c.spec.camera.fov_m;
    let physics: Vec<_> = (0..2)
        .map(|m| {
            c.spec
                .runs
                .iter()
                .find(|r| r.material == m)
                .unwrap()
                .physics[0]
                .clone()
        })
        .collect();
    c.spec.runs.retain(|r| r.experiment != "collision");
    for m in 0..2 {
        for setup in ["rolling", "contact"] {
            for i in 0..n {
                let (gap, (lo, hi)) = if setup == "rolling" {
                    (rng.random_range(0.6e-3..1.5e-3), (0.04, 0.16))
                } else {
                    (0.0, (0.03, 0.3))
                };
                let dir = if rng.random::<bool>() { 1.0 } else { -1.0 };
                let margin = rng.random_range(0.5e-3..1.5e-3);
                let z0 = if dir > 0.0 { margin } else { fov - margin };
                let d = c.spec.materials[m].diameter_m;
                c.spec.runs.push(RunSpec {
                    id: format!("{setup}-{}-{:03}", c.spec.materials[m].name, i + 1),
                    experiment: "collision",
                    setup,
                    material: m,
                    physics: [physics[m].clone(), physics[m].clone()],
                    z0: [z0, z0 + dir * (d + gap)],
                    v0: dir * rng.random_range(lo..hi),
                    frac: rng.random::<f64>(),
                    duration_s: SIZE.duration_s,
                });
            }
        }
    }
    c
}

fn recordings(c: &Case) -> Vec<Recording> {
    let dir = tempfile::tempdir().unwrap();
    write_dataset(dir.path(), &c.spec.render(false)).unwrap();
    let mut files = BTreeMap::new();
    for f in ["runs.csv", "trajectories.csv"] {
        files.insert(f.to_string(), std::fs::read(dir.path().join(f)).unwrap());
    }
    ingest(&files, &IngestParams::default())
        .expect("an indsim dataset ingests")
        .recordings
}

fn summary(findings: &[Finding]) -> String {
    findings
        .iter()
        .map(|f| {
            format!(
                "{} {:?} {} {}: F {:.2} p {:.2e} ph {:.2e} | {} | {} | {}",
                f.where_["material"],
                f.where_.get("setup"),
                f.effect,
                if f.accepted { "ACCEPTED" } else { "no" },
                f.evidence.lr,
                f.evidence.p_value,
                f.evidence.p_holm,
                f.parameters
                    .iter()
                    .map(|(k, v)| format!("{k} = {:.4}", v.value))
                    .collect::<Vec<_>>()
                    .join(", "),
                f.evidence.decision,
                f.form
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

const NOISES: [&str; 6] = ["white", "ar1", "blur", "locked", "outliers", "mixture"];

/// The impact-law findings of a case with `law` and μ_pp (`u0`: weakening with slip speed).
fn law_findings(seed: u64, noise: &str, law: Option<Law>, mu_pp: f64, u0: Option<f64>) -> (Case, Vec<Finding>) {
    let mut c = pairs_case(seed, noise, 10);
    c.spec.restitution_law = law;
    c.spec.mu_pp = mu_pp;
    c.spec.mu_pp_weakening_mps = u0;
    let recs = recordings(&c);
    let f = test_impact_laws(&recs, Groove::CHAPTER, &[]);
    (c, f)
}

fn accepted<'a>(f: &'a [Finding], effect: &str) -> Vec<&'a Finding> {
    f.iter().filter(|f| f.accepted && f.effect == effect).collect()
}

/// The largest difference between an accepted restitution finding's map and the true law at
/// the map's speeds.
fn map_error(f: &Finding, law: &Law) -> f64 {
    let m = &f.where_["map"];
    let speeds: Vec<f64> = serde_json::from_value(m["speeds_mps"].clone()).unwrap();
    let values: Vec<f64> = serde_json::from_value(m["values"].clone()).unwrap();
    speeds
        .iter()
        .zip(&values)
        .map(|(v, c)| (c - law.at(*v)).abs())
        .fold(0.0, f64::max)
}

#[test]
#[ignore]
fn probe() {
    let laws = [
        ("humped", Law::Humped { c: 0.95, v_a: 0.05, v_p: 0.4 }),
        ("sticky", Law::Sticky { c: 0.85, v_s: 0.01, w: 0.02 }),
        ("visco", Law::Viscoelastic { a: 0.5 }),
    ];
    let mut lines = Vec::new();
    for (k, (label, law)) in laws.iter().enumerate() {
        for (j, noise) in NOISES.iter().enumerate() {
            let seed = 500 + 10 * k as u64 + j as u64;
            let (_, f) = law_findings(seed, noise, Some(*law), 1.4, None);
            let acc = accepted(&f, "restitution_law");
            lines.push(format!(
                "{label} {noise}: {} groups named; map errors {:?}\n{}",
                acc.len(),
                acc.iter().map(|f| format!("{:.3}", map_error(f, law))).collect::<Vec<_>>(),
                summary(&f)
            ));
        }
    }
    for (j, noise) in NOISES.iter().enumerate() {
        let (_, f) = law_findings(600 + j as u64, noise, None, 0.3, Some(0.05));
        lines.push(format!("weakening {noise}: {} named\n{}", accepted(&f, "pair_friction_slip_speed").len(), summary(&f)));
    }
    for seed in 0..20u64 {
        let noise = NOISES[seed as usize % 6];
        let mu = if seed % 2 == 0 { 1.4 } else { 0.2 };
        let (_, f) = law_findings(700 + seed, noise, None, mu, None);
        let loud: Vec<_> = f.iter().filter(|f| f.accepted).collect();
        lines.push(format!("null {seed} {noise} mu {mu}: {} loud\n{}", loud.len(), summary(&f)));
    }
    eprintln!("{}", lines.join("\n"));
}

#[test]
#[ignore]
fn probe_one() {
    let seed: u64 = std::env::var("SEED").unwrap().parse().unwrap();
    let noise = std::env::var("NOISE").unwrap();
    let mu: f64 = std::env::var("MU").unwrap().parse().unwrap();
    let c = {
        let mut c = pairs_case(seed, &noise, 10);
        c.spec.mu_pp = mu;
        c.spec.mu_pp_weakening_mps = std::env::var("U0").ok().map(|v| v.parse().unwrap());
        c
    };
    let recs = recordings(&c);
    for r in recs.iter().filter(|r| r.info.experiment == groove::recording::Experiment::Collision) {
        let f = groove::fit::collision::fit_collision(r, &groove::fit::collision::CollisionOptions::default());
        for im in &f.impacts {
            if im.contact == groove::artifacts::collision_fit::Contact::Slip {
                eprintln!(
                    "{} #{} v {:.4} dvz {:.4}±{:.5} dva {:.4}±{:.5} S {:.4} mu {:.3}",
                    f.run, im.index, im.impact_speed_mps.value, im.target_dvz_mps.value,
                    im.target_dvz_mps.se.unwrap_or(f64::NAN), im.target_dva_mps.value,
                    im.target_dva_mps.se.unwrap_or(f64::NAN), im.spin_sum_before_mps,
                    im.target_dva_mps.value.abs() / (2.5 * im.target_dvz_mps.value)
                );
            }
        }
    }
}
