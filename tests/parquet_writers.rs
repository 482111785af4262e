//! Parquet written by the tools users have (pyarrow and pandas: snappy, zstd, gzip, data pages
//! v1 and v2, dictionary and plain pages, byte-stream-split and delta encodings, shuffled rows
//! with pandas' index column, int32 particles, a typed runs.parquet) reads as the same runs as
//! the CSV of the same rows: the same recordings, and through the stage the same item bytes.
//! The files are made by tests/fixtures/parquet_writers/make_fixtures.py (by hand: CI has no
//! pyarrow).

use groove::ingest::{self, IngestParams};
use groove::recording::Recording;
use std::collections::BTreeMap;
use std::path::Path;

#[path = "support/ingest_stage.rs"]
mod ingest_stage;
use ingest_stage::{folder_files, stage_outputs};

type Files = BTreeMap<String, Vec<u8>>;

const WRITERS: [&str; 6] = [
    "pyarrow_default",
    "pyarrow_v2_zstd",
    "pyarrow_plain_gzip",
    "pyarrow_encodings",
    "pandas_shuffled",
    "runs_parquet",
];

fn folder(name: &str) -> Files {
    folder_files(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/fixtures/parquet_writers")
            .join(name),
    )
}

#[test]
fn parquet_of_common_writers_reads_as_the_csv_of_the_same_rows() {
    let csv = folder("csv");
    let want = ingest::ingest(&csv, &IngestParams::default()).unwrap();
    assert_eq!(
        want.recordings.len(),
        5,
        "four single runs and a collision run"
    );
    assert!(want.skipped.is_empty());
    let want_items = stage_outputs(&csv, &toml::Table::new());
    for writer in WRITERS {
        let files = folder(writer);
        assert!(files.contains_key("trajectories.parquet"), "{writer}");
        let got = ingest::ingest(&files, &IngestParams::default())
            .unwrap_or_else(|e| panic!("{writer}: {e}"));
        let runs = |r: &[Recording]| r.iter().map(|r| r.info.run.clone()).collect::<Vec<_>>();
        assert_eq!(runs(&got.recordings), runs(&want.recordings), "{writer}");
        for (g, w) in got.recordings.iter().zip(&want.recordings) {
            assert!(g == w, "{writer}: run {} reads otherwise", w.info.run);
        }
        assert!(got.skipped.is_empty(), "{writer}");
        let items = stage_outputs(&files, &toml::Table::new());
        assert_eq!(
            items.keys().collect::<Vec<_>>(),
            want_items.keys().collect::<Vec<_>>()
        );
        for (name, artifact) in &want_items {
            assert!(items[name] == *artifact, "{writer}: output {name} differs");
        }
    }
}
