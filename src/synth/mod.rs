//! The virtual experiment: writes a dataset in the interchange format from a truth file.
//!
//! Files of this folder:
//!
//! - `camera.rs`: The virtual camera
//! - `runs.rs`: One run of the virtual experiment
//! - `tables.rs`: The dataset tables as text, with fixed float formatting so the bytes never vary
//! - `truth.rs`: The truth file of the virtual experiment
//!
//! `run_synth` reads the truth TOML, simulates every run with the physics module (one seeded
//! ChaCha8 stream per run), records it with the virtual camera, and writes `runs.csv`,
//! `trajectories.csv` and, under `truth/`, a copy of the truth file plus `runs_truth.csv` (the
//! hidden initial conditions). The output is byte-for-byte the same for the same truth file.

mod camera;
mod runs;
mod tables;
mod truth;

pub use truth::{CameraSpec, Directions, Material, RunGroup, Truth};

use std::path::Path;

/// `groove synth --truth FILE --out DIR`: read the truth TOML, simulate every run, write
/// `runs.csv` and `trajectories.csv` (and a copy of the truth under `DIR/truth/`). Seeded and
/// byte-for-byte deterministic.
pub fn run_synth(
    truth_toml: &Path,
    out_dir: &Path,
) -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    run_synth_as(truth_toml, out_dir, false)
}

/// `run_synth`, writing the trajectories as trajectories.parquet when `parquet` (the values of
/// trajectories.csv, typed: `run` text, `particle` and `frame` Int64, `t_s` and `z_m` Float64,
/// each number the one the CSV text reads as; zstd-compressed).
pub fn run_synth_as(
    truth_toml: &Path,
    out_dir: &Path,
    parquet: bool,
) -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let text = std::fs::read_to_string(truth_toml).map_err(|e| {
        format!(
            "cannot read truth file {}: {e}; pass an existing TOML file with --truth",
            truth_toml.display()
        )
    })?;
    let truth = Truth::parse(&text).map_err(|e| format!("{}: {e}", truth_toml.display()))?;
    let tables = synth_tables(&truth);
    let truth_dir = out_dir.join("truth");
    std::fs::create_dir_all(&truth_dir).map_err(|e| {
        format!(
            "cannot create {}: {e}; choose a writable --out directory",
            truth_dir.display()
        )
    })?;
    let write = |name: &Path, body: &str| {
        std::fs::write(name, body).map_err(|e| format!("cannot write {}: {e}", name.display()))
    };
    write(&out_dir.join("runs.csv"), &tables.runs_csv)?;
    let (csv, parquet_file) = (
        out_dir.join("trajectories.csv"),
        out_dir.join("trajectories.parquet"),
    );
    // the other form of an earlier synth into this folder goes: both would be ambiguous
    let other = if parquet { &csv } else { &parquet_file };
    match std::fs::remove_file(other) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(format!("cannot remove {}: {e}", other.display()).into())
        }
        _ => {}
    }
    if parquet {
        let bytes = tables::parquet_of_csv(&tables.trajectories_csv)?;
        std::fs::write(&parquet_file, bytes)
            .map_err(|e| format!("cannot write {}: {e}", parquet_file.display()))?;
    } else {
        write(&csv, &tables.trajectories_csv)?;
    }
    write(&truth_dir.join("truth.toml"), &text)?;
    write(&truth_dir.join("runs_truth.csv"), &tables.runs_truth_csv)?;
    Ok(())
}

/// The dataset as text: what `run_synth` writes.
pub struct SynthTables {
    pub runs_csv: String,
    pub trajectories_csv: String,
    pub runs_truth_csv: String,
}

/// Simulate and record every run of `truth` (no files).
pub fn synth_tables(truth: &Truth) -> SynthTables {
    let mut all = Vec::new();
    let mut index = 0;
    for group in &truth.runs {
        for j in 0..group.count {
            all.push(runs::synth_run(truth, group, j, index));
            index += 1;
        }
    }
    SynthTables {
        runs_csv: tables::runs_csv(&all, truth.camera.fps),
        trajectories_csv: tables::trajectories_csv(&all),
        runs_truth_csv: tables::runs_truth_csv(&all),
    }
}
