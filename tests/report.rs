//! Report tests: figures and pages rendered from small hand-made artifacts; content, self-containment,
//! well-formedness and byte-identical re-rendering.

#[path = "support/files.rs"]
mod files;

use groove::engine::stage::{Artifact, StageInput};
use groove::physics::{Baseline, Groove};
use groove::report::{render_figures, render_pages, FigureOptions, ReportData};
use serde_json::{json, Value};
use std::collections::BTreeMap;

// ---------------------------------------------------------------- fixtures

/// A single run with known parameters, sampled at 10 kHz for 40 ms from the closed form.
fn single(run: &str, material: &str, v0: f64, mu: f64, t_drag: f64) -> (Value, Value, String) {
    let b = Baseline {
        mu,
        t_drag_s: t_drag,
        groove: Groove::CHAPTER,
    };
    let (z0, t0) = (1.0e-3, 4.0e-5);
    let t: Vec<f64> = (0..400).map(|i| i as f64 * 1e-4).collect();
    let z: Vec<f64> = t
        .iter()
        .map(|&ti| z0 + b.state(v0, ti + t0).0 + 1e-6 * (ti * 7919.0).sin())
        .collect();
    let frame: Vec<i64> = (0..400).collect();
    let rec = json!({"info": {"run": run, "experiment": "single", "material": material, "diameter_m": 3.0e-4,
                              "fps": 10000.0, "setup": null, "extra": {}},
                     "tracks": [{"particle": 0, "frame": frame, "t_s": t, "z_m": z}]});
    let t1 = b.switch_time_s(v0);
    // the fit stage's layout (fit::SingleFit inside RunFit, tagged by "experiment")
    let fit = json!({"experiment": "single", "run": run, "material": material,
        "groove": {"s": Groove::CHAPTER.s, "k": 2.5},
        "v0_mps": v0, "v0_se": 1e-4, "mu": mu, "mu_se": 0.004, "t_drag_s": t_drag, "t_drag_se": 0.002,
        "z0_m": z0, "z0_se": 1e-7, "t0_s": t0, "t0_se": 1e-6, "t1_s": t1, "rms_m": 1.0e-6, "scale_m": 1.0e-6,
        "outlier_cut_m": 5e-6, "n_frames": 400, "n_used": 400, "n_outliers": 0, "iterations": 7,
        "termination": "small_step", "status": "converged"});
    let csv = format!("{run},{material},{v0:.6},0.0001,{mu:.6},0.004,{t_drag:.6},0.002,{t1:.6},0.000001,converged\n");
    (rec, fit, csv)
}

fn collision(
    run: &str,
    material: &str,
    setup: &str,
    speeds: &[(f64, f64, f64, f64)],
) -> (Value, Value) {
    // striker rolls at 0.1 m/s into a target resting 1 mm ahead; after the impact at 5 ms it slows to
    // 0.01 m/s and the target moves at 0.08 m/s (shapes only matter for the drawing)
    let t: Vec<f64> = (0..300).map(|i| i as f64 * 1e-4).collect();
    let zs: Vec<f64> = t
        .iter()
        .map(|&ti| {
            if ti < 5e-3 {
                0.1 * ti
            } else {
                5e-4 + 0.01 * (ti - 5e-3) + 0.0004 * (ti - 5e-3).sqrt()
            }
        })
        .collect();
    let zt: Vec<f64> = t
        .iter()
        .map(|&ti| {
            if ti < 5e-3 {
                8e-4
            } else {
                8e-4 + 0.08 * (ti - 5e-3) * (1.0 - (ti - 5e-3) * 10.0)
            }
        })
        .collect();
    let frame: Vec<i64> = (0..300).collect();
    let rec = json!({"info": {"run": run, "experiment": "collision", "material": material, "diameter_m": 3.0e-4,
                              "fps": 10000.0, "setup": setup, "extra": {}},
                     "tracks": [{"particle": 0, "frame": frame, "t_s": t, "z_m": zs},
                                {"particle": 1, "frame": frame, "t_s": t, "z_m": zt}]});
    let e = |v: f64| json!({"value": v, "se": 1e-3});
    let kin = |v: f64, va: f64| json!({"v_mps": e(v), "va_mps": e(va)});
    let impacts: Vec<Value> = speeds
        .iter()
        .enumerate()
        .map(|(i, &(v1, v2p, va2p, va1))| {
            let v1p = v1 - v2p * 0.95;
            json!({"index": i, "t_s": e(5e-3 + i as f64 * 1e-3),
                   "striker_before": kin(v1, va1), "striker_after": kin(v1p, va1 - va2p),
                   "target_before": kin(0.0, 0.0), "target_after": kin(v2p, va2p),
                   "striker_before_source": if setup == "contact" { "momentum_conservation" } else { "fitted" },
                   "impact_speed_mps": e(v1), "restitution": e((v2p - v1p) / v1),
                   "target_dvz_mps": e(v2p), "target_dva_mps": e(va2p), "striker_dva_mps": e(-va2p),
                   "spin_sum_before_mps": va1, "spin_sum_after_mps": e(va1),
                   "momentum_mismatch_mps": 0.0, "contact": if i % 2 == 0 { "slip" } else { "stick" }})
        })
        .collect();
    let seg = |p: u32, t0: f64, t1: f64, sw: f64| {
        json!({"particle": p, "t_start_s": t0, "t_end_s": t1, "z_start_m": 0.0, "v_start_mps": e(0.1),
               "va_start_mps": e(0.0), "t_drag_s": e(0.06), "t_switch_s": sw, "spin_identified": true, "phases": [], "n_points": 50})
    };
    let fit = json!({"experiment": "collision", "run": run, "material": material, "setup": setup,
        "direction": 1, "termination": "small_cost_change", "status": "converged", "message": "", "mu_pg": e(0.33), "t_drag_s": e(0.06),
        "segments": [seg(0, 0.0, 5e-3, 2e-3), seg(0, 5e-3, 0.03, 9e-3), seg(1, 5e-3, 0.03, 8e-3)],
        "impacts": impacts, "rms_m": 1e-6, "noise_m": 1e-6, "n_points": 600, "n_outliers": 0, "iterations": 9});
    (rec, fit)
}

struct Fixture {
    runs: BTreeMap<String, Vec<u8>>,
    fits: BTreeMap<String, Vec<u8>>,
    files: BTreeMap<&'static str, Vec<u8>>,
}

