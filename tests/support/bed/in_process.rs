//! One drawn case through ingest and discovery in this process (no `groove run`): the tests that
//! fix a seed use it, the bench runs the whole pipeline instead (`pipeline.rs`).

use super::draw::Case;
use crate::indsim::writer::write_dataset;
use groove::discover::{discover, Diagnosis, Options};
use groove::ingest::{ingest, IngestParams};
use groove::recording::Recording;
use std::collections::BTreeMap;

/// The case's dataset written in the interchange format and ingested as any dataset is.
pub fn ingest_case(c: &Case) -> Vec<Recording> {
    let dir = tempfile::tempdir().unwrap();
    write_dataset(dir.path(), &c.spec.render(false)).unwrap();
    let mut files = BTreeMap::new();
    for f in ["runs.csv", "trajectories.csv"] {
        files.insert(f.to_string(), std::fs::read(dir.path().join(f)).unwrap());
    }
    ingest(&files, &IngestParams::default())
        .expect("an indsim dataset ingests")
        .recordings
}

/// The case's dataset ingested (`ingest_case`) and discovered with the default options and
/// `seed`.
pub fn discover_case(c: &Case, seed: u64) -> Diagnosis {
    discover(
        &ingest_case(c),
        &Options {
            seed,
            ..Options::default()
        },
    )
}
