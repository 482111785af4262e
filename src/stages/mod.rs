//! The built-in stage kinds: each adapts a pure analysis function to the engine's `StageKind` contract.

use crate::engine::stage::StageKind;

pub mod aggregate;
pub mod compare;
pub mod discover;
pub mod figures;
pub mod fit;
pub mod fit_io;
pub mod ingest;
pub mod report;
pub mod simulate;
pub mod validate;

/// Every built-in kind, in a fixed order. The command line hands them to the engine
/// (`Catalog::with_kinds`); `command` is the engine's own kind and is not listed.
pub fn registry() -> Vec<Box<dyn StageKind>> {
    #[allow(unused_mut)]
    let mut kinds: Vec<Box<dyn StageKind>> = Vec::new();
    // one line per kind, e.g. `kinds.push(Box::new(ingest::Ingest));`
    kinds.push(Box::new(ingest::Ingest));
    kinds.push(Box::new(fit::Fit));
    kinds.push(Box::new(aggregate::Aggregate));
    kinds.push(Box::new(simulate::Simulate));
    kinds.push(Box::new(compare::Compare));
    kinds.push(Box::new(discover::Discover));
    kinds.push(Box::new(validate::Validate));
    kinds.push(Box::new(figures::Figures));
    kinds.push(Box::new(report::Report));
    kinds
}
