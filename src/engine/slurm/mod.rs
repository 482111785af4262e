//! The Slurm executor: `groove run --executor slurm` takes one allocation and runs the stages
//! that must run (and batches of per-item work) as job steps (`srun --exact`) inside it.
//!
//! Files of this folder:
//!
//! - `alloc.rs`: One Slurm allocation per partition, and job steps inside it (`srun --exact`)
//! - `config.rs`: `[slurm]` in `pipeline.toml`
//! - `executor.rs`: The controller side
//! - `job.rs`: What one job step is asked to do
//! - `worker.rs`: The job-step side
//!
//! [`config`] reads `[slurm]` and per-stage resources, [`alloc`] holds the allocation and runs
//! steps, [`job`] is the file a step reads. A step runs `groove slurm-step FILE` on a compute
//! node: it executes its keys and commits each into the project's store (which must be on a
//! filesystem the nodes share), then exits; the controller then opens the committed entries.

pub mod alloc;
pub mod config;
pub mod executor;
pub mod job;
pub mod worker;

pub use executor::SlurmExecutor;
