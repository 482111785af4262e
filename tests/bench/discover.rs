//! Bench: the whole discovery on 60 synthesized runs (a concealed rolling resistance), with the
//! time of each part and of each candidate's joint fit. Prints times; asserts nothing.

use groove::discover::candidate::{Extra, Spec};
use groove::discover::data::prepare_runs;
use groove::discover::forward::{extra_starts, Model};
use groove::discover::perrun::measure_noise;
use groove::discover::{discover, Options};
use std::time::Instant;

#[path = "../discover_data/mod.rs"]
mod discover_data;
use discover_data::{synthesize, Shape, Truth, S};

fn main() {
    let shape = Shape {
        runs: 60,
        frames: 600,
        outliers: true,
        shuffle: false,
    };
    let truth = Truth {
        roll_c: 0.004,
        ..Truth::baseline()
    };
    let recs = synthesize(&truth, &shape, 7);
    println!(
        "discovery bench: {} runs x {} frames, {} rayon threads",
        shape.runs,
        shape.frames,
        rayon::current_num_threads()
    );

    let t = Instant::now();
    let (mut runs, materials) = prepare_runs(&recs, 20);
    let spec = Spec {
        n_materials: materials.len(),
        s: S,
        k: 2.5,
        extras: vec![],
    };
    let params = spec.global_params(&materials);
    let per_run = measure_noise(&mut runs, &spec, &params);
    println!(
        "per-run baseline fits + noise: {:8.3} s",
        t.elapsed().as_secs_f64()
    );

    let t = Instant::now();
    let mut g = vec![0.3; materials.len()];
    g.extend(vec![0.06; materials.len()]);
    let l: Vec<_> = per_run.iter().map(|f| f.local).collect();
    let base = Model::fit(spec.clone(), &materials, &runs, &g, &l, 80);
    println!(
        "joint baseline fit:            {:8.3} s ({} iterations)",
        t.elapsed().as_secs_f64(),
        base.fit.iterations
    );

    let zmin = runs
        .iter()
        .flat_map(|r| r.z_m.iter().copied())
        .fold(f64::INFINITY, f64::min);
    let zmax = runs
        .iter()
        .flat_map(|r| r.z_m.iter().copied())
        .fold(f64::NEG_INFINITY, f64::max);
    for extra in [
        Extra::QuadraticDrag,
        Extra::SaturatingDrag,
        Extra::RollingResistance,
        Extra::GrooveTilt,
        Extra::VelocityFriction {
            materials: materials.len(),
        },
        Extra::PositionForce {
            harmonics: 2,
            z_min_m: zmin,
            span_m: zmax - zmin,
        },
    ] {
        let t = Instant::now();
        let m = base.extend(&extra, &extra_starts(&extra), &materials, &runs, 40);
        println!(
            "candidate {:<55} joint fit {:8.3} s, LR {:12.1}",
            extra.form(),
            t.elapsed().as_secs_f64(),
            base.fit.chi2 - m.fit.chi2
        );
    }

    let t = Instant::now();
    let d = discover(
        &recs,
        &Options {
            seed: 7,
            ..Options::default()
        },
    );
    let accepted: Vec<&str> = d
        .findings
        .iter()
        .filter(|f| f.accepted)
        .map(|f| f.effect.as_str())
        .collect();
    let secs = t.elapsed().as_secs_f64();
    println!(
        "whole discovery:               {:8.3} s, accepted {:?}",
        secs, accepted
    );
    // the figures before issue 11 (five named forms, fixed 24 replicates) on this machine class
    println!(
        "before issue 11: 6-150 s on 60 runs, 27 s on the shipped data; target <= 10 s / <= 15 s; now {:.1} s ({:.2}x of 10 s)",
        secs,
        secs / 10.0
    );
}
