//! Whole-run pair fits on synthesized collision datasets of known truth (`groove synth` truth
//! files in tests/fixtures/truths/): μ_pp from slipping first impacts within 10 %, the μ_pp
//! profile's bound or interval containing the chapter's 1.4 when first impacts stick, the
//! restitution law chosen by held-out error with parameters within 15 %.

use groove::discover::pairs::check_pairs;
use groove::fit::collision::profile::{default_grid, profile_mu_pp, ProfileVerdict};
use groove::fit::collision::whole_summary::{analyze, WholeRunOptions};
use groove::fit::collision::wholerun::{fit_group, FitSpec, LawForm, PairRun, MU_PP};
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

/// μ_pp = 1.4 (first impacts stick): the profile's bound or interval contains 1.4 and the
/// words say which; the contact setup's law is the saturating one, parameters within 15 %.
#[test]
#[ignore = "known failure, issue 15 open: fully converged (active-set bounds), the whole-run fit gives mu_pp = 1.387 [1.3785, 1.3956] on this synthetic stick set, 1 % below the truth 1.4, with white residuals (lag-1 rho -0.01): a bias between synth and the fit model not yet found; run with -- --ignored"]
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
    let (c_inf, v_ref) = (&law.parameters[0], &law.parameters[1]);
    assert!((c_inf.value - 0.6).abs() < 0.15 * 0.6, "c_inf {c_inf:?}");
    assert!((v_ref.value - 0.15).abs() < 0.15 * 0.15, "v_ref {v_ref:?}");
    assert!(c_inf.lo <= c_inf.value && c_inf.value <= c_inf.hi);
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

/// Timing probe on the shipped data (not a test of results): `cargo test --test
/// collision_wholerun -- --ignored --nocapture`.
#[test]
#[ignore]
fn probe_shipped() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let recs = read_dataset_dir(&data, &IngestParams::default()).unwrap();
    for material in ["316", "440c"] {
        let runs = pair_runs(&recs, material);
        let t = std::time::Instant::now();
        let fit = fit_group(&runs, &FitSpec::new(Groove::CHAPTER), None, 80);
        eprintln!(
            "{material}: {:?} in {} iterations, {:.1} s; shared {:?} cost {:.0} n {}",
            fit.result.termination,
            fit.result.iterations,
            t.elapsed().as_secs_f64(),
            fit.result.shared,
            fit.cost(),
            runs.iter().map(|r| r.n_samples()).sum::<usize>()
        );
    }
}
