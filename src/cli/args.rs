//! The command-line grammar (clap): verbs and their options.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Run a whole groove-experiment analysis with one command; rerun only what went stale.
///
/// Exit codes: 0 success; 1 ran, but a check failed (`publish` or `status --exit-code` with
/// stale stages, `verify` dropped something, `diff --fail-above` exceeded); 2 error (bad config,
/// bad data, IO, a stage failed).
#[derive(Debug, Parser)]
#[command(name = "groove", version, about, long_about)]
pub struct Cli {
    #[command(subcommand)]
    pub verb: Verb,
}

/// The pipeline file read when `--config` is not given.
pub const DEFAULT_CONFIG: &str = "pipeline.toml";

/// Which pipeline, on which dataset, writing which reports folder.
#[derive(Debug, Args)]
pub struct Project {
    /// The pipeline file (default: pipeline.toml); relative paths inside it resolve against its
    /// folder. Without one here, `--data DIR` runs the built-in pipeline (the analysis as shipped).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Use this dataset folder instead of the pipeline's `[project] data`.
    #[arg(long, value_name = "DIR")]
    pub data: Option<PathBuf>,
    /// Write reports here instead of the pipeline's `[project] reports`.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

impl Project {
    /// The pipeline file: `--config`, else `pipeline.toml`.
    pub fn config_path(&self) -> PathBuf {
        self.config
            .clone()
            .unwrap_or_else(|| PathBuf::from(DEFAULT_CONFIG))
    }
}

/// Which project's store (`clean`, `gc`, `verify`): the folder of the pipeline file. Without one
/// here, the current folder (where the built-in pipeline keeps its `.groove`).
#[derive(Debug, Args)]
pub struct StoreProject {
    /// The pipeline file (default: pipeline.toml); its folder holds the store `.groove/`.
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
}

/// The shared remote cache (see README, "Remote cache and Slurm").
#[derive(Debug, Args, Clone)]
pub struct RemoteArgs {
    /// Use this remote cache: file:///shared/path or s3://bucket/prefix (else GROOVE_REMOTE,
    /// else `[remote] url` in pipeline.toml).
    #[arg(long, value_name = "URL")]
    pub remote: Option<String>,
    /// Use no remote, whatever the environment and pipeline.toml say.
    #[arg(long, conflicts_with = "remote")]
    pub no_remote: bool,
    /// Exit 2 when the remote fails instead of warning and going on locally.
    #[arg(long)]
    pub remote_required: bool,
}

/// `--remote-read-only`, for the verbs that may write to the remote but need not (`run`, `pull`).
#[derive(Debug, Args, Clone)]
pub struct ReadOnly {
    /// Look results up on the remote but never write to it.
    #[arg(long)]
    pub remote_read_only: bool,
}

#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum Executor {
    /// Run stages on this machine.
    Local,
    /// Run stages as job steps in one Slurm allocation (`[slurm]` in pipeline.toml).
    Slurm,
}

