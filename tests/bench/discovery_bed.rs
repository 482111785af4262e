//! The randomized discovery bench: draws datasets with the independent simulator (150 with one
//! or two effects in every place, 50 nulls, every noise model), runs each through the whole
//! pipeline, scores diagnosis.json against the truth and prints tables per place, shape and
//! noise model. Results are appended to a file, one line per dataset, so the set can be run in
//! chunks and resumed.
//!
//! Usage: cargo bench --bench discovery_bed -- --groove BIN [--quick] [--from N] [--to M]
//!        [--results FILE] [--work DIR] [--keep] [--table] [--draw]
//! (`--draw` prints the drawn datasets, their effects and true sizes, and runs nothing;
//! `--pipeline FILE` runs each dataset with that pipeline.toml instead of this checkout's, for a
//! binary built from another commit.)
//! (tests/bench/discovery_bed.sh builds the release binary and calls this.)

#[allow(dead_code)]
#[path = "../support/indsim/mod.rs"]
mod indsim;

#[allow(dead_code)]
#[path = "../support/bed/mod.rs"]
mod bed;

use bed::draw::{draw, FULL, FULL_SIZE, QUICK_SIZE};
use bed::pipeline::run_case;
use bed::table::{read, tables};
use std::io::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// The quick subset: a force, a friction effect and a null, on small datasets.
pub const QUICK: [usize; 3] = [0, 1, 3];

struct Args {
    groove: Option<PathBuf>,
    quick: bool,
    from: usize,
    to: usize,
    results: PathBuf,
    work: PathBuf,
    keep: bool,
    table_only: bool,
    draw_only: bool,
    pipeline: Option<PathBuf>,
}

fn usage(msg: &str) -> ! {
    eprintln!("discovery_bed: {msg}");
    eprintln!("usage: discovery_bed --groove BIN [--quick] [--from N] [--to M] [--results FILE] [--work DIR] [--keep] [--table] [--draw] [--pipeline FILE]");
    std::process::exit(2)
}

fn parse() -> Args {
    let target = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".to_string());
    let mut a = Args {
        groove: std::env::var_os("GROOVE_BIN").map(PathBuf::from),
        quick: false,
        from: 0,
        to: usize::MAX,
        results: PathBuf::new(),
        work: PathBuf::from(&target).join("discovery_bed"),
        keep: false,
        table_only: false,
        draw_only: false,
        pipeline: None,
    };
    let mut it = std::env::args().skip(1);
    let mut results = None;
    while let Some(arg) = it.next() {
        let mut value = |name: &str| {
            it.next()
                .unwrap_or_else(|| usage(&format!("{name} needs a value")))
        };
        let number = |s: String, name: &str| {
            s.parse::<usize>()
                .unwrap_or_else(|_| usage(&format!("{name} takes a whole number, not {s:?}")))
        };
        match arg.as_str() {
            "--groove" => a.groove = Some(PathBuf::from(value("--groove"))),
            "--quick" => a.quick = true,
            "--from" => a.from = number(value("--from"), "--from"),
            "--to" => a.to = number(value("--to"), "--to"),
            "--results" => results = Some(PathBuf::from(value("--results"))),
            "--work" => a.work = PathBuf::from(value("--work")),
            "--keep" => a.keep = true,
            "--table" => a.table_only = true,
            "--draw" => a.draw_only = true,
            "--pipeline" => a.pipeline = Some(PathBuf::from(value("--pipeline"))),
            "--bench" => {} // passed by `cargo bench`
            other => usage(&format!("unknown argument {other:?}")),
        }
    }
    let name = if a.quick {
        "results-quick.jsonl"
    } else {
        "results.jsonl"
    };
    a.results = results.unwrap_or_else(|| a.work.join(name));
    a
}

fn fail(msg: String) -> ! {
    eprintln!("discovery_bed: {msg}");
    std::process::exit(1)
}

