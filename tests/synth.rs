//! Synth tests: determinism, the truth file's checks, and that the shipped truth reproduces the
//! chapter's fitted drag time T = 0.052 + 1.10 v0 when fitted with the linear-drag baseline.

use groove::physics::{simulate, Baseline, Model, State};
use groove::synth::{run_synth, run_synth_as, synth_tables, Truth};
use std::path::Path;

fn shipped_truth_text() -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/truth/truth.toml"))
        .expect("data/truth/truth.toml exists")
}

fn small_truth() -> Truth {
    let mut truth = Truth::parse(&shipped_truth_text()).unwrap();
    for g in &mut truth.runs {
        g.count = 3;
    }
    truth
}

#[test]
fn synth_is_byte_for_byte_deterministic_and_seeded() {
    let truth = small_truth();
    let a = synth_tables(&truth);
    let b = synth_tables(&truth);
    assert_eq!(a.runs_csv, b.runs_csv);
    assert_eq!(a.trajectories_csv, b.trajectories_csv);
    let mut other = truth.clone();
    other.seed += 1;
    assert_ne!(synth_tables(&other).trajectories_csv, a.trajectories_csv);
}

#[test]
fn run_synth_writes_the_dataset_and_a_copy_of_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let text = toml::to_string(&small_truth()).unwrap();
    let truth_path = dir.path().join("t.toml");
    std::fs::write(&truth_path, &text).unwrap();
    let out = dir.path().join("out");
    run_synth(&truth_path, &out).unwrap();
    let runs = std::fs::read_to_string(out.join("runs.csv")).unwrap();
    assert_eq!(runs.lines().count(), 1 + 6 * 3);
    assert!(runs.starts_with("run,experiment,material,diameter_m,fps,setup"));
    let traj = std::fs::read_to_string(out.join("trajectories.csv")).unwrap();
    assert!(traj.starts_with("run,particle,frame,t_s,z_m\n"));
    assert_eq!(
        std::fs::read_to_string(out.join("truth/truth.toml")).unwrap(),
        text
    );
    // every run has rows, collision runs have both particles
    for line in runs.lines().skip(1) {
        let id = line.split(',').next().unwrap();
        let n0 = traj
            .lines()
            .filter(|l| l.starts_with(&format!("{id},0,")))
            .count();
        let n1 = traj
            .lines()
            .filter(|l| l.starts_with(&format!("{id},1,")))
            .count();
        assert!(n0 > 100, "{id}: {n0} rows");
        assert_eq!(n1 > 0, !id.starts_with("single"), "{id}: {n1} target rows");
    }
}

/// `groove synth --format parquet`: the same dataset with trajectories.parquet, which ingests to
/// the CSV's items byte for byte (streamed a row group batch at a time).
#[test]
fn synth_as_parquet_writes_the_values_of_the_csv() {
    use groove::ingest::{ingest_items, IngestParams};
    let dir = tempfile::tempdir().unwrap();
    let truth_path = dir.path().join("t.toml");
    std::fs::write(&truth_path, toml::to_string(&small_truth()).unwrap()).unwrap();
    let (csv, parquet) = (dir.path().join("csv"), dir.path().join("parquet"));
    run_synth(&truth_path, &csv).unwrap();
    // into a folder an earlier synth wrote as CSV: the CSV form goes, so the folder is one dataset
    run_synth(&truth_path, &parquet).unwrap();
    run_synth_as(&truth_path, &parquet, true).unwrap();
    assert!(!parquet.join("trajectories.csv").exists());
    let read = |d: &Path, names: [&str; 2]| {
        names
            .iter()
            .map(|n| (n.to_string(), std::fs::read(d.join(n)).unwrap()))
            .collect::<std::collections::BTreeMap<_, _>>()
    };
    let from_csv = read(&csv, ["runs.csv", "trajectories.csv"]);
    let from_parquet = read(&parquet, ["runs.csv", "trajectories.parquet"]);
    assert_eq!(from_csv["runs.csv"], from_parquet["runs.csv"]);
    assert!(from_parquet["trajectories.parquet"].starts_with(b"PAR1"));
    let params = IngestParams::default();
    let (a, b) = (
        ingest_items(&from_csv, &params).unwrap(),
        ingest_items(&from_parquet, &params).unwrap(),
    );
    assert!(b.how.contains("decoded from Parquet"), "{}", b.how);
    assert_eq!(a.runs.len(), 18);
    assert!(a.runs == b.runs, "Parquet gives other items than the CSV");
}

#[test]
fn truth_errors_say_what_to_fix() {
    let text = shipped_truth_text().replace("material = \"440c\"", "material = \"440C\"");
    let err = Truth::parse(&text).unwrap_err();
    assert!(
        err.contains("material `440C`") && err.contains("[[materials]]"),
        "{err}"
    );
    let err = run_synth(Path::new("/nonexistent/truth.toml"), Path::new("/tmp")).unwrap_err();
    assert!(err.to_string().contains("--truth"), "{err}");
}