fn fixture(with_collisions: bool, with_extras: bool) -> Fixture {
    let mut runs = BTreeMap::new();
    let mut fits = BTreeMap::new();
    let mut csv = String::from("run,material,v0_mps,v0_se,mu,mu_se,T_s,T_se,t1_s,rms_m,status\n");
    let singles = [
        ("s316_a", "316", 0.025, 0.337, 0.0795),
        ("s316_b", "316", 0.05, 0.340, 0.107),
        ("s316_c", "316", -0.08, 0.334, 0.14),
        ("s440_a", "440c", 0.02, 0.29, 0.074),
        ("s440_b", "440c", 0.06, 0.294, 0.118),
        ("s440_c", "440c", -0.09, 0.292, 0.151),
    ];
    for (run, m, v0, mu, t) in singles {
        let (rec, fit, line) = single(run, m, v0, mu, t);
        runs.insert(format!("{run}.json"), item_bytes(&rec));
        fits.insert(format!("{run}.json"), serde_json::to_vec(&fit).unwrap());
        csv.push_str(&line);
    }
    if with_collisions {
        let sets = [
            (
                "c316_r",
                "316",
                "rolling",
                vec![(0.1, 0.08, -0.25, 0.17), (0.2, 0.15, -0.5, 0.35)],
            ),
            ("c316_c", "316", "contact", vec![(0.15, 0.14, -0.2, 0.0)]),
            ("c440_r", "440c", "rolling", vec![(0.12, 0.1, -0.33, 0.2)]),
            ("c440_c", "440c", "contact", vec![(0.05, 0.05, -0.1, 0.0)]),
        ];
        for (run, m, setup, sp) in sets {
            let (rec, fit) = collision(run, m, setup, &sp);
            runs.insert(format!("{run}.json"), item_bytes(&rec));
            fits.insert(format!("{run}.json"), serde_json::to_vec(&fit).unwrap());
        }
    }
    let mut files = BTreeMap::new();
    files.insert("fits_csv", csv.into_bytes());
    if with_extras {
        let est = |v: f64, lo: f64, hi: f64| json!({"value": v, "interval": {"lo": lo, "hi": hi}});
        let mat = |mu: f64| {
            json!({"n_runs": 3, "n_converged": 3, "mu_weighted": est(mu, mu - 0.004, mu + 0.004),
                   "mu_fast": est(mu, mu - 0.006, mu + 0.006), "n_fast": 2,
                   "t_vs_v0": {"intercept_s": est(0.052, 0.047, 0.058), "slope_s_per_mps": est(1.1, 1.0, 1.2)},
                   "mu_vs_v0": {"intercept": est(mu, mu - 0.01, mu + 0.01), "slope_per_mps": est(0.0, -0.1, 0.1)},
                   "speed_range_mps": [0.02, 0.09]})
        };
        let iv = |v: f64, lo: f64, hi: f64| json!({"value": v, "lo": lo, "hi": hi});
        let curve = |m: &str, setup: &str, a: f64| {
            json!({"material": m, "setup": setup, "n_impacts": 2, "n_runs": 1, "c0": iv(1.0, 0.9, 1.1),
                   "slope_per_mps": iv(a, a - 0.5, a + 0.5), "a_per_mps": iv(a, a - 0.4, a + 0.4), "c_inf": iv(0.5, 0.4, 0.6),
                   "v_ref_mps": iv(0.2, 0.1, 0.3), "mean_c": 0.7,
                   "min_speed_mps": 0.05, "max_speed_mps": 0.2})
        };
        let summary = json!({
            "single": {"n_runs": 6, "n_converged": 6, "fast_min_speed_mps": 0.03,
                       "materials": {"316": mat(0.337), "440c": mat(0.293)}, "pooled": mat(0.315)},
            "collisions": {"n_runs": 4, "n_runs_fitted": 4, "n_impacts": 5, "k": 2.5,
                "mu_pp": {"value": iv(1.38, 1.27, 1.5), "from_slip_slope": iv(1.36, 1.2, 1.5),
                          "from_impulse_fit": iv(1.38, 1.27, 1.5), "stick_lower_bound": 0.6,
                          "n_slip": 4, "n_stick": 1, "n_undetermined": 0},
                "restitution": [curve("316", "rolling", 3.1), curve("316", "contact", 1.3),
                                curve("440c", "rolling", 3.0), curve("440c", "contact", 0.9)],
                "spin_points": [], "restitution_points": [], "bootstrap_seed": 1, "bootstrap_resamples": 400,
                "notes": []},
            "notes": [], "bootstrap": {"resamples": 400, "level": 0.95, "seed": 1, "unit": "run"}});
        let score = |cv: f64, terms: &[&str]| json!({"cv_rms_m": cv, "rms_m": cv * 0.9, "chi2": 1000.0, "n_global_params": 3, "terms": terms});
        let evidence = |round: usize, lr: f64, p: f64, decision: &str| {
            json!({"round": round, "lr": lr, "extra_params": 1, "bootstrap_replicates": 40, "null_mean_lr": 1.1,
                   "p_value": p, "p_empirical": p, "p_holm": p * 2.0, "cv_paired_t": 4.2, "cv_rms_m": 1.02e-6,
                   "decision": decision})
        };
        let point = |v0: f64, t: f64| json!({"run": "r", "material": "316", "v0_mps": v0, "t_s": t, "mu": 0.33, "z0_m": 0.0});
        let bins = |r: f64| {
            json!({"by_phase": {"rolling": {"n": 100, "rms_m": r, "mean_m": 0.0, "mean_z": 0.0, "rms_over_noise": r / 1e-6},
                                "sliding": {"n": 50, "rms_m": 1e-6, "mean_m": 0.0, "mean_z": 0.0, "rms_over_noise": 1.0}},
                   "by_speed": {}, "by_position": {}, "by_direction": {}, "by_material": {},
                   "runs_test_z": -8.0 * r / 1.3e-6, "runs_test_p": 0.0, "lag1_autocorrelation": 0.4, "lag1_z": 9.0})
        };
        let diagnosis = json!({"mismatch": true, "findings": [
            {"effect": "velocity_dependent_drag", "accepted": true, "form": "saturating",
             "parameters": {"t0_s": {"value": 0.051, "stderr": 0.002}, "tp_s_per_mps": {"value": 1.12, "stderr": 0.04}},
             "evidence": evidence(1, 85.2, 0.001, "accepted"),
             "where": {"phase": "rolling", "speed": "all", "drift": "T rises with v0"},
             "baseline": score(1.31e-6, &[]), "extended": score(1.02e-6, &["saturating_drag"])},
            {"effect": "rolling_resistance", "accepted": false, "form": "c g sign(v)",
             "parameters": {"c": {"value": 0.0011, "stderr": 0.0003}},
             "evidence": evidence(1, 3.1, 0.3, "rejected"), "where": {},
             "baseline": score(1.31e-6, &[]), "extended": score(1.29e-6, &["rolling_resistance"])}],
            "candidates": [
                {"round": 1, "effect": "velocity_dependent_drag", "form": "saturating", "accepted": true,
                 "parameters": {"tp_s_per_mps": {"value": 1.12, "stderr": 0.04}}, "evidence": evidence(1, 85.2, 0.001, "accepted")},
                {"round": 1, "effect": "rolling_resistance", "form": "c g sign(v)", "accepted": false,
                 "parameters": {"c": {"value": 0.0011, "stderr": 0.0003}}, "evidence": evidence(1, 3.1, 0.3, "rejected")},
                {"round": 2, "effect": "groove_tilt", "form": "g sin(alpha)", "accepted": false,
                 "parameters": {"alpha_deg": {"value": 0.001, "stderr": 0.002}}, "evidence": evidence(2, 0.4, 0.6, "rejected")}],
            "model": score(1.02e-6, &["saturating_drag"]), "model_parameters": {}, "baseline_model": score(1.31e-6, &[]),
            "residuals_before": bins(1.3e-6), "residuals_after": bins(1.0e-6),
            "drift": {"before": [point(0.02, 0.074), point(0.06, 0.118), point(0.09, 0.151)],
                      "after": [point(0.02, 0.052), point(0.06, 0.051), point(0.09, 0.053)],
                      "lines_before": {"t_s vs |v0| (316)": {"n": 3, "intercept": 0.052, "slope": 1.1, "slope_se": 0.05, "t": 22.0}},
                      "lines_after": {"t_s vs |v0| (316)": {"n": 3, "intercept": 0.052, "slope": 0.01, "slope_se": 0.05, "t": 0.2}},
                      "note": "per-run T with the accepted terms held fixed"},
            "runs_used": 6, "materials": ["316", "440c"],
            "settings": {"bootstrap": 40, "alpha": 0.01, "folds": 5, "seed": 1, "candidates": []}, "note": ""});
        // the validate stage's layout
        let pv = |m: &str, q: &str, truth: f64, rec: f64| {
            json!({"material": m, "quantity": q, "truth": truth, "recovered": rec, "low": rec - 0.005,
                   "high": rec + 0.005, "error": rec - truth, "within_interval": true})
        };
        let validation = json!({"truth": true,
            "parameters": [pv("316", "mu_weighted", 0.337, 0.337), pv("316", "mu_fast", 0.337, 0.337),
                           {"material": "316", "quantity": "restitution_rolling",
                            "truth_law": "{\"speed_dependent\":{\"c0\":1.0,\"v_ref_mps\":0.4}}"},
                           pv("440c", "mu_weighted", 0.293, 0.292), pv("440c", "mu_fast", 0.293, 0.293)],
            "mu_pp": {"truth": 1.4, "recovered": 1.38},
            "effects": {"truth": [{"effect": "velocity_dependent_drag",
                                   "term": {"term": "saturating_drag", "t0_s": 0.05, "tp_s_per_mps": 1.1}}],
                        "accepted": ["velocity_dependent_drag"], "missed": [], "spurious": [], "all_named": true}});
        let provenance = json!({"groove_version": "0.1.0", "code_commit": "0123456789abcdef0123456789abcdef01234567",
            "fingerprints": {"figures": "aa11", "report": "bb22"}, "seed": 20261122,
            "inputs": [{"path": "data/runs.csv", "sha256": "c0ffee"}, {"path": "data/trajectories.csv", "sha256": "beef"}],
            "stages": [{"stage": "fit", "kind": "fit", "key": "k1"}, {"stage": "report", "kind": "report", "key": "k2"}],
            "params": {"fit": {"max_iter": 200, "min_frames": 20}, "report": {"title": "groove report", "source_date_epoch": null}}});
        files.insert("summary", serde_json::to_vec(&summary).unwrap());
        files.insert("diagnosis", serde_json::to_vec(&diagnosis).unwrap());
        files.insert("validation", serde_json::to_vec(&validation).unwrap());
        files.insert("provenance", serde_json::to_vec(&provenance).unwrap());
    } else {
        files.insert("validation", br#"{"truth": false}"#.to_vec());
    }
    Fixture { runs, fits, files }
}

fn artifacts(f: &Fixture) -> BTreeMap<String, Artifact> {
    let mut a = BTreeMap::new();
    a.insert("runs".to_string(), Artifact::Collection(f.runs.clone()));
    a.insert("fits".to_string(), Artifact::Collection(f.fits.clone()));
    for (k, v) in &f.files {
        a.insert(k.to_string(), Artifact::File(v.clone()));
    }
    a
}

fn data(a: &BTreeMap<String, Artifact>) -> ReportData {
    let refs: BTreeMap<&str, &Artifact> = a.iter().map(|(k, v)| (k.as_str(), v)).collect();
    ReportData::from_inputs(&groove::stages::report::unpack(&refs)).expect("fixture artifacts read")
}

/// figures, html, md of a fixture.
fn render(f: &Fixture, date: Option<i64>) -> (BTreeMap<String, String>, String, String) {
    let a = artifacts(f);
    let d = data(&a);
    let figs = render_figures(&d, &FigureOptions::default()).expect("figures render");
    let pages = render_pages(&d, &figs, "groove report", date).expect("pages render");
    (figs, pages.html, pages.md)
}

// ---------------------------------------------------------------- a tiny well-formedness check

const VOID: [&str; 6] = ["meta", "link", "br", "hr", "img", "input"];

/// Check that every element is closed in order (HTML void elements excepted); returns the number of
/// elements seen, or where the nesting breaks.
fn well_formed(doc: &str) -> Result<usize, String> {
    let mut stack: Vec<String> = Vec::new();
    let mut n = 0;
    let mut rest = doc;
    while let Some(i) = rest.find('<') {
        rest = &rest[i..];
        if rest.starts_with("<!--") {
            let end = rest.find("-->").ok_or("unclosed comment")?;
            rest = &rest[end + 3..];
            continue;
        }
        if rest.starts_with("<!") || rest.starts_with("<?") {
            let end = rest.find('>').ok_or("unclosed declaration")?;
            rest = &rest[end + 1..];
            continue;
        }
        let end = rest
            .find('>')
            .ok_or_else(|| format!("unclosed tag near {:?}", &rest[..rest.len().min(40)]))?;
        let tag = &rest[1..end];
        rest = &rest[end + 1..];
        if let Some(name) = tag.strip_prefix('/') {
            let name = name.trim().to_ascii_lowercase();
            match stack.pop() {
                Some(open) if open == name => {}
                other => return Err(format!("</{name}> closes {other:?}")),
            }
            continue;
        }
        let name = tag
            .split(|c: char| c.is_whitespace() || c == '/')
            .next()
            .unwrap_or("")
            .to_ascii_lowercase();
        if name.is_empty() || !name.chars().next().unwrap().is_ascii_alphabetic() {
            return Err(format!("bad tag <{tag}>"));
        }
        n += 1;
        if tag.ends_with('/') || VOID.contains(&name.as_str()) {
            continue;
        }
        if name == "style" || name == "script" {
            let close = format!("</{name}>");
            let e = rest.find(&close).ok_or("unclosed style")?;
            rest = &rest[e + close.len()..];
            continue;
        }
        stack.push(name);
    }
    if stack.is_empty() {
        Ok(n)
    } else {
        Err(format!("unclosed elements {stack:?}"))
    }
}

// ---------------------------------------------------------------- tests

const ALL_FIGURES: [&str; 11] = [
    "fig_4_2b.svg",
    "fig_4_2c.svg",
    "fig_4_2d.svg",
    "fig_4_3c.svg",
    "fig_4_3d.svg",
    "fig_4_4a.svg",
    "fig_4_4b.svg",
    "fig_4_4c.svg",
    "fig_secondary.svg",
    "fig_discovery_cv.svg",
    "fig_discovery_drift.svg",
];

#[test]
fn every_figure_renders_as_well_formed_svg_with_labelled_axes() {
    let (mut figs, _, _) = render(&fixture(true, true), None);
    let csv: BTreeMap<String, String> = figs
        .iter()
        .filter(|(k, _)| k.ends_with(".csv"))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    figs.retain(|k, _| k.ends_with(".svg"));
    let names: Vec<&str> = figs.keys().map(String::as_str).collect();
    let mut want = ALL_FIGURES.to_vec();
    want.sort();
    assert_eq!(names, want);
    // every figure of data points has its CSV (a residual strip's points their own), one row a
    // point, and each point a title
    for (name, svg) in &figs {
        let points = svg.matches("<circle class=\"pt\"").count();
        let rows: usize = ["", "_residuals"]
            .iter()
            .filter_map(|part| csv.get(&name.replace(".svg", &format!("{part}.csv"))))
            .map(|c| c.lines().count() - 1)
            .sum();
        assert_eq!(rows, points, "{name}: CSV rows against titled points");
        assert_eq!(svg.matches("<title>").count(), points, "{name}");
    }
    for want in [
        "fig_4_2b_residuals.csv",
        "fig_4_3c_residuals.csv",
        "fig_4_2c.csv",
        "fig_4_2d.csv",
        "fig_4_4a.csv",
        "fig_4_4b.csv",
        "fig_discovery_cv.csv",
    ] {
        assert!(csv.contains_key(want), "{want} missing: {:?}", csv.keys());
    }
    assert!(
        csv["fig_4_2c.csv"]
            .starts_with("series,run,initial speed |v0| (m/s),fitted drag time T (s)\n")
            && csv["fig_4_2c.csv"].contains("\n316: fitted T,s316_a,0.025,"),
        "{}",
        csv["fig_4_2c.csv"]
    );
    assert!(figs["fig_4_2c.svg"].contains("<title>run s316_a, 316: fitted T: initial speed |v0| (m/s) = 0.025; fitted drag time T (s) = "));
    for (name, svg) in &figs {
        assert!(svg.contains("<svg"), "{name}");
        well_formed(svg).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    // units on the axes
    assert!(figs["fig_4_2b.svg"].contains("time t (ms)") && figs["fig_4_2b.svg"].contains("(mm)"));
    assert!(figs["fig_4_2c.svg"].contains("|v0| (m/s)") && figs["fig_4_2c.svg"].contains("T (s"));
    assert!(figs["fig_4_2c.svg"].contains("Stokes drag in free air: 2.18 s"));
    assert!(figs["fig_4_2d.svg"].contains("chapter: 0.337 (316), 0.293 (440c)"));
    assert!(
        figs["fig_4_4a.svg"].contains("μ_pp = 1.38"),
        "μ_pp line from summary.json"
    );
    assert!(figs["fig_secondary.svg"].contains("78.5°"));
}

#[test]
fn markdown_has_every_section_in_order_and_the_numbers() {
    let (figs, _, md) = render(&fixture(true, true), Some(1_795_305_600));
    let heads = [
        "## 1. Summary",
        "## 2. The data",
        "## 3. The chapter reproduced",
        "## 4. Discovery",
        "## 5. Equation audit",
        "## 6. Provenance",
    ];
    let pos: Vec<usize> = heads
        .iter()
        .map(|h| md.find(h).unwrap_or_else(|| panic!("missing {h}")))
        .collect();
    assert!(pos.windows(2).all(|w| w[0] < w[1]), "sections out of order");
    let sub = [
        "### 3.1 Fig. 4.2b",
        "### 3.2 Fig. 4.2c",
        "### 3.3 Fig. 4.2d",
        "### 3.4 Figs. 4.3c–d",
        "### 3.5 Fig. 4.4a",
        "### 3.6 Figs. 4.4b–c",
        "### 3.7 Secondary collisions",
    ];
    let pos: Vec<usize> = sub
        .iter()
        .map(|h| md.find(h).unwrap_or_else(|| panic!("missing {h}")))
        .collect();
    assert!(
        pos.windows(2).all(|w| w[0] < w[1]),
        "chapter figures out of order"
    );
    for name in figs.keys().filter(|k| k.ends_with(".svg")) {
        assert!(
            md.contains(&format!("](figures/{name})")),
            "report.md does not reference {name}"
        );
    }
    assert!(md.contains("2026-11-22"));
    // key numbers: ours, chapter's, truth; Stokes; the factor and bound; the audit's sign change
    for needle in [
        "0.3370 [0.3310, 0.3430]",
        "| 0.337 |",
        "| truth |",
        "2.18",
        "0.074 (wrong)",
        "0.0900",
        "78.46",
        "48.1",
        "1.380 [1.270, 1.500]",
        "> 0.60",
        "3.100 [2.700, 3.500]",
        "t_s vs \\|v0\\| (316)",
        "round",
        "Against the truth (this dataset is synthetic): concealed physics velocity dependent drag",
        "| velocity dependent drag | tp_s_per_mps | 1.120 ± 0.040 | 1.100 |",
        "saturating: c_inf = 1.000; v_ref_mps = 0.4000",
        "velocity dependent drag (saturating)",
        "0123456789abcdef0123456789abcdef01234567",
        "| data/runs.csv | c0ffee |",
    ] {
        assert!(md.contains(needle), "report.md lacks {needle:?}");
    }
    // table cells with |v0| are escaped so the table stays a table
    assert!(md.contains("\\|v0\\|"));
    assert!(!md.contains("\n\n\n"));
}

#[test]
fn html_is_self_contained_well_formed_and_has_every_figure() {
    let (figs, html, _) = render(&fixture(true, true), None);
    let n = well_formed(&html).unwrap_or_else(|e| panic!("report.html: {e}"));
    assert!(n > 500, "suspiciously few elements: {n}");
    for bad in [
        "http://", "https://", " src=", "<script", "<link", "@import", "url(",
    ] {
        assert!(!html.contains(bad), "report.html contains {bad:?}");
    }
    let svgs: Vec<&String> = figs.keys().filter(|k| k.ends_with(".svg")).collect();
    assert_eq!(html.matches("<svg").count(), svgs.len());
    assert!(html.contains("<a href=\"figures/fig_4_2c.csv\">Data (CSV)</a>"));
    for name in svgs {
        assert!(
            html.contains(&format!(
                "<figure id=\"{}\">",
                name.trim_end_matches(".svg")
            )),
            "{name}"
        );
    }
    assert!(html.contains("<style>") && html.starts_with("<!DOCTYPE html>"));
    assert!(html.contains("|v0| &gt; 0.03"), "text is HTML-escaped");
}

/// The page's text without its inline figures and style sheet.
fn text_outside_svg_and_style(html: &str) -> String {
    let mut out = String::new();
    let mut rest = html;
    loop {
        let next = ["<svg", "<style>"]
            .iter()
            .filter_map(|open| rest.find(open).map(|i| (i, *open)))
            .min();
        let Some((i, open)) = next else {
            out.push_str(rest);
            return out;
        };
        out.push_str(&rest[..i]);
        let close = if open == "<svg" { "</svg>" } else { "</style>" };
        let end = rest[i..].find(close).expect("closed") + i + close.len();
        rest = &rest[end..];
    }
}

#[test]
fn the_shipped_html_shows_no_markdown_markup() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/reports/");
    let html = std::fs::read_to_string(format!("{dir}report.html")).unwrap();
    let md = std::fs::read_to_string(format!("{dir}report.md")).unwrap();
    // the Markdown page has emphasis and code spans, the HTML page shows them as elements
    assert!(md.contains("**saturating** (chosen)") && md.contains("`after`"));
    assert!(html.contains("<strong>saturating</strong> (chosen)"));
    assert!(html.contains("<code>after</code>"));
    let text = text_outside_svg_and_style(&html);
    for mark in ["**", "`", "](", "\\|"] {
        let at = text
            .find(mark)
            .map(|i| text[i..].chars().take(80).collect::<String>());
        assert_eq!(at, None, "report.html shows Markdown {mark:?}");
    }
}

/// The summary paragraph (section 1) of a Markdown page.
fn summary_of(md: &str) -> &str {
    let start = md.find("## 1. Summary").expect("a summary");
    let end = md[start..].find("## 2.").map_or(md.len(), |e| start + e);
    &md[start..end]
}

/// Discovery run through its stage on `f`'s recordings with `params`; its diagnosis.json.
fn diagnosis_of(f: &Fixture, params: &str) -> Vec<u8> {
    let kind = groove::stages::registry()
        .into_iter()
        .find(|k| k.kind() == "discover")
        .expect("discover registered");
    let runs = Artifact::Collection(f.runs.clone());
    let params: toml::Table = toml::from_str(params).unwrap();
    let input = StageInput {
        params: &params,
        inputs: [("runs", &runs)].into_iter().collect(),
        item: None,
        seed: 1,
        progress: None,
        put_item: None,
        memo: None,
    };
    let Artifact::File(bytes) = kind
        .run(&input)
        .expect("discover runs")
        .remove("diagnosis")
        .unwrap()
    else {
        panic!("diagnosis is a file")
    };
    bytes
}

#[test]
fn below_the_discovery_floor_the_summary_says_discovery_did_not_run() {
    let mut f = fixture(false, false);
    f.files
        .insert("diagnosis", diagnosis_of(&f, "min_frames = 12"));
    let (_, html, md) = render(&f, None);
    let summary = summary_of(&md);
    assert!(
        summary.contains(
            "Discovery did not run: 6 single runs with at least 12 frames, fewer than the 10"
        ),
        "{summary}"
    );
    assert!(!summary.contains("found nothing missing"), "{summary}");
    assert!(!html.contains("Discovery found nothing missing"));
}

#[test]
fn a_clean_discovery_gives_its_detection_limits_in_the_summary() {
    let mut f = fixture(true, true);
    let mut diag: Value = serde_json::from_slice(&f.files["diagnosis"]).unwrap();
    diag["mismatch"] = json!(false);
    for list in ["findings", "candidates"] {
        for c in diag[list].as_array_mut().unwrap() {
            c["accepted"] = json!(false);
        }
    }
    diag["candidates"][2]["evidence"]["detection_limit"] = json!({"parameter": "alpha_deg",
        "value": 0.0213, "text": "a groove tilt above 0.0213 ° would have been found"});
    f.files
        .insert("diagnosis", serde_json::to_vec(&diag).unwrap());
    let (_, _, md) = render(&f, None);
    let summary = summary_of(&md);
    assert!(
        summary.contains("Discovery found nothing missing in 6 single runs")
            && summary
                .contains("it would have found a groove tilt above 0.0213 ° (its detection limits"),
        "{summary}"
    );
    // without any limit, the summary says the power is not known
    diag["candidates"][2]["evidence"]
        .as_object_mut()
        .unwrap()
        .remove("detection_limit");
    f.files
        .insert("diagnosis", serde_json::to_vec(&diag).unwrap());
    let (_, _, md) = render(&f, None);
    assert!(
        summary_of(&md).contains("gave no detection limit"),
        "{}",
        summary_of(&md)
    );
}

#[test]
fn counts_of_one_are_singular() {
    let mut f = fixture(false, false);
    f.runs.retain(|name, _| name == "s316_a.json");
    f.fits.retain(|name, _| name == "s316_a.json");
    let csv = String::from_utf8(f.files["fits_csv"].clone()).unwrap();
    let kept: String = csv
        .lines()
        .filter(|l| l.starts_with("run,") || l.starts_with("s316_a,"))
        .map(|l| format!("{l}\n"))
        .collect();
    f.files.insert("fits_csv", kept.into_bytes());
    let (_, _, md) = render(&f, None);
    let summary = summary_of(&md);
    assert!(
        summary.contains("Analysed 1 recorded run: 1 single-particle run with a baseline fit and 0 collision runs"),
        "{summary}"
    );
}

/// The value of attribute `name` in the text of one tag.
fn attr_of(tag: &str, name: &str) -> Option<f64> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    tag[i..].split('"').next()?.parse().ok()
}

