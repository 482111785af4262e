//! The command line for daily use, through the `groove` binary: `init` then `run` in an empty
//! folder, `status --exit-code` and its counts line, `dag` marked by state, `show` of stored
//! results, `diff` of two results (a param change gives the σ table, `--fail-above` exits 1),
//! completion scripts, the help's promises, and the messages that must name the right culprit
//! (`--data` naming a missing folder or a file, positions in millimetres, `run ingest`'s closing
//! line).
//!
//! One small dataset (tests/fixtures/truths/e2e_small.toml) is synthesized once and one project
//! initialised with `groove init` runs it once; the other tests copy that project.

#[path = "support/files.rs"]
mod files;

use files::{copy_tree, groove, ok, repo, scratch, synth, text};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// The dataset, synthesized once.
fn dataset() -> &'static Path {
    static DATA: OnceLock<PathBuf> = OnceLock::new();
    DATA.get_or_init(|| {
        let out = scratch("daily_cli").join("dataset");
        synth(scratch("daily_cli"), "e2e_small", &out);
        out
    })
}

/// A project made by `groove init`, the dataset put into its data/, run once.
fn base() -> &'static Path {
    static BASE: OnceLock<PathBuf> = OnceLock::new();
    BASE.get_or_init(|| {
        let project = scratch("daily_cli").join("base");
        std::fs::create_dir_all(&project).unwrap();
        let said = ok(&groove(&project, &["init"]), "groove init");
        assert!(
            said.contains("pipeline.toml") && said.contains("data/"),
            "{said}"
        );
        for f in ["runs.csv", "trajectories.csv"] {
            std::fs::copy(dataset().join(f), project.join("data").join(f)).unwrap();
        }
        let said = ok(&groove(&project, &["run"]), "groove run after init");
        assert!(said.contains("report: reports/report.html"), "{said}");
        project
    })
}

fn copy_of_base(name: &str) -> PathBuf {
    let to = scratch("daily_cli").join(name);
    copy_tree(base(), &to);
    to
}

#[test]
fn init_writes_the_built_in_pipeline_and_a_dataset_skeleton_and_refuses_to_overwrite() {
    let dir = scratch("daily_cli").join("init_twice");
    let out = groove(scratch("daily_cli"), &["init", dir.to_str().unwrap()]);
    ok(&out, "groove init DIR");
    let toml = std::fs::read_to_string(dir.join("pipeline.toml")).unwrap();
    assert_eq!(
        toml,
        std::fs::read_to_string(repo().join("pipeline.toml")).unwrap()
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("data/trajectories.csv")).unwrap(),
        "run,particle,frame,t_s,z_m\n"
    );
    std::fs::write(dir.join("pipeline.toml"), "# mine\n").unwrap();
    let again = groove(scratch("daily_cli"), &["init", dir.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(2));
    let err = text(&again.stderr);
    assert!(
        err.contains("already exist") && err.contains("overwrites nothing"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("pipeline.toml")).unwrap(),
        "# mine\n"
    );
}

#[test]
fn status_counts_the_stages_and_exit_code_says_whether_any_is_stale() {
    let project = copy_of_base("status");
    let fresh = groove(&project, &["status", "--exit-code"]);
    let said = ok(&fresh, "status --exit-code on a fresh project");
    assert!(
        said.contains("groove: 10 stages: 10 fresh, 0 stale"),
        "{said}"
    );
    // a param change makes aggregate and everything after it stale
    let toml = project.join("pipeline.toml");
    let text0 = std::fs::read_to_string(&toml).unwrap();
    let edited = text0.replace(
        "kind = \"aggregate\"\n",
        "kind = \"aggregate\"\nparams = { fast_min_speed_mps = 0.0 }\n",
    );
    assert_ne!(edited, text0);
    std::fs::write(&toml, edited).unwrap();
    let stale = groove(&project, &["status", "--exit-code"]);
    assert_eq!(stale.status.code(), Some(1), "{}", text(&stale.stderr));
    let said = text(&stale.stdout);
    // aggregate, and refit, validate, figures and report after it
    assert!(
        said.contains("stale  aggregate") && said.contains("10 stages: 5 fresh, 5 stale"),
        "{said}"
    );
    // without the flag, stale is still exit 0
    assert_eq!(groove(&project, &["status"]).status.code(), Some(0));
}

