//! Whole-run pair fits on synthesized collision datasets of known truth (`groove synth` truth
//! files in tests/fixtures/truths/): μ_pp from slipping first impacts within 10 % (0.2–0.45),
//! the μ_pp profile's bound or interval containing the chapter's 1.4 when first impacts stick
//! (one dataset, and unbiased with its coverage over 16 seeds), the fit's model reproducing
//! noise-free synthesized tracks at the truth, the restitution law chosen by held-out error with
//! parameters within 15 %, pairs under a drag the single runs do not share flagged, a null
//! recorded at 2 kHz or under correlated tracking noise flagged nothing, a length calibration
//! error named as such, and (on demand) μ_pg and μ_pp under the accepted physics on the shipped
//! truth with a waviness or a tilt added.

#[path = "support/noise.rs"]
mod noise;

use groove::artifacts::collision_summary::{LawForm, ProfileVerdict};
use groove::discover::pairs::check_pairs;
use groove::fit::collision::profile::{default_grid, profile_mu_pp};
use groove::fit::collision::whole_summary::{analyze, WholeRunOptions};
use groove::fit::collision::wholerun::{fit_group, FitSpec, PairRun, MU_PP};
use groove::ingest::{read_dataset_dir, IngestParams};
use groove::lsq::Termination;
use groove::physics::Groove;
use groove::physics::{Friction, Model, Term};
use groove::recording::Setup;
use groove::recording::{Experiment, Recording};
use groove::synth::{synth_tables, Truth};
use std::collections::BTreeMap;
use std::path::Path;

fn fixture(name: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/truths")
        .join(name);
    std::fs::read_to_string(p).unwrap()
}

/// Synthesize the dataset of a truth file and read it back as the analysis would.
fn dataset(truth_text: &str) -> Vec<Recording> {
    let truth = Truth::parse(truth_text).unwrap();
    let tables = synth_tables(&truth);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("runs.csv"), tables.runs_csv).unwrap();
    std::fs::write(dir.path().join("trajectories.csv"), tables.trajectories_csv).unwrap();
    read_dataset_dir(dir.path(), &IngestParams::default()).unwrap()
}

fn pair_runs(recs: &[Recording], material: &str) -> Vec<PairRun> {
    recs.iter()
        .filter(|r| r.info.experiment == Experiment::Collision && r.info.material == material)
        .map(|r| PairRun::from_recording(r, r.info.setup).unwrap())
        .collect()
}

/// μ_pp = 0.3: the first impacts slip, and the whole-run fit's μ_pp is within 10 % of the truth,
/// inside a two-sided profile interval.
#[test]
fn mu_pp_from_slipping_impacts_within_ten_percent() {
    let recs = dataset(&fixture("collision_slip.toml"));
    let runs = pair_runs(&recs, "440c");
    assert_eq!(runs.len(), 8);
    let best = fit_group(&runs, &FitSpec::new(Groove::CHAPTER), None, 80);
    assert!(
        best.result.termination.is_converged(),
        "{:?}",
        best.result.termination
    );
    let mu = best.result.shared[MU_PP];
    assert!((mu - 0.3).abs() < 0.03, "μ_pp {mu} vs 0.3");
    let profile = profile_mu_pp(&runs, &best, &default_grid(), 25);
    match profile.verdict {
        ProfileVerdict::Interval { estimate, lo, hi } => {
            assert!((estimate - 0.3).abs() < 0.03, "estimate {estimate}");
            assert!(lo < 0.3 && 0.3 < hi && hi / lo < 1.5, "interval {lo}..{hi}");
        }
        v => panic!("expected an interval, got {v:?}"),
    }
}

/// Towards the ends of the slip range, μ_pp = 0.2 and 0.45 (the slip fixture with only μ_pp
/// changed): the whole-run μ_pp is within 10 %. At 0.2 every rolling striker's first impact
/// slips; at 0.45 some already stick (a rolling striker's slips only while μ_pp < 1/(s k (1 + C)),
/// about 0.43 at C = 0.6), and the secondary impacts carry μ_pp.
#[test]
fn mu_pp_across_the_slip_range_within_ten_percent() {
    for mu_true in [0.2, 0.45] {
        let text =
            fixture("collision_slip.toml").replace("mu_pp = 0.3", &format!("mu_pp = {mu_true}"));
        assert!(text.contains(&format!("mu_pp = {mu_true}")));
        let runs = pair_runs(&dataset(&text), "440c");
        let best = fit_group(&runs, &FitSpec::new(Groove::CHAPTER), None, 80);
        assert!(best.converged(), "{mu_true}: {:?}", best.result.termination);
        let mu = best.result.shared[MU_PP];
        assert!(
            (mu - mu_true).abs() < 0.1 * mu_true,
            "μ_pp {mu} vs {mu_true}"
        );
        // at 0.2 the first impact of every rolling run slips in the fitted model
        for (run, own) in runs.iter().zip(&best.result.own) {
            if run.setup != Setup::Rolling || mu_true > 0.3 {
                continue;
            }
            let model = best.spec.model(&best.result.shared);
            let pair = best
                .spec
                .pair(&best.result.shared, run.setup, run.diameter_m);
            let rel: Vec<f64> = run.t_s.iter().map(|t| (t - own[3]).max(0.0)).collect();
            let tr = groove::physics::simulate_pair(&model, &pair, run.init(own, 1.0), &rel);
            assert!(
                tr.impacts.first().is_some_and(|im| im.slip),
                "{mu_true} {}: first impact sticks",
                run.run
            );
        }
    }
}

