//! The `groove` command line (being built).

fn main() {
    eprintln!("groove: not built yet");
    std::process::exit(2);
}