/// What a figure's layout gets wrong: a legend box over a data point, a text past the canvas.
fn layout_faults(name: &str, svg: &str) -> Vec<String> {
    let mut faults = Vec::new();
    let (w, h) = (
        attr_of(svg, "width").unwrap_or(0.0),
        attr_of(svg, "height").unwrap_or(0.0),
    );
    let tags: Vec<&str> = svg.split('<').skip(1).collect();
    let boxes = legend_boxes(&tags);
    let points: Vec<(f64, f64)> = tags
        .iter()
        .filter(|t| t.starts_with("circle class=\"pt\""))
        .filter_map(|t| Some((attr_of(t, "cx")?, attr_of(t, "cy")?)))
        .collect();
    for b in &boxes {
        // a marker reaches 5 px from its point
        if let Some(p) = points.iter().find(|p| {
            p.0 > b[0] - 5.0
                && p.0 < b[0] + b[2] + 5.0
                && p.1 > b[1] - 5.0
                && p.1 < b[1] + b[3] + 5.0
        }) {
            faults.push(format!(
                "{name}: legend box {b:?} covers the data point at {p:?}"
            ));
        }
    }
    // every text inside the canvas (its width estimated at 0.55 em a character, a sans-serif
    // digit's width)
    for (i, t) in tags.iter().enumerate() {
        if !t.starts_with("text ") {
            continue;
        }
        let text = t.split_once('>').map_or("", |(_, rest)| rest.trim());
        let text = text
            .replace("&apos;", "'")
            .replace("&quot;", "\"")
            .replace("&lt;", "<")
            .replace("&gt;", ">")
            .replace("&amp;", "&");
        let (Some(x), Some(y), Some(size)) =
            (attr_of(t, "x"), attr_of(t, "y"), attr_of(t, "font-size"))
        else {
            continue;
        };
        let len = text.chars().count() as f64 * 0.55 * size;
        let (lo, hi) = if t.contains("rotate(") {
            (y - len / 2.0, y + len / 2.0)
        } else if t.contains("text-anchor=\"end\"") {
            (x - len, x)
        } else if t.contains("text-anchor=\"middle\"") {
            (x - len / 2.0, x + len / 2.0)
        } else {
            (x, x + len)
        };
        let room = if t.contains("rotate(") { h } else { w };
        if lo < 0.0 || hi > room || y < 0.0 || y > h {
            faults.push(format!(
                "{name}: text {text:?} (tag {i}) runs past the canvas: {lo:.0}..{hi:.0} of {room}"
            ));
        }
    }
    assert!(w > 0.0 && h > 0.0, "{name}: no canvas size");
    faults
}

