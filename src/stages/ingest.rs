//! The `ingest` stage kind: the dataset folder's files in, checked recordings and the list of skipped runs out.

use crate::engine::stage::{
    typed_params, Artifact, CheckedRead, InputFile, ParamError, StageError, StageInput, StageKind,
    StageOutputs, IN_STORE_INPUT,
};
use crate::ingest::{self, IngestParams, Items, Streamed};
use std::collections::BTreeMap;

/// `kind = "ingest"`: input `dataset` (a folder's top-level files; trajectories.csv or .parquet
/// is read from disk in pieces, so it may be larger than memory), outputs `runs` (run → `Recording` in
/// the binary format of `recording::item`) and `skipped` (JSON list of `{run, reason}`). (A Parquet table of all samples
/// was an output too; no stage read it, and writing it cost as much as reading the CSV typed.)
pub struct Ingest;

impl StageKind for Ingest {
    fn kind(&self) -> &'static str {
        "ingest"
    }

    fn inputs(&self) -> &'static [&'static str] {
        &["dataset"]
    }

    fn outputs(&self) -> &'static [&'static str] {
        &["runs", "skipped"]
    }

    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        let (typed, json) = typed_params::<IngestParams>(params)?;
        typed.check().map_err(|p| ParamError {
            key: p.key,
            message: format!("{}; {}", p.message, p.fix),
        })?;
        Ok(json)
    }

    fn streamed_inputs(&self) -> &'static [&'static str] {
        &["dataset"]
    }

    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (params, _) =
            typed_params::<IngestParams>(input.params).map_err(|e| StageError(e.to_string()))?;
        let dataset = match input.inputs.get("dataset") {
            Some(Artifact::OnDisk(files)) => Dataset::OnDisk(files),
            Some(Artifact::Collection(files)) => Dataset::InMemory(files),
            Some(Artifact::InStore(_)) => return Err(StageError(IN_STORE_INPUT.into())),
            Some(Artifact::File(_)) => {
                return Err(StageError(
                    "input dataset is a single file; bind it to the dataset folder (inputs = { dataset = \"${data}\" })".into(),
                ))
            }
            None => {
                return Err(StageError(
                    "input dataset is missing; bind it to the dataset folder (inputs = { dataset = \"${data}\" })".into(),
                ))
            }
        };
        let (runs, skipped) = match input.put_item {
            // each item into the store as it is made: never all items at once
            Some(put) => {
                let get = |key: &[u8; 32]| input.memo.and_then(|m| m.get(key));
                let kept = |sha256: String| Ok(sha256);
                let memo = input.memo.map(|_| ingest::ItemMemo {
                    get: &get,
                    kept: &kept,
                });
                let items = items_of(dataset, &params, &|bytes| put(&bytes), memo)?;
                input.report(&format!("{} runs, {}", items.runs.len(), items.how));
                // what was made from whole runs' lines, for the next run (only once the
                // stream has ended well: `ingest::Items::memo_made`)
                if let Some(memo) = input.memo {
                    for (key, name) in &items.memo_made {
                        if let Some(Ok(sha256)) = items.runs.get(name) {
                            memo.put(*key, sha256);
                        }
                    }
                }
                let runs = items
                    .runs
                    .into_iter()
                    .map(|(name, sha)| sha.map(|sha| (name, sha)))
                    .collect::<Result<_, _>>()?;
                (Artifact::InStore(runs), items.skipped)
            }
            None => {
                let items = items_of(dataset, &params, &|bytes| bytes, None)?;
                input.report(&format!("{} runs, {}", items.runs.len(), items.how));
                (Artifact::Collection(items.runs), items.skipped)
            }
        };
        let mut out = StageOutputs::new();
        out.insert("runs".into(), runs);
        out.insert(
            "skipped".into(),
            Artifact::File(ingest::skipped_json(&skipped)),
        );
        Ok(out)
    }
}

