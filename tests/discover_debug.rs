//! temporary debugging of the joint fit (to delete)
use groove::discover::{discover, Options};
use std::time::Instant;
#[path = "discover_data/mod.rs"]
mod discover_data;
use discover_data::{synthesize, Truth, SMALL};

#[test]
fn debug_quad() {
    let truth = Truth { quad_c_per_m: 20.0, ..Truth::baseline() };
    let recs = synthesize(&truth, &SMALL, 3);
    let t = Instant::now();
    let opts = Options { bootstrap: 12, bootstrap_iterations: 3, folds: 4, position_harmonics: vec![1, 2], max_terms: 2, seed: 3, ..Options::default() };
    let d = discover(&recs, &opts);
    eprintln!("{:.1}s", t.elapsed().as_secs_f64());
    eprintln!("base {:?}", d.baseline_model);
    for r in &d.candidates {
        eprintln!("r{} {:<28} lr {:9.1} null {:6.2} p {:.2e} ph {:.2e} cvt {:?} cv {:?} {} {:?}", r.round, r.effect, r.evidence.lr, r.evidence.null_mean_lr, r.evidence.p_value, r.evidence.p_holm, r.evidence.cv_paired_t, r.evidence.cv_rms_m, r.evidence.decision, r.parameters.iter().next());
    }
}
