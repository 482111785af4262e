//! A fitted term's parameters as reported: physical names and SI units (each form says its own),
//! a value that ended at a bound of its search said in words, a force in time's amplitude with
//! each run's phase integrated out.

use super::candidate::{ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::forms::Fitted;
use super::model::Model;
use super::timeforce;
use crate::artifacts::diagnosis::Estimate;
use rayon::prelude::*;
use std::collections::BTreeMap;

/// The parameters of extra term `i` of `m`, in SI units with physical names.
pub fn term_parameters(m: &Model, i: usize, materials: &[String]) -> BTreeMap<String, Estimate> {
    let off = m.spec.extra_offset(i);
    let e = &m.spec.extras[i];
    let n = e.params().len();
    e.parameters(&Fitted {
        x: &m.fit.global[off..],
        se: &m.fit.global_se[off..],
        global: &m.fit.global,
        global_se: &m.fit.global_se,
        n_materials: m.spec.n_materials,
        materials,
        params: &m.params[off..off + n],
    })
}

/// The parameters of extra term `i` of `m` that ended at a bound of their search, in words: such a
/// value is a limit the data pushed against, not an estimate (a velocity-dependent friction
/// fitted to two materials of which one has none ends with that material's v_c at its floor).
pub fn bound_notes(m: &Model, i: usize, materials: &[String]) -> Vec<String> {
    let off = m.spec.extra_offset(i);
    let n = m.spec.extras[i].params().len();
    let mut notes = Vec::new();
    for k in 0..n {
        let (x, info) = (m.fit.global[off + k], &m.params[off + k]);
        let Some(lower) = pinned(m, i, k) else {
            continue;
        };
        let e = &m.spec.extras[i];
        notes.push(match e.bound_note(k, x, info, lower, materials) {
            Some(note) => note,
            None => format!(
                "{} = {x:.4e} at its {} bound: a limit the fit pushed against, not an estimate",
                info.name,
                if lower { "lower" } else { "upper" }
            ),
        });
    }
    notes
}

/// Whether extra term `i` of `m` has a parameter other than its scale at a bound of its search
/// (as `bound_notes` says it): a centre or a place the data pushed to the end of the groove is a
/// feature they do not place (a bump centred at the end of the observed stretch is a step seen
/// from one side). Its scale is not counted at either end: a step sharper than the search
/// resolves is still a step there, and a scale at an end is judged by `scale_at_bound`.
pub fn placed_at_bound(m: &Model, i: usize) -> bool {
    let e = &m.spec.extras[i];
    let scale = e.scale().map(|(k, _)| k);
    (0..e.params().len())
        .filter(|&k| Some(k) != scale)
        .any(|k| pinned(m, i, k).is_some())
}

/// Whether extra term `i` of `m` is held back in a tie: a parameter other than its scale at a
/// bound of its search (`placed_at_bound`), or a term physical only over the data's speeds
/// (`Form::physical_only_within_data`).
pub fn held_back(m: &Model, i: usize) -> bool {
    let off = m.spec.extra_offset(i);
    let e = &m.spec.extras[i];
    placed_at_bound(m, i) || e.physical_only_within_data(&m.fit.global[off..off + e.params().len()])
}

/// The bound (`Some(true)` the lower) parameter `k` of extra term `i` of `m` is pinned at; a
/// term that starts where it vanishes, at its bound, is not pinned there (unless the form says
/// so: `notes_start_bound`).
fn pinned(m: &Model, i: usize, k: usize) -> Option<bool> {
    let off = m.spec.extra_offset(i);
    let (x, info) = (m.fit.global[off + k], &m.params[off + k]);
    let lower = side_of_bound(x, info, 1e-6)?;
    let vanishes_there = lower && info.start == info.lo && !m.spec.extras[i].notes_start_bound();
    (!vanishes_there).then_some(lower)
}

/// Which bound `x` sits at (`Some(true)` the lower), within `rel` of the parameter's range.
pub fn side_of_bound(x: f64, info: &ParamInfo, rel: f64) -> Option<bool> {
    let tol = rel * (info.hi - info.lo);
    if x <= info.lo + tol {
        Some(true)
    } else if x >= info.hi - tol {
        Some(false)
    } else {
        None
    }
}

/// Why a searched form's scale (a wavelength, a width, a frequency) fitted in full is not a
/// finding: it ran to the end of its search, so the data hold no such feature inside the range
/// the search can resolve (on two speed effects at once, a wave at the shortest wavelength
/// allowed soaked up what neither effect alone explained). `None` when the scale is inside.
pub fn scale_at_bound(m: &Model) -> Option<String> {
    let i = m.spec.extras.len().checked_sub(1)?;
    let off = m.spec.extra_offset(i);
    let e = &m.spec.extras[i];
    let (idx, what) = e.scale()?;
    let x = m.fit.global[off + idx];
    let lower = side_of_bound(x, &m.params[off + idx], 1e-2)?;
    // the fine end, and the coarse end only where a form says so: a wave longer, a bump wider
    // or a common vibration slower than the search reaches is still a slow variation the data
    // show (bound_notes says so in words); a vibration with its own phase in each run is not
    let text = e.scale_at_end(x, lower)?;
    Some(format!(
        "rejected: {text}; a {what} at the end of the search is no feature the data resolve"
    ))
}

/// The parameters of extra term `i` of `m` as reported: `term_parameters`, with a force in
/// time's amplitude taken with each run's phase integrated out, not fitted (the fitted phases
/// also fit the noise and make it read high; timeforce.rs).
pub fn reported_parameters(
    m: &Model,
    i: usize,
    materials: &[String],
    runs: &[RunData],
) -> BTreeMap<String, Estimate> {
    let mut parameters = term_parameters(m, i, materials);
    let off = m.spec.extra_offset(i);
    let e = &m.spec.extras[i];
    let n = e.params().len();
    let cov: Vec<Vec<f64>> = m
        .fit
        .global_cov
        .get(off..off + n)
        .map(|rows| rows.iter().map(|r| r[off..off + n].to_vec()).collect())
        .unwrap_or_default();
    e.report_over_runs(&m.fit.global[off..], &cov, runs, &mut parameters);
    if e.run_phase() {
        if let Some(a) = amplitude_over_phases(&m.spec, &m.fit.global, &m.fit.local, runs) {
            for name in ["amplitude_mps2", "peak_accel_mps2"] {
                if let Some(p) = parameters.get_mut(name) {
                    p.value = a;
                }
            }
        }
    }
    parameters
}
/// The amplitude of a force periodic in time with each run's phase integrated out (uniform over
/// the circle) instead of fitted: the maximum of the marginal likelihood, at the joint fit's
/// frequency and locals. `None` without such a term.
///
/// The joint fit profiles a phase per run, and a phase chosen per run also fits that run's noise:
/// with n runs and the effect's total χ² X, the profiled amplitude comes out high by about
/// n/(2X) (the Rice bias: E|y| = √(A² + 2σ²) for a two-component projection; 6.5 % for 60 runs
/// at X = 460), and the excess does not fall with more runs, since every run brings its own
/// phase (Neyman and Scott's incidental parameters). Integrating the phases out leaves one
/// parameter for all runs, and its maximum-likelihood estimate is consistent.
fn amplitude_over_phases(
    spec: &Spec,
    global: &[f64],
    local: &[[f64; N_LOCAL]],
    runs: &[RunData],
) -> Option<f64> {
    let sums: Vec<([f64; 5], f64)> = runs
        .par_iter()
        .zip(local)
        .filter_map(|(run, l)| {
            let m = spec.sim_model(global, run.material, l[2]);
            let (idx, amp, _) = timeforce::time_term(&m)?;
            (amp != 0.0).then(|| {
                (
                    timeforce::run_sums(&m, idx, l, run),
                    run.sigma_m * run.sigma_m,
                )
            })
        })
        .collect();
    let amp = {
        let m = spec.sim_model(global, runs.first()?.material, local.first()?[2]);
        timeforce::time_term(&m)?.1
    };
    if sums.is_empty() || amp == 0.0 {
        return None;
    }
    let total = |scale: f64| -> f64 {
        sums.iter()
            .map(|(k, var)| timeforce::log_marginal(k, scale, *var))
            .sum()
    };
    // the scale in [0, 2] that maximises it (the profiled amplitude is scale 1, and above)
    Some(crate::lsq::golden::minimize(|x| -total(x), 0.0, 2.0, 50) * amp)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discover::forms::{Extra, Localized};
    use crate::discover::joint;

    /// A model of one material and a localized force at `x` = (amplitude, centre, width), its
    /// centre searched over 0–10 mm and its width over 0.1–5 mm.
    fn bump_at(x: [f64; 3]) -> Model {
        let spec = Spec {
            n_materials: 1,
            s: 0.5,
            k: 2.5,
            extras: vec![Extra::from(Localized {
                z_lo: 0.0,
                z_hi: 0.01,
                w_lo: 1e-4,
                w_hi: 5e-3,
            })],
        };
        let params = spec.global_params(&["316".to_string()]);
        let mut global = vec![0.3, 0.08];
        global.extend(x);
        let n = global.len();
        Model {
            spec,
            params,
            fit: joint::Fitted {
                global,
                local: vec![],
                chi2: 0.0,
                chi2_run: vec![],
                global_se: vec![0.0; n],
                global_cov: vec![],
                iterations: 1,
                converged: true,
            },
        }
    }

    #[test]
    fn a_term_placed_at_an_end_of_its_search_is_said_to_be_and_its_scale_there_is_not() {
        // inside every range: placed
        assert!(!placed_at_bound(&bump_at([0.1, 4e-3, 1e-3]), 0));
        // its centre at either end of the groove's stretch
        assert!(placed_at_bound(&bump_at([0.1, 0.0, 1e-3]), 0));
        assert!(placed_at_bound(&bump_at([0.1, 0.01, 1e-3]), 0));
        // within 10⁻⁶ of the range counts as at the end; 10⁻³ of it does not
        assert!(placed_at_bound(&bump_at([0.1, 0.01 - 1e-9, 1e-3]), 0));
        assert!(!placed_at_bound(&bump_at([0.1, 0.01 - 1e-5, 1e-3]), 0));
        // the width is the scale: at either end it is judged elsewhere, not here
        assert!(!placed_at_bound(&bump_at([0.1, 4e-3, 1e-4]), 0));
        assert!(!placed_at_bound(&bump_at([0.1, 4e-3, 5e-3]), 0));
        // an amplitude pushed to its limit is a parameter at a bound too
        assert!(placed_at_bound(&bump_at([-5.0, 4e-3, 1e-3]), 0));
        // and a held-back term is one placed at a bound
        assert!(held_back(&bump_at([0.1, 0.0, 1e-3]), 0));
        assert!(!held_back(&bump_at([0.1, 4e-3, 1e-3]), 0));
    }
}
