//! Collision fits on pairs simulated by `physics::simulate_pair` with known μ_pp and C(v), 1 µm
//! noise, dropped frames, outliers and an unknown kick time: impacts, restitution and μ_pp are
//! recovered within stated tolerances across seeds, both setups and both directions.

use groove::artifacts::collision_fit::{Contact, PreImpactSource, Termination, NO_IMPACT};
use groove::fit::collision::{fit_collision, summarize_seeded, CollisionFit, CollisionOptions};
use groove::ingest::{read_dataset_dir, IngestParams};
use groove::physics::{
    simulate_pair, Friction, Groove, Impact, Model, PairParams, Restitution, State, Term,
};
use groove::recording::{Experiment, Recording, RunInfo, Setup, Track};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::collections::BTreeMap;
use std::path::Path;

const R_M: f64 = 150e-6;
const FPS: f64 = 10_000.0;
const MU_PG: f64 = 0.3;
const T_DRAG_S: f64 = 0.06;
const DURATION_S: f64 = 0.06;
/// The restitution law of the simulations: C = 0.6 + 0.4 e^{−v/0.15 m/s}.
const LAW: Restitution = Restitution::SpeedDependent {
    c0: 0.6,
    v_ref_mps: 0.15,
};

struct Case {
    setup: Setup,
    v0_mps: f64,
    mu_pp: f64,
    /// +1: the striker moves toward +z.
    direction: f64,
    seed: u64,
}

/// Simulate a run and record it like a camera: frames at 10 kHz starting a random fraction of a
/// frame after the kick, 1 µm Gaussian noise, 1 % dropped frames, 0.3 % outliers of 20–60 µm,
/// a common unknown offset. Returns the recording and the true impacts (lab frame).
fn record(case: &Case) -> (Recording, Vec<Impact>) {
    let mut rng = ChaCha8Rng::seed_from_u64(case.seed);
    let delay_s = rng.random_range(0.05..0.95) / FPS;
    let gap_m = match case.setup {
        Setup::Rolling => 2.0 * R_M + 1e-3,
        Setup::Contact => 2.0 * R_M,
    };
    let d = case.direction;
    let init = [
        State {
            z_m: 0.0,
            v_mps: d * case.v0_mps,
            va_mps: 0.0,
        },
        State {
            z_m: d * gap_m,
            v_mps: 0.0,
            va_mps: 0.0,
        },
    ];
    let n = (DURATION_S * FPS) as usize;
    let t_sim: Vec<f64> = (0..n).map(|i| i as f64 / FPS + delay_s).collect();
    let pair = PairParams {
        restitution: LAW,
        mu_pp: case.mu_pp,
        radius_m: R_M,
        force: None,
        slip: None,
    };
    let traj = simulate_pair(&Model::baseline(MU_PG, T_DRAG_S), &pair, init, &t_sim);
    let offset = rng.random_range(-2e-3..2e-3);
    let noise = Normal::new(0.0, 1e-6).unwrap();
    let tracks = (0..2)
        .map(|p| {
            let (mut frame, mut t_s, mut z_m) = (Vec::new(), Vec::new(), Vec::new());
            for (i, z) in traj.particles[p].z_m.iter().enumerate() {
                if rng.random::<f64>() < 0.01 {
                    continue;
                }
                let mut z = z + offset + noise.sample(&mut rng);
                if rng.random::<f64>() < 0.003 {
                    z += rng.random_range(20e-6..60e-6)
                        * if rng.random::<bool>() { 1.0 } else { -1.0 };
                }
                frame.push(i as i64);
                t_s.push(i as f64 / FPS);
                z_m.push(z);
            }
            Track {
                particle: p as u32,
                frame,
                t_s,
                z_m,
            }
        })
        .collect();
    let impacts = traj
        .impacts
        .into_iter()
        .map(|mut im| {
            im.t_s -= delay_s;
            im
        })
        .collect();
    let info = RunInfo {
        run: format!(
            "{:?}-{}-{}",
            case.setup,
            case.seed,
            if d > 0.0 { "up" } else { "down" }
        ),
        experiment: Experiment::Collision,
        material: "440c".into(),
        diameter_m: 2.0 * R_M,
        fps: FPS,
        setup: Some(case.setup),
        extra: BTreeMap::new(),
    };
    (Recording { info, tracks }, impacts)
}

