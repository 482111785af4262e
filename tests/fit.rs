//! Fit tests on synthetic runs with known truth (closed form + 1 µm noise + 0.5 % outliers +
//! dropped frames + unknown kick time and offset), several seeds, both directions.

#[path = "support/single_runs.rs"]
mod single_runs;

use groove::artifacts::FitStatus;
use groove::engine::stage::{Artifact, StageInput, StageKind};
use groove::fit::aggregate::{aggregate_single, AggregateOptions};
use groove::fit::model::Prepared;
use groove::fit::residuals::{residuals, Phase};
use groove::fit::single::{fit_track, SingleFit};
use groove::fit::track_problem::Workspace;
use groove::fit::{fit_segment, FitOptions, FreeParams, RunFit, SegmentInit};
use groove::physics::{Baseline, Groove};
use groove::recording::{Experiment, Recording, RunInfo, Track};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use single_runs::{runs, sample, Camera, Run};
use std::collections::BTreeMap;

const SEEDS: [u64; 4] = [1, 2, 3, 4];
/// μ of one run is determined by the sliding phase (t1 ≈ 0.1 s·|v0|), and it trades off against
/// the kick time t0 inside the first frame (the data only see the spin at the first frame through
/// the switch time). At 1 µm noise its standard error is ≈ 0.002 at 0.09 m/s, ≈ 0.005 at 0.06 m/s
/// and ≈ 0.01 at 0.04 m/s. So a single run is held to 0.01 from this speed on, and every run to
/// 4 of its own standard errors; the per-material mean (the "μ within 0.01") is tested in
/// the aggregate test.
const MU_SPEED_MPS: f64 = 0.06;

fn fit(run: &Run, opts: &FitOptions, ws: &mut Workspace) -> SingleFit {
    fit_track(&run.t_s, &run.z_m, Camera::CHAPTER.fps, opts, ws)
}

/// Checks a fit against the truth; returns the pulls (fit − truth)/se of μ, T, v0.
fn check_recovery(run: &Run, f: &SingleFit) -> [f64; 3] {
    let t = run.truth;
    let ctx = format!("truth {t:?}\nfit {f:?}");
    assert_eq!(f.status, FitStatus::Converged, "{ctx}");
    assert!(
        (f.v0_mps / t.v0_mps - 1.0).abs() < 0.01,
        "v0 off by more than 1 %\n{ctx}"
    );
    assert!(
        (f.t_drag_s / t.t_drag_s - 1.0).abs() < 0.05,
        "T off by more than 5 %\n{ctx}"
    );
    if t.v0_mps.abs() >= MU_SPEED_MPS {
        assert!((f.mu - t.mu).abs() < 0.01, "μ off by more than 0.01\n{ctx}");
    }
    let se = f.mu_se.expect("a standard error of μ");
    assert!(
        (f.mu - t.mu).abs() < 4.0 * se,
        "μ off by more than 4 se\n{ctx}"
    );
    assert!(f.rms_m < 1.1e-6, "rms above the 1 µm noise\n{ctx}");
    [
        (f.mu - t.mu) / se,
        (f.t_drag_s - t.t_drag_s) / f.t_drag_se.unwrap(),
        (f.v0_mps - t.v0_mps) / f.v0_se.unwrap(),
    ]
}

#[test]
fn recovers_truth_of_single_runs_across_seeds_and_directions() {
    let opts = FitOptions::default();
    let mut ws = Workspace::default();
    let (mut n_pos, mut n_neg) = (0, 0);
    let mut sum_sq = [0.0; 3];
    for seed in SEEDS {
        for (mu, speed) in [(0.337, (0.005, 0.1)), (0.293, (0.005, 0.1))] {
            for run in runs(seed, 12, speed, mu, Camera::CHAPTER) {
                let f = fit(&run, &opts, &mut ws);
                let pulls = check_recovery(&run, &f);
                for k in 0..3 {
                    sum_sq[k] += pulls[k] * pulls[k];
                }
                if run.truth.v0_mps > 0.0 {
                    n_pos += 1
                } else {
                    n_neg += 1
                }
            }
        }
    }
    assert!(
        n_pos > 20 && n_neg > 20,
        "both directions covered: {n_pos} / {n_neg}"
    );
    // the standard errors are honest: the pulls scatter with an RMS near 1 (the bounded kick
    // time makes them somewhat conservative)
    let n = (n_pos + n_neg) as f64;
    for (k, name) in ["mu", "T", "v0"].iter().enumerate() {
        let rms = (sum_sq[k] / n).sqrt();
        assert!((0.4..1.5).contains(&rms), "pull RMS of {name} is {rms}");
    }
}