#[test]
fn dag_marks_each_stage_fresh_or_stale_in_every_format() {
    let project = copy_of_base("dag");
    std::fs::remove_file(project.join("reports/report.md")).unwrap();
    let text_form = ok(&groove(&project, &["dag"]), "dag");
    assert!(
        text_form.contains("fit (fit foreach runs) [fresh]"),
        "{text_form}"
    );
    assert!(text_form.contains("report (report) [stale]"), "{text_form}");
    let dot = ok(&groove(&project, &["dag", "--format", "dot"]), "dag dot");
    assert!(
        dot.contains(
            "\"report\" [label=\"report\\n(report, stale)\", style=filled, fillcolor=\"#ffcc80\"]"
        ),
        "{dot}"
    );
    let mermaid = ok(
        &groove(&project, &["dag", "--format", "mermaid"]),
        "dag mermaid",
    );
    assert!(
        mermaid.contains("classDef stale fill:#ffcc80") && mermaid.contains("class report stale"),
        "{mermaid}"
    );
}

#[test]
fn show_prints_the_converted_runs_and_a_fit() {
    let project = copy_of_base("show");
    let table = ok(
        &groove(&project, &["show", "ingest:runs"]),
        "show ingest:runs",
    );
    let runs = std::fs::read_to_string(project.join("data/runs.csv")).unwrap();
    let first_run = runs
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .to_string();
    assert!(
        table.lines().next().unwrap().contains("mean_speed_mps"),
        "{table}"
    );
    assert!(table.contains(&format!("{first_run}  single")), "{table}");
    let csv = ok(
        &groove(
            &project,
            &["show", "ingest:runs", "--csv", "--item", &first_run],
        ),
        "show --csv --item",
    );
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("run,particle,frame,t_s,z_m"));
    // the converted positions are the dataset's rows of that run, to the value
    let given: Vec<(i64, f64)> = std::fs::read_to_string(project.join("data/trajectories.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .filter(|l| l.starts_with(&format!("{first_run},")))
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f[2].parse().unwrap(), f[4].parse().unwrap())
        })
        .collect();
    let shown: Vec<(i64, f64)> = lines
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            assert_eq!(f[0], first_run);
            (f[2].parse().unwrap(), f[4].parse().unwrap())
        })
        .collect();
    assert!(!shown.is_empty());
    assert_eq!(shown, given);
    let fit = ok(
        &groove(
            &project,
            &["show", "fit:fits", "--item", &first_run, "--json"],
        ),
        "show fit:fits --item",
    );
    let v: serde_json::Value = serde_json::from_str(&fit).unwrap();
    assert!(v.to_string().contains(&first_run), "{fit}");
    let bad = groove(&project, &["show", "fit:fitz"]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        text(&bad.stderr).contains("stage `fit` has no output `fitz`; it writes: fits"),
        "{}",
        text(&bad.stderr)
    );
    let no_item = groove(&project, &["show", "fit:fits", "--item", "no-such-run"]);
    assert_eq!(no_item.status.code(), Some(2));
    assert!(text(&no_item.stderr).contains("has no item `no-such-run`"));
}

