//! Stage contracts: the bytes of every artifact that crosses a stage boundary, made by the stage
//! kinds themselves on a small synthesized dataset (tests/fixtures/truths/e2e_small.toml), are
//! pinned in tests/golden/, and each reads back into its `groove::artifacts` type and writes the
//! same bytes again, so a renamed or reordered field shows in review. The README's contract block
//! is generated from the same types.
//!
//! After an intended contract change: `GROOVE_BLESS=1 cargo test --test contracts`, then review
//! the diff of tests/golden/.

use groove::artifacts::{self, contract};
use groove::engine::stage::{Artifact, StageInput, StageKind};
use groove::stages;
use groove::synth::{synth_tables, Truth};
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

const SEED: u64 = 20261122;

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Compare `bytes` with tests/golden/`name` (or write it under GROOVE_BLESS=1).
fn golden(name: &str, bytes: &[u8]) {
    let path = repo().join("tests/golden").join(name);
    if std::env::var_os("GROOVE_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, bytes).unwrap();
        return;
    }
    let want = std::fs::read(&path).unwrap_or_else(|_| {
        panic!("tests/golden/{name} is missing; run GROOVE_BLESS=1 cargo test --test contracts")
    });
    assert!(
        want == bytes,
        "{name} differs from tests/golden/{name}: a stage contract changed; if intended, run \
         GROOVE_BLESS=1 cargo test --test contracts and review the diff\n--- got:\n{}",
        String::from_utf8_lossy(bytes)
    );
}

/// The bytes read into the artifact type and written again, compact or pretty as the writer does.
fn round_trip<T: DeserializeOwned + Serialize>(name: &str, bytes: &[u8], pretty: bool) {
    let value: T = artifacts::from_json(name, bytes).unwrap();
    let mut again = if pretty {
        serde_json::to_vec_pretty(&value).unwrap()
    } else {
        serde_json::to_vec(&value).unwrap()
    };
    if pretty {
        again.push(b'\n');
    }
    assert!(
        again == bytes,
        "{name} does not survive its type: reading and writing it changes the bytes"
    );
}

fn run(
    kind: &dyn StageKind,
    inputs: &BTreeMap<&str, &Artifact>,
    item: Option<&str>,
) -> BTreeMap<String, Artifact> {
    let params = toml::Table::new();
    kind.run(&StageInput {
        params: &params,
        inputs: inputs.clone(),
        item,
        seed: SEED,
        progress: None,
        put_item: None,
        memo: None,
    })
    .unwrap_or_else(|e| panic!("stage {} failed: {}", kind.kind(), e.0))
}

fn file(a: &Artifact) -> &[u8] {
    match a {
        Artifact::File(b) => b,
        Artifact::Collection(_) | Artifact::InStore(_) | Artifact::OnDisk(_) => {
            panic!("a file was expected")
        }
    }
}

fn items(a: &Artifact) -> &BTreeMap<String, Vec<u8>> {
    match a {
        Artifact::Collection(m) => m,
        Artifact::File(_) | Artifact::InStore(_) | Artifact::OnDisk(_) => {
            panic!("a collection was expected")
        }
    }
}

/// Every artifact of ingest → fit → aggregate → simulate → compare → validate on the small dataset.
struct Made {
    skipped: Vec<u8>,
    fits: BTreeMap<String, Vec<u8>>,
    summary: Vec<u8>,
    fits_csv: Vec<u8>,
    residuals: BTreeMap<String, Vec<u8>>,
    comparison: Vec<u8>,
    validation: Vec<u8>,
    under_accepted: Vec<u8>,
}

fn made() -> Made {
    let truth_text =
        std::fs::read_to_string(repo().join("tests/fixtures/truths/e2e_small.toml")).unwrap();
    let truth = Truth::parse(&truth_text).unwrap();
    let tables = synth_tables(&truth);
    let dataset = Artifact::Collection(BTreeMap::from([
        ("runs.csv".to_string(), tables.runs_csv.into_bytes()),
        (
            "trajectories.csv".to_string(),
            tables.trajectories_csv.into_bytes(),
        ),
    ]));
    let ingest = run(
        &stages::ingest::Ingest,
        &BTreeMap::from([("dataset", &dataset)]),
        None,
    );
    let runs = items(&ingest["runs"]);
    let mut fits = BTreeMap::new();
    let mut residuals = BTreeMap::new();
    for (item, rec) in runs {
        let rec_a = Artifact::File(rec.clone());
        let fit = run(
            &stages::fit::Fit,
            &BTreeMap::from([("runs", &rec_a)]),
            Some(item),
        );
        let fit_bytes = file(&fit["fits"]).to_vec();
        let fit_a = Artifact::File(fit_bytes.clone());
        let sim = run(
            &stages::simulate::Simulate,
            &BTreeMap::from([("runs", &rec_a), ("fits", &fit_a)]),
            Some(item),
        );
        residuals.insert(item.clone(), file(&sim["residuals"]).to_vec());
        fits.insert(item.clone(), fit_bytes);
    }
    let fits_a = Artifact::Collection(fits.clone());
    let runs_a = ingest["runs"].clone();
    let agg = run(
        &stages::aggregate::Aggregate,
        &BTreeMap::from([("fits", &fits_a), ("runs", &runs_a)]),
        None,
    );
    let residuals_a = Artifact::Collection(residuals.clone());
    let cmp = run(
        &stages::compare::Compare,
        &BTreeMap::from([("residuals", &residuals_a)]),
        None,
    );
    // validation against this dataset's truth; the diagnosis is the shipped one (discovery is
    // too slow for this test and its contract is pinned by the shipped reports/)
    let truth_a = Artifact::File(truth_text.into_bytes());
    let diagnosis_a = Artifact::File(std::fs::read(repo().join("reports/diagnosis.json")).unwrap());
    let val = run(
        &stages::validate::Validate,
        &BTreeMap::from([
            ("truth", &truth_a),
            ("summary", &agg["summary"]),
            ("diagnosis", &diagnosis_a),
        ]),
        None,
    );
    // the refit under the shipped diagnosis' accepted physics (a saturating drag, which the
    // whole-run fits already carry: their numbers are kept, nothing is fitted again)
    let refit = run(
        &stages::refit::Refit,
        &BTreeMap::from([
            ("diagnosis", &diagnosis_a),
            ("runs", &runs_a),
            ("summary", &agg["summary"]),
        ]),
        None,
    );
    Made {
        under_accepted: file(&refit["physics"]).to_vec(),
        skipped: file(&ingest["skipped"]).to_vec(),
        fits,
        summary: file(&agg["summary"]).to_vec(),
        fits_csv: file(&agg["fits_csv"]).to_vec(),
        residuals,
        comparison: file(&cmp["comparison"]).to_vec(),
        validation: file(&val["validation"]).to_vec(),
    }
}