/// μ_pp = 1.4 (first impacts stick): the profile's bound or interval contains 1.4 and the
/// words say which; the contact setup's law is the saturating one, parameters within 15 %.
/// (One dataset, seed 33: a 95 % interval misses one draw in twenty by construction, and the
/// fixture's comment says why seed 32 was left; the coverage over seeds is tested below.)
#[test]
fn strong_friction_profile_contains_the_truth_and_the_law_is_recovered() {
    let recs = dataset(&fixture("collision_stick.toml"));
    let summary = analyze(&recs, Groove::CHAPTER, &WholeRunOptions::default());
    let m = &summary.materials[0];
    assert_eq!(m.material, "316");
    assert_ne!(m.status, Termination::MaxIterations, "{:?}", m.notes);
    assert!(m.profile.verdict.contains(1.4), "{:?}", m.profile);
    let words = m.mu_pp_words();
    match m.profile.verdict {
        ProfileVerdict::LowerBound { lo } => {
            assert!(words.contains("bound μ_pp from below at"), "{words}");
            assert!(lo > 0.3 && lo < 1.4, "bound {lo}");
        }
        ProfileVerdict::Interval { .. } => assert!(words.contains("inside it"), "{words}"),
        v => panic!("the recordings should constrain μ_pp: {v:?}"),
    }
    let contact = m
        .restitution
        .iter()
        .find(|c| c.setup == Setup::Contact)
        .unwrap();
    assert_eq!(contact.chosen, LawForm::Saturating, "{contact:?}");
    let law = contact.chosen_candidate().unwrap();
    let (c_inf, v_ref) = (&law.parameters["c_inf"], &law.parameters["v_ref_mps"]);
    assert!((c_inf.value - 0.6).abs() < 0.15 * 0.6, "c_inf {c_inf:?}");
    assert!((v_ref.value - 0.15).abs() < 0.15 * 0.15, "v_ref {v_ref:?}");
    assert!(c_inf.lo() <= c_inf.value && c_inf.value <= c_inf.hi());
    assert!(
        v_ref.lo() <= 0.15 * 1.15 && 0.15 * 0.85 <= v_ref.hi(),
        "{v_ref:?}"
    );
    // every candidate was scored on held-out runs
    assert!(contact.candidates.iter().all(|c| c.heldout_rms_noise > 0.5));
}

/// The single runs' physics of 440c, taken as exact (no standard errors).
fn physics(mu: f64, terms: Vec<Term>) -> BTreeMap<String, (Model, [f64; 3])> {
    [(
        "440c".to_string(),
        (
            Model {
                groove: Groove::CHAPTER,
                friction: Friction::Constant { mu },
                variation: Default::default(),
                terms,
            },
            [0.0; 3],
        ),
    )]
    .into()
}

/// Pairs under a drag the single runs do not share are flagged; pairs under the single runs'
/// own physics are not.
#[test]
fn pairs_under_a_drag_the_single_runs_do_not_share_are_flagged() {
    let finding = |recs: &[Recording], model: BTreeMap<String, (Model, [f64; 3])>| {
        let (findings, _) = check_pairs(recs, &model, Groove::CHAPTER, 80);
        findings
            .into_iter()
            .find(|f| f.effect == "pair_physics_mismatch")
            .unwrap()
    };
    let odd = dataset(&fixture("pair_drag.toml"));
    let f = finding(&odd, physics(0.293, vec![Term::LinearDrag { t_s: 0.06 }]));
    assert!(f.accepted, "{:?}", f.evidence);
    assert_eq!(f.where_["experiment"], serde_json::json!("collision"));
    let same = dataset(&fixture("collision_slip.toml"));
    let f = finding(
        &same,
        physics(
            0.293,
            vec![Term::SaturatingDrag {
                t0_s: 0.0541,
                tp_s_per_mps: 2.66,
            }],
        ),
    );
    assert!(!f.accepted, "{:?}", f.evidence);
}

