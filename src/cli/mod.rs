//! The verbs: each loads the pipeline, calls the engine, and prints its result.

pub mod args;

use args::{Cli, DagFormat, Project, Verb};
use groove::engine::config::{self, Overrides};
use groove::engine::publish::{publish, Published};
use groove::engine::run::{run, RunOptions};
use groove::engine::{dag, maintenance, status, Catalog, EngineError, Pipeline};
use std::process::ExitCode;

fn load(project: &Project, catalog: &Catalog) -> Result<Pipeline, EngineError> {
    let overrides = Overrides {
        data: project.data.clone(),
        reports: project.out.clone(),
    };
    config::load(&project.config, &overrides, catalog)
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
        } => {
            let pipeline = load(&project, &catalog)?;
            let opts = RunOptions {
                targets: stages,
                force,
                jobs,
                dry_run,
                quiet: false,
            };
            let summary = run(&catalog, &pipeline, &opts)?;
            if dry_run {
                if summary.would_run.is_empty() {
                    println!("groove: nothing to run; every stage is fresh");
                } else {
                    println!("would run:");
                    print!("{}", status::render(&summary.would_run));
                }
                return Ok(ExitCode::SUCCESS);
            }
            let report = pipeline.reports_dir.join("report.html");
            let shown = if report.is_file() {
                report
            } else {
                pipeline.reports_dir.clone()
            };
            println!(
                "groove: {} stage{} run, {} reused, {:.2} s; report: {}",
                summary.ran.len(),
                if summary.ran.len() == 1 { "" } else { "s" },
                summary.reused.len(),
                summary.elapsed_s,
                pipeline.show(&shown)
            );
            Ok(ExitCode::SUCCESS)
        }
        Verb::Status { project, json } => {
            let pipeline = load(&project, &catalog)?;
            let statuses = status::status(&catalog, &pipeline, None)?;
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&statuses).expect("statuses serialize")
                );
            } else {
                print!("{}", status::render(&statuses));
            }
            Ok(ExitCode::SUCCESS)
        }
        Verb::Dag { project, format } => {
            let pipeline = load(&project, &catalog)?;
            let format = match format {
                DagFormat::Text => dag::Format::Text,
                DagFormat::Dot => dag::Format::Dot,
                DagFormat::Mermaid => dag::Format::Mermaid,
            };
            print!("{}", dag::render(&pipeline, format));
            Ok(ExitCode::SUCCESS)
        }
        Verb::Clean { project } => {
            let pipeline = load(&project, &catalog)?;
            let removed = maintenance::clean(&pipeline)?;
            println!(
                "groove: removed {removed} item(s) from {}",
                pipeline.show(&pipeline.root.join(".groove"))
            );
            Ok(ExitCode::SUCCESS)
        }
        Verb::Gc { project } => {
            let pipeline = load(&project, &catalog)?;
            let (entries, objects) = maintenance::gc(&pipeline)?;
            println!("groove: removed {entries} store entr{} and {objects} object(s) not in pipeline.lock", if entries == 1 { "y" } else { "ies" });
            Ok(ExitCode::SUCCESS)
        }
        Verb::Synth { truth, out } => {
            groove::synth::run_synth(&truth, &out)
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
                    eprint!("{}", status::render(&stale));
                    Ok(ExitCode::from(1))
                }
                Published::Written { dir, files } => {
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