#[test]
fn outliers_at_half_a_percent_move_mu_by_less_than_0_005() {
    // The outliers' own influence: the fit with outliers against the fit of the same clean run
    // with those frames removed (what perfect rejection gives). Against the full clean run, losing
    // a frame of the short sliding phase may shift a poorly determined μ by a fraction of its
    // standard error; that is a loss of data, not the outlier pulling the fit, and is bounded
    // separately.
    let opts = FitOptions::default();
    let mut ws = Workspace::default();
    let clean = Camera {
        outlier_rate: 0.0,
        ..Camera::CHAPTER
    };
    let (mut flagged, mut injected) = (0, 0);
    for seed in SEEDS {
        let with = runs(seed, 12, (0.005, 0.1), 0.337, Camera::CHAPTER);
        let without = runs(seed, 12, (0.005, 0.1), 0.337, clean);
        for (a, b) in with.iter().zip(&without) {
            let keep: Vec<usize> = (0..b.t_s.len()).filter(|&i| !a.outlier[i]).collect();
            let t: Vec<f64> = keep.iter().map(|&i| b.t_s[i]).collect();
            let z: Vec<f64> = keep.iter().map(|&i| b.z_m[i]).collect();
            let fa = fit(a, &opts, &mut ws);
            let removed = fit_track(&t, &z, 1e4, &opts, &mut ws);
            let full = fit(b, &opts, &mut ws);
            assert!(
                (fa.mu - removed.mu).abs() < 0.005,
                "outliers moved μ {} → {}\n{:?}",
                removed.mu,
                fa.mu,
                a.truth
            );
            assert!(
                (fa.t_drag_s / removed.t_drag_s - 1.0).abs() < 0.005,
                "outliers moved T\n{:?}",
                a.truth
            );
            let se = full.mu_se.unwrap();
            assert!(
                (fa.mu - full.mu).abs() < 0.005_f64.max(se),
                "μ {} → {} (se {se})\n{:?}",
                full.mu,
                fa.mu,
                a.truth
            );
            injected += a.outlier.iter().filter(|&&o| o).count();
            flagged += fa.n_outliers;
        }
    }
    // every injected jump is ≥ 10 σ: the fit must flag (nearly) all of them, and little else
    assert!(injected > 50, "{injected}");
    assert!(
        flagged >= injected * 95 / 100 && flagged <= injected + injected / 10 + 5,
        "{flagged} flagged, {injected} injected"
    );
}

#[test]
fn mirrored_runs_give_mirrored_fits() {
    let opts = FitOptions::default();
    let mut ws = Workspace::default();
    for run in runs(9, 6, (0.01, 0.1), 0.3, Camera::CHAPTER) {
        let mirror_z: Vec<f64> = run.z_m.iter().map(|z| -z).collect();
        let a = fit_track(&run.t_s, &run.z_m, 1e4, &opts, &mut ws);
        let b = fit_track(&run.t_s, &mirror_z, 1e4, &opts, &mut ws);
        assert!(
            (a.v0_mps + b.v0_mps).abs() < 1e-9 * a.v0_mps.abs().max(1.0),
            "{a:?}\n{b:?}"
        );
        assert!((a.mu - b.mu).abs() < 1e-7 && (a.t_drag_s / b.t_drag_s - 1.0).abs() < 1e-7);
    }
}