/// Discovery as the stage runs it (the single runs, then the pairs against their physics), with
/// the light settings of the discovery tests.
fn diagnose(recs: &[Recording], seed: u64) -> groove::discover::Diagnosis {
    let options = groove::discover::Options {
        bootstrap: 12,
        bootstrap_iterations: 5,
        folds: 4,
        max_terms: 3,
        seed,
        ..groove::discover::Options::default()
    };
    let mut d = groove::discover::discover(recs, &options);
    groove::discover::pairs::add_pair_findings(&mut d, recs, Groove::CHAPTER);
    d
}

/// A null recorded at 2 kHz: the pairs' free fit, which contains the held one, never ends above
/// it (from its default start it once ended with T0 at its floor and 18× the held χ², read as a
/// mismatch at p = 0), and the single runs' μ about 1 % high (3σ by the joint fit's errors) is a
/// significant but small difference, not other physics: nothing accepted.
#[test]
fn a_null_at_2_khz_flags_no_pair_physics() {
    let truth = Truth::parse(&fixture("null_2khz.toml")).unwrap();
    let recs = dataset(&fixture("null_2khz.toml"));
    let d = diagnose(&recs, truth.seed);
    let pairs = pair_physics_findings(&d);
    for f in &pairs {
        let gain = f.where_["deviance_gain"].as_f64().unwrap();
        assert!(
            gain >= 0.0,
            "free fit above the held one: {gain} {:?}",
            f.evidence
        );
        assert!(!f.accepted, "{:?} {:?}", f.where_, f.evidence);
        // with the single runs' errors weighed (they were taken as exact when the joint fit's
        // covariance was singular, and the 440c pairs' μ_pg, 1 % off, read p Holm 3e-61)
        assert!(f.evidence.p_holm >= 0.01, "{}", f.evidence.decision);
    }
    // the joint fit's covariance is singular on this dataset (a run whose z0, t0, v0 the data
    // cannot tell apart); the errors come from the information with each run's locals projected
    for (name, e) in &d.model_parameters {
        let se = e.se.unwrap_or(f64::NAN);
        assert!(se.is_finite() && se > 0.0, "{name}: {se}");
    }
    assert!(
        d.findings.iter().all(|f| !f.accepted),
        "{:?}",
        d.findings
            .iter()
            .filter(|f| f.accepted)
            .map(|f| &f.effect)
            .collect::<Vec<_>>()
    );
}

