//! Driving a built `groove` binary (any build: the tests' own, or the one a bench is given): the
//! run of a project folder laid out as the tests make them, and what a run said.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

/// `groove run` in a project folder holding `pipeline.toml`, `data/` and `reports/`.
pub const RUN_IN_PROJECT: [&str; 7] = [
    "run",
    "--config",
    "pipeline.toml",
    "--data",
    "data",
    "--out",
    "reports",
];

/// `binary ARGS` in `cwd`, without the remote settings of the environment the tests run in.
pub fn command(binary: &Path, cwd: &Path, args: &[&str]) -> Command {
    let mut c = Command::new(binary);
    c.args(args)
        .current_dir(cwd)
        .env_remove("GROOVE_REMOTE")
        .env_remove("GROOVE_REMOTE_READ_ONLY");
    c
}

/// Everything a run said: stdout, then stderr.
pub fn said(out: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}