#[test]
fn model_matches_physics_baseline() {
    // the fit's own closed form (with derivatives) against physics::Baseline, both directions
    for (v0, mu, t) in [
        (0.05, 0.337, 0.107),
        (-0.02, 0.293, 0.074),
        (0.1, 0.5, 0.03),
    ] {
        let base = Baseline {
            mu,
            t_drag_s: t,
            groove: Groove::CHAPTER,
        };
        let m = Prepared::new(&[0.0, 0.0, v0, 0.0, mu, t], Groove::CHAPTER).unwrap();
        assert!(
            (m.t1_s / base.switch_time_s(v0) - 1.0).abs() < 1e-9,
            "t1 {} vs {}",
            m.t1_s,
            base.switch_time_s(v0)
        );
        for i in 0..800 {
            let tt = i as f64 * 1e-4;
            let (dz, v, phase) = base.state(v0, tt);
            let (mz, mv, sliding) = m.state(tt);
            assert!(
                (dz - mz).abs() < 1e-12 + 1e-9 * dz.abs(),
                "z at {tt}: {dz} vs {mz}"
            );
            assert!((v - mv).abs() < 1e-10, "v at {tt}: {v} vs {mv}");
            if tt > 0.0 && (tt - m.t1_s).abs() > 1e-9 {
                assert_eq!(
                    matches!(phase, groove::physics::Phase::Sliding),
                    sliding,
                    "phase at {tt}"
                );
            }
        }
    }
}

#[test]
fn segment_fit_recovers_velocity_and_spin_after_a_kick() {
    // a segment that starts with a nonzero spin (as after an impact): fit v0 and va0 with μ, T fixed
    let g = Groove::CHAPTER;
    let base = Baseline {
        mu: 0.3,
        t_drag_s: 0.08,
        groove: g,
    };
    let (v0, va0) = (0.06, 0.03);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let normal = rand_distr::Normal::new(0.0, 1e-6).unwrap();
    let t: Vec<f64> = (0..300).map(|i| 0.01 + i as f64 * 1e-4).collect();
    let z: Vec<f64> = t
        .iter()
        .map(|&tt| {
            2e-3 + base.state_from(v0, va0, tt - 0.01).0
                + rand_distr::Distribution::sample(&normal, &mut rng)
        })
        .collect();
    let init = SegmentInit {
        t_ref_s: 0.01,
        z0_m: z[0],
        v0_mps: 0.04,
        va0_mps: 0.0,
        mu: 0.3,
        t_drag_s: 0.08,
        free: FreeParams {
            z0: true,
            v0: true,
            va0: true,
            mu: false,
            t_drag: false,
        },
    };
    let f = fit_segment(&t, &z, init, &FitOptions::default());
    assert!(f.termination.is_converged(), "{f:?}");
    assert!((f.v0_mps - v0).abs() < 2e-4, "{f:?}");
    assert!((f.va0_mps - va0).abs() < 2e-3, "{f:?}");
    assert!(f.se.mu.is_none() && f.se.v0_mps.is_some());
}

#[test]
fn aggregates_recover_a_known_drag_line_within_their_intervals() {
    // Five independent datasets of 2 × 40 runs with T = 0.04 + 0.8·|v0| and 3 % scatter between
    // runs (as real runs scatter). Each gives 95 % intervals of intercept and slope per material:
    // 20 intervals, of which at least 17 must hold the truth (a binomial tail of 1.6 % for
    // honest 95 % intervals), each narrow enough to mean something; the per-material μ over the
    // fast runs must be within 0.01 every time.
    let opts = FitOptions::default();
    let mut ws = Workspace::default();
    let (a, b) = (0.04, 0.8);
    let mut covered = 0;
    for seed in [21u64, 22, 23, 24, 25] {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut fits = Vec::new();
        for (material, mu) in [("316", 0.337), ("440c", 0.293)] {
            for i in 0..40 {
                let mut truth = single_runs::random_truth(&mut rng, (0.005, 0.1), mu, 1e4);
                let scatter = 1.0
                    + 0.03
                        * rand_distr::Distribution::<f64>::sample(
                            &rand_distr::StandardNormal,
                            &mut rng,
                        );
                truth.t_drag_s = (a + b * truth.v0_mps.abs()) * scatter;
                let run = sample(truth, Camera::CHAPTER, &mut rng);
                let mut f = fit(&run, &opts, &mut ws);
                f.run = format!("{material}_{i:02}");
                f.material = material.into();
                fits.push(f);
            }
        }
        let s = aggregate_single(&fits, &AggregateOptions::default(), seed);
        for (material, mu) in [("316", 0.337), ("440c", 0.293)] {
            let m = &s.materials[material];
            assert_eq!(m.n_converged, 40);
            let line = m.t_vs_v0;
            let (ia, ib) = (
                line.intercept_s.interval.unwrap(),
                line.slope_s_per_mps.interval.unwrap(),
            );
            covered += ia.contains(a) as usize + ib.contains(b) as usize;
            assert!(
                ia.hi - ia.lo < 0.01 && ib.hi - ib.lo < 0.2,
                "{material}: intervals too wide: {ia:?} {ib:?}"
            );
            let fast = m.mu_fast;
            assert!((fast.value - mu).abs() < 0.01, "{material}: {fast:?}");
            assert!(
                (m.mu_weighted.value - mu).abs() < 0.01,
                "{material}: {:?}",
                m.mu_weighted
            );
        }
        // seeded: the same input gives the same intervals
        assert_eq!(
            s,
            aggregate_single(&fits, &AggregateOptions::default(), seed)
        );
    }
    assert!(
        covered >= 17,
        "only {covered} of 20 intervals hold the true line"
    );
}

