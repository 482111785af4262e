//! The `aggregate` stage kind: all run fits in, summary.json and fits.csv out; `runs` needs only the collision recordings (`fit:pair_runs`).

use super::fit_io::{collection_input, json_pretty, param_error, parse_item, recording, run_info};
use crate::artifacts::summary::{BootstrapInfo, MaterialSummary, Summary};
use crate::engine::stage::{
    typed_params, Artifact, ObjectMemo, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::aggregate::{aggregate_single_memo, restart_note, AggregateOptions, SummaryMemo};
use crate::fit::{collision, fits_csv, RunFit};
use rayon::prelude::*;

/// `kind = "aggregate"`: per-material aggregates of the fits.
pub struct Aggregate;

impl StageKind for Aggregate {
    fn kind(&self) -> &'static str {
        "aggregate"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["fits", "runs"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["summary", "fits_csv"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        let (opts, json) = typed_params::<AggregateOptions>(params)?;
        opts.validate().map_err(param_error)?;
        Ok(json)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        let (opts, _) = typed_params::<AggregateOptions>(input.params)
            .map_err(|e| StageError(e.to_string()))?;
        let fits = collection_input(input, "fits", "aggregate")?;
        let runs = collection_input(input, "runs", "aggregate")?;
        let mut singles = Vec::new();
        // each single fit's digest (of its item's bytes), for the memo of material summaries
        let mut digests = Vec::new();
        let mut collisions = Vec::new();
        let mut pair_recordings = Vec::new();
        // parsed on every core, then taken in item order (the first bad item is the error)
        let parsed: Vec<Result<RunFit, StageError>> = fits
            .par_iter()
            .map(|(item, bytes)| parse_item::<RunFit>(item, bytes, "the fit"))
            .collect();
        for ((item, bytes), fit) in fits.iter().zip(parsed) {
            match fit? {
                RunFit::Single(f) => {
                    singles.push(f);
                    digests.push(*blake3::hash(bytes).as_bytes());
                }
                RunFit::Collision(c) => {
                    let rec = runs.get(item).filter(|b| !b.is_empty()).ok_or_else(|| {
                        StageError(format!(
                            "the fit of `{item}` has no recording in `runs`; bind `runs` to \"fit:pair_runs\" (or the ingest output the fit stage read)"
                        ))
                    })?;
                    collisions.push((run_info(item, rec)?, c));
                    pair_recordings.push(recording(item, rec)?);
                }
            }
        }
        let mut notes = Vec::new();
        let single = if singles.is_empty() {
            notes.push(
                "no single runs in this dataset: μ_pg and the T-vs-v0 line are skipped".to_string(),
            );
            None
        } else {
            notes.extend(restart_note(&singles));
            let memo = input
                .memo
                .zip(input.put_item)
                .map(|(memo, put)| Summaries { memo, put });
            Some(aggregate_single_memo(
                &singles,
                &opts,
                input.seed,
                memo.as_ref().map(|m| (&digests[..], m as &dyn SummaryMemo)),
            ))
        };
        let collisions = if collisions.is_empty() {
            notes.push(
                "no collision runs in this dataset: μ_pp and restitution are skipped".to_string(),
            );
            None
        } else {
            let mut c = collision::summarize_seeded(&collisions, opts.k, input.seed);
            let groove = crate::physics::Groove::of_params(opts.groove_angle_deg, opts.k);
            c.whole_run = Some(collision::whole_summary::analyze(
                &pair_recordings,
                groove,
                &collision::whole_summary::WholeRunOptions::default(),
            ));
            Some(c)
        };
        let summary = Summary {
            single,
            collisions,
            notes,
            bootstrap: BootstrapInfo {
                resamples: opts.bootstrap_resamples,
                level: opts.level,
                seed: input.seed,
                unit: "whole runs, resampled with replacement within each material".into(),
            },
        };
        Ok([
            (
                "summary".to_string(),
                Artifact::File(json_pretty(&summary)?),
            ),
            (
                "fits_csv".to_string(),
                Artifact::File(fits_csv::render(&singles).into_bytes()),
            ),
        ]
        .into())
    }
}

/// The material summaries an earlier run of the stage made, kept as objects in the store
/// (`StageInput::memo`): the JSON of summary.json's own type, which reads back to the same
/// output bytes.
struct Summaries<'a> {
    memo: &'a dyn ObjectMemo,
    put: &'a (dyn Fn(&[u8]) -> Result<String, StageError> + Sync),
}

impl SummaryMemo for Summaries<'_> {
    fn get(&self, key: &[u8; 32]) -> Option<MaterialSummary> {
        let bytes = self.memo.read(&self.memo.get(key)?)?;
        serde_json::from_slice(&bytes).ok()
    }

    fn put(&self, key: [u8; 32], summary: &MaterialSummary) {
        let bytes = serde_json::to_vec(summary).expect("a summary serializes");
        // only a speed-up: a summary not kept is made again next time
        if let Ok(sha256) = (self.put)(&bytes) {
            self.memo.put(key, &sha256);
        }
    }
}