/// A null under correlated tracking noise (AR(1), lag-1 0.6, 1 µm, over 0.2 µm white) flags no
/// pair physics: the free pair fits leave about twice the noise, and their covariances are
/// widened by that misfit (χ² per degree of freedom) besides the residuals' correlation. Before,
/// the 316 pairs' test read p Holm 7e-4 on this seed (now 0.14).
/// `GROOVE_PAIR_AR_SEED=<n>` tries another seed.
#[test]
fn correlated_tracking_noise_is_not_pair_physics() {
    let seed: u64 = std::env::var("GROOVE_PAIR_AR_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(PAIR_AR_SEED);
    let text = fixture("null.toml").replace("noise_m = 1.0e-6", "noise_m = 0.2e-6");
    assert!(text.contains("noise_m = 0.2e-6"));
    let truth = Truth::parse(&text).unwrap();
    let mut recs = dataset(&text);
    noise::with_correlated_noise(&mut recs, 0.6, 1e-6, seed);
    let d = diagnose(&recs, truth.seed);
    let pairs = pair_physics_findings(&d);
    for f in &pairs {
        println!(
            "seed {seed}: {} p Holm {:.2e}",
            f.where_["material"], f.evidence.p_holm
        );
        assert!(
            f.evidence.p_holm >= 0.01,
            "{} {:?}",
            f.evidence.decision,
            f.where_
        );
        assert!(!f.accepted);
    }
}

/// The seed of `correlated_tracking_noise_is_not_pair_physics`.
const PAIR_AR_SEED: u64 = 5;

/// The pair physics test's findings, one per material of the two.
fn pair_physics_findings(
    d: &groove::discover::Diagnosis,
) -> Vec<&groove::artifacts::diagnosis::Finding> {
    let pairs: Vec<_> = d
        .findings
        .iter()
        .filter(|f| f.effect == "pair_physics_mismatch")
        .collect();
    assert_eq!(pairs.len(), 2, "one test per material");
    pairs
}

/// A 2 % error of the length calibration (every position × 1.02, the diameter in runs.csv as it
/// was) is absorbed by the single runs' μ, but moves where the pairs touch: freeing friction and
/// drag read it as a pair physics mismatch on the rolling pairs (μ_pg 3.7 %, the drag time 13 %
/// off, accepted at p Holm 2e-5). Now the contact distance freed with the single runs' physics
/// held fits the pairs better than freeing friction and drag (1.02 × the diameter, within
/// 0.3 %), nothing is accepted, and a note says to check the calibration.
#[test]
fn a_length_calibration_error_is_named_not_read_as_friction() {
    let truth = Truth::parse(&fixture("null.toml")).unwrap();
    let mut recs = dataset(&fixture("null.toml"));
    for track in recs.iter_mut().flat_map(|r| r.tracks.iter_mut()) {
        for z in &mut track.z_m {
            *z *= 1.02;
        }
    }
    let d = diagnose(&recs, truth.seed);
    let accepted: Vec<_> = d.findings.iter().filter(|f| f.accepted).collect();
    assert!(
        accepted.is_empty(),
        "{:?}",
        accepted
            .iter()
            .map(|f| (&f.effect, &f.evidence.decision))
            .collect::<Vec<_>>()
    );
    let rolling = d
        .findings
        .iter()
        .find(|f| f.effect == "pair_physics_mismatch" && f.where_["material"] == "316")
        .expect("the 316 pairs are tested");
    assert!(
        rolling
            .evidence
            .decision
            .starts_with("not friction or drag"),
        "{}",
        rolling.evidence.decision
    );
    let scale = rolling.where_["contact_over_diameter"]["value"]
        .as_f64()
        .unwrap();
    assert!(
        (scale - 1.02).abs() < 0.003,
        "contact at {scale} × the diameter"
    );
    assert!(
        d.note.contains("check the length calibration"),
        "{}",
        d.note
    );
}

/// Timing probe on the shipped data (not a test of results): `cargo test --test
/// collision_wholerun -- --ignored --nocapture probe_shipped`.
#[test]
#[ignore]
fn probe_shipped() {
    use groove::fit::collision::restitution_law::{choose_law, with_chosen};
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let recs = read_dataset_dir(&data, &IngestParams::default()).unwrap();
    for material in ["316", "440c"] {
        let runs = pair_runs(&recs, material);
        let spec = FitSpec::new(Groove::CHAPTER);
        let t = std::time::Instant::now();
        let fit = fit_group(&runs, &spec, None, 80);
        let t_fit = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let choices: Vec<_> = [Setup::Rolling, Setup::Contact]
            .into_iter()
            .filter_map(|s| choose_law(&runs, &fit, s, 3, 25))
            .collect();
        let t_law = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let best = fit_group(&runs, &with_chosen(&spec, &choices), Some(&fit), 80);
        let t_refit = t.elapsed().as_secs_f64();
        let t = std::time::Instant::now();
        let profile = profile_mu_pp(&runs, &best, &default_grid(), 25);
        let t_profile = t.elapsed().as_secs_f64();
        eprintln!(
            "{material}: fit {t_fit:.1} s ({:?}, {} it), laws {t_law:.1} s, refit {t_refit:.1} s, profile {t_profile:.1} s; {:?}; refit {:?}; profile not converged at {:?}, not fitted {:?}, inflation {:.3} (scale {:.3})",
            fit.result.termination,
            fit.result.iterations,
            profile.verdict,
            best.result.termination,
            profile.points.iter().filter(|p| !p.converged).map(|p| p.mu_pp).collect::<Vec<_>>(),
            profile.not_fitted,
            profile.inflation,
            profile.scale_factor
        );
    }
}

/// The true initial conditions of every run of a synthesized dataset (`runs_truth.csv`, read
/// here in the test only): per run, per particle, (z0, v0, va0, t of the first frame).
fn true_inits(truth: &Truth) -> BTreeMap<String, Vec<[f64; 4]>> {
    let mut out: BTreeMap<String, Vec<[f64; 4]>> = BTreeMap::new();
    for line in synth_tables(truth).runs_truth_csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let x = |i: usize| f[i].parse::<f64>().unwrap();
        out.entry(f[0].to_string())
            .or_default()
            .push([x(2), x(3), x(4), x(5)]);
    }
    out
}

/// The whole-run fit's own parameters (striker z, gap, kick speed, kick time) of a run at the
/// truth.
fn true_own(run: &PairRun, init: &[[f64; 4]]) -> Vec<f64> {
    let gap = run.direction * (init[1][0] - init[0][0]) - run.diameter_m;
    vec![init[0][0], gap, init[0][1], -init[0][3]]
}