fn recording(id: &str, material: &str, run: &Run) -> Recording {
    Recording {
        info: RunInfo {
            run: id.into(),
            experiment: Experiment::Single,
            material: material.into(),
            diameter_m: 300e-6,
            fps: 1e4,
            setup: None,
            extra: BTreeMap::new(),
        },
        tracks: vec![Track {
            particle: 0,
            frame: run.t_s.iter().map(|t| (t * 1e4).round() as i64).collect(),
            t_s: run.t_s.clone(),
            z_m: run.z_m.clone(),
        }],
    }
}

#[test]
fn residuals_of_a_good_fit_are_the_noise_and_flag_the_outliers() {
    let run = &runs(13, 1, (0.05, 0.06), 0.3, Camera::CHAPTER)[0];
    let rec = recording("r1", "316", run);
    let fit = RunFit::Single(groove::fit::fit_single(&rec, &FitOptions::default()));
    let res = residuals(&rec, &fit, Groove::CHAPTER);
    assert_eq!(res.status, "ok");
    assert_eq!(
        res.outlier, run.outlier,
        "flags equal the injected outliers"
    );
    let inl: Vec<f64> = res
        .residual_m
        .iter()
        .zip(&res.outlier)
        .filter(|(_, &o)| !o)
        .map(|(r, _)| *r)
        .collect();
    let rms = (inl.iter().map(|r| r * r).sum::<f64>() / inl.len() as f64).sqrt();
    assert!((rms / 1e-6 - 1.0).abs() < 0.1, "rms {rms}");
    assert!(res.phase[0] == Phase::Sliding && *res.phase.last().unwrap() == Phase::Rolling);
}

fn stage_input<'a>(
    params: &'a toml::Table,
    inputs: BTreeMap<&'a str, &'a Artifact>,
    item: Option<&'a str>,
) -> StageInput<'a> {
    StageInput {
        params,
        inputs,
        item,
        seed: 3,
        progress: None,
        put_item: None,
        memo: None,
    }
}

