//! The contracts between stages: one serde type per artifact that crosses a stage boundary, used by
//! the stage that writes it and by every stage that reads it (readers deserialize these types; a
//! renamed field fails loudly instead of blanking part of the report).
//!
//! One file per artifact family: `run_fit` + `collision_fit` (the `fit` stage's item per run),
//! `fits_table` (fits.csv), `summary` (summary.json), `residuals` (`simulate`'s item per run),
//! `comparison` (`compare`), `diagnosis` (diagnosis.json), `validation` (`validate`), `provenance`
//! (`engine:provenance`), `skipped` (`ingest:skipped`); `estimate` is the one `Estimate` (value,
//! standard error, interval) with the adapters that keep each file's shape; `contract` lists the documented fields of
//! the published files for the README; `nan_null` carries a not-computed number as JSON `null`.

pub mod checked_json;
pub mod collision_fit;
pub mod comparison;
pub mod contract;
pub mod diagnosis;
pub mod estimate;
pub mod fits_table;
pub mod nan_null;
pub mod provenance;
pub mod residuals;
pub mod run_fit;
pub mod skipped;
pub mod summary;
pub mod validation;

pub use comparison::Comparison;
pub use diagnosis::Diagnosis;
pub use estimate::{Estimate, Interval};
pub use fits_table::FitsRow;
pub use provenance::Provenance;
pub use residuals::RunResiduals;
pub use run_fit::{RunFit, SingleFit};
pub use skipped::Skipped;
pub use summary::Summary;
pub use validation::Validation;

/// Decode one JSON artifact into its type; the error names the artifact and how to fix it.
pub fn from_json<T: serde::de::DeserializeOwned>(name: &str, bytes: &[u8]) -> Result<T, String> {
    serde_json::from_slice(bytes).map_err(|e| {
        format!("{name} does not match its contract ({e}); rerun the stage that makes it")
    })
}