#[test]
fn no_legend_covers_a_point_and_no_label_leaves_the_canvas() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/figures");
    let mut figs: BTreeMap<String, String> = BTreeMap::new();
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "svg") {
            let name = format!("shipped {}", path.file_name().unwrap().to_string_lossy());
            figs.insert(name, std::fs::read_to_string(&path).unwrap());
        }
    }
    assert!(figs.len() >= 11, "the shipped figures: {:?}", figs.keys());
    let (fixture_figs, _, _) = render(&fixture(true, true), None);
    for (k, v) in fixture_figs
        .into_iter()
        .filter(|(k, _)| k.ends_with(".svg"))
    {
        figs.insert(format!("fixture {k}"), v);
    }
    // and a report of few runs, made by the shipped pipeline end to end
    let ten = ten_run_figures();
    assert!(ten.len() >= 11, "the 10-run figures: {:?}", ten.keys());
    for (k, v) in ten {
        figs.insert(format!("10-run {k}"), v);
    }
    let faults: Vec<String> = figs.iter().flat_map(|(k, v)| layout_faults(k, v)).collect();
    assert!(faults.is_empty(), "{}", faults.join("\n"));
}

/// Every figure of the report the shipped pipeline makes of a small dataset: 10 single runs of
/// 30 ms and two collision runs of each setup and material (tests/fixtures/truths/report_ten.toml),
/// synthesized and run through the built binary.
fn ten_run_figures() -> BTreeMap<String, String> {
    let dir = files::scratch("report");
    let project = dir.join("ten");
    let _ = std::fs::remove_dir_all(&project);
    std::fs::create_dir_all(&project).unwrap();
    files::synth(dir, "report_ten", &project.join("data"));
    std::fs::copy(
        files::repo().join("pipeline.toml"),
        project.join("pipeline.toml"),
    )
    .unwrap();
    files::ok(
        &files::groove(&project, &files::cli::RUN_IN_PROJECT),
        "groove run on the 10-run dataset",
    );
    let runs = std::fs::read_to_string(project.join("data/runs.csv")).unwrap();
    assert_eq!(
        runs.lines().filter(|l| l.contains(",single,")).count(),
        10,
        "{runs}"
    );
    std::fs::read_dir(project.join("reports/figures"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "svg"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read_to_string(&p).unwrap())
        })
        .collect()
}