#[test]
fn stages_fit_aggregate_simulate_compare_run_end_to_end() {
    let params = toml::Table::new();
    let mut runs_items = BTreeMap::new();
    let mut fit_items = BTreeMap::new();
    let mut res_items = BTreeMap::new();
    let synth = runs(17, 4, (0.01, 0.1), 0.3, Camera::CHAPTER);
    for (i, run) in synth.iter().enumerate() {
        let id = format!("run{}", 4 - i); // not in sorted order
        let rec = Artifact::File(groove::recording::item::encode(&recording(&id, "316", run)));
        let out = groove::stages::fit::Fit
            .run(&stage_input(&params, [("runs", &rec)].into(), Some(&id)))
            .unwrap();
        let Artifact::File(bytes) = &out["fits"] else {
            panic!("fits is a file")
        };
        let parsed: RunFit = serde_json::from_slice(bytes).unwrap();
        assert!(matches!(parsed, RunFit::Single(_)));
        fit_items.insert(id.clone(), bytes.clone());
        runs_items.insert(id, rec);
    }
    let fits = Artifact::Collection(fit_items);
    let runs_coll = Artifact::Collection(
        runs_items
            .iter()
            .map(|(k, v)| match v {
                Artifact::File(b) => (k.clone(), b.clone()),
                _ => unreachable!(),
            })
            .collect(),
    );
    let agg = groove::stages::aggregate::Aggregate
        .run(&stage_input(
            &params,
            [("fits", &fits), ("runs", &runs_coll)].into(),
            None,
        ))
        .unwrap();
    let Artifact::File(csv) = &agg["fits_csv"] else {
        panic!()
    };
    let csv = String::from_utf8(csv.clone()).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(
        lines[0],
        "run,material,v0_mps,v0_se,mu,mu_se,T_s,T_se,t1_s,rms_m,status"
    );
    assert_eq!(lines.len(), 5);
    assert!(lines[1].starts_with("run1,316,") && lines[4].starts_with("run4,316,"));
    assert!(lines[1..]
        .iter()
        .all(|l| l.ends_with(",converged") && l.split(',').count() == 11));
    let Artifact::File(summary) = &agg["summary"] else {
        panic!()
    };
    let summary: serde_json::Value = serde_json::from_slice(summary).unwrap();
    assert!(summary["collisions"].is_null());
    assert!(summary["notes"][0]
        .as_str()
        .unwrap()
        .contains("no collision runs"));
    assert_eq!(summary["single"]["materials"]["316"]["n_converged"], 4);
    for (id, rec) in &runs_items {
        let out = groove::stages::simulate::Simulate
            .run(&stage_input(
                &params,
                [("runs", rec), ("fits", &fits)].into(),
                Some(id),
            ))
            .unwrap();
        let Artifact::File(b) = &out["residuals"] else {
            panic!()
        };
        // foreach = ["runs", "fits"]: the run's own fit as a File gives the same bytes
        let own = fits_item(&fits, id);
        let alone = groove::stages::simulate::Simulate
            .run(&stage_input(
                &params,
                [("runs", rec), ("fits", &own)].into(),
                Some(id),
            ))
            .unwrap();
        assert_eq!(alone["residuals"], out["residuals"]);
        res_items.insert(id.clone(), b.clone());
    }
    let res = Artifact::Collection(res_items);
    let cmp = groove::stages::compare::Compare
        .run(&stage_input(&params, [("residuals", &res)].into(), None))
        .unwrap();
    let Artifact::File(c) = &cmp["comparison"] else {
        panic!()
    };
    let c: serde_json::Value = serde_json::from_slice(c).unwrap();
    assert_eq!(c["n_runs"], 4);
    let rms = c["overall"]["rms_m"].as_f64().unwrap();
    assert!((rms / 1e-6 - 1.0).abs() < 0.1, "pooled rms {rms}");
    // white noise: no autocorrelation, runs test unremarkable
    assert!(c["overall"]["lag1_autocorr"].as_f64().unwrap().abs() < 0.1);
    assert!(c["overall"]["runs_test_z"].as_f64().unwrap().abs() < 4.0);
    // a fit of a run is deterministic bytes
    let again = groove::stages::fit::Fit
        .run(&stage_input(
            &params,
            [("runs", &runs_items["run1"])].into(),
            Some("run1"),
        ))
        .unwrap();
    assert_eq!(again["fits"], fits_item(&fits, "run1"));
}

fn fits_item(fits: &Artifact, id: &str) -> Artifact {
    match fits {
        Artifact::Collection(m) => Artifact::File(m[id].clone()),
        _ => unreachable!(),
    }
}

#[test]
fn too_short_a_track_is_a_failed_fit_not_a_panic() {
    let run = &runs(
        1,
        1,
        (0.05, 0.06),
        0.3,
        Camera {
            n_frames: 5,
            ..Camera::CHAPTER
        },
    )[0];
    let f = fit_track(
        &run.t_s,
        &run.z_m,
        1e4,
        &FitOptions::default(),
        &mut Workspace::default(),
    );
    assert_eq!(f.status, FitStatus::Failed);
    let json = serde_json::to_string(&RunFit::Single(f.clone())).unwrap();
    let back: RunFit = serde_json::from_str(&json).unwrap();
    let RunFit::Single(b) = back else { panic!() };
    assert!(b.rms_m.is_nan() && b.termination == f.termination);
}

