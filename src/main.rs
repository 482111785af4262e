//! The `groove` command line: parse arguments, run one verb, print errors once, exit 0, 1 or 2.

mod cli;

fn main() -> std::process::ExitCode {
    use clap::Parser;
    let args = cli::args::Cli::parse();
    match cli::dispatch(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("groove: error: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
