//! The virtual experiment: writes a dataset in the interchange format from a truth file (being built).

use std::path::Path;

/// `groove synth --truth FILE --out DIR`: read the truth TOML, simulate every run, write
/// `runs.csv` and `trajectories.csv` (and a copy of the truth under `DIR/truth/`). Seeded and
/// byte-for-byte deterministic.
pub fn run_synth(
    truth_toml: &Path,
    out_dir: &Path,
) -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
    let _ = (truth_toml, out_dir);
    Err("synth is not built yet".into())
}
