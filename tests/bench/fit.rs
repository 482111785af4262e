//! Benchmark: fit 10,000 synthetic single runs of 600 frames on one core and print runs/s.
//!
//! `cargo bench --bench fit -- [--runs N] [--parallel] [--dump DIR [--dump-count M]]`. With
//! `--dump`, the first M runs (`runs.csv`: run,t_s,z_m), the fit's start values (`starts.csv`) and
//! the measured rate (`rust_rate.txt`) are written for `tests/bench/fit_vs_scipy.sh`. Rates are
//! per core: CPU seconds of the single-threaded loop (wall time is printed beside them).

#[path = "../support/single_runs.rs"]
mod single_runs;

use groove::artifacts::FitStatus;
use groove::fit::single::fit_track;
use groove::fit::start::single_start;
use groove::fit::track_problem::Workspace;
use groove::fit::FitOptions;
use rayon::prelude::*;
use single_runs::{runs, Camera};
use std::fmt::Write as _;
use std::time::Instant;

/// CPU time of this process in seconds (Linux: utime + stime from /proc/self/stat), so that the
/// rate per core is right on a shared machine; None elsewhere.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    let rest = &stat[stat.rfind(')')? + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0) // USER_HZ is 100 on Linux
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
    };
    let n: usize = arg("--runs").map_or(10_000, |s| s.parse().expect("--runs takes a count"));
    let dump = arg("--dump");
    let dump_count: usize =
        arg("--dump-count").map_or(n, |s| s.parse().expect("--dump-count takes a count"));
    let parallel = args.iter().any(|a| a == "--parallel");

    let t_synth = Instant::now();
    let mut all = runs(2026, n / 2, (0.005, 0.1), 0.337, Camera::CHAPTER);
    all.extend(runs(2027, n - n / 2, (0.005, 0.1), 0.293, Camera::CHAPTER));
    let frames: usize = all.iter().map(|r| r.t_s.len()).sum();
    println!(
        "synthesized {} runs, {:.0} frames per run on average, in {:.2} s",
        all.len(),
        frames as f64 / n as f64,
        t_synth.elapsed().as_secs_f64()
    );

    let opts = FitOptions::default();
    let fps = Camera::CHAPTER.fps;
    let start = Instant::now();
    let cpu0 = cpu_seconds();
    let mut ws = Workspace::default();
    let mut converged = 0usize;
    let mut iterations = 0u64;
    let mut worst_v0 = 0.0f64;
    for r in &all {
        let f = fit_track(&r.t_s, &r.z_m, fps, &opts, &mut ws);
        converged += (f.status == FitStatus::Converged) as usize;
        iterations += f.iterations as u64;
        worst_v0 = worst_v0.max((f.v0_mps / r.truth.v0_mps - 1.0).abs());
    }
    let wall = start.elapsed().as_secs_f64();
    // per core: CPU seconds of this (single-threaded) loop when available, else wall time
    let secs = match (cpu0, cpu_seconds()) {
        (Some(a), Some(b)) if b > a => b - a,
        _ => wall,
    };
    let rate = n as f64 / secs;
    println!(
        "one core: {n} fits in {secs:.2} CPU s ({wall:.2} s wall) = {rate:.0} runs/s per core ({:.1} µs per run); {converged} converged, {:.1} LM iterations per run, worst |v0 error| {:.2} %",
        1e6 / rate,
        iterations as f64 / n as f64,
        100.0 * worst_v0
    );

    if parallel {
        let threads = rayon::current_num_threads();
        let start = Instant::now();
        let done: usize = all
            .par_iter()
            .map_init(Workspace::default, |ws, r| {
                (fit_track(&r.t_s, &r.z_m, fps, &opts, ws).status == FitStatus::Converged) as usize
            })
            .sum();
        let secs = start.elapsed().as_secs_f64();
        println!(
            "{threads} threads: {n} fits in {secs:.2} s = {:.0} runs/s ({done} converged)",
            n as f64 / secs
        );
    }

    if let Some(dir) = dump {
        let dir = std::path::PathBuf::from(dir);
        std::fs::create_dir_all(&dir).expect("cannot create the dump directory");
        let mut runs_csv = String::from("run,t_s,z_m\n");
        let mut starts = String::from(
            "run,fps,z0_m,t0_s,v0_mps,mu,t_drag_s,true_v0_mps,true_mu,true_t_drag_s\n",
        );
        let mut scratch = Vec::new();
        for (i, r) in all.iter().enumerate().take(dump_count) {
            for (t, z) in r.t_s.iter().zip(&r.z_m) {
                let _ = writeln!(runs_csv, "{i},{t:.7e},{z:.10e}");
            }
            let x = single_start(&r.t_s, &r.z_m, fps, opts.groove(), &mut scratch);
            let _ = writeln!(
                starts,
                "{i},{fps},{:.10e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e}",
                x[0], x[1], x[2], x[4], x[5], r.truth.v0_mps, r.truth.mu, r.truth.t_drag_s
            );
        }
        std::fs::write(dir.join("runs.csv"), runs_csv).expect("cannot write runs.csv");
        std::fs::write(dir.join("starts.csv"), starts).expect("cannot write starts.csv");
        std::fs::write(dir.join("rust_rate.txt"), format!("{rate}\n"))
            .expect("cannot write rust_rate.txt");
        println!(
            "wrote {}/runs.csv, starts.csv, rust_rate.txt",
            dir.display()
        );
    }
}
