//! The Slurm executor on a real cluster: `.ci/run` starts a one-node cluster (Debian's
//! slurm-wlm and munge, tests/infra/slurm.sh), exports SLURM_CONF and runs these `#[ignore]`d
//! tests with `--include-ignored`. Every stage that must run becomes a job step (`srun --exact`)
//! inside one allocation; results come back through the project's store.

#[path = "support/project.rs"]
mod project;

use project::{assert_same_tree, files, Project};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn need_cluster() {
    assert!(
        std::env::var("SLURM_CONF").is_ok(),
        "SLURM_CONF is not set: start the one-node cluster with `tests/infra/slurm.sh start DIR` and export SLURM_CONF=DIR/slurm.conf (as .ci/run does)"
    );
}

/// A job name no other test uses.
fn job_name(tag: &str) -> String {
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_nanos();
    format!(
        "groove-{tag}-{}-{}",
        std::process::id(),
        nanos % 1_000_000_000
    )
}

/// Jobs (allocations) with this name, in any state.
fn jobs_named(name: &str) -> Vec<String> {
    let out = Command::new("squeue")
        .args(["-h", "-t", "all", "-n", name, "-o", "%i"])
        .output()
        .expect("squeue");
    let mut ids: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| l.trim().to_string())
        .filter(|l| !l.is_empty())
        .collect();
    ids.sort();
    ids.dedup();
    ids
}

fn slurm_table(name: &str) -> String {
    format!("\n[slurm]\njob_name = \"{name}\"\ncpus = 2\ntime = \"00:30:00\"\n\n[slurm.kinds.command]\ncpus = 1\n")
}

/// `layers` × `width` command stages; each stage of a layer reads two of the layer before.
fn dag_pipeline(layers: usize, width: usize) -> String {
    let mut s = String::from("[project]\nseed = 3\ndata = \"data\"\nreports = \"reports\"\n");
    for l in 0..layers {
        for i in 0..width {
            let inputs = if l == 0 {
                format!(
                    "a = \"data/s{i}.txt\", b = \"data/s{}.txt\"",
                    (i + 1) % width
                )
            } else {
                format!(
                    "a = \"s{}_{i}:o\", b = \"s{}_{}:o\"",
                    l - 1,
                    l - 1,
                    (i + 1) % width
                )
            };
            s.push_str(&format!(
                "\n[stages.s{l}_{i}]\nkind = \"command\"\ncmd = \"echo s{l}_{i} >> trace.txt; cat {{in.a}} {{in.b}} | cksum > {{out.o}}; echo s{l}_{i} >> {{out.o}}\"\ninputs = {{ {inputs} }}\noutputs = {{ o = \"${{reports}}/s{l}_{i}.txt\" }}\n"
            ));
        }
    }
    s
}

fn dag_project(layers: usize, width: usize, extra: &str) -> Project {
    let p = Project::new(&format!("{}{extra}", dag_pipeline(layers, width)));
    for i in 0..width {
        p.write(&format!("data/s{i}.txt"), &format!("seed {i}\n"));
    }
    p
}

#[test]
#[ignore = "needs a Slurm cluster; .ci/run starts a one-node one"]
fn a_200_stage_dag_on_slurm_matches_a_local_run_in_one_allocation() {
    need_cluster();
    let name = job_name("dag");
    let local = dag_project(20, 10, &slurm_table(&name));
    let started = Instant::now();
    local.ok(&["run"]);
    let local_s = started.elapsed().as_secs_f64();
    assert_eq!(local.take_trace().len(), 200);

    let on_slurm = dag_project(20, 10, &slurm_table(&name));
    let started = Instant::now();
    let out = on_slurm.ok(&["run", "--executor", "slurm"]);
    let slurm_s = started.elapsed().as_secs_f64();
    assert_eq!(on_slurm.take_trace().len(), 200, "{out}");
    assert!(
        out.contains("slurm: 1 allocation taken, 200 job steps"),
        "{out}"
    );
    assert_eq!(jobs_named(&name).len(), 1, "exactly one allocation");
    assert_eq!(local.read("pipeline.lock"), on_slurm.read("pipeline.lock"));
    assert_same_tree(&local.path("reports"), &on_slurm.path("reports"));
    println!("benchmark: 200-stage command DAG: local {local_s:.1} s, slurm {slurm_s:.1} s (one allocation, 200 job steps)");
    assert!(
        slurm_s <= local_s + 30.0,
        "slurm took {slurm_s:.1} s against {local_s:.1} s locally"
    );
    // nothing changed: status and a second run agree, with no allocation taken
    let out = on_slurm.ok(&["run", "--executor", "slurm"]);
    assert!(out.contains("groove: 0 stages run"), "{out}");
    assert!(
        out.contains("slurm: 0 allocations taken, 0 job steps"),
        "{out}"
    );
    assert_eq!(jobs_named(&name).len(), 1);
    let status = on_slurm.ok(&["status"]);
    assert!(
        status.contains("200 stages: 200 fresh, 0 stale") && !status.contains("stale  "),
        "{status}"
    );
}

