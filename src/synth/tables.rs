//! The dataset tables as text, with fixed float formatting so the bytes never vary.

use super::runs::SynthRun;
use crate::recording::Setup;
use std::fmt::Write;

/// runs.csv: one row per run.
pub(crate) fn runs_csv(runs: &[SynthRun], fps: f64) -> String {
    let mut out = String::from("run,experiment,material,diameter_m,fps,setup,v0_laser_mps\n");
    for r in runs {
        let setup = match r.setup {
            Some(Setup::Rolling) => "rolling",
            Some(Setup::Contact) => "contact",
            None => "",
        };
        let experiment = serde_json::to_value(r.experiment).expect("enum serializes");
        let _ = writeln!(
            out,
            "{},{},{},{:.3e},{},{},{:.5}",
            r.id,
            experiment.as_str().unwrap_or("single"),
            r.material,
            r.diameter_m,
            fps,
            setup,
            r.v0_laser_mps
        );
    }
    out
}

/// trajectories.csv: one row per particle per kept frame.
pub(crate) fn trajectories_csv(runs: &[SynthRun]) -> String {
    let n: usize = runs.iter().map(|r| r.rows.len()).sum();
    let mut out = String::with_capacity(40 * n + 64);
    out.push_str("run,particle,frame,t_s,z_m\n");
    for r in runs {
        for row in &r.rows {
            let _ = writeln!(
                out,
                "{},{},{},{:.7},{:.9}",
                r.id, row.particle, row.frame, row.t_s, row.z_m
            );
        }
    }
    out
}

/// truth/runs_truth.csv: the hidden initial conditions of every run (for validation only).
pub(crate) fn runs_truth_csv(runs: &[SynthRun]) -> String {
    let mut out = String::from("run,particle,z0_m,v0_mps,va0_mps,t_first_frame_s\n");
    for r in runs {
        for (p, s) in r.init.iter().enumerate() {
            let _ = writeln!(
                out,
                "{},{},{:.9},{:.9},{:.9},{:.9}",
                r.id, p, s.z_m, s.v_mps, s.va_mps, r.t_first_frame_s
            );
        }
    }
    out
}

/// trajectories.csv's text as a Parquet file: the same values, typed as ingest's fast path
/// reads the CSV (`ingest::typed_trajectories`: `run` text, `particle` and `frame` Int64, `t_s`
/// and `z_m` Float64), zstd-compressed, in polars' row groups.
pub(crate) fn parquet_of_csv(csv: &str) -> Result<Vec<u8>, String> {
    use polars::prelude::*;
    let mut df = crate::ingest::typed_trajectories(csv.as_bytes())
        .ok_or("the trajectories do not read back as a typed table")?;
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes)
        .with_compression(ParquetCompression::Zstd(None))
        .finish(&mut df)
        .map_err(|e| format!("the trajectories cannot be written as Parquet ({e})"))?;
    Ok(bytes)
}
