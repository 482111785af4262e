//! The ingest stage run in memory (no store, so items come back as bytes), and a fixture
//! folder's files as the stage's dataset, for the suites that compare what ingest makes.
#![allow(dead_code)]

use groove::engine::stage::{Artifact, StageInput, StageKind};
use groove::stages::ingest::Ingest;
use std::collections::BTreeMap;
use std::path::Path;

/// The ingest stage's outputs for the dataset `files` with `params`.
pub fn stage_outputs(
    files: &BTreeMap<String, Vec<u8>>,
    params: &toml::Table,
) -> BTreeMap<String, Artifact> {
    let dataset = Artifact::Collection(files.clone());
    let input = StageInput {
        params,
        inputs: BTreeMap::from([("dataset", &dataset)]),
        item: None,
        seed: 1,
        progress: None,
        put_item: None,
        memo: None,
    };
    Ingest
        .run(&input)
        .unwrap_or_else(|e| panic!("stage failed: {e}"))
}

/// The files at the top of `dir`, by name.
pub fn folder_files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            let n = p.file_name().unwrap().to_string_lossy().into_owned();
            files.insert(n, std::fs::read(&p).unwrap());
        }
    }
    files
}