#[test]
#[ignore = "needs a Slurm cluster; .ci/run starts a one-node one"]
fn per_item_work_goes_in_batches_not_one_step_per_item() {
    need_cluster();
    let name = job_name("items");
    let pipeline = format!(
        "[project]\nseed = 1\ndata = \"data\"\nreports = \"reports\"\n\n[stages.each]\nkind = \"command\"\nforeach = \"runs\"\ncmd = \"echo {{item}} >> trace.txt; cksum < {{in.runs}} > {{out.sum}}\"\ninputs = {{ runs = \"data\" }}\noutputs = {{ sum = \"${{reports}}/sums\" }}\n{}",
        slurm_table(&name)
    );
    let local = Project::new(&pipeline);
    let remote = Project::new(&pipeline);
    for p in [&local, &remote] {
        for i in 0..100 {
            p.write(&format!("data/r{i:03}.csv"), &format!("{i}\n"));
        }
    }
    local.ok(&["run"]);
    let out = remote.ok(&["run", "--executor", "slurm"]);
    assert_eq!(remote.take_trace().len(), 100);
    // 100 items over a 2-CPU allocation with 1-CPU steps: 2 steps of 50 items
    assert!(
        out.contains("slurm: 1 allocation taken, 2 job steps"),
        "{out}"
    );
    assert_same_tree(&local.path("reports"), &remote.path("reports"));
    assert_eq!(local.read("pipeline.lock"), remote.read("pipeline.lock"));
}

