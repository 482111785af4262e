//! The engine: config, DAG, content-addressed store, scheduler. It knows no physics.
//!
//! Files of this folder:
//!
//! - `atomic.rs`: Atomic file writes: a name no other writer uses, and write-then-rename
//! - `catalog.rs`: What the engine runs with
//! - `command.rs`: The `command` kind
//! - `context.rs`: What one evaluation works with
//! - `dag.rs`: The stage graph
//! - `error.rs`: The engine's error: a bad config (with its TOML line), IO, or a failed stage
//! - `evaluate.rs`: Walking the DAG
//! - `execute.rs`: Running one key of a stage
//! - `hash_on_read.rs`: The first run over a streamed input reads it once
//! - `hashing.rs`: sha256 hex digests
//! - `identity.rs`: The code identity compiled into this binary
//! - `inputs.rs`: path inputs: a file or a folder, read whole or left on disk
//! - `key.rs`: The cache key of a stage
//! - `lock_digests.rs`: `.groove/lock-digests.json`
//! - `lockfile.rs`: `pipeline.lock`
//! - `maintenance.rs`: `groove clean` and `groove gc`
//! - `materialize.rs`: Writing stored outputs to their paths in the project
//! - `memo.rs`: A stage's object memo
//! - `pack.rs`: Packs: the many small blobs and entries of one stage run in a few files
//! - `pack_writer.rs`: Writing packs (`engine::pack`)
//! - `pipeline.rs`: The validated pipeline
//! - `progress.rs`: Progress on the console: a bar on a terminal, plain lines otherwise
//! - `project_lock.rs`: The project lock: one `groove run` (or `gc`, `clean`) at a time per project
//! - `provenance.rs`: The `engine:provenance` input
//! - `publish.rs`: `groove publish --to DIR`: the report bundle, only when every stage is fresh
//! - `reasons.rs`: Why a stage is stale
//! - `run.rs`: `groove run`: take the project lock
//! - `stage.rs`: The contract between the engine and a stage kind
//! - `status.rs`: `groove status`: every stage fresh or stale, with the reasons
//! - `store.rs`: The content-addressed store under `.groove/` beside `pipeline.toml`
//! - `store_upkeep.rs`: Keeping the store sound and small
//! - `config/`: Reading `pipeline.toml` in two layers
//! - `remote/`: A shared remote cache
//! - `slurm/`: The Slurm executor
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