fn fit(case: &Case) -> (CollisionFit, Vec<Impact>, RunInfo) {
    let (rec, truth) = record(case);
    let fit = fit_collision(&rec, &CollisionOptions::default());
    assert!(
        fit.usable(),
        "{}: {:?} {}",
        rec.info.run,
        fit.termination,
        fit.message
    );
    (fit, truth, rec.info)
}

/// The target's true Δv_z and Δv_a of an impact in the striker-forward frame.
fn target_change(im: &Impact, direction: f64) -> (f64, f64) {
    let (pre, post) = (im.pre[1], im.post[1]);
    (
        direction * (post.v_mps - pre.v_mps),
        direction * (post.va_mps - pre.va_mps),
    )
}

#[test]
fn rolling_setup_first_impact_both_directions() {
    for seed in 1..=4u64 {
        for direction in [1.0, -1.0] {
            let case = Case {
                setup: Setup::Rolling,
                v0_mps: 0.05 + 0.04 * seed as f64,
                mu_pp: 1.4,
                direction,
                seed,
            };
            let (fit, truth, _) = fit(&case);
            let (im, tr) = (&fit.impacts[0], &truth[0]);
            let (dvz, dva) = target_change(tr, direction);
            assert_eq!(fit.direction as f64, direction);
            // C within 0.02, impact speed within 1 %, time within a fifth of a frame
            assert!(
                (im.restitution.value - tr.restitution).abs() < 0.02,
                "seed {seed}: C {} vs {}",
                im.restitution.value,
                tr.restitution
            );
            assert!((im.impact_speed_mps.value - tr.v_impact_mps).abs() < 0.01 * tr.v_impact_mps);
            assert!(
                (im.t_s.value - tr.t_s).abs() < 0.2 / FPS,
                "t {} vs {}",
                im.t_s.value,
                tr.t_s
            );
            // the target's jump in v and spin (stick: v_a2' = −v_a1/2) within 2 % / 3 mm/s
            assert!((im.target_dvz_mps.value - dvz).abs() < 0.02 * dvz);
            assert!(
                (im.target_dva_mps.value - dva).abs() < 3e-3,
                "dva {} vs {dva}",
                im.target_dva_mps.value
            );
            assert_eq!(im.contact, Contact::Stick);
            // the fitted trajectory (Fig. 4.3c–d) follows the striker's samples within 5 µm
            let (rec, _) = record(&case);
            let st = rec.track(0).unwrap();
            let off: Vec<f64> = st
                .t_s
                .iter()
                .zip(&st.z_m)
                .filter_map(|(&t, &z)| Some(fit.position_m(0, t, Groove::CHAPTER)? - z))
                .collect();
            let mut dev: Vec<f64> = off.iter().map(|d| d.abs()).collect();
            dev.sort_by(|a, b| a.total_cmp(b));
            assert!(
                off.len() > 100 && dev[dev.len() / 2] < 2e-6 && dev[dev.len() * 9 / 10] < 5e-6,
                "median {}",
                dev[dev.len() / 2]
            );
            assert!(!tr.slip);
            // lab-frame velocities carry the direction
            assert!(im.striker_before.v_mps.value * direction > 0.0);
            assert!(
                (fit.mu_pg.value - MU_PG).abs() < 0.01,
                "mu {}",
                fit.mu_pg.value
            );
            // drag: every segment's T within 3 standard errors (short runs constrain it weakly)
            for seg in &fit.segments {
                let (t, se) = (seg.t_drag_s.value, seg.t_drag_s.se.unwrap());
                assert!(
                    (t - T_DRAG_S).abs() < 3.0 * se && se < 0.5 * T_DRAG_S,
                    "T {t} ± {se}"
                );
            }
        }
    }
}

