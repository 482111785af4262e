//! Runs whose item an earlier ingest already made from the same bytes: a piece of strict-layout
//! CSV split into its runs' blocks of lines, each whole run keyed by a BLAKE3 digest of what its
//! item is made of, so that after an edit of one recording only that run's lines (and the runs
//! at the piece's edges) are parsed again. The keys are looked up in the stage's memo
//! (`engine::stage::ObjectMemo`); a key found stands for the run's item in the store.

use super::csv_fast::{self, Rows};
use crate::recording::RunInfo;
use rayon::prelude::*;
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;

/// The item an earlier run made under a key, by its sha256, if the store still holds it.
pub type RunMemo<'m> = &'m (dyn Fn(&[u8; 32]) -> Option<String> + Sync);

/// A piece's runs in file order: lines to parse, or a whole run whose item the memo gave.
pub enum Step<'t> {
    Parsed(Vec<Rows<'t>>),
    Found { id: &'t str, sha256: String },
}

/// What a piece comes to: its steps, and the key of every whole run among the lines parsed
/// (run id → key), for the caller to remember with the item it makes.
pub struct Plan<'t> {
    pub steps: Vec<Step<'t>>,
    pub keys: HashMap<String, [u8; 32]>,
}

/// The memo key of a whole run: BLAKE3 of the key's version, `min_frames`, the run's row of
/// runs.csv and its lines' bytes — all its item is made of with the code and params, which the
/// stage's memo is salted with.
pub fn run_key(info: &RunInfo, min_frames: usize, lines: &[u8]) -> [u8; 32] {
    let mut h = blake3::Hasher::new();
    h.update(b"groove ingest run v1\0");
    h.update(&(min_frames as u64).to_le_bytes());
    h.update(&serde_json::to_vec(info).expect("a run's info serializes"));
    h.update(b"\0");
    h.update(lines);
    *h.finalize().as_bytes()
}

/// The plan of a piece's lines (`body`, no header): its first and last blocks of one run id
/// may go on in the pieces around it and are always parsed; a block between them is a whole
/// run, and is found in `memo` or parsed. Lines parsed together are consecutive, so the
/// stream sees every run in file order, as if it had parsed the whole piece. `None` when the
/// piece is not for this path (a line without a comma, fewer than three blocks, a line the
/// strict parser refuses): nothing of it was handed on, and it is read as before.
pub fn plan<'t>(
    body: &'t [u8],
    infos: &BTreeMap<&str, &RunInfo>,
    min_frames: usize,
    memo: RunMemo,
) -> Option<Plan<'t>> {
    let blocks = csv_fast::segments(body)?;
    if blocks.len() < 3 {
        return None;
    }
    let id = |r: &Range<usize>| std::str::from_utf8(csv_fast::id_at(body, r.start)?).ok();
    // each whole run's key, and what the memo holds under it (hashed on every core)
    let looked: Vec<(Option<[u8; 32]>, Option<String>)> = blocks[1..blocks.len() - 1]
        .par_iter()
        .map(|r| {
            let key = id(r)
                .and_then(|id| infos.get(id))
                .map(|info| run_key(info, min_frames, &body[r.clone()]));
            (key, key.as_ref().and_then(memo))
        })
        .collect();
    let found = |i: usize| (1..blocks.len() - 1).contains(&i) && looked[i - 1].1.is_some();
    // consecutive blocks not found are parsed together
    let mut spans: Vec<Result<Range<usize>, usize>> = Vec::new();
    for (i, r) in blocks.iter().enumerate() {
        match spans.last_mut() {
            _ if found(i) => spans.push(Err(i)),
            Some(Ok(open)) => open.end = r.end,
            _ => spans.push(Ok(r.clone())),
        }
    }
    let parsed: Vec<Option<Vec<Rows>>> = spans
        .par_iter()
        .map(|s| match s {
            Ok(r) => csv_fast::parse_body(&body[r.clone()]),
            Err(_) => Some(Vec::new()),
        })
        .collect();
    let mut steps = Vec::with_capacity(spans.len());
    for (span, rows) in spans.iter().zip(parsed) {
        steps.push(match span {
            Ok(_) => Step::Parsed(rows?),
            Err(i) => Step::Found {
                id: id(&blocks[*i])?,
                sha256: looked[i - 1].1.clone()?,
            },
        });
    }
    let keys = blocks[1..blocks.len() - 1]
        .iter()
        .zip(&looked)
        .filter(|(_, (_, hit))| hit.is_none())
        .filter_map(|(r, (key, _))| Some((id(r)?.to_string(), (*key)?)))
        .collect();
    Some(Plan { steps, keys })
}
