//! The ingest stage's artifacts as bytes: file-name-safe item names, the Parquet table of all
//! samples, and the JSON list of skipped runs. Same input, same bytes.

use crate::recording::Recording;
use polars::prelude::*;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

/// A run left out with `skip_bad_runs`, and why.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub struct Skipped {
    pub run: String,
    pub reason: String,
}

/// The collection item name of a run: the id itself if it is file-name safe (`[A-Za-z0-9._-]`,
/// not `.` or `..`), otherwise the id with every other character replaced by `_`, then `-` and the
/// first 8 hex digits of the id's SHA-256, so distinct ids keep distinct names. The true id stays
/// in the recording (`info.run`).
pub fn item_name(run: &str) -> String {
    let safe = |c: char| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-');
    if !run.is_empty() && run != "." && run != ".." && run.chars().all(safe) {
        return run.to_string();
    }
    let mapped: String = run.chars().map(|c| if safe(c) { c } else { '_' }).collect();
    let digest = Sha256::digest(run.as_bytes());
    let hex: String = digest[..4].iter().map(|b| format!("{b:02x}")).collect();
    format!("{mapped}-{hex}")
}

/// All samples as one typed Parquet table with the interchange columns (`run` string, `particle`
/// and `frame` int64, `t_s` and `z_m` float64), rows sorted by run, particle and frame, so it can
/// be read back as `trajectories.parquet`.
pub fn table_parquet(recordings: &[Recording]) -> PolarsResult<Vec<u8>> {
    let n: usize = recordings
        .iter()
        .flat_map(|r| &r.tracks)
        .map(|t| t.frame.len())
        .sum();
    let mut run: Vec<&str> = Vec::with_capacity(n);
    let mut particle: Vec<i64> = Vec::with_capacity(n);
    let mut frame: Vec<i64> = Vec::with_capacity(n);
    let mut t_s: Vec<f64> = Vec::with_capacity(n);
    let mut z_m: Vec<f64> = Vec::with_capacity(n);
    for r in recordings {
        for t in &r.tracks {
            run.extend(std::iter::repeat_n(r.info.run.as_str(), t.frame.len()));
            particle.extend(std::iter::repeat_n(i64::from(t.particle), t.frame.len()));
            frame.extend_from_slice(&t.frame);
            t_s.extend_from_slice(&t.t_s);
            z_m.extend_from_slice(&t.z_m);
        }
    }
    let mut df = DataFrame::new(
        n,
        vec![
            Column::new("run".into(), run),
            Column::new("particle".into(), particle),
            Column::new("frame".into(), frame),
            Column::new("t_s".into(), t_s),
            Column::new("z_m".into(), z_m),
        ],
    )?;
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes).finish(&mut df)?;
    Ok(bytes)
}

/// The skipped runs as a pretty JSON list, sorted by run.
pub fn skipped_json(skipped: &[Skipped]) -> Vec<u8> {
    let mut sorted = skipped.to_vec();
    sorted.sort();
    let mut bytes = serde_json::to_vec_pretty(&sorted).unwrap_or_else(|_| b"[]".to_vec());
    bytes.push(b'\n');
    bytes
}
