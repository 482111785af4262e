//! The aggregate stage reads only the collision recordings (`fit:pair_runs`): the same summary and fits.csv as with every recording bound.

use groove::engine::stage::{Artifact, StageInput, StageKind};
use groove::ingest::{ingest_items, IngestParams};
use groove::recording::{item::decode_info, Experiment};
use groove::stages::{aggregate::Aggregate, fit::Fit};
use std::collections::BTreeMap;
use std::path::Path;

fn input<'a>(
    params: &'a toml::Table,
    inputs: BTreeMap<&'a str, &'a Artifact>,
    item: Option<&'a str>,
) -> StageInput<'a> {
    StageInput {
        params,
        inputs,
        item,
        seed: 11,
        progress: None,
        put_item: None,
        memo: None,
    }
}

fn file(out: &BTreeMap<String, Artifact>, name: &str) -> Vec<u8> {
    match &out[name] {
        Artifact::File(b) => b.clone(),
        Artifact::Collection(_) | Artifact::InStore(_) | Artifact::OnDisk(_) => {
            panic!("`{name}` should be a file")
        }
    }
}

/// Six single runs and two collision runs of the shipped dataset, as `ingest:runs` items.
fn some_runs() -> BTreeMap<String, Vec<u8>> {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let files: BTreeMap<String, Vec<u8>> = ["runs.csv", "trajectories.csv"]
        .iter()
        .map(|f| (f.to_string(), std::fs::read(data.join(f)).unwrap()))
        .collect();
    let all = ingest_items(&files, &IngestParams::default()).unwrap().runs;
    let (mut singles, mut pairs) = (0, 0);
    all.into_iter()
        .filter(|(_, b)| match decode_info(b).unwrap().experiment {
            Experiment::Single => {
                singles += 1;
                singles <= 6
            }
            Experiment::Collision => {
                pairs += 1;
                pairs <= 2
            }
        })
        .collect()
}

#[test]
fn aggregate_from_pair_runs_equals_aggregate_from_every_recording() {
    let params = toml::Table::new();
    let runs = some_runs();
    assert_eq!(
        runs.len(),
        8,
        "the shipped data has 6 single and 2 collision runs"
    );
    let (mut fits, mut pair_runs) = (BTreeMap::new(), BTreeMap::new());
    for (item, bytes) in &runs {
        let rec = Artifact::File(bytes.clone());
        let out = Fit
            .run(&input(&params, [("runs", &rec)].into(), Some(item)))
            .unwrap();
        let pair = file(&out, "pair_runs");
        match decode_info(bytes).unwrap().experiment {
            Experiment::Single => assert!(
                pair.is_empty(),
                "{item}: a single run's pair_runs item is empty"
            ),
            Experiment::Collision => assert_eq!(
                &pair, bytes,
                "{item}: a collision run's pair_runs item is its recording"
            ),
        }
        fits.insert(item.clone(), file(&out, "fits"));
        pair_runs.insert(item.clone(), pair);
    }
    let fits = Artifact::Collection(fits);
    let every = Artifact::Collection(runs);
    let only_pairs = Artifact::Collection(pair_runs.clone());
    let whole = Aggregate
        .run(&input(
            &params,
            [("fits", &fits), ("runs", &every)].into(),
            None,
        ))
        .unwrap();
    let light = Aggregate
        .run(&input(
            &params,
            [("fits", &fits), ("runs", &only_pairs)].into(),
            None,
        ))
        .unwrap();
    for name in ["summary", "fits_csv"] {
        assert_eq!(file(&whole, name), file(&light, name), "{name} differs");
    }
    let summary: serde_json::Value = serde_json::from_slice(&file(&light, "summary")).unwrap();
    assert_eq!(summary["collisions"]["n_runs"], 2, "{summary}");
    assert_eq!(summary["single"]["n_runs"], 6, "{summary}");

    // A collision run whose recording is missing is named, with the binding to use.
    let (gone, _) = pair_runs.iter().find(|(_, b)| !b.is_empty()).unwrap();
    let gone = gone.clone();
    pair_runs.insert(gone.clone(), Vec::new());
    let broken = Artifact::Collection(pair_runs);
    let Err(err) = Aggregate.run(&input(
        &params,
        [("fits", &fits), ("runs", &broken)].into(),
        None,
    )) else {
        panic!("a missing collision recording fails the stage");
    };
    assert!(
        err.0.contains(&gone) && err.0.contains("fit:pair_runs"),
        "{}",
        err.0
    );
}