#[test]
#[ignore = "needs a Slurm cluster; .ci/run starts a one-node one"]
fn a_failing_step_exits_2_naming_the_stage_and_its_stderr_and_commits_nothing() {
    need_cluster();
    let name = job_name("fail");
    let p = Project::new(&format!(
        "[project]\nseed = 1\n\n[stages.good]\nkind = \"command\"\ncmd = \"echo ok > {{out.o}}\"\noutputs = {{ o = \"good.txt\" }}\n\n[stages.bad]\nkind = \"command\"\ncmd = \"cat {{in.g}} > /dev/null; echo the detector is unplugged >&2; exit 3\"\ninputs = {{ g = \"good:o\" }}\noutputs = {{ o = \"bad.txt\" }}\n{}",
        slurm_table(&name)
    ));
    let out = p.groove(&["run", "--executor", "slurm"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("stage `bad`") && stderr.contains("the detector is unplugged"),
        "{stderr}"
    );
    // good's entry only
    assert_eq!(files(&p.path(".groove/entries"), &[]).len(), 1);
    assert!(!p.path("bad.txt").exists());
    assert!(jobs_named(&name).len() == 1);
}

#[test]
#[ignore = "needs a Slurm cluster; .ci/run starts a one-node one"]
fn a_cancelled_allocation_exits_2_and_the_rerun_does_only_the_unfinished_work() {
    need_cluster();
    let name = job_name("cancel");
    let p = Project::new(&format!(
        "[project]\nseed = 1\n\n[stages.first]\nkind = \"command\"\ncmd = \"echo first >> trace.txt; echo 1 > {{out.o}}\"\noutputs = {{ o = \"first.txt\" }}\n\n[stages.slow]\nkind = \"command\"\ncmd = \"echo slow >> trace.txt; if [ -f hold ]; then sleep 120; fi; cat {{in.f}} > {{out.o}}\"\ninputs = {{ f = \"first:o\" }}\noutputs = {{ o = \"slow.txt\" }}\n\n[stages.last]\nkind = \"command\"\ncmd = \"echo last >> trace.txt; cat {{in.s}} > {{out.o}}\"\ninputs = {{ s = \"slow:o\" }}\noutputs = {{ o = \"last.txt\" }}\n{}",
        slurm_table(&name)
    ));
    p.write("hold", "");
    let child = p
        .command(&["run", "--executor", "slurm"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    while !p.path("trace.txt").exists()
        || !std::fs::read_to_string(p.path("trace.txt"))
            .unwrap()
            .contains("slow")
    {
        assert!(Instant::now() < deadline, "stage slow never started");
        std::thread::sleep(Duration::from_millis(100));
    }
    let jobs = jobs_named(&name);
    assert_eq!(jobs.len(), 1);
    assert!(Command::new("scancel")
        .arg(&jobs[0])
        .status()
        .unwrap()
        .success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("ended (cancelled, preempted or out of time)")
            && stderr.contains("resumes"),
        "{stderr}"
    );
    assert_eq!(
        p.take_trace(),
        vec!["first".to_string(), "slow".to_string()]
    );
    std::fs::remove_file(p.path("hold")).unwrap();
    let out = p.ok(&["run", "--executor", "slurm"]);
    assert_eq!(
        p.take_trace(),
        vec!["last".to_string(), "slow".to_string()],
        "{out}"
    );
    assert_eq!(p.read("last.txt"), "1\n");
}

/// The code commit the report names (masked: a clone may name another one).
fn masked(path: &Path) -> Vec<u8> {
    let bytes = std::fs::read(path).unwrap();
    let Ok(text) = String::from_utf8(bytes.clone()) else {
        return bytes;
    };
    let md = std::fs::read_to_string(path.parent().unwrap().join("report.md")).unwrap_or_default();
    let commit = md
        .lines()
        .find_map(|l| l.strip_prefix("| code commit | "))
        .and_then(|r| r.split(' ').next())
        .unwrap_or("")
        .to_string();
    if commit.len() >= 7 {
        text.replace(&commit, "<commit>").into_bytes()
    } else {
        bytes
    }
}

#[test]
#[ignore = "runs the shipped analysis on a Slurm cluster (minutes); .ci/run runs it"]
fn the_shipped_analysis_on_slurm_makes_the_committed_reports() {
    need_cluster();
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"));
    let name = job_name("shipped");
    let text = std::fs::read_to_string(repo.join("pipeline.toml")).unwrap();
    let p = Project::new(&format!("{text}{}", slurm_table(&name)));
    let data = repo.join("data").display().to_string();
    let out = p.ok(&["run", "--executor", "slurm", "--data", &data]);
    assert!(out.contains("slurm: 1 allocation taken"), "{out}");
    let committed = repo.join("reports");
    let fresh = p.path("reports");
    assert_eq!(files(&committed, &[".keep"]), files(&fresh, &[".keep"]));
    for f in files(&committed, &[".keep"]) {
        assert!(
            masked(&committed.join(&f)) == masked(&fresh.join(&f)),
            "reports/{} differs from the committed one",
            f.display()
        );
    }
}

#[test]
fn a_bad_slurm_table_is_exit_2_naming_its_line_before_any_allocation() {
    for (table, needle) in [
        ("[slurm]\ncpus = 0\n", "cpus must be at least 1"),
        ("[slurm]\ncpu = 2\n", "unknown field `cpu`"),
        (
            "[slurm.kinds.command]\nmemory = \"2G\"\n",
            "unknown field `memory`",
        ),
    ] {
        let p = Project::new(&format!(
            "[project]\nseed = 1\n\n[stages.a]\nkind = \"command\"\ncmd = \"echo 1 > {{out.o}}\"\noutputs = {{ o = \"a.txt\" }}\n\n{table}"
        ));
        let out = p.groove(&["run", "--executor", "slurm"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{table}: {stderr}");
        assert!(
            stderr.contains("pipeline.toml:") && stderr.contains(needle),
            "{table}: {stderr}"
        );
        assert!(!p.path("a.txt").exists());
        // the table is valid pipeline.toml for everything else
        if needle.contains("at least") {
            p.ok(&["status"]);
        }
    }
}
