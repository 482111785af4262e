//! The aggregate stage reads only the collision recordings (`fit:pair_runs`): the same summary and
//! fits.csv as with every recording bound; and its memo of material summaries gives the summary
//! made without it.

use groove::engine::stage::{Artifact, ObjectMemo, StageInput, StageKind};
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

/// The shipped dataset's runs as `ingest:runs` items.
fn shipped_runs() -> BTreeMap<String, Vec<u8>> {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let files: BTreeMap<String, Vec<u8>> = ["runs.csv", "trajectories.csv"]
        .iter()
        .map(|f| (f.to_string(), std::fs::read(data.join(f)).unwrap()))
        .collect();
    ingest_items(&files, &IngestParams::default()).unwrap().runs
}

/// Six single runs and two collision runs of the shipped dataset, as `ingest:runs` items.
fn some_runs() -> BTreeMap<String, Vec<u8>> {
    let all = shipped_runs();
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

/// The stage's memo as the engine keeps it: keys → objects, objects by sha256.
#[derive(Default)]
struct Kept {
    keys: std::sync::Mutex<BTreeMap<[u8; 32], String>>,
    objects: std::sync::Mutex<BTreeMap<String, Vec<u8>>>,
    puts: std::sync::atomic::AtomicUsize,
}

impl ObjectMemo for Kept {
    fn get(&self, key: &[u8; 32]) -> Option<String> {
        self.keys.lock().unwrap().get(key).cloned()
    }

    fn put(&self, key: [u8; 32], sha256: &str) {
        self.puts.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.keys.lock().unwrap().insert(key, sha256.to_string());
    }

    fn read(&self, sha256: &str) -> Option<Vec<u8>> {
        self.objects.lock().unwrap().get(sha256).cloned()
    }
}

/// `t_drag_s` of a fit's JSON, wherever it sits, times 1.01.
fn slower(v: &mut serde_json::Value) {
    if let Some(map) = v.as_object_mut() {
        for (k, x) in map.iter_mut() {
            match x.as_f64() {
                Some(t) if k == "t_drag_s" => *x = serde_json::json!(t * 1.01),
                _ => slower(x),
            }
        }
    }
}

/// With a memo of material summaries the summary is the one made without it, byte for byte:
/// the first run keeps each material's summary and the pooled one; a second run takes all of
/// them from the memo; after one fit of 440c changed, 316's summary is taken and only 440c's and
/// the pooled one are made again.
#[test]
fn the_memo_of_material_summaries_gives_the_summary_made_without_it() {
    let params = toml::Table::new();
    // four single runs of each material
    let mut counts = BTreeMap::new();
    let runs: BTreeMap<String, Vec<u8>> = shipped_runs()
        .into_iter()
        .filter(|(_, b)| {
            let info = decode_info(b).unwrap();
            let n = counts.entry(info.material.clone()).or_insert(0);
            *n += usize::from(info.experiment == Experiment::Single);
            info.experiment == Experiment::Single && *n <= 4
        })
        .collect();
    let mut fits = BTreeMap::new();
    for (item, bytes) in &runs {
        let rec = Artifact::File(bytes.clone());
        let out = Fit
            .run(&input(&params, [("runs", &rec)].into(), Some(item)))
            .unwrap();
        fits.insert(item.clone(), file(&out, "fits"));
    }
    let empty: BTreeMap<String, Vec<u8>> = runs.keys().map(|k| (k.clone(), Vec::new())).collect();
    let pair_runs = Artifact::Collection(empty);
    let summary = |fits: &BTreeMap<String, Vec<u8>>, memo: Option<&Kept>| {
        let fits = Artifact::Collection(fits.clone());
        let put_item = |bytes: &[u8]| {
            let sha = groove::engine::hashing::sha256_hex(bytes);
            if let Some(m) = memo {
                m.objects
                    .lock()
                    .unwrap()
                    .insert(sha.clone(), bytes.to_vec());
            }
            Ok(sha)
        };
        let mut i = input(
            &params,
            [("fits", &fits), ("runs", &pair_runs)].into(),
            None,
        );
        i.put_item = Some(&put_item);
        i.memo = memo.map(|m| m as &dyn ObjectMemo);
        file(&Aggregate.run(&i).unwrap(), "summary")
    };
    let kept = Kept::default();
    let puts = || kept.puts.load(std::sync::atomic::Ordering::Relaxed);
    let want = summary(&fits, None);
    let said: serde_json::Value = serde_json::from_slice(&want).unwrap();
    assert_eq!(said["single"]["materials"].as_object().unwrap().len(), 2);
    assert_eq!(summary(&fits, Some(&kept)), want);
    assert_eq!(puts(), 3, "two materials and the pooled summary");
    assert_eq!(summary(&fits, Some(&kept)), want);
    assert_eq!(puts(), 3, "all three found");

    let (item, _) = fits
        .iter()
        .find(|(_, b)| String::from_utf8_lossy(b).contains("440c"))
        .unwrap();
    let mut fit: serde_json::Value = serde_json::from_slice(&fits[item]).unwrap();
    slower(&mut fit);
    let mut edited = fits.clone();
    edited.insert(item.clone(), serde_json::to_vec(&fit).unwrap());
    let want_edited = summary(&edited, None);
    assert_ne!(want_edited, want);
    assert_eq!(summary(&edited, Some(&kept)), want_edited);
    assert_eq!(
        puts(),
        5,
        "440c and the pooled summary made again, 316 found"
    );
}
