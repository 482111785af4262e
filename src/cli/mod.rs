//! The verbs: each loads the pipeline, calls the engine, and prints its result.
//!
//! Files of this folder:
//!
//! - `args.rs`: The command-line grammar (clap): verbs and their options
//! - `completions.rs`: `groove completions SHELL`
//! - `diff.rs`: `groove diff [A] [B]`
//! - `init.rs`: `groove init [DIR]`
//! - `show.rs`: `groove show STAGE:OUTPUT`
//! - `status.rs`: `groove status` and `groove dag` for scripts and eyes
//!
//! # The verbs
//!
//! Every verb has `--help`. `run`, `status`, `dag`, `clean`, `gc` and `publish` take
//! `--config FILE` (default `./pipeline.toml`; relative paths inside it resolve against its folder),
//! `--data DIR` (replaces `[project] data`) and `--out DIR` (replaces `[project] reports`; both
//! relative to the current folder), so the same analysis runs on any dataset in the interchange
//! format.
//!
//! | verb | what it does |
//! | --- | --- |
//! | `groove run [STAGE…]` | runs what is stale: every stage, or the named ones and what they need. `--jobs N` worker threads (default: one per core), `--force STAGE` (repeatable) reruns a stage even when its result is stored, `--dry-run` prints what would run and why. Ends with one line: stages run, reused, time, report path. |
//! | `groove status [--json]` | every stage, fresh or stale, with the reasons (which input, param or code changed, old → new). `--json` prints `[{"stage", "state": "fresh"\|"stale", "reasons": [..]}]`, stable for scripts. Needs no lock; never runs anything. |
//! | `groove dag [--format text\|dot\|mermaid]` | the stage graph, in topological order (text) or for Graphviz / Mermaid. |
//! | `groove clean` | removes the store `.groove/` (outputs in the project and `pipeline.lock` stay). |
//! | `groove gc` | drops store entries that `pipeline.lock` does not reference (older params, older code), then objects neither they nor the memos of the lock's stages reference (an aggregate's material summaries stay for the next edit), and the memos of stages the lock does not hold. Refuses (exit 2, nothing removed) when `pipeline.lock` is missing, unreadable or names no stage. |
//! | `groove verify` | checks every store object against its sha256; drops damaged objects and the entries naming a missing one, and lists them (exit 1 if anything was dropped; the next `run` recomputes it). |
//! | `groove synth --truth FILE --out DIR [--format parquet]` | writes a synthetic dataset from a truth file (`--format parquet`: trajectories.parquet, the same values typed and zstd-compressed, instead of trajectories.csv). |
//! | `groove publish --to DIR` | refuses with exit 1, naming each stale stage and why, unless every stage is fresh; otherwise writes the bundle to DIR: every output materialized inside the reports folder (report.html, report.md, figures/, and the tables beside them) taken from the store, `pipeline.lock`, and `SHA256SUMS` (`sha256sum -c` format). DIR must be new, empty or an earlier bundle; it is replaced whole. |
//!
//! # Exit codes
//!
//! | code | meaning |
//! | --- | --- |
//! | 0 | success |
//! | 1 | ran, but a check failed: `publish` with stale stages, `verify` that dropped something |
//! | 2 | error: bad `pipeline.toml` (with its line), bad data, IO, a stage failed (with its stderr), bad arguments |
//!
//! Errors are printed once, by `main`, as `groove: error: …`, lowercase, saying how to fix.

pub mod args;
mod completions;
mod diff;
mod init;
mod show;
mod status;

use args::{Cli, Executor, Project, RemoteArgs, StoreProject, Verb, DEFAULT_CONFIG};
use groove::engine::config::{self, Overrides};
use groove::engine::publish::{publish, Published};
use groove::engine::run::{run, RunOptions};
use groove::engine::{maintenance, status as stage_status, Catalog, EngineError, Pipeline};
use std::path::Path;
use std::process::ExitCode;

/// The analysis as shipped (the repository's `pipeline.toml`): what `groove run --data DIR`
/// runs in a folder that has no pipeline file of its own.
const BUILT_IN_PIPELINE: &str = include_str!("../../pipeline.toml");

fn load(project: &Project, catalog: &Catalog) -> Result<Pipeline, EngineError> {
    let overrides = Overrides {
        data: project.data.clone(),
        reports: project.out.clone(),
    };
    if uses_built_in(project) {
        eprintln!(
            "groove: no {} here: running the built-in pipeline (the analysis as shipped) on {}; its cache goes to ./.groove",
            DEFAULT_CONFIG,
            project.data.as_deref().unwrap_or(Path::new("data")).display()
        );
        let bytes = BUILT_IN_PIPELINE.as_bytes().to_vec();
        return config::load_bytes(&project.config_path(), bytes, &overrides, catalog);
    }
    config::load(&project.config_path(), &overrides, catalog)
}