#[test]
fn contact_setup_restitution_from_momentum_conservation() {
    for seed in 11..=14u64 {
        for direction in [1.0, -1.0] {
            let v0 = 0.03 + 0.05 * (seed - 10) as f64;
            let case = Case {
                setup: Setup::Contact,
                v0_mps: v0,
                mu_pp: 1.4,
                direction,
                seed,
            };
            let (fit, truth, _) = fit(&case);
            let (im, tr) = (&fit.impacts[0], &truth[0]);
            assert_eq!(
                im.striker_before_source,
                PreImpactSource::MomentumConservation
            );
            assert!(
                (im.restitution.value - tr.restitution).abs() < 0.03,
                "seed {seed}: C {} vs {}",
                im.restitution.value,
                tr.restitution
            );
            assert!(
                (im.impact_speed_mps.value - tr.v_impact_mps).abs() < 0.02 * tr.v_impact_mps,
                "v {} vs {}",
                im.impact_speed_mps.value,
                tr.v_impact_mps
            );
            // spins start at zero and a resting pair sticks without spin change
            assert!(im.target_dva_mps.value.abs() < 2e-3);
            assert!(
                (fit.mu_pg.value - MU_PG).abs() < 0.01,
                "mu {}",
                fit.mu_pg.value
            );
        }
    }
}

/// Weak particle–particle friction: a rolling striker's first impact slips, and the slope of
/// the target's Δv_a against Δv_z gives μ_pp k.
#[test]
fn mu_pp_from_slip_impacts_within_ten_percent() {
    for &mu_pp in &[0.2, 0.3] {
        let mut fits = Vec::new();
        for seed in 0..6u64 {
            let v0 = 0.05 + 0.01 * seed as f64;
            let direction = if seed % 2 == 0 { 1.0 } else { -1.0 };
            let case = Case {
                setup: Setup::Rolling,
                v0_mps: v0,
                mu_pp,
                direction,
                seed: 100 + seed,
            };
            let (fit, truth, info) = fit(&case);
            assert!(truth[0].slip, "the test needs slip impacts");
            let im = &fit.impacts[0];
            assert_eq!(
                im.contact,
                Contact::Slip,
                "seed {seed}: sums {} -> {:?}, before {:?} after {:?} / {:?} {:?}",
                im.spin_sum_before_mps,
                im.spin_sum_after_mps,
                im.striker_before,
                im.striker_after,
                im.target_before,
                im.target_after
            );
            fits.push((info, fit));
        }
        let summary = summarize_seeded(&fits, 2.5, 7);
        let slope = summary.mu_pp.from_slip_slope.unwrap();
        let model = summary.mu_pp.from_impulse_fit.unwrap();
        assert!(
            (slope.value - mu_pp).abs() < 0.1 * mu_pp,
            "slope {slope:?} vs {mu_pp}"
        );
        assert!(
            (model.value - mu_pp).abs() < 0.1 * mu_pp,
            "impulse fit {model:?} vs {mu_pp}"
        );
        assert!(model.lo() <= model.value && model.value <= model.hi());
    }
}

/// Strong friction (the chapter's 1.4): first impacts stick, so μ_pp is only bounded below.
#[test]
fn stick_impacts_bound_mu_pp_from_below() {
    let fits: Vec<_> = (0..4u64)
        .map(|seed| {
            let case = Case {
                setup: Setup::Rolling,
                v0_mps: 0.06 + 0.02 * seed as f64,
                mu_pp: 1.4,
                direction: 1.0,
                seed: 200 + seed,
            };
            let (fit, _, info) = fit(&case);
            (info, fit)
        })
        .collect();
    let summary = summarize_seeded(&fits, 2.5, 7);
    assert_eq!(summary.mu_pp.n_slip, 0);
    assert!(summary.mu_pp.value.is_none());
    let bound = summary.mu_pp.stick_lower_bound.unwrap();
    assert!(bound > 0.1 && bound < 1.4, "bound {bound}");
}

