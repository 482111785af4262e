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
use groove::artifacts::diagnosis::Finding;
use groove::discover::pairs::check_pairs;
use groove::ingest::{ingest, IngestParams};
use groove::physics::{Friction, Groove, Model, Term};
use groove::recording::Recording;
use indsim::effects::Drag;
use indsim::pair::Between;
use indsim::writer::write_dataset;
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
    let recs = recordings(c);
    check_pairs(&recs, &single_physics(c), Groove::CHAPTER, 80, 0.0).0
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

#[test]
#[ignore]
fn probe() {
    let shapes = [
        Between::Screened {
            amp: -3.0,
            range: 50e-6,
        },
        Between::Screened {
            amp: 1.5,
            range: 150e-6,
        },
        Between::InversePower {
            amp: -4.0,
            d: 30e-6,
            p: 3.0,
        },
        Between::Bridge {
            amp: -2.0,
            rupture: 100e-6,
        },
    ];
    for (k, b) in shapes.into_iter().enumerate() {
        let c = pairs_case(100 + k as u64, "white", Some(b));
        let t = std::time::Instant::now();
        let f = pair_findings(&c);
        eprintln!(
            "{b:?} work {:.3e} ({:.0} s)\n{}\n",
            b.work(),
            t.elapsed().as_secs_f64(),
            summary(&f)
        );
    }
    let c = pairs_case(7, "mixture", None);
    let t = std::time::Instant::now();
    let f = pair_findings(&c);
    eprintln!("null ({:.0} s)\n{}", t.elapsed().as_secs_f64(), summary(&f));
}