/// The texts of an SVG, in order.
fn texts_of(svg: &str) -> Vec<String> {
    svg.split("<text ")
        .skip(1)
        .filter_map(|t| {
            Some(
                t.split_once('>')?
                    .1
                    .split("</text>")
                    .next()?
                    .trim()
                    .to_string(),
            )
        })
        .collect()
}

#[test]
fn the_shipped_figures_draw_what_the_report_chose_and_each_tick_once() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/reports/");
    let read = |f: &str| std::fs::read_to_string(format!("{dir}{f}")).unwrap();
    let md = read("report.md");
    // the table chooses the saturating law for every material and setup; the figures draw it
    assert_eq!(md.matches("**saturating** (chosen)").count(), 4);
    for fig in ["figures/fig_4_4b.svg", "figures/fig_4_4c.svg"] {
        let texts = texts_of(&read(fig));
        for setup in ["rolling", "in contact"] {
            let want = format!("{setup}: saturating law, chosen by the whole-run fit");
            assert!(texts.contains(&want), "{fig}: no {want:?} in {texts:?}");
        }
        assert!(
            !texts.iter().any(|t| t.contains("C = 1 −")),
            "{fig}: {texts:?}"
        );
    }
    // the μ_pp profile on a linear axis, each interval marked
    let texts = texts_of(&read("figures/fig_mu_pp_profile.svg"));
    assert!(
        texts.contains(&"μ_pp (particle–particle friction)".to_string()),
        "{texts:?}"
    );
    assert!(!texts.iter().any(|t| t.contains("log10")), "{texts:?}");
    for m in ["316", "440c"] {
        assert!(
            texts
                .iter()
                .any(|t| t.starts_with(&format!("{m}: 95 % interval ["))),
            "{m}: {texts:?}"
        );
    }
    // the log axis of Fig. 4.2c (its labels end at the axis) writes each tick once
    let svg = read("figures/fig_4_2c.svg");
    let y_labels: Vec<&str> = svg
        .split("<text ")
        .filter(|t| t.contains("text-anchor=\"end\""))
        .collect();
    let texts = texts_of(&format!("<text {}", y_labels.join("<text ")));
    let ticks: Vec<&String> = texts.iter().filter(|t| t.parse::<f64>().is_ok()).collect();
    assert!(ticks.len() >= 3, "{ticks:?}");
    let mut unique = ticks.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(ticks.len(), unique.len(), "{ticks:?}");
}