/// C against impact speed: the fitted falling curve matches the simulated law within 0.05.
#[test]
fn restitution_curve_follows_the_law() {
    let fits: Vec<_> = (0..10u64)
        .map(|seed| {
            let case = Case {
                setup: Setup::Contact,
                v0_mps: 0.02 + 0.03 * seed as f64,
                mu_pp: 1.4,
                direction: 1.0,
                seed: 300 + seed,
            };
            let (fit, _, info) = fit(&case);
            (info, fit)
        })
        .collect();
    let summary = summarize_seeded(&fits, 2.5, 7);
    let curve = &summary.restitution[0];
    assert_eq!(curve.setup, Some(Setup::Contact));
    for v in [0.05, 0.1, 0.2, 0.3] {
        let c = curve.c_inf.value + (1.0 - curve.c_inf.value) * (-v / curve.v_ref_mps.value).exp();
        assert!(
            (c - LAW.at(v)).abs() < 0.05,
            "C({v}) = {c} vs {}",
            LAW.at(v)
        );
        let line = curve.c0.value - curve.slope_per_mps.value * v;
        assert!(
            (line - LAW.at(v)).abs() < 0.08,
            "line C({v}) = {line} vs {}",
            LAW.at(v)
        );
    }
    assert!(
        curve.slope_per_mps.lo() > 0.0,
        "C falls with speed: {:?}",
        curve.slope_per_mps
    );
    // the summary serializes with units in the names and reads back
    let json = serde_json::to_string(&summary).unwrap();
    assert!(json.contains("\"impact_speed_mps\""));
    let back: groove::fit::collision::CollisionSummary = serde_json::from_str(&json).unwrap();
    assert_eq!(back.restitution.len(), summary.restitution.len());
}

#[test]
fn run_without_impact_or_target_is_reported_not_fatal() {
    // a slow striker stops short of the target
    let case = Case {
        setup: Setup::Rolling,
        v0_mps: 0.008,
        mu_pp: 1.4,
        direction: 1.0,
        seed: 9,
    };
    let (rec, truth) = record(&case);
    assert!(truth.is_empty());
    let fit = fit_collision(&rec, &CollisionOptions::default());
    assert_eq!(fit.status, NO_IMPACT);
    assert!(!fit.usable());
    assert!(fit.impacts.is_empty());
    let mut lone = rec.clone();
    lone.tracks.truncate(1);
    let fit = fit_collision(&lone, &CollisionOptions::default());
    assert_eq!(fit.termination, Termination::TooFewPoints);
    assert_eq!(fit.status, "failed");
    assert!(fit.message.contains("target"));
    // a fit record survives a JSON round trip
    let back: CollisionFit = serde_json::from_str(&serde_json::to_string(&fit).unwrap()).unwrap();
    assert_eq!(
        (back.termination, &back.status),
        (fit.termination, &fit.status)
    );
}

fn truth_toml() -> toml::Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/truth/truth.toml");
    let table: toml::Table = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    toml::Value::Table(table)
}

/// The restitution law of a material and setup in the shipped truth.
fn shipped_law(material: &str, setup: Setup) -> Restitution {
    let truth = truth_toml();
    let mat = truth["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"].as_str() == Some(material))
        .unwrap();
    let key = if setup == Setup::Rolling {
        "restitution_rolling"
    } else {
        "restitution_contact"
    };
    mat[key].clone().try_into().unwrap()
}

/// The truth of the shipped dataset's collision runs: re-simulate each run from its initial
/// state in `data/truth/runs_truth.csv` with the physics of `data/truth/truth.toml`.
fn shipped_truth(run: &str, material: &str, setup: Setup) -> Vec<Impact> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/truth");
    let truth = truth_toml();
    let terms: Vec<Term> = truth["physics"]["terms"].clone().try_into().unwrap();
    let groove = Groove {
        k: truth["groove"]["k"].as_float().unwrap(),
        ..Groove::from_angle_deg(truth["groove"]["theta_deg"].as_float().unwrap())
    };
    let mat = truth["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"].as_str() == Some(material))
        .unwrap();
    let friction: Friction = mat["friction"].clone().try_into().unwrap();
    let restitution = shipped_law(material, setup);
    let radius_m = 0.5 * mat["diameter_m"].as_float().unwrap();
    let mu_pp = truth["pair"]["mu_pp"].as_float().unwrap();
    let rows = std::fs::read_to_string(root.join("runs_truth.csv")).unwrap();
    let mut init = [State {
        z_m: 0.0,
        v_mps: 0.0,
        va_mps: 0.0,
    }; 2];
    let mut delay_s = 0.0;
    for row in rows.lines().skip(1) {
        let f: Vec<&str> = row.split(',').collect();
        if f[0] == run {
            let x: Vec<f64> = f[2..].iter().map(|v| v.parse().unwrap()).collect();
            init[f[1].parse::<usize>().unwrap()] = State {
                z_m: x[0],
                v_mps: x[1],
                va_mps: x[2],
            };
            delay_s = x[3];
        }
    }
    let model = Model {
        groove,
        friction,
        variation: Default::default(),
        terms,
    };
    let t: Vec<f64> = (0..1000).map(|i| i as f64 * 1e-4).collect();
    let pair = PairParams {
        restitution,
        mu_pp,
        radius_m,
        force: None,
        slip: None,
    };
    let mut impacts = simulate_pair(&model, &pair, init, &t).impacts;
    impacts.iter_mut().for_each(|im| im.t_s -= delay_s);
    impacts
}

