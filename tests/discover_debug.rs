//! temporary debugging of the joint fit (to delete)
use groove::discover::candidate::{Extra, Spec};
use groove::discover::data::prepare_runs;
use groove::discover::forward::Model;
use groove::discover::perrun::measure_noise;
use std::time::Instant;
#[path = "discover_data/mod.rs"]
mod discover_data;
use discover_data::{synthesize, Truth, S, SMALL};

#[test]
fn debug_roll() {
    let truth = Truth { roll_c: 0.004, ..Truth::baseline() };
    let recs = synthesize(&truth, &SMALL, 1);
    let t = Instant::now();
    let (mut runs, materials) = prepare_runs(&recs, 20);
    let spec = Spec { n_materials: materials.len(), s: S, k: 2.5, extras: vec![] };
    let params = spec.global_params(&materials);
    let per_run = measure_noise(&mut runs, &spec, &params);
    eprintln!("perrun {:.2}s", t.elapsed().as_secs_f64());
    for (r, f) in runs.iter().zip(&per_run).take(6) {
        eprintln!("{} mu {:.4} T {:.4} v0 {:.5} t0 {:.2e} sigma {:.2e} rms {:.2e} conv {}", r.run, f.mu, f.t_s, f.local[2], f.local[1], r.sigma_m, f.rms_m, f.converged);
    }
    let t = Instant::now();
    let g = vec![0.32, 0.3, 0.07, 0.07];
    let l: Vec<_> = per_run.iter().map(|f| f.local).collect();
    let base = Model::fit(spec.clone(), &materials, &runs, &g, &l, 80);
    eprintln!("base {:.2}s it {} chi2 {:.1} g {:?}", t.elapsed().as_secs_f64(), base.fit.iterations, base.fit.chi2, base.fit.global);
    for it in [10, 40, 100] {
        let t = Instant::now();
        let m = base.extend(&Extra::RollingResistance, &materials, &runs, it);
        eprintln!("roll[{it}] {:.2}s it {} conv {} chi2 {:.1} g {:?}", t.elapsed().as_secs_f64(), m.fit.iterations, m.fit.converged, m.fit.chi2, m.fit.global);
    }
    // truth start
    let mut g = vec![0.337, 0.293, 0.06, 0.06, 0.004];
    let m = Model::fit(spec.with(Extra::RollingResistance), &materials, &runs, &g, &base.fit.local, 100);
    eprintln!("roll from truth: it {} chi2 {:.1} g {:?}", m.fit.iterations, m.fit.chi2, m.fit.global);
    g.truncate(4);
}
