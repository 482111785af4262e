//! The built-in stage kinds: each adapts a pure analysis function to the engine's `StageKind` contract.
//!
//! Files of this folder:
//!
//! - `aggregate.rs`: The `aggregate` stage kind
//! - `compare.rs`: The `compare` stage kind
//! - `discover.rs`: The `discover` stage kind: recordings in, diagnosis.json out
//! - `figures.rs`: The `figures` stage kind
//! - `fit.rs`: The `fit` stage kind
//! - `fit_io.rs`: helpers shared by the fit-side stage kinds
//! - `ingest.rs`: The `ingest` stage kind
//! - `refit.rs`: The `refit` stage kind
//! - `report.rs`: The `report` stage kind
//! - `simulate.rs`: The `simulate` stage kind
//! - `validate.rs`: The `validate` stage kind
//!
//! `fit:pair_runs` holds, per run, the recording again for a collision run and nothing for a single
//! run: aggregate needs only the collision recordings (the whole-run pair fits), so it binds that
//! instead of `ingest:runs` and does not load every single-run recording (the store keeps one copy
//! of identical bytes, so the collision recordings are not stored twice).

use crate::engine::stage::StageKind;

pub mod aggregate;
pub mod compare;
pub mod discover;
pub mod figures;
pub mod fit;
pub mod fit_io;
pub mod ingest;
pub mod refit;
pub mod report;
pub mod simulate;
pub mod validate;

/// Every built-in kind, in a fixed order. The command line hands them to the engine
/// (`Catalog::with_kinds`); `command` is the engine's own kind and is not listed.
pub fn registry() -> Vec<Box<dyn StageKind>> {
    // one line per kind
    vec![
        Box::new(ingest::Ingest),
        Box::new(fit::Fit),
        Box::new(aggregate::Aggregate),
        Box::new(simulate::Simulate),
        Box::new(compare::Compare),
        Box::new(discover::Discover),
        Box::new(refit::Refit),
        Box::new(validate::Validate),
        Box::new(figures::Figures),
        Box::new(report::Report),
    ]
}
