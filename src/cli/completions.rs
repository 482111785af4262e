//! `groove completions SHELL`: a completion script for bash, zsh, fish, elvish or PowerShell,
//! generated from the command-line grammar itself, so it never falls behind it.

use super::args::Cli;
use clap::CommandFactory;

/// Writes the script for `shell` to stdout.
pub fn print(shell: clap_complete::Shell) {
    let mut cmd = Cli::command();
    clap_complete::generate(shell, &mut cmd, "groove", &mut std::io::stdout());
}