/// The fit's shared parameters at the truth of the two-setup fixtures (saturating drag and
/// saturating laws, material 316 or 440c).
fn true_shared(truth: &Truth, material: &str) -> Vec<f64> {
    use groove::physics::Restitution;
    let m = truth.material(material).unwrap();
    let Friction::Constant { mu } = m.friction else {
        panic!("constant friction expected")
    };
    let Some(Term::SaturatingDrag { t0_s, tp_s_per_mps }) = truth.physics.terms.first().cloned()
    else {
        panic!("saturating drag expected")
    };
    let law = |r: Restitution| match r {
        Restitution::SpeedDependent { c0, v_ref_mps } => [c0, v_ref_mps.ln()],
        _ => panic!("saturating law expected"),
    };
    let [a, b] = law(m.restitution_rolling);
    let [c, d] = law(m.restitution_contact);
    vec![mu, t0_s.ln(), tp_s_per_mps, truth.pair.mu_pp, a, b, c, d]
}

/// The fit's model is the synthesizer's: at the true parameters (shared and per run) it
/// reproduces noise-free synthesized tracks of both setups, stick (μ_pp = 1.4) and slip
/// (μ_pp = 0.3), to the 1 nm the tables are written with, at every frame of both particles
/// (impact times, post-impact velocities, spin transfer and rolling transitions all enter).
#[test]
fn the_fit_model_at_the_true_parameters_reproduces_noise_free_tracks() {
    use groove::fit::collision::wholerun::residuals;
    for (file, material) in [
        ("collision_stick.toml", "316"),
        ("collision_slip.toml", "440c"),
    ] {
        let text = fixture(file)
            .replace("noise_m = 1.0e-6", "noise_m = 0.0")
            .replace("subpixel = 20", "subpixel = 50000")
            .replace("dropped_frame_rate = 0.003", "dropped_frame_rate = 0.0")
            .replace("outlier_rate = 0.002", "outlier_rate = 0.0");
        let truth = Truth::parse(&text).unwrap();
        assert_eq!(truth.camera.noise_m, 0.0, "{file}: the camera edit missed");
        let inits = true_inits(&truth);
        let shared = true_shared(&truth, material);
        let runs = pair_runs(&dataset(&text), material);
        assert!(runs.len() >= 8, "{file}");
        let spec = FitSpec::new(Groove::from_angle_deg(truth.groove.theta_deg));
        for run in &runs {
            let own = true_own(run, &inits[&run.run]);
            let mut r = vec![0.0; run.n_samples()];
            residuals(run, &spec, &shared, &own, &mut r);
            let worst = r.iter().map(|u| u.abs() * run.sigma_m).fold(0.0, f64::max);
            assert!(worst < 2e-9, "{file} {}: {worst:e} m", run.run);
        }
    }
}

/// Over 16 synthesized stick datasets (μ_pp = 1.4, seeds 33–48 of the stick fixture), the
/// whole-run μ_pp is unbiased (mean within 0.3 % of 1.4, about three standard errors of the
/// mean) and its 95 % profile interval covers 1.4 in at least 13 (a binomial 95 % coverage
/// falls below that with probability 0.7 %; a 1 % bias would leave about a third covered).
#[test]
fn the_mu_pp_profile_is_unbiased_and_covers_the_truth_over_seeds() {
    let text = fixture("collision_stick.toml");
    let spec = FitSpec::new(Groove::CHAPTER);
    let (mut estimates, mut covered) = (Vec::new(), 0);
    for seed in 33..49u64 {
        let t = text.replacen("seed = ", &format!("seed = {seed} # was "), 1);
        let runs = pair_runs(&dataset(&t), "316");
        let best = fit_group(&runs, &spec, None, 80);
        assert!(
            best.converged(),
            "seed {seed}: {:?}",
            best.result.termination
        );
        let profile = profile_mu_pp(&runs, &best, &[1.4], 25);
        estimates.push(best.result.shared[MU_PP]);
        covered += usize::from(profile.verdict.contains(1.4));
        assert!(
            matches!(profile.verdict, ProfileVerdict::Interval { .. }),
            "seed {seed}: {:?}",
            profile.verdict
        );
    }
    let mean = estimates.iter().sum::<f64>() / estimates.len() as f64;
    assert!(
        (mean - 1.4).abs() < 0.004,
        "mean μ_pp {mean}: {estimates:?}"
    );
    assert!(covered >= 13, "{covered} of 16 cover 1.4: {estimates:?}");
}

