//! The ingest stage's artifacts as bytes: file-name-safe item names and the JSON list of skipped
//! runs. Same input, same bytes.

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

/// The skipped runs as a pretty JSON list, sorted by run.
pub fn skipped_json(skipped: &[Skipped]) -> Vec<u8> {
    let mut sorted = skipped.to_vec();
    sorted.sort();
    let mut bytes = serde_json::to_vec_pretty(&sorted).unwrap_or_else(|_| b"[]".to_vec());
    bytes.push(b'\n');
    bytes
}