/// The collision runs of the shipped dataset (with its concealed non-linear drag) against their
/// truth: every fit converged (none at its iteration limit), every first impact's C within
/// 0.03, impact speed within 3 % (the approach is fitted with linear drag, the data have a
/// speed-dependent one), time within half a frame (rolling setup); the contact-setup curves of
/// both materials within 0.02 of their laws.
#[test]
fn shipped_dataset_impacts_match_their_truth() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let recs = read_dataset_dir(&data, &IngestParams::default()).unwrap();
    let mut fits = Vec::new();
    for rec in recs
        .iter()
        .filter(|r| r.info.experiment == Experiment::Collision)
    {
        let (run, setup) = (&rec.info.run, rec.info.setup.unwrap());
        let fit = fit_collision(rec, &CollisionOptions::default());
        // no collision fit on the shipped data ends at its iteration limit (issue 15)
        assert!(
            fit.termination != Termination::MaxIterations,
            "{run}: stopped at its iteration limit ({} iterations): {}",
            fit.iterations,
            fit.message
        );
        assert!(
            fit.termination.is_converged(),
            "{run}: {:?} {}",
            fit.termination,
            fit.message
        );
        let truth = shipped_truth(run, &rec.info.material, setup);
        let (im, tr) = (&fit.impacts[0], &truth[0]);
        assert!(
            (im.restitution.value - tr.restitution).abs() < 0.03,
            "{run}: C {} vs {}",
            im.restitution.value,
            tr.restitution
        );
        assert!(
            (im.impact_speed_mps.value - tr.v_impact_mps).abs() < 0.03 * tr.v_impact_mps,
            "{run}: v {} vs {}",
            im.impact_speed_mps.value,
            tr.v_impact_mps
        );
        if setup == Setup::Rolling {
            assert!(
                (im.t_s.value - tr.t_s).abs() < 0.5 / rec.info.fps,
                "{run}: t {} vs {}",
                im.t_s.value,
                tr.t_s
            );
        }
        fits.push((rec.info.clone(), fit));
    }
    assert_eq!(fits.len(), 48);
    let summary = summarize_seeded(&fits, 2.5, 1);
    for material in ["316", "440c"] {
        let curve = summary
            .restitution
            .iter()
            .find(|c| c.material == material && c.setup == Some(Setup::Contact))
            .unwrap();
        let truth = shipped_law(material, Setup::Contact);
        let fitted = |v: f64| {
            curve.c_inf.value + (1.0 - curve.c_inf.value) * (-v / curve.v_ref_mps.value).exp()
        };
        for v in [0.05f64, 0.1, 0.2, 0.3] {
            assert!(
                (fitted(v) - truth.at(v)).abs() < 0.02,
                "{material}: C({v}) = {} vs {}",
                fitted(v),
                truth.at(v)
            );
        }
    }
    // μ_pp = 1.4: every resolved impact sticks, so only a lower bound below the truth is reported
    assert!(summary.mu_pp.value.is_none() || summary.mu_pp.n_slip > 0);
    if let Some(bound) = summary.mu_pp.stick_lower_bound {
        assert!(bound < 1.4 * 1.05, "bound {bound}");
    }
}
