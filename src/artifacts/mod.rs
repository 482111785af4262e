//! The contracts between stages: one serde type per artifact that crosses a stage boundary, used by
//! the stage that writes it and by every stage that reads it (readers deserialize these types; a
//! renamed field fails loudly instead of blanking part of the report).
//!
//! Files of this folder:
//!
//! - `checked_json.rs`: Writing an artifact's JSON only when it reads back as its own type
//! - `collision_fit.rs`: The per-run result of a collision fit
//! - `collision_summary.rs`: The collision aggregates of summary.json
//! - `comparison.rs`: The `compare` stage's `comparison`
//! - `contract.rs`: The documented contract of the published files
//! - `diagnosis.rs`: diagnosis.json (output of `discover`)
//! - `estimate.rs`: One `Estimate` for every artifact
//! - `fits_table.rs`: fits.csv (output of `aggregate`)
//! - `nan_null.rs`: Serde helper: an `f64` that may be NaN
//! - `provenance.rs`: `engine:provenance` as its readers see it
//! - `residuals.rs`: The `simulate` stage's item per run
//! - `run_fit.rs`: The `fit` stage's item per run
//! - `skipped.rs`: `ingest:skipped`
//! - `summary.rs`: The types of summary.json
//! - `under_accepted.rs`: under_accepted_physics.json (output of `refit`)
//! - `validation.rs`: The `validate` stage's `validation`
//!
//! One file per artifact family: `run_fit` + `collision_fit` (the `fit` stage's item per run),
//! `fits_table` (fits.csv), `summary` (summary.json), `residuals` (`simulate`'s item per run),
//! `comparison` (`compare`), `diagnosis` (diagnosis.json), `validation` (`validate`), `provenance`
//! (`engine:provenance`), `skipped` (`ingest:skipped`); `estimate` is the one `Estimate` (value,
//! standard error, interval) with the adapters that keep each file's shape; `contract` lists the documented fields of
//! the published files for the README; `nan_null` carries a not-computed number as JSON `null`.
//!
//! # The published files in detail
//!
//! Beside the report in the reports folder (scripts may rely on these):
//!
//! - `fits.csv`: one row per single run: `run, material, v0_mps, v0_se, mu, mu_se, T_s, T_se, t1_s,
//!   rms_m, status`;
//! - `summary.json`: per material μ with its bootstrap interval, the T-vs-v0 line's intercept and slope
//!   with intervals; μ_pp and restitution curves where collision runs exist, and under
//!   `collisions.whole_run` the whole-run pair fits per material: shared μ_pg, drag, μ_pp, the μ_pp
//!   profile (`profile.points`, walked outward from the estimate until the deviance passes 10⁴,
//!   the grid values beyond in `profile.not_fitted`; `profile.verdict` = interval or one-sided
//!   bound; the deviance divided by `profile.inflation`, the larger of the run `dispersion` and the
//!   residuals' Huber `scale_factor` times their `serial_factor`), the restitution law per setup
//!   chosen by held-out error (`restitution[].chosen`, `candidates` with `parameters` by name as
//!   `{value, lo, hi}`, 95 %), and per run the kick, impacts and residuals by phase and time since impact
//!   (when a profile fit with μ_pp held ends more than 1 below the joint fit, which frees μ_pp, the
//!   joint fit is started again from it, once, and the profile redone, and the material's `notes`
//!   say so, and say it again when a profile fit still lies lower, whose μ_pp is then the
//!   profile's estimate, not the table's:
//!   under a 2 mm waviness the whole-run model leaves out, 440c's joint fit had ended at μ_pp 0.61
//!   with the profile 300,000 lower at 1.58, and the table printed 0.61 as the best fit);
//! - `diagnosis.json`: what discovery found (`mismatch`, `findings` with `effect`, `accepted`, `form`,
//!   `parameters`, `evidence` (with `detection_limit`), `where`, `baseline`/`extended` held-out
//!   errors; `force_maps` before/after and `spectra`); effect IDs: `velocity_dependent_drag`,
//!   `rolling_resistance`, `groove_tilt`, `velocity_dependent_friction`, `position_dependent_force`,
//!   `time_dependent_force`, `unexplained`;
//! - `report.html` (one self-contained file), `report.md` and `figures/*.svg`.

pub mod checked_json;
pub mod collision_fit;
pub mod collision_summary;
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
pub mod under_accepted;
pub mod validation;

pub use comparison::Comparison;
pub use diagnosis::Diagnosis;
pub use estimate::{Estimate, Interval};
pub use fits_table::FitsRow;
pub use provenance::Provenance;
pub use residuals::RunResiduals;
pub use run_fit::{FitStatus, RunFit, SingleFit};
pub use skipped::Skipped;
pub use summary::Summary;
pub use validation::Validation;

/// Decode one JSON artifact into its type; the error names the artifact and how to fix it.
pub fn from_json<T: serde::de::DeserializeOwned>(name: &str, bytes: &[u8]) -> Result<T, String> {
    serde_json::from_slice(bytes).map_err(|e| {
        format!("{name} does not match its contract ({e}); rerun the stage that makes it")
    })
}
