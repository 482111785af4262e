//! Bench: the whole discovery (and the discover stage's pair check) on the shipped data and on
//! two 60-run `groove synth` datasets, with wall and CPU time beside the figures before issue 11's
//! speed work. Prints; asserts nothing. Run it in the dev profile (no release build of polars):
//!
//!     RAYON_NUM_THREADS=2 cargo test --locked --features s3 --bench discover

mod cpu;

use cpu::cpu_s;
use groove::discover::pairs::add_pair_findings;
use groove::discover::{discover, Diagnosis, Options};
use groove::ingest::{ingest, IngestParams};
use groove::recording::Recording;
use groove::synth::{synth_tables, Truth};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// Seed of the shipped pipeline (`[project] seed` of pipeline.toml).
const SHIPPED_SEED: u64 = 20261122;

/// The figures before (main at f6c06e9, the same 2-core machine under a load average of ≈ 10,
/// `groove run discover --force discover` with RAYON_NUM_THREADS=2): (CPU s, wall s) of the
/// discover stage.
const BEFORE: [(&str, f64, f64); 3] = [
    ("shipped data (pair check included)", 31.8, 64.8),
    ("60 runs, tilt + waviness", 22.8, 47.0),
    ("60 runs, nothing missing", 8.6, 17.6),
];

fn read_dataset(dir: &Path) -> Vec<Recording> {
    let mut files = BTreeMap::new();
    for name in ["runs.csv", "trajectories.csv"] {
        files.insert(
            name.to_string(),
            std::fs::read(dir.join(name)).expect("the dataset's CSV files"),
        );
    }
    ingest(&files, &IngestParams::default())
        .expect("the dataset ingests")
        .recordings
}

fn synthesized(name: &str) -> (Vec<Recording>, u64) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/truths")
        .join(format!("{name}.toml"));
    let truth = Truth::parse(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let tables = synth_tables(&truth);
    let mut files = BTreeMap::new();
    files.insert("runs.csv".to_string(), tables.runs_csv.into_bytes());
    files.insert(
        "trajectories.csv".to_string(),
        tables.trajectories_csv.into_bytes(),
    );
    let recs = ingest(&files, &IngestParams::default())
        .expect("a synthesized dataset ingests")
        .recordings;
    (recs, truth.seed)
}

/// Discovery as the stage runs it (default options, the pair check after); prints its times.
fn bench(label: &str, recs: &[Recording], seed: u64, before: (f64, f64)) {
    let opts = Options {
        seed,
        ..Options::default()
    };
    let (c0, t0) = (cpu_s(), Instant::now());
    let mut d: Diagnosis = discover(recs, &opts);
    let (c1, t1) = (cpu_s(), t0.elapsed().as_secs_f64());
    add_pair_findings(&mut d, recs, groove::physics::Groove::CHAPTER);
    let (c2, t2) = (cpu_s(), t0.elapsed().as_secs_f64());
    let accepted: Vec<&str> = d
        .findings
        .iter()
        .filter(|f| f.accepted)
        .map(|f| f.effect.as_str())
        .collect();
    let replicates: Vec<usize> = d
        .candidates
        .iter()
        .map(|c| c.evidence.bootstrap_replicates)
        .collect();
    println!("{label}: {} runs used, accepted {accepted:?}", d.runs_used);
    println!(
        "  discovery {:6.1} s CPU {:6.1} s wall; with the pair check {:6.1} s CPU {:6.1} s wall (before: {:.1} s CPU, {:.1} s wall)",
        c1 - c0,
        t1,
        c2 - c0,
        t2,
        before.0,
        before.1
    );
    println!("  replicates per candidate row: {replicates:?}");
}

fn main() {
    println!(
        "discovery bench, {} rayon threads; target: the whole discovery <= 15 s on the shipped data and <= 10 s on 60 runs (wall, 2 idle cores)",
        rayon::current_num_threads()
    );
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let shipped = read_dataset(&root.join("data"));
    bench(
        BEFORE[0].0,
        &shipped,
        SHIPPED_SEED,
        (BEFORE[0].1, BEFORE[0].2),
    );
    for (i, name) in [(1, "two_effects"), (2, "null")] {
        let (recs, seed) = synthesized(name);
        bench(BEFORE[i].0, &recs, seed, (BEFORE[i].1, BEFORE[i].2));
    }
}