#[derive(Debug, Subcommand)]
pub enum Verb {
    /// Run what is stale: all stages, or the named ones and what they need.
    Run {
        /// Stages to bring up to date (default: all).
        #[arg(value_name = "STAGE")]
        stages: Vec<String>,
        #[command(flatten)]
        project: Project,
        /// Worker threads for independent stages and items (default: one per core).
        #[arg(long, short, value_name = "N")]
        jobs: Option<usize>,
        /// Run this stage even if its result is in the store (repeatable).
        #[arg(long, value_name = "STAGE")]
        force: Vec<String>,
        /// Only print what would run, and why.
        #[arg(long)]
        dry_run: bool,
        /// Where stages run: here, or as job steps of one Slurm allocation.
        #[arg(long, value_enum, default_value_t = Executor::Local)]
        executor: Executor,
        #[command(flatten)]
        remote: RemoteArgs,
        #[command(flatten)]
        read_only: ReadOnly,
    },
    /// Upload every result pipeline.lock names from the local store to the remote cache
    /// (blobs first, then entries; what the remote has is not sent again).
    Push {
        #[command(flatten)]
        project: Project,
        #[command(flatten)]
        remote: RemoteArgs,
    },
    /// Fill the local store from the remote cache with every result the pipeline can reuse
    /// (each blob verified by sha256); runs nothing.
    Pull {
        #[command(flatten)]
        project: Project,
        #[command(flatten)]
        remote: RemoteArgs,
        #[command(flatten)]
        read_only: ReadOnly,
    },
    /// Run one Slurm job step (started by `groove run --executor slurm`, not by hand).
    #[command(hide = true)]
    SlurmStep {
        /// The step file the controller wrote.
        file: PathBuf,
    },
    /// For every stage: fresh or stale, and why (which input, param or code changed).
    /// Ends with a counts line (`9 stages: 7 fresh, 2 stale`).
    Status {
        #[command(flatten)]
        project: Project,
        /// Print `[{stage, state, reasons}]` as JSON (stable for scripts).
        #[arg(long)]
        json: bool,
        /// Exit 1 when any stage is stale (0 when every stage is fresh), for scripts and CI.
        #[arg(long)]
        exit_code: bool,
    },
    /// Print the stage graph, each stage marked fresh or stale (dot and Mermaid: by colour).
    Dag {
        #[command(flatten)]
        project: Project,
        #[arg(long, value_enum, default_value_t = DagFormat::Text)]
        format: DagFormat,
    },
    /// Start a project in DIR (default: here): the built-in pipeline.toml and an empty dataset
    /// folder `data/` (runs.csv and trajectories.csv with their headers). Overwrites nothing.
    Init {
        /// The project folder (made if missing).
        #[arg(value_name = "DIR", default_value = ".")]
        dir: PathBuf,
    },
    /// Print a stored result readably: `groove show ingest:runs` (a line per run), `--csv` (the
    /// runs as interchange CSV), `fit:fits --item RUN` (the fit as JSON), `aggregate:summary`.
    /// Reads the results of the last run (pipeline.lock) from the store; changes nothing.
    Show {
        /// STAGE:OUTPUT, e.g. ingest:runs, fit:fits, discover:diagnosis.
        #[arg(value_name = "STAGE:OUTPUT")]
        target: String,
        #[command(flatten)]
        project: Project,
        /// Only this item of a per-item output (e.g. a run id).
        #[arg(long, value_name = "KEY")]
        item: Option<String>,
        /// As CSV (recordings: run,particle,frame,t_s,z_m, the interchange format).
        #[arg(long, conflicts_with = "json")]
        csv: bool,
        /// As JSON.
        #[arg(long)]
        json: bool,
    },
    /// Compare two results number by number: every number of summary.json and diagnosis.json
    /// side by side with its change in combined standard errors (σ), findings that appeared or
    /// disappeared, and params changed. A and B are result folders (reports/), published bundles
    /// or git revisions (their committed reports/); default A: the bundle the last `groove
    /// publish` wrote, else HEAD; B: the working reports.
    Diff {
        /// The baseline: a folder or a git revision (default: the bundle the last `groove
        /// publish` wrote, else HEAD).
        #[arg(value_name = "A")]
        a: Option<String>,
        /// The result compared with it: a folder or a git revision (default: the reports folder).
        #[arg(value_name = "B")]
        b: Option<String>,
        /// Print every compared number as JSON.
        #[arg(long)]
        json: bool,
        /// Print unchanged numbers too.
        #[arg(long)]
        all: bool,
        /// Exit 1 when any estimate moved by more than SIGMA combined standard errors.
        #[arg(long, value_name = "SIGMA")]
        fail_above: Option<f64>,
    },
    /// Print a shell completion script: e.g. `groove completions bash > ~/.local/share/bash-completion/completions/groove`.
    Completions {
        /// The shell.
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Remove the store (`.groove/`); outputs and pipeline.lock stay.
    Clean {
        #[command(flatten)]
        project: StoreProject,
    },
    /// Drop store entries that pipeline.lock does not reference.
    Gc {
        #[command(flatten)]
        project: StoreProject,
    },
    /// Check every object of the store against its hash; drop damaged objects and the entries
    /// that name them (their stages run again). Exit 1 if anything was dropped.
    Verify {
        #[command(flatten)]
        project: StoreProject,
    },
    /// Write a synthetic dataset from a truth file (the virtual experiment).
    Synth {
        /// The truth TOML (parameters and runs to simulate).
        #[arg(long, value_name = "FILE")]
        truth: PathBuf,
        /// The dataset folder to write.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// The trajectories as trajectories.csv (the default) or trajectories.parquet (the same
        /// values, typed, zstd-compressed; runs.csv stays CSV).
        #[arg(long, value_enum, default_value = "csv")]
        format: SynthFormat,
    },
    /// Copy the report bundle with pipeline.lock and a sha256 manifest to DIR; refuses (exit 1)
    /// while any stage is stale.
    Publish {
        #[command(flatten)]
        project: Project,
        /// The folder to write the bundle to (new, empty, or an earlier bundle).
        #[arg(long, value_name = "DIR")]
        to: PathBuf,
    },
}

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum DagFormat {
    Text,
    Dot,
    Mermaid,
}

/// The file `groove synth` writes the trajectories to.
#[derive(Debug, Clone, Copy, ValueEnum, PartialEq, Eq)]
pub enum SynthFormat {
    Csv,
    Parquet,
}
