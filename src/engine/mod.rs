//! The engine: config, DAG, content-addressed store, scheduler. It knows no physics.
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