#[test]
fn the_layout_check_catches_a_covered_point_and_a_clipped_label() {
    let svg = r##"<svg width="100" height="50"><rect x="10" y="10" width="30" height="20" opacity="0.85" fill="#FFFFFF" stroke="none"/>
<text x="95" y="40" text-anchor="middle" font-size="10">110.0</text>
<circle class="pt" cx="20" cy="15" r="6"><title>run a</title></circle></svg>"##;
    let faults = layout_faults("t", svg);
    assert_eq!(faults.len(), 2, "{faults:?}");
    let fine = svg
        .replace("cx=\"20\"", "cx=\"60\"")
        .replace("x=\"95\"", "x=\"80\"");
    assert_eq!(layout_faults("t", &fine), Vec::<String>::new());
}

#[test]
fn sections_open_with_what_they_found_and_fold_their_statistics() {
    let (_, html, md) = render(&fixture(true, true), None);
    // the verdict first, under the heading, in both pages
    for (id, start) in [
        (
            "summary",
            "Discovery found missing physics and accepted: velocity dependent drag",
        ),
        (
            "data",
            "6 single-particle runs with a baseline fit and 4 collision runs",
        ),
        ("fig-4-2c", "The drag time T rises with |v0|"),
        (
            "fig-4-2d",
            "The friction coefficient μ_pg of the runs faster than 0.03 m/s: 316 ",
        ),
        ("discovery", "Verdict: discovery accepted one finding."),
    ] {
        let at = html.find(&format!("<section id=\"{id}\">")).expect(id);
        let after_heading = html[at..]
            .split_once("</h")
            .unwrap()
            .1
            .split_once('\n')
            .unwrap()
            .1;
        assert!(
            after_heading.starts_with(&format!("<p class=\"lead\">{start}")),
            "{id}: {}",
            &after_heading[..200.min(after_heading.len())]
        );
        assert!(md.contains(&format!("\n\n{start}")), "{id} in report.md");
    }
    // discovery's tables folded in the HTML page, in full in the Markdown
    let disc = &html[html.find("<section id=\"discovery\">").unwrap()..];
    let disc = &disc[..disc.find("</section>").unwrap()];
    assert!(disc.matches("<table").count() >= 2, "{disc}");
    assert_eq!(
        disc.matches("<details>").count(),
        disc.matches("<table").count()
    );
    assert!(disc.contains("<details>\n<summary>Every candidate tested"));
    assert!(md.contains("*Every candidate tested: evidence and fitted size"));
    assert!(md.contains("| 2 | groove tilt | g sin(alpha) | no |"));
    well_formed(&html).unwrap();
}

#[test]
fn two_renders_are_byte_identical() {
    let f = fixture(true, true);
    let a = render(&f, Some(0));
    let b = render(&f, Some(0));
    assert_eq!(a.0, b.0);
    assert_eq!(a.1, b.1);
    assert_eq!(a.2, b.2);
}

#[test]
fn missing_parts_are_said_not_fatal() {
    let (figs, html, md) = render(&fixture(false, false), None);
    assert!(!figs.contains_key("fig_4_3c.svg") && !figs.contains_key("fig_discovery_cv.svg"));
    assert!(figs.contains_key("fig_4_2b.svg") && figs.contains_key("fig_secondary.svg"));
    assert!(md.contains("no collision runs in this dataset"));
    assert!(md.contains("no diagnosis.json"));
    assert!(md.contains("no provenance input"));
    assert!(
        !md.contains("| truth |"),
        "no truth column without a truth file"
    );
    well_formed(&html).unwrap();
}

#[test]
fn stage_kinds_run_through_the_contract() {
    let reg = groove::stages::registry();
    let figures = reg
        .iter()
        .find(|k| k.kind() == "figures")
        .expect("figures registered");
    let report = reg
        .iter()
        .find(|k| k.kind() == "report")
        .expect("report registered");
    let f = fixture(true, true);
    let a = artifacts(&f);
    let params = toml::Table::new();
    let input = StageInput {
        params: &params,
        inputs: a.iter().map(|(k, v)| (k.as_str(), v)).collect(),
        item: None,
        seed: 1,
        progress: None,
        put_item: None,
        memo: None,
    };
    let out = figures.run(&input).expect("figures stage runs");
    let Artifact::Collection(items) = &out["figures"] else {
        panic!("figures is a collection")
    };
    assert_eq!(
        items.keys().filter(|k| k.ends_with(".svg")).count(),
        ALL_FIGURES.len()
    );
    let mut a2 = a.clone();
    a2.insert("figures".into(), out["figures"].clone());
    let p: toml::Table = toml::from_str("source_date_epoch = 86400").unwrap();
    let input = StageInput {
        params: &p,
        inputs: a2.iter().map(|(k, v)| (k.as_str(), v)).collect(),
        item: None,
        seed: 1,
        progress: None,
        put_item: None,
        memo: None,
    };
    let pages = report.run(&input).expect("report stage runs");
    let Artifact::File(md) = &pages["md"] else {
        panic!()
    };
    assert!(String::from_utf8_lossy(md).contains("1970-01-02"));
    let bad: toml::Table = toml::from_str("colour = 1").unwrap();
    let err = report.canonical_params(&bad).unwrap_err().to_string();
    assert!(err.contains("colour"), "{err}");
}

#[test]
fn fixture_report_is_written_for_the_browser_check() {
    // tests/browser.sh renders this file in headless Chromium
    let (figs, html, md) = render(&fixture(true, true), Some(1_795_305_600));
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("report-fixture");
    std::fs::create_dir_all(dir.join("figures")).unwrap();
    std::fs::write(dir.join("report.html"), &html).unwrap();
    std::fs::write(dir.join("report.md"), &md).unwrap();
    for (k, v) in &figs {
        std::fs::write(dir.join("figures").join(k), v).unwrap();
    }
    assert_eq!(
        std::fs::read_to_string(dir.join("report.html")).unwrap(),
        html
    );
}

#[test]
fn the_checker_catches_broken_nesting() {
    assert!(well_formed("<div><p>x</div></p>").is_err());
    assert!(well_formed("<div><br></div>").is_ok());
    assert!(well_formed("<div>").is_err());
}

/// A recording given as its JSON fields, as the `ingest:runs` item bytes.
fn item_bytes(rec: &serde_json::Value) -> Vec<u8> {
    let rec: groove::recording::Recording = serde_json::from_value(rec.clone()).unwrap();
    groove::recording::item::encode(&rec)
}

