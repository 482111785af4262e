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
    // one line per kind
    vec![
        Box::new(ingest::Ingest),
        Box::new(fit::Fit),
        Box::new(aggregate::Aggregate),
        Box::new(simulate::Simulate),
        Box::new(compare::Compare),
        Box::new(discover::Discover),
        Box::new(validate::Validate),
        Box::new(figures::Figures),
        Box::new(report::Report),
    ]
}
