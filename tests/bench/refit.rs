//! Bench: the refit stage (the chapter's numbers under the physics discovery accepted) beside the
//! discover stage, on the shipped data and on a larger dataset of `groove synth`: the shipped
//! truth with its run counts scaled to `--runs N` (default 1,000; the shipped mix of single and
//! collision runs) and an extra term the refit must carry into the whole-run pair fits
//! (`--term tilt`, the default: the groove tilted by 0.2°; `--term wave`: a 2 mm waviness of
//! 0.05 m/s², whose pair simulations cost far more). Wall and CPU time of each; the baseline
//! whole-run analysis (the aggregate stage's part, which the refit starts from) is timed beside
//! them. Prints; asserts nothing. In the dev profile (no release build of polars):
//!
//!     RAYON_NUM_THREADS=2 cargo test --locked --features s3 --bench refit [-- --runs N --term tilt|wave --no-shipped]

mod cpu;

use cpu::cpu_s;
use groove::discover::pairs::add_pair_findings;
use groove::discover::{discover, Options};
use groove::fit::collision::whole_summary::{analyze, WholeRunOptions};
use groove::fit::refit::under_accepted;
use groove::ingest::{ingest, IngestParams};
use groove::physics::Groove;
use groove::recording::{Experiment, Recording};
use groove::synth::{synth_tables, Truth};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

/// Seed of the shipped pipeline (`[project] seed` of pipeline.toml).
const SHIPPED_SEED: u64 = 20261122;

/// Wall and CPU seconds of `f`, and its value.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (c0, t0) = (cpu_s(), Instant::now());
    let out = f();
    (out, t0.elapsed().as_secs_f64(), cpu_s() - c0)
}

fn ingested(files: BTreeMap<String, Vec<u8>>) -> Vec<Recording> {
    ingest(&files, &IngestParams::default())
        .expect("the dataset ingests")
        .recordings
}

fn shipped() -> Vec<Recording> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let files = ["runs.csv", "trajectories.csv"]
        .into_iter()
        .map(|n| (n.to_string(), std::fs::read(dir.join(n)).unwrap()))
        .collect();
    ingested(files)
}

/// The shipped truth with every group's `count` scaled so that they add up to `n` (the
/// remainder to the first groups), `term` added to the physics, and seed 1.
fn scaled_truth(n: usize, term: &str) -> String {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data/truth/truth.toml"),
    )
    .unwrap();
    let counts: Vec<usize> = text
        .lines()
        .filter_map(|l| l.strip_prefix("count = ")?.trim().parse().ok())
        .collect();
    let total: usize = counts.iter().sum();
    let mut scaled: Vec<usize> = counts.iter().map(|c| c * n / total).collect();
    let short = n.saturating_sub(scaled.iter().sum());
    for s in scaled.iter_mut().take(short) {
        *s += 1;
    }
    let mut next = scaled.into_iter();
    let extra = match term {
        "tilt" => "[[physics.terms]]\nterm = \"groove_tilt\"\nalpha_deg = 0.2\n\n",
        "wave" => "[[physics.terms]]\nterm = \"position_force\"\namp_mps2 = 0.05\nwavelength_m = 2.0e-3\nphase_rad = 0.7\n\n",
        other => panic!("--term {other}: use tilt or wave"),
    };
    let at = text
        .find("[pair]")
        .expect("the shipped truth has a [pair] table");
    format!("{}{extra}{}", &text[..at], &text[at..])
        .lines()
        .map(|l| {
            if l.starts_with("seed = ") {
                "seed = 1".to_string()
            } else if l.starts_with("count = ") {
                format!("count = {}", next.next().unwrap())
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn synthesized(truth_text: &str) -> Vec<Recording> {
    let tables = synth_tables(&Truth::parse(truth_text).expect("the scaled truth parses"));
    ingested(BTreeMap::from([
        ("runs.csv".to_string(), tables.runs_csv.into_bytes()),
        (
            "trajectories.csv".to_string(),
            tables.trajectories_csv.into_bytes(),
        ),
    ]))
}

/// The discover stage (default options, then the pair check), the baseline whole-run analysis
/// and the refit stage on `recs`; prints one table row.
fn bench(label: &str, recs: &[Recording], seed: u64) {
    let n_pairs = recs
        .iter()
        .filter(|r| r.info.experiment == Experiment::Collision)
        .count();
    let opts = Options {
        seed,
        ..Options::default()
    };
    let (d, t_disc, c_disc) = timed(|| {
        let mut d = discover(recs, &opts);
        add_pair_findings(&mut d, recs, Groove::CHAPTER);
        d
    });
    let whole = WholeRunOptions::default();
    let (baseline, t_base, c_base) = timed(|| analyze(recs, Groove::CHAPTER, &whole));
    let (u, t_refit, c_refit) =
        timed(|| under_accepted(&d, recs, Some(&baseline), Groove::CHAPTER, &whole));
    let terms: Vec<&str> = u.terms.iter().map(|t| t.effect.as_str()).collect();
    let refitted: Vec<String> = u
        .collisions
        .as_ref()
        .map(|c| {
            c.whole_run
                .materials
                .iter()
                .filter(|m| !c.unchanged.contains(&m.material))
                .map(|m| format!("{} μ_pp {:.3}", m.material, m.mu_pp.value))
                .collect()
        })
        .unwrap_or_default();
    println!(
        "| {label} | {} ({n_pairs} pairs) | {t_disc:.1} / {c_disc:.1} | {t_base:.1} / {c_base:.1} | {t_refit:.2} / {c_refit:.2} | {:.3} | {terms:?}; refitted: {refitted:?} |",
        recs.len(),
        t_refit / t_disc,
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let value = |flag: &str| {
        args.iter()
            .position(|a| a == flag)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let n: usize = value("--runs").map_or(1000, |v| v.parse().expect("--runs N"));
    let term = value("--term").unwrap_or_else(|| "tilt".into());
    println!(
        "refit bench, {} rayon threads, {} cores",
        rayon::current_num_threads(),
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    println!("| dataset | runs | discover s (wall / CPU) | baseline whole-run s | refit s | refit / discover | carried; refitted |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    if !args.iter().any(|a| a == "--no-shipped") {
        bench("shipped data", &shipped(), SHIPPED_SEED);
    }
    let recs = synthesized(&scaled_truth(n, &term));
    bench(&format!("shipped truth × {n} runs, {term}"), &recs, 1);
}