#[test]
fn fitted_trajectories_carry_their_residuals_below_on_the_same_time_axis() {
    let (figs, _, _) = render(&fixture(true, true), None);
    for name in ["fig_4_2b.svg", "fig_4_3c.svg"] {
        let svg = &figs[name];
        assert!(
            texts_of(svg).iter().any(|t| t == "data − model (µm)"),
            "{name} has no residual strip"
        );
        let height = attr_of(&svg[..svg.find('>').unwrap()], "height").unwrap();
        // small dots in the strip, below the chart's standard 500 px
        let below = svg
            .split("<circle ")
            .skip(1)
            .filter(|c| {
                attr_of(&format!(" {c}"), "cy").is_some_and(|y| y > 500.0 && y < height)
                    && attr_of(&format!(" {c}"), "r") == Some(2.0)
            })
            .count();
        assert!(below >= 5, "{name}: {below} residual points");
        // each of them titled (run and values), and in the strip's own CSV
        let titled = svg
            .split("<circle class=\"pt\"")
            .skip(1)
            .filter(|c| {
                attr_of(&format!(" {c}"), "cy").is_some_and(|y| y > 500.0)
                    && c.contains("data − model (µm) = ")
            })
            .count();
        assert_eq!(titled, below, "{name}: titled residual points");
        let strip = &figs[&name.replace(".svg", "_residuals.csv")];
        assert_eq!(strip.lines().count() - 1, below, "{name}: {strip}");
        assert!(
            layout_faults(name, svg).is_empty(),
            "{:?}",
            layout_faults(name, svg)
        );
    }
}

/// The attribute `name` of a tag as text.
fn attr_text<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    tag[i..].split('"').next()
}

/// A marker's look: element, size or shape, fill and stroke; and where it sits.
fn marker_of(tag: &str) -> Option<(String, (f64, f64))> {
    let paint = format!(
        "fill={:?} stroke={:?} width={:?}",
        attr_text(tag, "fill"),
        attr_text(tag, "stroke"),
        attr_text(tag, "stroke-width")
    );
    if tag.starts_with("circle ") && !tag.contains("class=\"pt\"") {
        let at = (attr_of(tag, "cx")?, attr_of(tag, "cy")?);
        return Some((format!("circle r={:?} {paint}", attr_of(tag, "r")), at));
    }
    // a rectangle by its paint alone: a bar chart's legend shows a swatch of its bars' colour
    if tag.starts_with("rect ") {
        let at = (attr_of(tag, "x")?, attr_of(tag, "y")?);
        return Some((format!("rect {paint}"), at));
    }
    if tag.starts_with("polygon ") {
        let pts: Vec<(f64, f64)> = attr_text(tag, "points")?
            .split_whitespace()
            .filter_map(|p| {
                let (x, y) = p.split_once(',')?;
                Some((x.parse().ok()?, y.parse().ok()?))
            })
            .collect();
        let first = *pts.first()?;
        let shape: Vec<(f64, f64)> = pts.iter().map(|p| (p.0 - first.0, p.1 - first.1)).collect();
        return Some((format!("polygon {shape:?} {paint}"), first));
    }
    None
}

/// Legend boxes: the half-opaque white rectangles the legend is drawn on (x, y, width, height).
fn legend_boxes(tags: &[&str]) -> Vec<[f64; 4]> {
    tags.iter()
        .filter(|t| t.starts_with("rect ") && t.contains("opacity=\"0.85\" fill=\"#FFFFFF\""))
        .filter_map(|t| {
            Some([
                attr_of(t, "x")?,
                attr_of(t, "y")?,
                attr_of(t, "width")?,
                attr_of(t, "height")?,
            ])
        })
        .collect()
}

/// Legend samples with no plotted marker of the same look.
fn legend_marker_faults(name: &str, svg: &str) -> Vec<String> {
    let tags: Vec<&str> = svg.split('<').skip(1).collect();
    let boxes = legend_boxes(&tags);
    let inside = |p: (f64, f64)| {
        boxes
            .iter()
            .any(|b| p.0 > b[0] && p.0 < b[0] + b[2] && p.1 > b[1] && p.1 < b[1] + b[3])
    };
    let (mut samples, mut plotted) = (Vec::new(), Vec::new());
    for t in &tags {
        if let Some((look, at)) = marker_of(t) {
            if inside(at) {
                samples.push(look);
            } else {
                plotted.push(look);
            }
        }
    }
    samples
        .into_iter()
        .filter(|s| !plotted.contains(s))
        .map(|s| format!("{name}: the legend shows {s}, which no plotted marker is"))
        .collect()
}

#[test]
fn legend_markers_are_the_plotted_markers_and_points_name_their_run() {
    let mut figs: BTreeMap<String, String> = BTreeMap::new();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("reports/figures");
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "svg") {
            let name = format!("shipped {}", path.file_name().unwrap().to_string_lossy());
            figs.insert(name, std::fs::read_to_string(&path).unwrap());
        }
    }
    let (fixture_figs, _, _) = render(&fixture(true, true), None);
    for (k, v) in fixture_figs.iter().filter(|(k, _)| k.ends_with(".svg")) {
        figs.insert(format!("fixture {k}"), v.clone());
    }
    let faults: Vec<String> = figs
        .iter()
        .flat_map(|(k, v)| legend_marker_faults(k, v))
        .collect();
    assert!(faults.is_empty(), "{}", faults.join("\n"));
    // the check sees a filled legend sample beside open plotted circles
    let bad = r##"<svg><rect x="0" y="0" width="50" height="20" opacity="0.85" fill="#FFFFFF" stroke="none"/>
<circle cx="10" cy="10" r="5" opacity="1" fill="#FF0000" stroke="none"/>
<circle cx="80" cy="80" r="5" opacity="1" fill="none" stroke="#FF0000" stroke-width="2"/></svg>"##;
    assert_eq!(legend_marker_faults("t", bad).len(), 1);
    // every point of a figure of runs names its run in its title
    for name in [
        "fig_4_2b",
        "fig_4_3c",
        "fig_4_3d",
        "fig_4_4a",
        "fig_4_4b",
        "fig_4_4c",
        "fig_discovery_drift",
    ] {
        let csv = std::fs::read_to_string(dir.join(format!("{name}.csv"))).unwrap();
        // a residual strip's points are rows of their own CSV
        let strip =
            std::fs::read_to_string(dir.join(format!("{name}_residuals.csv"))).unwrap_or_default();
        let rows: Vec<&str> = csv.lines().skip(1).chain(strip.lines().skip(1)).collect();
        assert!(!rows.is_empty(), "{name}");
        let svg = &figs[&format!("shipped {name}.svg")];
        let titles = svg.matches("<title>run ").count();
        assert_eq!(
            titles,
            rows.len(),
            "{name}: {titles} of {} points name their run",
            rows.len()
        );
    }
}

/// The fixture with discovery accepting a saturating drag, run s316_a (Fig. 4.2b's) recorded
/// under it (μ 0.337, T0 54 ms, T' 2.66 s/(m/s)) while its baseline fit keeps a linear drag, and
/// the refit's `under_accepted` giving the material's μ and drag line.
fn fixture_with_accepted_drag() -> Fixture {
    use groove::physics::{simulate, Friction, Model, State, Term};
    let mut f = fixture(true, true);
    let (mu, t0_s, tp) = (0.337, 0.054, 2.66);
    let model = Model {
        groove: Groove::CHAPTER,
        friction: Friction::Constant { mu },
        variation: Default::default(),
        terms: vec![Term::SaturatingDrag {
            t0_s,
            tp_s_per_mps: tp,
        }],
    };
    let (z0, t_kick, v0) = (1.0e-3, 4.0e-5, 0.025);
    let t: Vec<f64> = (0..400).map(|i| i as f64 * 1e-4).collect();
    let tt: Vec<f64> = t.iter().map(|x| x + t_kick).collect();
    let init = State {
        z_m: z0,
        v_mps: v0,
        va_mps: 0.0,
    };
    let z: Vec<f64> = simulate(&model, init, &tt)
        .z_m
        .iter()
        .zip(&t)
        .map(|(z, ti)| z + 2e-7 * (ti * 7919.0).sin())
        .collect();
    let (rec, mut fit, _) = single("s316_a", "316", v0, mu, 0.0795);
    let mut rec = rec;
    rec["tracks"][0]["z_m"] = json!(z);
    // the baseline's own fit of this run: a linear drag at the T its speed gives
    fit["t_drag_s"] = json!(t0_s + tp * v0);
    f.runs.insert("s316_a.json".into(), item_bytes(&rec));
    f.fits
        .insert("s316_a.json".into(), serde_json::to_vec(&fit).unwrap());
    let mut diag: Value = serde_json::from_slice(&f.files["diagnosis"]).unwrap();
    let e = |v: f64, se: f64| json!({"value": v, "stderr": se});
    diag["findings"][0]["form"] = json!("saturating: a = -v/(T0 + T'|v|)");
    diag["findings"][0]["parameters"] =
        json!({"t0_s_316": e(t0_s, 1e-4), "t0_s_440c": e(0.05, 1e-4), "tp_s_per_mps": e(tp, 0.01)});
    diag["model_parameters"] = json!({"mu_316": e(mu, 4e-4), "mu_440c": e(0.293, 3e-4),
        "t0_s_316": e(t0_s, 1e-4), "t0_s_440c": e(0.05, 1e-4), "tp_s_per_mps": e(tp, 0.01)});
    f.files
        .insert("diagnosis", serde_json::to_vec(&diag).unwrap());
    let est = |v: f64, se: f64| json!({"value": v, "se": se});
    let line = |t0: f64| json!({"intercept_s": est(t0, 1e-4), "slope_s_per_mps": est(tp, 0.01)});
    let under = json!({"accepted": true,
        "terms": [{"effect": "velocity_dependent_drag", "form": "saturating: a = -v/(T0 + T'|v|)",
                   "parameters": {"t0_s_316": t0_s, "t0_s_440c": 0.05, "tp_s_per_mps": tp}}],
        "single": {"source": "discovery's joint fit", "materials": {
            "316": {"mu": est(mu, 4e-4), "t_line": line(t0_s)},
            "440c": {"mu": est(0.293, 3e-4), "t_line": line(0.05)}}},
        "collisions": null, "notes": []});
    f.files
        .insert("under_accepted", serde_json::to_vec(&under).unwrap());
    f
}