/// The dataset folder as the stage gets it.
#[derive(Clone, Copy)]
enum Dataset<'a> {
    /// Left on disk by the engine: trajectories.csv is read in pieces, the rest whole.
    OnDisk(&'a BTreeMap<String, InputFile>),
    /// Read whole (tests, and callers without an engine).
    InMemory(&'a BTreeMap<String, Vec<u8>>),
}

/// The items of the dataset, each handed to `keep` as it is made.
fn items_of<T: Send>(
    dataset: Dataset,
    params: &IngestParams,
    keep: &(dyn Fn(Vec<u8>) -> T + Sync),
    memo: Option<ingest::ItemMemo<T>>,
) -> Result<Items<T>, StageError> {
    let failed = |e: ingest::IngestError| StageError(e.to_string());
    let bound = |p: ingest::Problem| StageError(ingest::IngestError::from(p).to_string());
    let files = match dataset {
        Dataset::InMemory(files) => {
            for (name, bytes) in files {
                ingest::bounds::check_header(name, bytes).map_err(bound)?;
            }
            return ingest::ingest_items_kept(files, params, ingest::CHUNK_BYTES, keep)
                .map_err(failed);
        }
        Dataset::OnDisk(files) => files,
    };
    // the trajectories stand in the map with no bytes, for their name: read in pieces below
    let streamed = ["trajectories.csv", "trajectories.parquet"]
        .into_iter()
        .find(|name| files.contains_key(*name));
    // every file's header width and, for those read whole, size, before any is read
    for (name, file) in files {
        ingest::bounds::check_header(name, &header_bytes(file)?).map_err(bound)?;
        if Some(name.as_str()) != streamed {
            let why = "every dataset file but the trajectories is";
            ingest::bounds::check_whole(
                name,
                size_of(file)?,
                why,
                "check that it is the file meant",
            )
            .map_err(bound)?;
        }
    }
    let mut bytes = BTreeMap::new();
    for (name, file) in files {
        let read = match Some(name.as_str()) == streamed {
            true => Vec::new(),
            false => file.read()?,
        };
        bytes.insert(name.clone(), read);
    }
    let Some((streamed, traj)) = streamed.and_then(|name| Some((name, files.get(name)?))) else {
        return ingest::ingest_items_kept(&bytes, params, ingest::CHUNK_BYTES, keep)
            .map_err(failed);
    };
    let streamed_items = ingest::stream_items(
        &bytes,
        Some(&mut OnDisk(traj.open()?)),
        params,
        ingest::CHUNK_BYTES,
        keep,
        memo,
    );
    let why = match streamed_items {
        Ok(Streamed::Done(items)) => return Ok(items),
        Ok(Streamed::ReadWhole(why)) => why,
        Err(e) => {
            return Err(StageError(format!(
                "{} could not be read: {e}",
                traj.path.display()
            )))
        }
    };
    // not for the fast path: read whole, which sorts the rows or names every problem
    let whole = format!("it cannot be read in pieces: {why}");
    let fix = match why.contains("not together") {
        true => "put each run's rows together (sorted by run) so that it is read in pieces",
        false => "mend that so that it is read in pieces (a few of its runs, copied to another dataset, name every problem)",
    };
    ingest::bounds::check_whole(streamed, size_of(traj)?, &whole, fix).map_err(bound)?;
    bytes.insert(streamed.into(), traj.read()?);
    ingest::ingest_items_whole(&bytes, params, why, keep).map_err(failed)
}

/// The size of a dataset file on disk.
fn size_of(file: &InputFile) -> Result<u64, StageError> {
    std::fs::metadata(&file.path)
        .map(|m| m.len())
        .map_err(|e| StageError(format!("{} cannot be read: {e}", file.path.display())))
}

/// The start of a dataset file, enough to hold its header line (`ingest::bounds::HEADER_BYTES`).
fn header_bytes(file: &InputFile) -> Result<Vec<u8>, StageError> {
    use std::io::Read;
    let mut start = Vec::new();
    std::fs::File::open(&file.path)
        .and_then(|f| {
            f.take(ingest::bounds::HEADER_BYTES as u64)
                .read_to_end(&mut start)
        })
        .map_err(|e| StageError(format!("{} cannot be read: {e}", file.path.display())))?;
    Ok(start)
}

/// A trajectories file on disk as the streamed read takes it: read in order through the
/// engine's check, and at an offset for a Parquet footer.
struct OnDisk(CheckedRead);

impl std::io::Read for OnDisk {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        self.0.read(buf)
    }
}

impl ingest::Source for OnDisk {
    fn file_len(&self) -> std::io::Result<u64> {
        self.0.file_len()
    }

    fn read_at(&self, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
        self.0.read_at(buf, offset)
    }
}
