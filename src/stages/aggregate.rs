//! The `aggregate` stage kind: all run fits in, summary.json and fits.csv out; `runs` needs only the collision recordings (`fit:pair_runs`).

use super::fit_io::{collection_input, json_pretty, param_error, parse_item, recording, run_info};
use crate::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use crate::fit::aggregate::{aggregate_single, restart_note, AggregateOptions};
use crate::fit::summary::{BootstrapInfo, Summary};
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
        let mut collisions = Vec::new();
        let mut pair_recordings = Vec::new();
        // parsed on every core, then taken in item order (the first bad item is the error)
        let parsed: Vec<Result<RunFit, StageError>> = fits
            .par_iter()
            .map(|(item, bytes)| parse_item::<RunFit>(item, bytes, "the fit"))
            .collect();
        for (item, fit) in fits.keys().zip(parsed) {
            match fit? {
                RunFit::Single(f) => singles.push(f),
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
            Some(aggregate_single(&singles, &opts, input.seed))
        };
        let collisions = if collisions.is_empty() {
            notes.push(
                "no collision runs in this dataset: μ_pp and restitution are skipped".to_string(),
            );
            None
        } else {
            let mut c = collision::summarize_seeded(&collisions, opts.k, input.seed);
            let groove = crate::physics::Groove {
                s: collision::CollisionOptions::default().s,
                k: opts.k,
            };
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