/// The project whose store `clean`, `gc` and `verify` look after: the pipeline file's (not
/// validated against a dataset: the store needs none), or, with no pipeline file here, the
/// current folder, where the built-in pipeline keeps its store.
fn store_project(project: &StoreProject, catalog: &Catalog) -> Result<Pipeline, EngineError> {
    let config = project
        .config
        .clone()
        .unwrap_or_else(|| std::path::PathBuf::from(DEFAULT_CONFIG));
    if project.config.is_some() || config.exists() {
        return config::load(&config, &Overrides::default(), catalog);
    }
    let root = std::env::current_dir()
        .map_err(|e| EngineError::Usage(format!("cannot tell the current folder: {e}")))?;
    Ok(Pipeline {
        config_path: root.join(DEFAULT_CONFIG),
        data_dir: root.join("data"),
        reports_dir: root.join("reports"),
        root,
        seed: 0,
        stages: Default::default(),
    })
}

/// A dataset given with `--data`, no `--config`, and no `pipeline.toml` in this folder.
fn uses_built_in(project: &Project) -> bool {
    project.data.is_some() && project.config.is_none() && !Path::new(DEFAULT_CONFIG).exists()
}

/// The remote settings from the flags, GROOVE_REMOTE and `[remote]`.
fn remote_settings(
    project: &Project,
    args: &RemoteArgs,
    read_only: bool,
) -> Result<Option<groove::engine::remote::Settings>, EngineError> {
    let flags = groove::engine::remote::settings::Flags {
        url: args.remote.clone(),
        no_remote: args.no_remote,
        read_only,
        required: args.remote_required,
    };
    groove::engine::remote::settings::resolve(&project.config_path(), &flags)
}