/// No collision fit of the shipped report ends at its iteration limit: every material's
/// whole-run fit converged and every μ_pp profile fit too (the per-run collision fits are
/// checked in tests/collision.rs). Reads the shipped reports/summary.json, so it follows the
/// regenerated reports.
#[test]
fn no_whole_run_fit_of_the_shipped_report_is_at_its_iteration_limit() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/summary.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let summary: groove::artifacts::summary::Summary = serde_json::from_str(&text)
        .unwrap_or_else(|e| panic!("{}: {e}; regenerate reports/", path.display()));
    let whole = summary.collisions.unwrap().whole_run.unwrap();
    assert_eq!(whole.materials.len(), 2);
    for m in &whole.materials {
        assert!(m.status.is_converged(), "{}: {:?}", m.material, m.status);
        assert!(m.iterations < m.max_iter, "{}", m.material);
        let stuck: Vec<f64> = m
            .profile
            .points
            .iter()
            .filter(|p| !p.converged)
            .map(|p| p.mu_pp)
            .collect();
        assert!(
            stuck.is_empty(),
            "{}: profile fits stuck at {stuck:?}",
            m.material
        );
        assert!(
            matches!(m.profile.verdict, ProfileVerdict::Interval { .. })
                && m.profile.verdict.contains(1.4),
            "{}: {:?}",
            m.material,
            m.profile.verdict
        );
    }
}

/// The impact test's finding of 440c on `recs`, the single runs' physics being the truth's.
fn impact_finding(recs: &[Recording]) -> groove::artifacts::diagnosis::Finding {
    let model = physics(
        0.293,
        vec![Term::SaturatingDrag {
            t0_s: 0.0541,
            tp_s_per_mps: 2.66,
        }],
    );
    let (findings, _) = check_pairs(recs, &model, Groove::CHAPTER, 80);
    findings
        .into_iter()
        .find(|f| f.effect == "impact_specific_mismatch")
        .unwrap()
}

/// Tracking outliers in the few samples after impacts are not an impact misfit (a 2 kHz camera
/// with 0.5 % outliers of 30 µm read 1.52× and was flagged before each squared residual was
/// capped and the runs became the test's units), while a ringing of the pair after its first
/// impact that the impulse rule does not hold (6 µm, 800 Hz, decaying in 2 ms) is flagged.
#[test]
fn outliers_after_impacts_are_not_an_impact_misfit_but_a_ringing_is() {
    let text = fixture("collision_slip.toml")
        .replace("fps = 10000.0", "fps = 2000.0")
        .replace("outlier_rate = 0.002", "outlier_rate = 0.005");
    let clean = dataset(&text);
    let f = impact_finding(&clean);
    assert!(!f.accepted, "{:?}", f.evidence);
    assert!(f.evidence.lr < 1.2, "mean square ratio {}", f.evidence.lr);
    assert!(
        f.where_["runs_tested"].as_u64().unwrap() >= 6,
        "{:?}",
        f.where_
    );
    let ringing: Vec<Recording> = clean
        .iter()
        .cloned()
        .map(|mut r| {
            if r.info.experiment != Experiment::Collision {
                return r;
            }
            // the first impact: where the target (particle 1) has left its start by 10 µm
            // for three frames in a row (one frame could be a tracking outlier)
            let target = r.track(1).unwrap();
            let moved = |z: &f64| (z - target.z_m[0]).abs() > 1e-5;
            let Some(k) = target.z_m.windows(3).position(|w| w.iter().all(moved)) else {
                return r;
            };
            let t_hit = target.t_s[k.saturating_sub(1)];
            for tr in &mut r.tracks {
                for (t, z) in tr.t_s.iter().zip(tr.z_m.iter_mut()) {
                    let dt = t - t_hit;
                    if dt > 0.0 {
                        *z += 6e-6
                            * (-dt / 2e-3).exp()
                            * (2.0 * std::f64::consts::PI * 800.0 * dt).sin();
                    }
                }
            }
            r
        })
        .collect();
    let f = impact_finding(&ringing);
    assert!(f.accepted, "{:?}", f.evidence);
    assert!(f.evidence.lr > 1.3, "mean square ratio {}", f.evidence.lr);
}

