//! Engine overhead benchmark (`cargo bench --bench engine`): no-op `groove run` and `groove status`
//! on 3 and 1,000 `command` stages, and on the default pipeline when it loads, with ratios
//! against the DVC and Snakemake figures measured for them (DVC 3.67 s, Snakemake 9.27 s). Prints; asserts nothing.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

const GROOVE: &str = env!("CARGO_BIN_EXE_groove");

/// Median wall time in seconds of `groove ARGS` in `dir` over `n` runs.
fn median_s(dir: &Path, args: &[&str], n: usize) -> f64 {
    let mut times: Vec<f64> = (0..n)
        .map(|_| {
            let t = Instant::now();
            let out = Command::new(GROOVE)
                .args(args)
                .current_dir(dir)
                .output()
                .expect("run groove");
            assert!(
                out.status.success(),
                "groove {args:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            t.elapsed().as_secs_f64()
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[n / 2]
}

fn once(dir: &Path, args: &[&str]) -> f64 {
    median_s(dir, args, 1)
}

/// `n` trivial stages in 10 independent chains; stage i reads stage i-10.
fn pipeline(n: usize) -> String {
    let mut s = String::from("[project]\nseed = 1\n");
    for i in 0..n {
        let input = if i < 10 {
            "\"seed.txt\"".to_string()
        } else {
            format!("\"s{}:o\"", i - 10)
        };
        s.push_str(&format!(
            "\n[stages.s{i}]\nkind = \"command\"\ncmd = \"cat {{in.x}} > {{out.o}}; echo {i} >> {{out.o}}\"\ninputs = {{ x = {input} }}\noutputs = {{ o = \"reports/s{i}.txt\" }}\n"
        ));
    }
    s
}

fn project(n: usize) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("pipeline.toml"), pipeline(n)).unwrap();
    std::fs::write(dir.path().join("seed.txt"), "seed\n").unwrap();
    dir
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().flatten() {
        let target = to.join(e.file_name());
        if e.path().is_dir() {
            copy_dir(&e.path(), &target);
        } else {
            std::fs::copy(e.path(), target).unwrap();
        }
    }
}

fn main() {
    println!(
        "groove engine overhead (median wall time; DVC 3.67 / Snakemake 9.27 as measured for them)"
    );

    let small = project(3);
    let full = once(small.path(), &["run"]);
    let run3 = median_s(small.path(), &["run"], 11);
    let status3 = median_s(small.path(), &["status"], 11);
    println!("3 stages: first run {full:.3} s (3 process spawns)");
    println!(
        "3 stages, nothing changed: run {:.1} ms (DVC repro 760 ms: {:.0}x faster; Snakemake 1090 ms: {:.0}x), status {:.1} ms (DVC status 630 ms: {:.0}x)",
        run3 * 1e3,
        0.76 / run3,
        1.09 / run3,
        status3 * 1e3,
        0.63 / status3
    );

    let big = project(1000);
    let full = once(big.path(), &["run"]);
    let run1000 = median_s(big.path(), &["run"], 5);
    let status1000 = median_s(big.path(), &["status"], 5);
    println!(
        "1,000 stages: full build {full:.2} s (Snakemake 47 s: {:.0}x)",
        47.0 / full
    );
    println!(
        "1,000 stages, nothing changed: run {:.0} ms (DVC 9.4 s: {:.0}x faster; Snakemake 1.86 s: {:.0}x), status {:.0} ms",
        run1000 * 1e3,
        9.4 / run1000,
        1.86 / run1000,
        status1000 * 1e3
    );
    println!(
        "per-stage no-op overhead: {:.3} ms (run), {:.3} ms (status)",
        (run1000 - run3) / 997.0 * 1e3,
        (status1000 - status3) / 997.0 * 1e3
    );

    // the default pipeline on the shipped data, when every kind is registered and data exists
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let probe = Command::new(GROOVE)
        .args(["dag"])
        .current_dir(repo)
        .output()
        .unwrap();
    if probe.status.success() && repo.join("data").is_dir() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::copy(repo.join("pipeline.toml"), dir.path().join("pipeline.toml")).unwrap();
        copy_dir(&repo.join("data"), &dir.path().join("data"));
        let full = once(dir.path(), &["run"]);
        let noop = median_s(dir.path(), &["run"], 11);
        println!(
            "default pipeline: full run {full:.2} s; nothing changed: run {:.1} ms (goal 20 ms; DVC 3-stage repro 760 ms: {:.0}x)",
            noop * 1e3,
            0.76 / noop
        );
    } else {
        println!("default pipeline: skipped (its kinds are not all registered yet)");
    }
}