/// The end of the full set's indices: `FULL`, or `--to` beyond it. Indices from `FULL` on are
/// draws of the same law that no session scored before, a sample the method was not tuned on
/// (`--from 200 --to 264`).
fn end_of(args: &Args) -> usize {
    if args.to == usize::MAX {
        FULL
    } else {
        FULL.max(args.to)
    }
}

/// Prints each drawn dataset of the selection: its noise and its effects with their true sizes.
fn print_draws(args: &Args) {
    let (indices, size) = if args.quick {
        (QUICK.to_vec(), QUICK_SIZE)
    } else {
        ((0..end_of(args)).collect::<Vec<_>>(), FULL_SIZE)
    };
    for index in indices
        .into_iter()
        .filter(|&i| i >= args.from && i < args.to)
    {
        let case = draw(index, size);
        let effects: Vec<String> = case
            .truths
            .iter()
            .map(|t| format!("{}/{} ×{:.2} {:?}", t.place, t.shape, t.multiple, t.sizes))
            .collect();
        // the force's range is drawn but not scored: shown so a misfit of it can be read
        let between = case
            .spec
            .pair_force
            .map(|b| format!(" (pair force drawn as {b:?})"))
            .unwrap_or_default();
        println!(
            "dataset {index}: noise {}: {}{between}",
            case.noise,
            if effects.is_empty() {
                "null".to_string()
            } else {
                effects.join("; ")
            }
        );
    }
}

fn main() {
    let args = parse();
    if args.draw_only {
        print_draws(&args);
        return;
    }
    let started = Instant::now();
    let mut records = read(&args.results).unwrap_or_else(|e| fail(e));
    if !args.table_only {
        let groove = args
            .groove
            .clone()
            .unwrap_or_else(|| usage("give the groove binary with --groove BIN or GROOVE_BIN"));
        let pipeline = args
            .pipeline
            .clone()
            .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("pipeline.toml"));
        let indices: Vec<usize> = if args.quick {
            QUICK.to_vec()
        } else {
            (0..end_of(&args)).collect()
        };
        let size = if args.quick { QUICK_SIZE } else { FULL_SIZE };
        if let Some(dir) = args.results.parent() {
            std::fs::create_dir_all(dir)
                .unwrap_or_else(|e| fail(format!("{}: {e}", dir.display())));
        }
        for index in indices
            .into_iter()
            .filter(|&i| i >= args.from && i < args.to)
        {
            if records
                .iter()
                .any(|r| r.index == index && r.quick == args.quick)
            {
                continue; // done in an earlier chunk
            }
            let case = draw(index, size);
            let dir = args.work.join(format!(
                "case-{index:03}{}",
                if args.quick { "-quick" } else { "" }
            ));
            let _ = std::fs::remove_dir_all(&dir);
            let record =
                run_case(&case, args.quick, &groove, &pipeline, &dir).unwrap_or_else(|e| fail(e));
            eprintln!(
                "dataset {index}: {} [{}] ×{:?} {:?} noise {} → named {} sized {} false accept {} accepted {:?} discover {:?} s ({})",
                if record.shapes.is_empty() { "null".to_string() } else { record.shapes.join("+") },
                record.places.join("+"),
                record.multiples,
                record.sizes,
                record.noise,
                record.named,
                record.sized,
                record.false_accept,
                record.accepted,
                record.discover_s,
                record.status,
            );
            let line = serde_json::to_string(&record).unwrap_or_else(|e| fail(e.to_string()));
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&args.results)
                .unwrap_or_else(|e| fail(format!("{}: {e}", args.results.display())));
            writeln!(f, "{line}")
                .unwrap_or_else(|e| fail(format!("{}: {e}", args.results.display())));
            records.push(record);
            if !args.keep {
                let _ = std::fs::remove_dir_all(&dir);
            }
        }
    }
    let mine: Vec<_> = records
        .into_iter()
        .filter(|r| r.quick == args.quick)
        .collect();
    println!("{}", tables(&mine));
    println!(
        "\n{} datasets in {}; this invocation took {:.0} s",
        mine.len(),
        args.results.display(),
        started.elapsed().as_secs_f64()
    );
}