#[test]
fn shipped_dataset_gives_its_truth_and_the_chapter_line() {
    // The shipped dataset (data/, made from data/truth/truth.toml with a concealed saturating
    // drag tuned so that linear-drag fits give the chapter's T = 0.052 + 1.10·v0): μ per material
    // within 0.01 of the truth, v0 of every single run within 2.5 % of runs_truth.csv (not 1 %:
    // the baseline's drag law is not the data's), and the pooled T-vs-v0 line within 10 % of the
    // chapter's.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let recs = groove::ingest::read_dataset_dir(&root.join("data"), &Default::default())
        .expect("the shipped dataset ingests");
    let truth_csv = std::fs::read_to_string(root.join("data/truth/runs_truth.csv")).unwrap();
    let true_v0: BTreeMap<String, f64> = truth_csv
        .lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[1] == "0").then(|| (f[0].to_string(), f[3].parse().unwrap()))
        })
        .collect();
    let truth: toml::Table = std::fs::read_to_string(root.join("data/truth/truth.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let mut fits = Vec::new();
    for rec in recs
        .iter()
        .filter(|r| r.info.experiment == Experiment::Single)
    {
        let f = groove::fit::fit_single(rec, &FitOptions::default());
        assert_eq!(f.status, FitStatus::Converged, "{}", f.run);
        let v0 = true_v0[&f.run];
        // linear drag is the wrong law for this data: extrapolated to the kick, v0 comes out
        // up to ~1.7 % high at 0.1 m/s (the bias the discovery stage is there to explain)
        assert!(
            (f.v0_mps / v0 - 1.0).abs() < 0.025,
            "{}: v0 {} vs {v0}",
            f.run,
            f.v0_mps
        );
        fits.push(f);
    }
    assert!(fits.len() >= 80, "{} single runs", fits.len());
    let s = aggregate_single(&fits, &AggregateOptions::default(), 1);
    for m in truth["materials"].as_array().unwrap() {
        let name = m["name"].as_str().unwrap();
        let mu = m["friction"]["mu"].as_float().unwrap();
        let got = &s.materials[name];
        assert!(
            (got.mu_fast.value - mu).abs() < 0.01,
            "{name}: {:?} vs {mu}",
            got.mu_fast
        );
        assert!(
            (got.mu_weighted.value - mu).abs() < 0.01,
            "{name}: {:?}",
            got.mu_weighted
        );
    }
    let line = s.pooled.t_vs_v0;
    assert!(
        (line.intercept_s.value / 0.052 - 1.0).abs() < 0.1,
        "{line:?}"
    );
    assert!(
        (line.slope_s_per_mps.value / 1.10 - 1.0).abs() < 0.1,
        "{line:?}"
    );
}

#[test]
fn stage_params_are_checked_and_defaults_filled_in() {
    use groove::stages::{aggregate::Aggregate, fit::Fit};
    let table = |k: &str, v: toml::Value| toml::Table::from_iter([(k.to_string(), v)]);
    let e = Fit
        .canonical_params(&table("outlier_sigma", toml::Value::Float(1.0)))
        .unwrap_err();
    assert_eq!(e.key, "outlier_sigma");
    assert!(e.message.contains("at least 2"), "{}", e.message);
    let e = Fit
        .canonical_params(&table("loss", toml::Value::String("cauchy".into())))
        .unwrap_err();
    assert!(e.message.contains("cauchy"), "{}", e.message);
    let e = Fit
        .canonical_params(&table("outlier_sigmaa", toml::Value::Float(5.0)))
        .unwrap_err();
    assert!(e.message.contains("outlier_sigmaa"), "{}", e.message);
    let v = Fit.canonical_params(&toml::Table::new()).unwrap();
    assert_eq!(v["groove_angle_deg"], 70.6);
    assert_eq!(v["loss"], "huber");
    let e = Aggregate
        .canonical_params(&table("level", toml::Value::Float(1.5)))
        .unwrap_err();
    assert_eq!(e.key, "level");
    // a per-run stage bound without `foreach` says how to fix it
    let coll = Artifact::Collection(BTreeMap::new());
    let params = toml::Table::new();
    let e = Fit
        .run(&stage_input(&params, [("runs", &coll)].into(), None))
        .err()
        .unwrap();
    assert!(e.0.contains("foreach = \"runs\""), "{}", e.0);
}