#[test]
fn diff_of_a_param_change_gives_the_sigma_table_and_fails_above_a_threshold() {
    let project = copy_of_base("diff");
    let before = scratch("daily_cli").join("diff_before");
    copy_tree(&project.join("reports"), &before);
    std::fs::copy(
        project.join("pipeline.lock"),
        scratch("daily_cli").join("pipeline.lock"),
    )
    .unwrap();
    // the same results: nothing moved, any threshold passes
    let same = groove(
        &project,
        &[
            "diff",
            before.to_str().unwrap(),
            "reports",
            "--fail-above",
            "0.001",
        ],
    );
    let said = ok(&same, "diff of identical results");
    assert!(
        said.contains(" 0 of ")
            && said.contains("findings accepted: appeared none; disappeared none"),
        "{said}"
    );
    let toml = project.join("pipeline.toml");
    let edited = std::fs::read_to_string(&toml).unwrap().replace(
        "kind = \"aggregate\"\n",
        "kind = \"aggregate\"\nparams = { fast_min_speed_mps = 0.0 }\n",
    );
    std::fs::write(&toml, edited).unwrap();
    ok(&groove(&project, &["run"]), "run after the param change");
    let out = groove(&project, &["diff", before.to_str().unwrap(), "reports"]);
    let said = ok(&out, "diff without a threshold");
    // the lock holds every param with its default filled in
    assert!(
        said.contains("aggregate.fast_min_speed_mps: 0.03 → 0.0"),
        "{said}"
    );
    let row = said
        .lines()
        .find(|l| l.contains("summary.json single.materials.316.mu_fast:"))
        .unwrap_or_else(|| panic!("no mu_fast row:\n{said}"));
    assert!(row.contains(" σ") && row.contains(" ± "), "{row}");
    let json = ok(
        &groove(
            &project,
            &["diff", before.to_str().unwrap(), "reports", "--json"],
        ),
        "diff --json",
    );
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let mu = v["numbers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["path"] == "single.materials.316.mu_fast")
        .unwrap();
    let sigma = mu["sigma"].as_f64().unwrap();
    let (a, b) = (mu["a"].as_f64().unwrap(), mu["b"].as_f64().unwrap());
    let combined =
        (mu["a_se"].as_f64().unwrap().powi(2) + mu["b_se"].as_f64().unwrap().powi(2)).sqrt();
    assert!(
        ((b - a) / combined - sigma).abs() < 1e-9 && sigma != 0.0,
        "{mu}"
    );
    let over = groove(
        &project,
        &[
            "diff",
            before.to_str().unwrap(),
            "reports",
            "--fail-above",
            &format!("{}", sigma.abs() / 2.0),
        ],
    );
    assert_eq!(over.status.code(), Some(1), "{}", text(&over.stderr));
    assert!(
        text(&over.stderr).contains("moved by more than"),
        "{}",
        text(&over.stderr)
    );
    let under = groove(
        &project,
        &[
            "diff",
            before.to_str().unwrap(),
            "reports",
            "--fail-above",
            "1e9",
        ],
    );
    assert_eq!(under.status.code(), Some(0));
}

#[test]
fn completions_are_generated_for_each_shell() {
    for (shell, word) in [
        ("bash", "complete -F"),
        ("zsh", "#compdef groove"),
        ("fish", "complete -c groove"),
    ] {
        let out = groove(scratch("daily_cli"), &["completions", shell]);
        let script = ok(&out, shell);
        assert!(script.contains(word), "{shell}:\n{script}");
        for verb in ["status", "diff", "show", "init"] {
            assert!(script.contains(verb), "{shell} lacks {verb}");
        }
    }
}

#[test]
fn help_promises_only_what_each_verb_does() {
    let help = |args: &[&str]| ok(&groove(scratch("daily_cli"), args), "help");
    let top = help(&["--help"]);
    assert!(top.contains("`verify` dropped something"), "{top}");
    assert!(!help(&["push", "--help"]).contains("--remote-read-only"));
    assert!(help(&["pull", "--help"]).contains("--remote-read-only"));
    assert!(help(&["run", "--help"]).contains("--remote-read-only"));
    for verb in ["clean", "gc", "verify"] {
        let h = help(&[verb, "--help"]);
        assert!(
            !h.contains("--data") && !h.contains("--out") && h.contains("--config"),
            "{verb}:\n{h}"
        );
    }
}

#[test]
fn run_ingest_alone_names_no_report() {
    let project = scratch("daily_cli").join("ingest_only");
    std::fs::create_dir_all(&project).unwrap();
    ok(&groove(&project, &["init"]), "init");
    for f in ["runs.csv", "trajectories.csv"] {
        std::fs::copy(dataset().join(f), project.join("data").join(f)).unwrap();
    }
    let said = ok(&groove(&project, &["run", "ingest"]), "run ingest");
    let last = said.lines().last().unwrap();
    assert!(!last.contains("report:"), "{last}");
    assert!(
        last.contains("results in the store") && last.contains("`groove show ingest:runs`"),
        "{last}"
    );
}

#[test]
fn data_naming_a_missing_folder_blames_the_flag() {
    let dir = scratch("daily_cli").join("no_data");
    std::fs::create_dir_all(&dir).unwrap();
    let out = groove(&dir, &["run", "--data", "no-such-folder"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("--data no-such-folder: there is no folder"),
        "{err}"
    );
    assert!(
        !err.contains("pipeline.toml:") && !err.contains("optional"),
        "{err}"
    );
}

#[test]
fn data_naming_a_file_says_to_pass_its_folder() {
    let dir = scratch("daily_cli").join("data_file");
    std::fs::create_dir_all(dir.join("mine")).unwrap();
    std::fs::copy(
        dataset().join("trajectories.csv"),
        dir.join("mine/trajectories.csv"),
    )
    .unwrap();
    let out = groove(&dir, &["run", "--data", "mine/trajectories.csv"]);
    assert_eq!(out.status.code(), Some(2));
    let err = text(&out.stderr);
    assert!(
        err.contains("--data mine/trajectories.csv is a file, not a folder; pass the folder that holds it: --data mine"),
        "{err}"
    );
}

#[test]
fn positions_in_millimetres_stop_with_the_fix() {
    let project = scratch("daily_cli").join("millimetres");
    std::fs::create_dir_all(&project).unwrap();
    ok(&groove(&project, &["init"]), "init");
    std::fs::copy(dataset().join("runs.csv"), project.join("data/runs.csv")).unwrap();
    let traj = std::fs::read_to_string(dataset().join("trajectories.csv")).unwrap();
    let mut mm = String::new();
    for (i, l) in traj.lines().enumerate() {
        if i == 0 {
            mm.push_str(l);
        } else {
            let (head, z) = l.rsplit_once(',').unwrap();
            // millimetres from a mid-view origin, so that no position passes the 10 m limit
            let z: f64 = z.parse().unwrap();
            mm.push_str(&format!("{head},{}", (z - 0.006) * 1000.0));
        }
        mm.push('\n');
    }
    std::fs::write(project.join("data/trajectories.csv"), mm).unwrap();
    let out = groove(&project, &["run"]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("trajectories.csv, column z_m"), "{err}");
    assert!(err.contains("the positions are not in metres"), "{err}");
    assert!(err.contains("divide them by 1000"), "{err}");
    assert!(!project.join("reports/report.html").exists());
}

/// μ of every converged single-run fit in `reports/fits.csv`, by run.
fn converged_mu(project: &Path) -> std::collections::BTreeMap<String, f64> {
    let csv = std::fs::read_to_string(project.join("reports/fits.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (run, mu, status) = (col("run"), col("mu"), col("status"));
    lines
        .map(|l| l.split(',').collect::<Vec<_>>())
        .filter(|f| f[status] == "converged")
        .map(|f| (f[run].to_string(), f[mu].parse().unwrap()))
        .collect()
}

/// The median of `values`.
fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

#[test]
fn the_groove_angle_set_once_reaches_every_stage_and_gives_back_the_mu_the_data_were_made_with() {
    // the small dataset made on a 90° groove (the chapter's is 70.6°), μ = 0.337 for 316
    let dir = scratch("daily_cli").join("groove_90");
    let truth = std::fs::read_to_string(repo().join("tests/fixtures/truths/e2e_small.toml"))
        .unwrap()
        .replace("theta_deg = 70.6", "theta_deg = 90.0");
    assert!(truth.contains("theta_deg = 90.0") && truth.contains("mu = 0.337"));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("truth.toml"), truth).unwrap();
    let out = dir.join("data").to_str().unwrap().to_string();
    ok(
        &groove(&dir, &["synth", "--truth", "truth.toml", "--out", &out]),
        "synth at 90°",
    );
    let pipeline = std::fs::read_to_string(repo().join("pipeline.toml")).unwrap();
    assert!(pipeline.contains("groove_angle_deg = 70.6"), "{pipeline}");
    let at = |angle: &str| {
        std::fs::write(
            dir.join("pipeline.toml"),
            pipeline.replace(
                "groove_angle_deg = 70.6",
                &format!("groove_angle_deg = {angle}"),
            ),
        )
        .unwrap();
    };
    let mu_316 = || {
        let mu = converged_mu(&dir);
        let of_316: Vec<f64> = mu
            .iter()
            .filter(|(run, _)| run.contains("316"))
            .map(|(_, mu)| *mu)
            .collect();
        assert!(of_316.len() >= 5, "{mu:?}");
        median(of_316)
    };
    at("90");
    ok(&groove(&dir, &["run"]), "run at 90°");
    let right = mu_316();
    assert!(
        (right / 0.337 - 1.0).abs() < 0.03,
        "μ on the data's own groove: {right}"
    );
    // the report draws and states the groove it was given
    let md = std::fs::read_to_string(dir.join("reports/report.md")).unwrap();
    assert!(md.contains("| opening angle θ (°) | 90.0 | 70.6 |"), "{md}");
    assert!(md.contains("no secondary collision follows"), "{md}");
    // set once: every stage that fits, simulates or draws the motion takes it, so its key changes
    at("70.6");
    let status: serde_json::Value =
        serde_json::from_str(&ok(&groove(&dir, &["status", "--json"]), "status")).unwrap();
    for stage in [
        "fit",
        "simulate",
        "aggregate",
        "discover",
        "figures",
        "report",
    ] {
        let s = status
            .as_array()
            .unwrap()
            .iter()
            .find(|s| s["stage"] == stage)
            .unwrap();
        assert!(
            s["reasons"]
                .to_string()
                .contains("param `groove_angle_deg` changed: 90 → 70.6")
                || s["reasons"]
                    .to_string()
                    .contains("param `groove_angle_deg` changed: 90.0 → 70.6"),
            "{stage}: {s}"
        );
    }
    // on the chapter's groove the same recordings give another μ, far from the one they hold
    ok(
        &groove(&dir, &["run", "aggregate"]),
        "run aggregate at 70.6°",
    );
    let wrong = mu_316();
    assert!(
        (wrong / 0.337 - 1.0).abs() > 0.1,
        "μ on the wrong groove: {wrong}"
    );
}

#[test]
fn diff_defaults_to_the_last_published_bundle_and_the_report_compares_with_a_baseline() {
    let project = copy_of_base("baseline");
    ok(
        &groove(&project, &["publish", "--to", "published"]),
        "publish",
    );
    // with no arguments: the bundle just published against the working reports
    let said = ok(&groove(&project, &["diff"]), "diff with no arguments");
    let first = said.lines().next().unwrap();
    assert!(
        first.contains("published") && first.ends_with("B = reports"),
        "{said}"
    );
    assert!(said.contains(" 0 of "), "{said}");
    // the report given the bundle as its baseline, after a param change
    let toml = project.join("pipeline.toml");
    let edited = std::fs::read_to_string(&toml)
        .unwrap()
        .replace(
            "kind = \"aggregate\"\n",
            "kind = \"aggregate\"\nparams = { fast_min_speed_mps = 0.0 }\n",
        )
        .replace(
            "skipped = \"ingest:skipped\" }",
            "skipped = \"ingest:skipped\", baseline = { path = \"published\", optional = true } }",
        );
    assert!(edited.contains("baseline = {"), "{edited}");
    std::fs::write(&toml, edited).unwrap();
    ok(&groove(&project, &["run"]), "run with a baseline");
    let md = std::fs::read_to_string(project.join("reports/report.md")).unwrap();
    assert!(
        md.contains("6. Provenance · 7. Compared with the baseline"),
        "{md}"
    );
    let section = md
        .split("## 7. Compared with the baseline")
        .nth(1)
        .unwrap_or_else(|| panic!("no baseline section:\n{md}"));
    assert!(section.contains("numbers changed"), "{section}");
    assert!(
        section.contains("| summary.json | single.materials.316.mu_fast |"),
        "{section}"
    );
    let html = std::fs::read_to_string(project.join("reports/report.html")).unwrap();
    assert!(html.contains("<a href=\"#baseline\">7. Compared with the baseline</a>"));
    // without a baseline the report has no such section (the shipped report is unchanged)
    let base_md = std::fs::read_to_string(base().join("reports/report.md")).unwrap();
    assert!(!base_md.contains("Compared with the baseline"));
}