/// The (t, value) rows of a figure's CSV for one series.
fn csv_rows(csv: &str, series: &str) -> Vec<(f64, f64)> {
    csv.lines()
        .skip(1)
        .filter(|l| l.starts_with(&format!("{series},")))
        .filter_map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            Some((c[2].parse().ok()?, c[3].parse().ok()?))
        })
        .collect()
}

#[test]
fn under_accepted_physics_the_trajectory_is_fitted_again_and_its_strip_shows_that_fit() {
    let f = fixture_with_accepted_drag();
    let (figs, html, md) = render(&f, None);
    let svg = &figs["fig_4_2b.svg"];
    let texts = texts_of(svg);
    assert!(
        texts
            .iter()
            .any(|t| t == "fitted under the accepted physics")
            && texts.iter().any(|t| t == "fitted baseline"),
        "{texts:?}"
    );
    assert!(
        layout_faults("fig_4_2b", svg).is_empty(),
        "{:?}",
        layout_faults("fig_4_2b", svg)
    );
    // the strip's points: titled, in their own CSV, and the accepted model's residuals (the data
    // were recorded under it: 0.2 µm of ripple), while the baseline misses the run by far more
    assert!(
        svg.contains("<title>run s316_a, sliding: time t (ms) = "),
        "no titled strip point"
    );
    let strip = &figs["fig_4_2b_residuals.csv"];
    assert!(
        strip.starts_with("series,run,time t (ms),data − model (µm)\n"),
        "{strip}"
    );
    let resid: Vec<f64> = ["sliding", "rolling"]
        .iter()
        .flat_map(|s| csv_rows(strip, s))
        .map(|p| p.1)
        .collect();
    assert!(resid.len() >= 100, "{} residual rows", resid.len());
    let worst = resid.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    assert!(worst < 0.5, "the strip's worst residual is {worst} µm");
    let rec: Value = {
        let r = groove::recording::item::decode(&f.runs["s316_a.json"]).unwrap();
        serde_json::to_value(r).unwrap()
    };
    let fit: Value = serde_json::from_slice(&f.fits["s316_a.json"]).unwrap();
    let b = Baseline {
        mu: fit["mu"].as_f64().unwrap(),
        t_drag_s: fit["t_drag_s"].as_f64().unwrap(),
        groove: Groove::CHAPTER,
    };
    let baseline_worst = rec["tracks"][0]["t_s"]
        .as_array()
        .unwrap()
        .iter()
        .zip(rec["tracks"][0]["z_m"].as_array().unwrap())
        .map(|(t, z)| {
            let (t, z) = (t.as_f64().unwrap(), z.as_f64().unwrap());
            (z - 1.0e-3 - b.state(0.025, t + 4.0e-5).0).abs() * 1e6
        })
        .fold(0.0f64, f64::max);
    assert!(
        baseline_worst > 10.0 * worst,
        "baseline {baseline_worst} µm, accepted {worst} µm"
    );
    // the section's opening says how closely each model follows the run
    let lead = between(&md, "### 3.1 ", "### 3.2 ");
    assert!(
        lead.contains("Fitted again under the physics discovery accepted")
            && lead.contains("against ")
            && lead.contains("the residuals below are this fit's"),
        "{lead}"
    );
    // both pages say which curve is which and link the strip's data
    for page in [&html, &md] {
        assert!(page.contains("the run fitted under the physics discovery accepted"));
        assert!(page.contains("figures/fig_4_2b_residuals.csv"));
    }
    // without the refit, the figure is the baseline's alone, as before
    let mut plain = fixture(true, true);
    plain.files.remove("under_accepted");
    let (figs, _, _) = render(&plain, None);
    assert!(!texts_of(&figs["fig_4_2b.svg"])
        .iter()
        .any(|t| t == "fitted under the accepted physics"));
}

/// The part of a page from `from` up to `to` (or its end).
fn between<'a>(page: &'a str, from: &str, to: &str) -> &'a str {
    let start = page.find(from).unwrap_or_else(|| panic!("no {from:?}"));
    let end = page[start..].find(to).map_or(page.len(), |e| start + e);
    &page[start..end]
}

#[test]
fn discovery_forms_are_formulas_in_the_summary_and_the_discovery_section() {
    let (_, html, md) = render(&fixture_with_accepted_drag(), None);
    let text = text_outside_svg_and_style(&html);
    // the drag law as diagnosis.json writes it is shown as MathML: T with subscript 0, |v|
    let t0 = "<msub><mi>T</mi><mn>0</mn></msub>";
    for (from, to) in [
        ("<section id=\"summary\">", "<section id=\"data\">"),
        ("<section id=\"discovery\">", "<section id=\"audit\">"),
        (
            "<section id=\"under-accepted\">",
            "<section id=\"discovery\">",
        ),
    ] {
        let part = between(&text, from, to);
        assert!(
            part.contains(t0) && part.contains("<mo lspace=\"0\" rspace=\"0\">|</mo><mi>v</mi><mo lspace=\"0\" rspace=\"0\">|</mo>"),
            "{from}: no MathML drag law"
        );
        for ascii in ["T0 + T'|v|", "a = -v/(", "T(|v|)"] {
            assert!(!part.contains(ascii), "{from}: {ascii:?} in plain text");
        }
    }
    // figure and table captions with a formula
    let fig_4_2c = between(
        &text,
        "<section id=\"fig-4-2c\">",
        "<section id=\"fig-4-2d\">",
    );
    assert!(
        fig_4_2c.contains("<caption>Fig. 4.2c: the <math>"),
        "4.2c table caption"
    );
    let fig_4_4 = between(
        &text,
        "<section id=\"fig-4-4bc\">",
        "<section id=\"secondary\">",
    );
    assert!(
        fig_4_4.contains("<figcaption>Fig. 4.4b: <math>"),
        "4.4b caption"
    );
    // the Markdown keeps the formulas between dollar signs, no pipe inside to break a table
    let summary = summary_of(&md);
    assert!(
        summary.contains(r"(saturating: $a = -v/(T_0 + T'\lvert v\rvert)$)"),
        "{summary}"
    );
    assert!(md.contains(r"| drag $T(\lvert v\rvert) = T_0 + T'\lvert v\rvert$ of 316: $T_0$ (s) |"));
}
