//! `groove status` and `groove dag` for scripts and eyes: the counts line, the exit code, the
//! graph marked by state.

use super::args::{DagFormat, Project};
use groove::engine::status::{self, StageStatus, State};
use groove::engine::{dag, Catalog, EngineError};
use std::collections::BTreeMap;
use std::io::IsTerminal;
use std::process::ExitCode;

/// `9 stages: 7 fresh, 2 stale`.
pub fn counts_line(statuses: &[StageStatus]) -> String {
    let stale = statuses.iter().filter(|s| s.state == State::Stale).count();
    let n = statuses.len();
    format!(
        "{n} stage{}: {} fresh, {stale} stale",
        if n == 1 { "" } else { "s" },
        n - stale
    )
}

/// `status`: the lines (or JSON) and the counts line; with `exit_code`, 1 when anything is stale.
pub fn status(
    catalog: &Catalog,
    project: &Project,
    json: bool,
    exit_code: bool,
) -> Result<ExitCode, EngineError> {
    let pipeline = super::load(project, catalog)?;
    let statuses = status::status(catalog, &pipeline, None)?;
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&statuses).expect("statuses serialize")
        );
    } else {
        print!("{}", status::render(&statuses));
        println!("groove: {}", counts_line(&statuses));
    }
    let stale = statuses.iter().any(|s| s.state == State::Stale);
    Ok(if exit_code && stale {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

/// `dag`: the graph with each stage's state (when it can be told: a pipeline whose inputs are
/// missing is drawn without).
pub fn dag(
    catalog: &Catalog,
    project: &Project,
    format: DagFormat,
) -> Result<ExitCode, EngineError> {
    let pipeline = super::load(project, catalog)?;
    let states: BTreeMap<String, String> = match status::status(catalog, &pipeline, None) {
        Ok(statuses) => statuses
            .into_iter()
            .map(|s| {
                let st = match s.state {
                    State::Fresh => "fresh",
                    State::Stale => "stale",
                };
                (s.stage, st.to_string())
            })
            .collect(),
        Err(e) => {
            eprintln!(
                "groove: the stages' states cannot be told ({e}); the graph is drawn without them"
            );
            BTreeMap::new()
        }
    };
    let format = match format {
        DagFormat::Text => dag::Format::Text,
        DagFormat::Dot => dag::Format::Dot,
        DagFormat::Mermaid => dag::Format::Mermaid,
    };
    let ansi = format == dag::Format::Text && std::io::stdout().is_terminal();
    print!(
        "{}",
        dag::render_with_state(&pipeline, format, &states, ansi)
    );
    Ok(ExitCode::SUCCESS)
}