/// Print the remote's closing line; with `--remote-required`, a remote error is exit 2.
fn remote_closing(
    cache: &groove::engine::remote::RemoteCache,
    required: bool,
) -> Result<ExitCode, EngineError> {
    println!("groove: {}", cache.closing_line());
    match (required, cache.first_error()) {
        (true, Some(e)) => Err(EngineError::Usage(format!(
            "the remote {} is required (--remote-required) but failed: {e}; fix it or drop --remote-required",
            cache.describe()
        ))),
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// Run one verb. `Ok` carries the exit code of a verb that ran (0, or 1 for a failed check).
pub fn dispatch(cli: Cli) -> Result<ExitCode, EngineError> {
    let catalog = Catalog::with_kinds(groove::stages::registry());
    match cli.verb {
        Verb::Run {
            stages,
            project,
            jobs,
            force,
            dry_run,
            executor,
            remote,
            read_only,
        } => {
            let pipeline = load(&project, &catalog)?;
            let opts = RunOptions {
                targets: stages,
                force,
                jobs,
                dry_run,
                quiet: false,
                remote: remote_settings(&project, &remote, read_only.remote_read_only)?,
                slurm: executor == Executor::Slurm,
            };
            let summary = run(&catalog, &pipeline, &opts)?;
            if dry_run {
                print_would_run(&summary);
                return Ok(ExitCode::SUCCESS);
            }
            print_run_summary(&pipeline, &summary);
            Ok(ExitCode::SUCCESS)
        }
        Verb::Push { project, remote } => push(&catalog, &project, &remote),
        Verb::Pull {
            project,
            remote,
            read_only,
        } => pull(&catalog, &project, &remote, read_only.remote_read_only),
        Verb::SlurmStep { file } => {
            let threads = std::env::var("SLURM_CPUS_PER_TASK")
                .ok()
                .and_then(|v| v.parse::<usize>().ok())
                .unwrap_or(1);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads.max(1))
                .build()
                .map_err(|e| EngineError::Usage(format!("cannot start worker threads: {e}")))?;
            pool.install(|| groove::engine::slurm::worker::run_step(&catalog, &file))?;
            Ok(ExitCode::SUCCESS)
        }
        Verb::Status {
            project,
            json,
            exit_code,
        } => status::status(&catalog, &project, json, exit_code),
        Verb::Dag { project, format } => status::dag(&catalog, &project, format),
        Verb::Init { dir } => {
            let wrote = init::init(&dir, BUILT_IN_PIPELINE)?;
            println!(
                "groove: wrote {} in {}; put your runs in data/ (README, \"Dataset format\"), or try `groove synth --truth TRUTH.toml --out data`, then `groove run`",
                wrote.join(", "),
                openable(&dir)
            );
            Ok(ExitCode::SUCCESS)
        }
        Verb::Show {
            target,
            project,
            item,
            csv,
            json,
        } => {
            let how = match (csv, json) {
                (true, _) => show::As::Csv,
                (_, true) => show::As::Json,
                _ => show::As::Readable,
            };
            show::show(&catalog, &project, &target, item.as_deref(), how)
        }
        Verb::Diff {
            a,
            b,
            json,
            all,
            fail_above,
        } => diff::diff(a.as_deref(), b.as_deref(), json, all, fail_above),
        Verb::Completions { shell } => {
            completions::print(shell);
            Ok(ExitCode::SUCCESS)
        }
        Verb::Clean { project } => {
            let pipeline = store_project(&project, &catalog)?;
            let removed = maintenance::clean(&pipeline)?;
            println!(
                "groove: removed {removed} item(s) from {}",
                pipeline.show(&pipeline.root.join(".groove"))
            );
            Ok(ExitCode::SUCCESS)
        }
        Verb::Gc { project } => {
            let pipeline = store_project(&project, &catalog)?;
            let (entries, objects) = maintenance::gc(&pipeline)?;
            println!("groove: removed {entries} store entr{} and {objects} object(s) not in pipeline.lock", if entries == 1 { "y" } else { "ies" });
            Ok(ExitCode::SUCCESS)
        }
        Verb::Verify { project } => verify(&catalog, &project),
        Verb::Synth { truth, out, format } => {
            let parquet = format == args::SynthFormat::Parquet;
            groove::synth::run_synth_as(&truth, &out, parquet)
                .map_err(|e| EngineError::Usage(format!("synth: {e}")))?;
            println!("groove: wrote a synthetic dataset to {}", out.display());
            Ok(ExitCode::SUCCESS)
        }
        Verb::Publish { project, to } => {
            let pipeline = load(&project, &catalog)?;
            match publish(&catalog, &pipeline, &to)? {
                Published::Refused(stale) => {
                    eprintln!(
                        "groove: not published: these stages are stale (run `groove run` first):"
                    );
                    eprint!("{}", stage_status::render(&stale));
                    Ok(ExitCode::from(1))
                }
                Published::Written { dir, files } => {
                    // `groove diff` compares with it by default; a store that cannot be
                    // written keeps no note (diff then compares with the committed reports)
                    let _ = std::fs::write(
                        pipeline.root.join(diff::LAST_PUBLISHED),
                        std::path::absolute(&dir)
                            .unwrap_or_else(|_| dir.clone())
                            .to_string_lossy()
                            .as_bytes(),
                    );
                    println!(
                        "groove: published {} files to {}",
                        files.len(),
                        dir.display()
                    );
                    Ok(ExitCode::SUCCESS)
                }
            }
        }
    }
}

/// `run --dry-run`: what would run and why.
fn print_would_run(summary: &groove::engine::run::RunSummary) {
    if summary.would_run.is_empty() {
        println!("groove: nothing to run; every stage is fresh");
    } else {
        println!("would run:");
        print!("{}", stage_status::render(&summary.would_run));
    }
}

/// A path as the user can open it from where they ran groove: relative to the current folder
/// when it lies inside it, otherwise whole (a path relative to the project's folder would not
/// open from elsewhere).
fn openable(path: &std::path::Path) -> String {
    let whole = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let cwd = std::env::current_dir().ok();
    let shown = cwd
        .as_deref()
        .and_then(|cwd| whole.strip_prefix(cwd).ok())
        .filter(|rel| !rel.as_os_str().is_empty())
        .unwrap_or(&whole);
    shown.to_string_lossy().replace('\\', "/")
}

/// The closing lines of `run`: stages run and reused, time, where the results are (the report
/// when a stage of this run writes it, else the files its stages write, else the store), Slurm
/// and remote lines.
fn print_run_summary(pipeline: &Pipeline, summary: &groove::engine::run::RunSummary) {
    let done: Vec<&String> = summary.ran.iter().chain(&summary.reused).collect();
    let written: Vec<&std::path::PathBuf> = done
        .iter()
        .filter_map(|s| pipeline.stages.get(s.as_str()))
        .flat_map(|spec| spec.outputs.values().flatten())
        .collect();
    let report = pipeline.reports_dir.join("report.html");
    let place = if written.contains(&&report) && report.is_file() {
        format!("report: {}", openable(&report))
    } else if written.is_empty() {
        let first = done
            .first()
            .and_then(|s| pipeline.stages.get(s.as_str()))
            .and_then(|spec| Some(format!("{}:{}", spec.name, spec.outputs.keys().next()?)))
            .unwrap_or_else(|| "STAGE:OUTPUT".to_string());
        format!("results in the store (`groove show {first}` prints one)")
    } else {
        let mut shown: Vec<String> = written.iter().map(|p| openable(p)).collect();
        shown.sort();
        format!("wrote {}", shown.join(", "))
    };
    println!(
        "groove: {} stage{} run, {} reused, {:.2} s; {place}",
        summary.ran.len(),
        if summary.ran.len() == 1 { "" } else { "s" },
        summary.reused.len(),
        summary.elapsed_s,
    );
    if let Some(line) = &summary.slurm_line {
        println!("groove: {line}");
    }
    if let Some(line) = &summary.remote_line {
        println!("groove: {line}");
    }
}

/// The pipeline and the remote settings of `push` / `pull`; no remote configured is an error
/// saying how to name one (`what`: "push to", "pull from").
fn with_remote(
    catalog: &Catalog,
    project: &Project,
    remote: &RemoteArgs,
    read_only: bool,
    what: &str,
) -> Result<(Pipeline, groove::engine::remote::Settings), EngineError> {
    let pipeline = load(project, catalog)?;
    let Some(settings) = remote_settings(project, remote, read_only)? else {
        return Err(EngineError::Usage(format!("no remote to {what}; pass --remote URL, set GROOVE_REMOTE, or add [remote] url to pipeline.toml")));
    };
    Ok((pipeline, settings))
}

/// `push`: every result pipeline.lock names, from the local store to the remote.
fn push(
    catalog: &Catalog,
    project: &Project,
    remote: &RemoteArgs,
) -> Result<ExitCode, EngineError> {
    let (pipeline, settings) = with_remote(catalog, project, remote, false, "push to")?;
    if settings.read_only {
        return Err(EngineError::Usage(format!("the remote {} is read-only here (GROOVE_REMOTE_READ_ONLY or `read_only = true` in [remote]); unset it to push", settings.url)));
    }
    let cache = std::sync::Arc::new(groove::engine::remote::open(&settings, &pipeline.root)?);
    let store = groove::engine::store::Store::at(&pipeline.root);
    let lock = groove::engine::lockfile::PipelineLock::load(&groove::engine::context::lock_path(
        &pipeline,
    ));
    let keys = groove::engine::remote::sync::lock_keys(&lock);
    let synced = groove::engine::remote::sync::push_all(&cache, &store, &keys, settings.jobs);
    println!(
        "groove: push: {} keys in pipeline.lock, {} not in the local store",
        synced.keys, synced.skipped
    );
    unreachable_is_an_error(&cache, "push to")?;
    remote_closing(&cache, settings.required)
}

/// Pushing or pulling is the verb's whole work: a remote that could not be reached (it turned
/// itself off after its first failure) is an error, exit 2, naming it and the fix.
fn unreachable_is_an_error(
    cache: &groove::engine::remote::RemoteCache,
    what: &str,
) -> Result<(), EngineError> {
    if !cache.is_disabled() {
        return Ok(());
    }
    println!("groove: {}", cache.closing_line());
    Err(EngineError::Usage(format!(
        "cannot {what} the remote {}: {}; {}",
        cache.describe(),
        cache.first_error().unwrap_or_default(),
        cache.hint()
    )))
}

/// `pull`: every stage's results from the remote into the local store.
fn pull(
    catalog: &Catalog,
    project: &Project,
    remote: &RemoteArgs,
    read_only: bool,
) -> Result<ExitCode, EngineError> {
    let (pipeline, settings) = with_remote(catalog, project, remote, read_only, "pull from")?;
    let cache = std::sync::Arc::new(groove::engine::remote::open(&settings, &pipeline.root)?);
    if let Err(why) = cache.check_present() {
        return Err(EngineError::Usage(format!(
            "cannot pull from the remote {}: {why}; {}",
            cache.describe(),
            cache.hint()
        )));
    }
    let fresh = groove::engine::remote::sync::pull(catalog, &pipeline, &cache)?;
    println!(
        "groove: pull: {fresh} of {} stages now have every result in the local store",
        pipeline.stages.len()
    );
    unreachable_is_an_error(&cache, "pull from")?;
    remote_closing(&cache, settings.required)
}

/// `verify`: every store object against its sha256; exit 1 when something was dropped.
fn verify(catalog: &Catalog, project: &StoreProject) -> Result<ExitCode, EngineError> {
    let pipeline = store_project(project, catalog)?;
    let v = maintenance::verify(&pipeline)?;
    println!(
        "groove: checked {} object(s) and {} store entr{}",
        v.objects,
        v.entries,
        if v.entries == 1 { "y" } else { "ies" }
    );
    for o in &v.dropped_objects {
        println!("dropped damaged object {o}");
    }
    for e in &v.dropped_entries {
        println!("dropped entry {e} (it named a damaged or missing object; its stage runs again)");
    }
    if v.dropped_objects.is_empty() && v.dropped_entries.is_empty() {
        println!("groove: the store is sound");
        Ok(ExitCode::SUCCESS)
    } else {
        println!("groove: run `groove run` to recompute what was dropped");
        Ok(ExitCode::from(1))
    }
}
