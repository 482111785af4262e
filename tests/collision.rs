//! Collision fits on simulated pairs with known μ_pp and C(v): impacts, restitution and μ_pp
//! are recovered within stated tolerances across seeds, both setups and both directions.

use groove::fit::collision::impulse::after_impact;
use groove::fit::collision::motion::Motion;
use groove::fit::collision::types::{CollisionStatus, Contact};
use groove::fit::collision::{fit_collision, summarize_seeded, CollisionOptions};
use groove::recording::{Experiment, Recording, RunInfo, Setup, Track};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;

const R_M: f64 = 150e-6;
const FPS: f64 = 10_000.0;
const MU_PG: f64 = 0.3;
const T_DRAG_S: f64 = 0.06;
const K: f64 = 2.5;

fn s() -> f64 {
    (70.6f64.to_radians() / 2.0).sin()
}

/// C(v) = 1 − a v, clipped to [0, 1].
fn restitution(a_per_mps: f64, v_mps: f64) -> f64 {
    (1.0 - a_per_mps * v_mps).clamp(0.0, 1.0)
}

/// A true impact: time, approach speed, C, and the target's Δv_z, Δv_a (striker-forward frame).
#[derive(Debug, Clone, Copy)]
struct TrueImpact {
    t_s: f64,
    speed_mps: f64,
    c: f64,
    slip: bool,
}

struct Case {
    setup: Setup,
    v0_mps: f64,
    mu_pp: f64,
    a_per_mps: f64,
    direction: f64,
    seed: u64,
}

/// Event-driven pair simulation with the closed-form motion between impacts (test generator).
fn simulate(case: &Case) -> (Recording, Vec<TrueImpact>) {
    let motion = Motion {
        mu: MU_PG,
        t_drag_s: T_DRAG_S,
        s: s(),
        k: K,
    };
    let mut rng = ChaCha8Rng::seed_from_u64(case.seed);
    let t_kick = -rng.random_range(0.05..0.95) / FPS;
    let gap0 = match case.setup {
        Setup::Rolling => 2.0 * R_M + 1e-3,
        Setup::Contact => 2.0 * R_M,
    };
    // pieces: (t_start, z, v, va) per particle
    let mut pieces: [Vec<(f64, f64, f64, f64)>; 2] = [
        vec![(t_kick, 0.0, case.v0_mps, 0.0)],
        vec![(t_kick, gap0, 0.0, 0.0)],
    ];
    let at = |p: &(f64, f64, f64, f64), t: f64| {
        let k = motion.state(p.2, p.3, t - p.0);
        (p.1 + k.dz_m, k.v_mps, k.va_mps)
    };
    let t_end = 0.06;
    let mut impacts = Vec::new();
    let mut t = t_kick;
    let h = 2e-6;
    while t < t_end && impacts.len() < 60 {
        let cur = [*pieces[0].last().unwrap(), *pieces[1].last().unwrap()];
        let gap = |t: f64| at(&cur[1], t).0 - at(&cur[0], t).0 - 2.0 * R_M;
        let closing = |t: f64| at(&cur[0], t).1 > at(&cur[1], t).1;
        let mut t_hit = None;
        if gap(t) <= 1e-15 && closing(t) {
            t_hit = Some(t);
        } else {
            let mut a = t;
            while a < t_end {
                let b = a + h;
                if gap(b) <= 0.0 && closing(b) {
                    let (mut lo, mut hi) = (a, b);
                    for _ in 0..60 {
                        let m = 0.5 * (lo + hi);
                        if gap(m) <= 0.0 {
                            hi = m
                        } else {
                            lo = m
                        }
                    }
                    t_hit = Some(hi);
                    break;
                }
                a = b;
            }
        }
        let Some(tc) = t_hit else { break };
        let (z1, v1, va1) = at(&cur[0], tc);
        let (z2, v2, va2) = at(&cur[1], tc);
        if v1 - v2 < 1e-6 {
            break;
        }
        let c = restitution(case.a_per_mps, v1 - v2);
        let ([(w1, wa1), (w2, wa2)], slip) = after_impact([(v1, va1), (v2, va2)], c, case.mu_pp, K);
        impacts.push(TrueImpact {
            t_s: tc,
            speed_mps: v1 - v2,
            c,
            slip,
        });
        pieces[0].push((tc, z1, w1, wa1));
        pieces[1].push((tc, z2, w2, wa2));
        t = tc + 1e-9;
    }
    let offset = rng.random_range(-2e-3..2e-3);
    let noise = Normal::new(0.0, 1e-6).unwrap();
    let n = (t_end * FPS) as i64;
    let mut tracks = Vec::new();
    for (p, list) in pieces.iter().enumerate() {
        let (mut frame, mut t_s, mut z_m) = (Vec::new(), Vec::new(), Vec::new());
        for f in 0..n {
            if rng.random::<f64>() < 0.01 {
                continue; // dropped frame
            }
            let t = f as f64 / FPS;
            let piece = list.iter().rev().find(|q| q.0 <= t).unwrap();
            let mut z = at(piece, t).0 + noise.sample(&mut rng);
            if rng.random::<f64>() < 0.003 {
                z += rng.random_range(20e-6..60e-6) * if rng.random::<bool>() { 1.0 } else { -1.0 };
            }
            frame.push(f);
            t_s.push(t);
            z_m.push(case.direction * (z + offset));
        }
        tracks.push(Track {
            particle: p as u32,
            frame,
            t_s,
            z_m,
        });
    }
    let info = RunInfo {
        run: format!("c{}", case.seed),
        experiment: Experiment::Collision,
        material: "440c".into(),
        diameter_m: 2.0 * R_M,
        fps: FPS,
        setup: Some(case.setup),
        extra: BTreeMap::new(),
    };
    (Recording { info, tracks }, impacts)
}