#[test]
fn camera_noise_has_the_stated_size() {
    let truth = small_truth();
    let tables = synth_tables(&truth);
    let truth_rows: Vec<&str> = tables.runs_truth_csv.lines().skip(1).collect();
    // first single run: compare recorded positions with the noise-free simulation
    let first: Vec<&str> = truth_rows[0].split(',').collect();
    let (id, z0, v0, t_first): (&str, f64, f64, f64) = (
        first[0],
        first[2].parse().unwrap(),
        first[3].parse().unwrap(),
        first[5].parse().unwrap(),
    );
    let rows: Vec<(f64, f64)> = tables
        .trajectories_csv
        .lines()
        .filter(|l| l.starts_with(&format!("{id},0,")))
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            (c[3].parse().unwrap(), c[4].parse().unwrap())
        })
        .collect();
    let material = truth.material("316").unwrap();
    let model = truth.model(material);
    let t: Vec<f64> = rows.iter().map(|r| r.0 + t_first).collect();
    let sim = simulate(
        &model,
        State {
            z_m: z0,
            v_mps: v0,
            va_mps: 0.0,
        },
        &t,
    );
    let resid: Vec<f64> = rows.iter().zip(&sim.z_m).map(|(r, z)| r.1 - z).collect();
    let inliers: Vec<f64> = resid.iter().copied().filter(|r| r.abs() < 6e-6).collect();
    let rms = (inliers.iter().map(|r| r * r).sum::<f64>() / inliers.len() as f64).sqrt();
    // 1 µm noise plus the 0.25 µm grid (± 0.07 µm rms): rms within 15 % of 1.03 µm for ~600 rows
    assert!((rms - 1.03e-6).abs() < 0.15e-6, "rms {rms}");
}

/// Least-squares fit of the baseline to (t, z): parameters (v0, μ, T, z0). Levenberg–Marquardt
/// with forward-difference derivatives; returns the parameters.
fn fit_baseline(t: &[f64], z: &[f64], guess: [f64; 4]) -> [f64; 4] {
    let model = |p: &[f64; 4], out: &mut Vec<f64>| {
        let b = Baseline::new(p[1], p[2]);
        out.resize(t.len(), 0.0);
        b.positions(p[0], t, out);
        for o in out.iter_mut() {
            *o += p[3];
        }
    };
    let cost = |p: &[f64; 4]| {
        let mut m = Vec::new();
        model(p, &mut m);
        m.iter().zip(z).map(|(a, b)| (a - b) * (a - b)).sum::<f64>()
    };
    let mut p = guess;
    let mut lambda = 1e-3;
    let mut c = cost(&p);
    let mut m0 = Vec::new();
    let mut m1 = Vec::new();
    for _ in 0..200 {
        model(&p, &mut m0);
        let mut jac = vec![[0.0; 4]; t.len()];
        for j in 0..4 {
            let mut q = p;
            let h = 1e-7 * p[j].abs().max(1e-6);
            q[j] += h;
            model(&q, &mut m1);
            for i in 0..t.len() {
                jac[i][j] = (m1[i] - m0[i]) / h;
            }
        }
        let mut a = [[0.0; 4]; 4];
        let mut g = [0.0; 4];
        for i in 0..t.len() {
            let r = z[i] - m0[i];
            for j in 0..4 {
                g[j] += jac[i][j] * r;
                for k in 0..4 {
                    a[j][k] += jac[i][j] * jac[i][k];
                }
            }
        }
        let mut improved = false;
        for _ in 0..20 {
            let mut aa = a;
            for (j, row) in aa.iter_mut().enumerate() {
                row[j] *= 1.0 + lambda;
            }
            let step = solve4(aa, g);
            let mut q = p;
            for j in 0..4 {
                q[j] += step[j];
            }
            q[1] = q[1].max(1e-3);
            q[2] = q[2].max(1e-3);
            let cq = cost(&q);
            if cq < c {
                let rel = (c - cq) / c.max(1e-300);
                p = q;
                c = cq;
                lambda = (lambda * 0.3).max(1e-12);
                improved = rel > 1e-12;
                break;
            }
            lambda *= 10.0;
        }
        if !improved {
            break;
        }
    }
    p
}

fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> [f64; 4] {
    for c in 0..4 {
        let piv = (c..4)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, piv);
        b.swap(c, piv);
        for r in c + 1..4 {
            let f = a[r][c] / a[c][c];
            let pivot_row = a[c];
            for (k, x) in a[r].iter_mut().enumerate().skip(c) {
                *x -= f * pivot_row[k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 4];
    for c in (0..4).rev() {
        let s: f64 = (c + 1..4).map(|k| a[c][k] * x[k]).sum();
        x[c] = (b[c] - s) / a[c][c];
    }
    x
}

/// Straight line through (x, y): (intercept, slope).
fn line(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    (my - sxy / sxx * mx, sxy / sxx)
}

#[test]
fn shipped_truth_gives_the_chapters_rising_drag_time() {
    // noise-free single runs of the shipped physics, 60 ms at 10,000 fps, fitted with the
    // linear-drag baseline: fitted T must follow T = 0.052 + 1.10 v0 and μ the truth
    let truth = Truth::parse(&shipped_truth_text()).unwrap();
    let t: Vec<f64> = (0..600).map(|k| k as f64 * 1e-4).collect();
    for name in ["316", "440c"] {
        let material = truth.material(name).unwrap();
        let model: Model = truth.model(material);
        let mu_true = material.friction.static_limit();
        let (mut v0s, mut ts, mut mus) = (vec![], vec![], vec![]);
        for i in 0..20 {
            let v0 = 0.005 + 0.095 * i as f64 / 19.0;
            let sim = simulate(
                &model,
                State {
                    z_m: 0.0,
                    v_mps: v0,
                    va_mps: 0.0,
                },
                &t,
            );
            let p = fit_baseline(&t, &sim.z_m, [v0 * 1.1, 0.3, 0.1, 0.0]);
            println!(
                "{name} v0 {v0:.4}: fit v0 {:.4} mu {:.4} T {:.4}",
                p[0], p[1], p[2]
            );
            v0s.push(p[0]);
            ts.push(p[2]);
            mus.push(p[1]);
        }
        let (t0, tp) = line(&v0s, &ts);
        let fast: Vec<f64> = mus
            .iter()
            .zip(&v0s)
            .filter(|(_, v)| **v > 0.03)
            .map(|(m, _)| *m)
            .collect();
        let mu_mean = fast.iter().sum::<f64>() / fast.len() as f64;
        println!(
            "{name}: T = {t0:.4} + {tp:.3} v0, mean mu (v0 > 0.03) {mu_mean:.4} (truth {mu_true})"
        );
        assert!((t0 - 0.052).abs() < 0.002, "{name}: T0 {t0}");
        assert!((tp - 1.10).abs() < 0.03, "{name}: T' {tp}");
        assert!(
            (mu_mean - mu_true).abs() < 0.01,
            "{name}: mu {mu_mean} vs {mu_true}"
        );
    }
}

#[test]
fn shipped_dataset_is_what_its_truth_file_makes() {
    // data/runs.csv and data/trajectories.csv are regenerated byte for byte from the truth file
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let tables = synth_tables(&Truth::parse(&shipped_truth_text()).unwrap());
    let read = |name: &str| std::fs::read_to_string(root.join(name)).unwrap();
    assert!(
        tables.runs_csv == read("data/runs.csv"),
        "data/runs.csv is stale: rerun `groove synth --truth data/truth/truth.toml --out data`"
    );
    assert!(
        tables.trajectories_csv == read("data/trajectories.csv"),
        "data/trajectories.csv is stale"
    );
    assert!(
        tables.runs_truth_csv == read("data/truth/runs_truth.csv"),
        "data/truth/runs_truth.csv is stale"
    );
}

#[test]
fn every_term_and_friction_law_reads_from_toml() {
    let mut text = shipped_truth_text();
    text = text.replace(
        "friction = { law = \"constant\", mu = 0.293 }",
        "friction = { law = \"velocity_dependent\", mu_inf = 0.293, v_c_mps = 0.005 }",
    );
    text.push_str(
        r#"
[[physics.terms]]
term = "linear_drag"
t_s = 2.2
[[physics.terms]]
term = "quadratic_drag"
c_per_m = 1.5
[[physics.terms]]
term = "rolling_resistance"
c = 0.001
[[physics.terms]]
term = "groove_tilt"
alpha_deg = 0.05
[[physics.terms]]
term = "position_force"
amp_mps2 = 0.02
wavelength_m = 2.0e-3
phase_rad = 0.0
"#,
    );
    let mut truth = Truth::parse(&text).unwrap();
    assert_eq!(truth.physics.terms.len(), 6);
    for g in &mut truth.runs {
        g.count = 2;
    }
    let tables = synth_tables(&truth);
    assert_eq!(tables.runs_csv.lines().count(), 1 + 6 * 2);
    assert!(tables.trajectories_csv.lines().count() > 12 * 500);
}

#[test]
fn shipped_dataset_ingests_cleanly() {
    use groove::recording::{Experiment, Setup};
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let recs = groove::ingest::read_dataset_dir(&dir, &Default::default())
        .unwrap_or_else(|e| panic!("shipped data must ingest: {e}"));
    assert_eq!(recs.len(), 2 * 48 + 4 * 12);
    for r in &recs {
        match r.info.experiment {
            Experiment::Single => assert!(r.tracks.len() == 1 && r.info.setup.is_none()),
            Experiment::Collision => assert!(
                r.tracks.len() == 2
                    && matches!(r.info.setup, Some(Setup::Rolling | Setup::Contact))
            ),
        }
        assert_eq!(r.info.fps, 10_000.0);
        assert!((r.info.diameter_m - 3e-4).abs() < 1e-12);
    }
}
