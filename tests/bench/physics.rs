//! Benchmark: 10,000 single-particle trajectories (0.1 s, 1,000 samples each) with an extra
//! term, through the event-driven integrator, against the closed-form baseline in the same process.
//! Run with `cargo bench --bench physics`. Prints rates and ratios; asserts nothing about time.

use groove::physics::{simulate, Baseline, Friction, Groove, Model, State, Term};
use std::hint::black_box;
use std::time::Instant;

const N: usize = 10_000;

fn main() {
    let t: Vec<f64> = (0..1000).map(|k| k as f64 * 1e-4).collect();
    let v0 = |i: usize| {
        (0.005 + 0.095 * (i % 97) as f64 / 96.0) * if i.is_multiple_of(2) { 1.0 } else { -1.0 }
    };
    let extra = Model {
        groove: Groove::CHAPTER,
        friction: Friction::Constant { mu: 0.337 },
        variation: Default::default(),
        terms: vec![
            Term::LinearDrag { t_s: 0.1 },
            Term::QuadraticDrag { c_per_m: 2.0 },
        ],
    };
    let saturating = Model {
        terms: vec![Term::SaturatingDrag {
            t0_s: 0.0465,
            tp_s_per_mps: 2.4,
        }],
        ..extra.clone()
    };
    // a slip held off zero by a tilt (half the runs go downhill) with a friction that vanishes
    // at zero slip in microseconds: stiff unless the slide creeps (`physics/mode.rs`)
    let creeping = Model {
        friction: Friction::VelocityDependent {
            mu_inf: 0.337,
            v_c_mps: 5e-5,
        },
        variation: Default::default(),
        terms: vec![
            Term::LinearDrag { t_s: 0.1 },
            Term::GrooveTilt { alpha_deg: 0.5 },
        ],
        ..extra.clone()
    };
    let baseline = Baseline::new(0.337, 0.1);

    let start = Instant::now();
    let mut out = vec![0.0; t.len()];
    for i in 0..N {
        baseline.positions(v0(i), &t, &mut out);
        black_box(&out);
    }
    let closed = N as f64 / start.elapsed().as_secs_f64();
    println!("closed form (baseline): {closed:>10.0} trajectories/s");

    for (name, model) in [
        ("linear + quadratic drag", &extra),
        ("saturating drag", &saturating),
        ("μ(v) with v_c = 50 µm/s and a tilt", &creeping),
    ] {
        let start = Instant::now();
        for i in 0..N {
            let init = State {
                z_m: 0.0,
                v_mps: v0(i),
                va_mps: 0.0,
            };
            black_box(simulate(model, init, &t));
        }
        let secs = start.elapsed().as_secs_f64();
        let rate = N as f64 / secs;
        println!(
            "integrator, {name}: {rate:>10.0} trajectories/s ({:.1} µs each; closed form is {:.1}x faster)",
            1e6 * secs / N as f64,
            closed / rate
        );
    }
}