/// The first item whose bytes contain `marker` (e.g. the experiment tag).
fn first_with<'a>(m: &'a BTreeMap<String, Vec<u8>>, marker: &str) -> (&'a str, &'a [u8]) {
    m.iter()
        .find(|(_, b)| String::from_utf8_lossy(b).contains(marker))
        .map(|(k, v)| (k.as_str(), v.as_slice()))
        .unwrap_or_else(|| panic!("no item with {marker}"))
}

#[test]
fn every_stage_artifact_is_pinned_and_reads_back_into_its_type() {
    let m = made();
    golden("skipped.json", &m.skipped);
    round_trip::<Vec<artifacts::Skipped>>("skipped", &m.skipped, true);

    let (_, single) = first_with(&m.fits, r#""experiment":"single""#);
    let (_, collision) = first_with(&m.fits, r#""experiment":"collision""#);
    golden("fit_single.json", single);
    golden("fit_collision.json", collision);
    for (item, bytes) in &m.fits {
        round_trip::<artifacts::RunFit>(&format!("fits item {item}"), bytes, false);
    }

    golden("summary.json", &m.summary);
    round_trip::<artifacts::Summary>("summary", &m.summary, true);

    golden("fits.csv", &m.fits_csv);
    let csv = String::from_utf8(m.fits_csv.clone()).unwrap();
    let rows = artifacts::fits_table::parse(&csv).unwrap();
    assert_eq!(rows.len(), csv.lines().count() - 1);
    assert!(rows
        .iter()
        .all(|r| r.v0_mps.is_some() && !r.status.is_empty()));

    let (item, single_res) = first_with(&m.residuals, r#""experiment":"single""#);
    golden("residuals_single.json", single_res);
    for (item, bytes) in &m.residuals {
        round_trip::<artifacts::RunResiduals>(&format!("residuals item {item}"), bytes, false);
    }
    assert!(m.fits.contains_key(item));

    golden("comparison.json", &m.comparison);
    round_trip::<artifacts::Comparison>("comparison", &m.comparison, true);

    golden("validation.json", &m.validation);
    round_trip::<artifacts::Validation>("validation", &m.validation, true);

    golden("under_accepted_physics.json", &m.under_accepted);
    round_trip::<artifacts::under_accepted::UnderAccepted>(
        "under_accepted_physics",
        &m.under_accepted,
        true,
    );
}

#[test]
fn the_shipped_published_files_read_back_into_their_types() {
    let reports = repo().join("reports");
    round_trip::<artifacts::Summary>(
        "reports/summary.json",
        &std::fs::read(reports.join("summary.json")).unwrap(),
        true,
    );
    round_trip::<artifacts::Diagnosis>(
        "reports/diagnosis.json",
        &std::fs::read(reports.join("diagnosis.json")).unwrap(),
        true,
    );
    round_trip::<artifacts::under_accepted::UnderAccepted>(
        "reports/under_accepted_physics.json",
        &std::fs::read(reports.join("under_accepted_physics.json")).unwrap(),
        true,
    );
    let csv = std::fs::read_to_string(reports.join("fits.csv")).unwrap();
    assert!(csv.starts_with(&format!("{}\n", artifacts::fits_table::HEADER)));
    assert_eq!(
        artifacts::fits_table::parse(&csv).unwrap().len(),
        csv.lines().count() - 1
    );
}

#[test]
fn a_validation_without_truth_and_a_provenance_record_keep_their_shape() {
    let none = serde_json::to_string(&artifacts::Validation::no_truth()).unwrap();
    assert_eq!(none, r#"{"truth":false}"#);
    // the engine's layout (engine::provenance), field for field
    let p = br#"{"groove_version":"0.1.0","code_commit":"abc","fingerprints":{"fit":"f1"},"seed":7,"inputs":[{"path":"${data}/runs.csv","sha256":"00"}],"stages":[{"stage":"fit","kind":"fit","key":"k"}],"params":{"fit":{"max_iter":200},"report":{"title":"t"}}}"#;
    round_trip::<artifacts::Provenance>("provenance", p, false);
    let renamed = String::from_utf8_lossy(p).replace("code_commit", "commit");
    assert!(
        artifacts::from_json::<artifacts::Provenance>("provenance", renamed.as_bytes())
            .unwrap_err()
            .contains("rerun")
    );
}

#[test]
fn the_readme_states_the_contract_the_types_define() {
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let block = contract::markdown();
    assert!(
        readme.contains(&block),
        "README.md's contract block is not what src/artifacts defines; replace the block between \
         the contract markers with:\n{block}"
    );
}