/// The shipped truth with `terms` (`[[physics.terms]]` tables) added to the single runs'
/// physics, drawn with seed 1.
fn shipped_truth_with(terms: &str) -> String {
    let shipped = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data/truth/truth.toml"),
    )
    .unwrap();
    let at = shipped.find("[pair]").unwrap();
    format!("{}{terms}{}", &shipped[..at], &shipped[at..])
        .lines()
        .map(|l| {
            if l.starts_with("seed = ") {
                "seed = 1"
            } else {
                l
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The shipped truth with a 2 mm waviness of 0.05 m/s² added, drawn with seed 1.
fn shipped_truth_with_a_wave() -> String {
    shipped_truth_with("[[physics.terms]]\nterm = \"position_force\"\namp_mps2 = 0.05\nwavelength_m = 2.0e-3\nphase_rad = 0.7\n\n")
}

/// The shipped truth with the groove tilted by 0.2° (a = −g sin α ≈ −0.034 m/s² along +z, the
/// tilt of tests/fixtures/truths/groove_tilt.toml), drawn with seed 1.
fn shipped_truth_with_a_tilt() -> String {
    shipped_truth_with("[[physics.terms]]\nterm = \"groove_tilt\"\nalpha_deg = 0.2\n\n")
}

/// Pairs under a 2 mm waviness that the single runs' physics carries: the shipped truth with
/// the wave added (seed 1), its 440c pairs, held at the physics discovery fitted to that
/// dataset's single runs (the wave within 0.4 % of the truth). The pair check must not call
/// it a pair mismatch, the free fit must describe the pairs, and μ_pp with that physics held
/// must be the truth's 1.4 within 2 %. Before the held fit started the free one, the free fit
/// from the defaults ended with T0 at a tenth of the single runs', 9× the noise (174 s), and
/// the pairs were flagged at χ²(3) = 32,063.
#[test]
fn pairs_under_a_carried_waviness_are_not_a_pair_mismatch() {
    let recs = dataset(&shipped_truth_with_a_wave());
    let model = physics(
        0.2933781584412408,
        vec![
            Term::SaturatingDrag {
                t0_s: 0.05408129348071177,
                tp_s_per_mps: 2.6589688142062626,
            },
            Term::PositionForce {
                amp_mps2: 0.050184019748588576,
                wavelength_m: 0.001999470266487831,
                phase_rad: 0.6831867091079138,
            },
        ],
    );
    let (findings, _) = check_pairs(&recs, &model, Groove::CHAPTER, 80);
    let f = findings
        .iter()
        .find(|f| f.effect == "pair_physics_mismatch")
        .expect("the 440c pairs are tested");
    assert!(!f.accepted, "{}", f.evidence.decision);
    let rms_free = f.where_["rms_noise_free"].as_f64().unwrap();
    assert!(rms_free < 1.2, "the free fit leaves {rms_free} × the noise");
    let mu_pp = f.where_["mu_pp_held"]["value"].as_f64().unwrap();
    assert!((mu_pp - 1.4).abs() < 0.02 * 1.4, "μ_pp held {mu_pp}");
}

/// The shipped truth's μ_pg of each material and its μ_pp.
const TRUE_MU_PG: [(&str, f64); 2] = [("316", 0.337), ("440c", 0.293)];
const TRUE_MU_PP: f64 = 1.4;

/// What a known-truth refit test reads: the accepted findings, the baseline's μ_pp profile
/// verdicts and the numbers under the accepted physics.
struct UnderTruth {
    accepted: Vec<(String, String)>,
    baseline: Vec<(String, ProfileVerdict)>,
    under: groove::artifacts::under_accepted::UnderAccepted,
}

/// Discovery (as in the stage, light settings, seed 1), the baseline whole-run analysis, and the
/// refit started from it, with their times printed.
fn refit_against_truth(recs: &[Recording]) -> UnderTruth {
    use groove::fit::refit::under_accepted;
    let started = std::time::Instant::now();
    let d = diagnose(recs, 1);
    let t_discover = started.elapsed().as_secs_f64();
    let accepted = d
        .findings
        .iter()
        .filter(|f| f.accepted)
        .map(|f| (f.effect.clone(), f.form.clone()))
        .collect();
    let opts = WholeRunOptions::default();
    let started = std::time::Instant::now();
    let baseline = analyze(recs, Groove::CHAPTER, &opts);
    let t_baseline = started.elapsed().as_secs_f64();
    let started = std::time::Instant::now();
    let under = under_accepted(&d, recs, Some(&baseline), Groove::CHAPTER, &opts);
    let t_refit = started.elapsed().as_secs_f64();
    eprintln!("discover {t_discover:.1} s, baseline {t_baseline:.1} s, refit {t_refit:.1} s");
    UnderTruth {
        accepted,
        baseline: baseline
            .materials
            .iter()
            .map(|m| (m.material.clone(), m.profile.verdict))
            .collect(),
        under,
    }
}

fn interval(v: &ProfileVerdict) -> Option<(f64, f64, f64)> {
    match *v {
        ProfileVerdict::Interval { estimate, lo, hi } => Some((estimate, lo, hi)),
        _ => None,
    }
}

/// The materials whose baseline μ_pp profile has an interval that excludes the truth (each
/// baseline verdict printed).
fn baseline_misses(t: &UnderTruth) -> Vec<String> {
    let mut out = Vec::new();
    for (m, v) in &t.baseline {
        let b = interval(v);
        eprintln!("{m}: baseline μ_pp {v:?}");
        if b.is_some_and(|(_, lo, hi)| !(lo <= TRUE_MU_PP && TRUE_MU_PP <= hi)) {
            out.push(m.clone());
        }
    }
    out
}

/// Under the accepted physics `effect` is carried, μ_pg of the single runs is within 0.005 of
/// the truth and the whole-run μ_pp within 3 % of it for both materials, with the fit at the
/// noise (each number printed).
fn assert_recovered_under_accepted(t: &UnderTruth, effect: &str) {
    let u = &t.under;
    assert!(u.accepted);
    assert!(u.terms.iter().any(|x| x.effect == effect), "{:?}", u.terms);
    let single = u.single.as_ref().expect("single runs");
    for (m, truth) in TRUE_MU_PG {
        let mu = single.materials[m].mu.value;
        eprintln!("{m}: μ_pg under the accepted physics {mu:.5} (truth {truth})");
        assert!((mu - truth).abs() < 0.005, "{m}: μ_pg {mu}");
    }
    let c = u.collisions.as_ref().expect("collision runs");
    assert!(c.unchanged.is_empty(), "{effect} changes the pair model");
    assert_eq!(c.whole_run.materials.len(), 2, "{:?}", u.notes);
    for m in &c.whole_run.materials {
        let (e, lo, hi) = interval(&m.profile.verdict)
            .unwrap_or_else(|| panic!("{}: {:?}", m.material, m.profile.verdict));
        eprintln!(
            "{}: μ_pp under the accepted physics {e:.3} [{lo:.3}, {hi:.3}], μ_pg {:.5}, RMS/noise {:.3}; notes {:?}",
            m.material, m.mu_pg.value, m.rms_noise, m.notes
        );
        assert!(
            (e - TRUE_MU_PP).abs() < 0.03 * TRUE_MU_PP,
            "{}: μ_pp {e}",
            m.material
        );
        assert!(m.rms_noise < 1.2, "{}: {}", m.material, m.rms_noise);
    }
}

/// The chapter's numbers under the accepted physics: the shipped truth with a 2 mm waviness
/// added (seed 1). Discovery names the drag and the wave; the baseline whole-run fits, which
/// leave the wave out, put μ_pp off the truth's 1.4 with an interval that excludes it for both
/// materials (316 at 1.030 [0.980, 1.064], 440c at 1.572 [1.511, 1.643]); the refit, carrying
/// the wave, must give μ_pp within 3 % of 1.4 for both materials (316 1.411, 440c 1.402), and
/// μ_pg of the single runs within 0.005. (The profile's 95 % interval is the noise's alone: at
/// 316's 1.411 it is [1.407, 1.416], so it is printed, not asserted.) Long (36 min in a dev
/// build on 2 busy cores: discovery 1,391 s, the baseline 148 s, the refit 642 s, whose pair
/// simulations under the wave cost ~100× the baseline's), so run on demand with `--ignored`.
#[test]
#[ignore]
fn under_the_accepted_waviness_mu_pp_is_recovered_where_the_baseline_misses_it() {
    let t = refit_against_truth(&dataset(&shipped_truth_with_a_wave()));
    assert!(
        t.accepted
            .iter()
            .any(|(e, f)| e == "position_dependent_force" && f.starts_with("periodic")),
        "{:?}",
        t.accepted
    );
    assert_eq!(
        baseline_misses(&t),
        ["316", "440c"],
        "the baseline should miss 1.4 for both materials here"
    );
    assert_recovered_under_accepted(&t, "position_dependent_force");
}

/// The same with the groove tilted by 0.2° instead (seed 1): discovery names the tilt; the
/// baseline whole-run fits, which leave it out, miss 1.4 for both materials (measured: 316 at
/// 1.048 [0.978, 1.152], 440c at 0.858 [0.857, 0.896]); the refit carrying the tilt gives μ_pg
/// within 0.005 and μ_pp within 3 % of the truth for both (1.400 [1.397, 1.403] each). About
/// 2 min in a dev build on 2 busy cores (discovery 56 s, the baseline 36 s, the refit 16 s: a
/// tilt acts alike on both particles of a pair, so its pair simulations cost no more than the
/// baseline's), so run on demand with `--ignored` like the waviness test.
#[test]
#[ignore]
fn under_the_accepted_tilt_mu_pp_is_recovered_where_the_baseline_misses_it() {
    let t = refit_against_truth(&dataset(&shipped_truth_with_a_tilt()));
    assert!(
        t.accepted.iter().any(|(e, _)| e == "groove_tilt"),
        "{:?}",
        t.accepted
    );
    assert_eq!(
        baseline_misses(&t),
        ["316", "440c"],
        "the baseline should miss 1.4 for both materials here"
    );
    assert_recovered_under_accepted(&t, "groove_tilt");
}