#[test]
fn rolling_first_impact_recovers_c_and_velocities() {
    for seed in 1..=4u64 {
        for direction in [1.0, -1.0] {
            let case = Case {
                setup: Setup::Rolling,
                v0_mps: 0.06 + 0.03 * seed as f64,
                mu_pp: 1.4,
                a_per_mps: 1.5,
                direction,
                seed,
            };
            let (rec, truth) = simulate(&case);
            let fit = fit_collision(&rec, &CollisionOptions::default());
            eprintln!(
                "status {:?} iters {} rms {:.2e} noise {:.2e} outl {}",
                fit.status, fit.iterations, fit.rms_m, fit.noise_m, fit.n_outliers
            );
            for im in &fit.impacts {
                eprintln!(
                    "  fit t {:.6} speed {:.4} C {:.3} dvz {:.4} dva {:.4} sum {:.4}->{:.4} {:?}",
                    im.t_s.value,
                    im.impact_speed_mps.value,
                    im.restitution.value,
                    im.target_dvz_mps.value,
                    im.target_dva_mps.value,
                    im.spin_sum_before_mps,
                    im.spin_sum_after_mps.value,
                    im.contact
                );
            }
            for im in &truth {
                eprintln!(
                    "  true t {:.6} speed {:.4} C {:.3} slip {}",
                    im.t_s, im.speed_mps, im.c, im.slip
                );
            }
            assert_eq!(fit.direction as f64, direction);
            let first = &fit.impacts[0];
            let t0 = truth[0];
            eprintln!(
                "seed {seed} dir {direction}: C {:.4} (true {:.4}), speed {:.4} (true {:.4}), mu {:.4}, T {:.4}, impacts {} (true {}), t {:.6} vs {:.6}",
                first.restitution.value, t0.c, first.impact_speed_mps.value, t0.speed_mps,
                fit.mu_pg.value, fit.t_drag_s.value, fit.impacts.len(), truth.len(), first.t_s.value, t0.t_s
            );
            assert!((first.restitution.value - t0.c).abs() < 0.05);
            assert!((first.impact_speed_mps.value - t0.speed_mps).abs() < 0.01 * t0.speed_mps);
            assert!((first.t_s.value - t0.t_s).abs() < 0.2 / FPS);
            assert!((fit.mu_pg.value - MU_PG).abs() < 0.01);
        }
    }
}

#[test]
fn scratch_debug() {
    let case = Case {
        setup: Setup::Rolling,
        v0_mps: 0.18,
        mu_pp: 1.4,
        a_per_mps: 1.5,
        direction: 1.0,
        seed: 4,
    };
    let (rec, truth) = simulate(&case);
    let fit = fit_collision(&rec, &CollisionOptions::default());
    eprintln!("{}", serde_json::to_string_pretty(&fit.segments).unwrap());
    eprintln!("{}", serde_json::to_string_pretty(&fit.impacts).unwrap());
    eprintln!("{:?}", truth);
}
