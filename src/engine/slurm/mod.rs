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
//!
//! # In use
//!
//! `groove run --executor slurm` runs on a login node (or inside an `sbatch` script) and takes **one
//! allocation** (`salloc --no-shell`; or the one it already runs in, `SLURM_JOB_ID`), then runs
//! every stage that must run as a **job step** inside it (`srun --exact`), never one `sbatch` per
//! stage. Per-item stages go in batches (at most `batch` items per step; by default spread over the
//! allocation's CPUs), never one step per tiny item. A step runs `groove slurm-step FILE` on a
//! compute node: it executes its keys and commits each into the project's store, then exits; the
//! controller opens the committed entries. So the project folder (with `.groove/`) and the groove
//! binary must be on a filesystem the compute nodes share, as Slurm sites have for home and
//! scratch. Exit codes and stderr come back from `srun` directly: no `sacct`, no polling.
//!
//! ```toml
//! [slurm]
//! partition = "debug"      # the allocation's partition (default: the cluster's default)
//! time = "02:00:00"        # the allocation's time limit
//! cpus = 8                 # CPUs of the allocation (default 2)
//! mem = "16G"              # its memory (default: the partition's)
//! job_name = "groove"
//!
//! [slurm.kinds.command]    # job-step resources for every stage of a kind
//! cpus = 1
//! mem = "2G"
//! time = "00:30:00"
//! batch = 16               # items of a per-item stage per step
//!
//! [stages.track.slurm]     # one stage's own (override its kind's)
//! cpus = 2
//! partition = "bigmem"     # a stage on another partition gets its own allocation there
//! ```
//!
//! - A failing step: exit 2 naming the stage and the tail of its stderr; no entry is committed for
//!   it (entries are atomic, as always).
//! - A cancelled, preempted or timed-out allocation: exit 2 saying so and that a rerun resumes; every
//!   key a step committed before is reused, so the rerun does only the unfinished work.
//! - `groove status` and `groove dag` are unchanged; the report and `pipeline.lock` are identical to
//!   a local run's (tested).
//! - The allocation is released (`scancel`) when the run ends; a controller killed with `kill -9`
//!   leaves it until its time limit.

pub mod alloc;
pub mod config;
pub mod executor;
pub mod job;
pub mod worker;

pub use executor::SlurmExecutor;
