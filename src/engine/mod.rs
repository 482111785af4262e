//! The engine: config, DAG, content-addressed store, scheduler. It knows no physics.
//!
//! # Invariants
//!
//! Each is checked by the tests that name it (`tests/hostile_store.rs`, `tests/fuzz_store.rs`,
//! `tests/hostile_project.rs`, `tests/soak.sh`):
//!
//! - No store or remote entry can make groove write, read or delete outside the project and its
//!   store: hashes are 64 lowercase hex digits, item and output names plain file names.
//! - Anything else read from a store or a remote is damage: dropped, and the stage runs again;
//!   never a panic.
//! - An entry holds exactly the outputs its stage declares; a remote entry of another shape is
//!   never committed locally.
//! - `verify` and `gc` never follow a link out of the store.
//! - Groove never deletes a file it did not write: a folder output replaces only what groove
//!   wrote there, and anything else in the way stops the run (exit 2) naming it.
//! - Staged outputs a killed run left (`.NAME.groove-new-*`) are removed by the next run.
//! - `run`, `status`, `publish` and `pull` agree about state: a reused entry's objects are
//!   there, a missing or damaged one makes its stage run again, and `pull` replaces a damaged
//!   local object by the remote's sound one.
//! - A kill at any moment of any verb leaves the store and the reports either as they were or
//!   as they are meant to be; `clean` drops every entry by one rename before anything else.
//! - `publish` copies one snapshot (the lock and the objects it names) under the project lock.
//! - Read-only commands stay read-only: `status`, `publish` and `dag` work on a store that
//!   cannot be written.
//! - Bad input exits 2 naming its file, row, column or line and the fix, and loses nothing;
//!   `push` to a remote that is not there exits 2.
//!
//! Flow: [`config::load`] turns `pipeline.toml` into a validated [`pipeline::Pipeline`];
//! [`evaluate`] walks the DAG in waves, hashing inputs and looking stage keys up in the
//! [`store::Store`]; [`run`] executes what is missing, [`status`] explains what is stale.

pub mod atomic;
pub mod catalog;
pub mod command;
pub mod config;
pub mod context;
pub mod dag;
pub mod error;
pub mod evaluate;
pub mod execute;
pub mod hash_on_read;
pub mod hashing;
pub mod identity;
pub mod inputs;
pub mod key;
pub mod lock_digests;
pub mod lockfile;
pub mod maintenance;
pub mod materialize;
pub mod memo;
pub mod pack;
pub mod pack_writer;
pub mod pipeline;
pub mod progress;
pub mod project_lock;
pub mod provenance;
pub mod publish;
pub mod reasons;
pub mod remote;
pub mod run;
pub mod slurm;
pub mod stage;
pub mod status;
pub mod store;
pub mod store_upkeep;

pub use catalog::Catalog;
pub use error::EngineError;
pub use pipeline::Pipeline;
