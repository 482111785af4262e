//! What the two forms periodic in lab z share (a force, `periodic_z`; friction,
//! `friction_periodic`) and the force periodic in time locked to the kick (`time_common`): their
//! coherent (sin, cos) scan, the amplitude and phase of a fitted (sin, cos)
//! pair, and the words for a wavelength at the end of its search.

use super::form::{ParamInfo, Search};
use crate::artifacts::diagnosis::Estimate;
use crate::discover::response::Prepared;
use crate::discover::screen_sums::{best_of, coherent_scan, most_sensitive, Trial, Typical};
use crate::discover::spectral::k_grid;
use std::f64::consts::TAU;

/// The search over the grid's wavenumbers in [k_lo, k_hi]: at each k, the runs' responses to
/// the acceleration `values(p, g, k)` gives at the grid points for g = sin and g = cos (None: the
/// run takes no part), regressed on the prepared runs coherently (one pair shared by every run).
pub fn search<F>(s: &Search, k_lo: f64, k_hi: f64, values: F) -> (Option<Trial>, Option<Typical>)
where
    F: Fn(&Prepared, fn(f64) -> f64, f64) -> Option<Vec<f64>> + Sync,
{
    let ks: Vec<f64> = k_grid(s.rg.span(), s.rg.lambda_min_m)
        .into_iter()
        .filter(|k| *k >= k_lo && *k <= k_hi)
        .collect();
    pair_scan(
        s,
        &ks,
        |p, k| {
            let fs = values(p, f64::sin, k)?;
            let fc = values(p, f64::cos, k)?;
            let (rs, rc) = p.track.respond_values_pair(&fs, &fc);
            Some(vec![p.column(rs), p.column(rc)])
        },
        |k| format!("at a wavelength of {:.3} mm", 1e3 * TAU / k),
    )
}

/// A coherent scan of a (sin, cos) pair over `grid` (wavenumbers, frequencies): at each value
/// x, a run's two response columns `columns(p, x)` (None: the run takes no part), regressed on
/// the prepared runs with one pair shared by every run; each trial's estimate is (x, sin, cos),
/// and the most sensitive trial is said by `at(x)`.
pub fn pair_scan<C, A>(
    s: &Search,
    grid: &[f64],
    columns: C,
    at: A,
) -> (Option<Trial>, Option<Typical>)
where
    C: Fn(&Prepared, f64) -> Option<Vec<Vec<f64>>> + Sync,
    A: Fn(f64) -> String,
{
    let (prep, v, reps) = (s.prep, s.v, s.reps.clone());
    let solved = coherent_scan(prep, v, 2, reps.clone(), grid, |p, &x| columns(p, x));
    pair_trials(solved, grid, reps.len(), at)
}

/// The trials of a coherent (sin, cos) scan solved at each value of `grid` (`Sums::solve`'s
/// statistic per replicate, coefficients and variances; None: no trial there), each estimate
/// (x, sin, cos), over `n_rep` replicates; the most sensitive trial is said by `at(x)`.
pub fn pair_trials<A>(
    solved: Vec<Option<(Vec<f64>, Vec<f64>, Vec<f64>)>>,
    grid: &[f64],
    n_rep: usize,
    at: A,
) -> (Option<Trial>, Option<Typical>)
where
    A: Fn(f64) -> String,
{
    let trials: Vec<Option<Trial>> = solved
        .into_iter()
        .zip(grid)
        .map(|(t, &x)| {
            let (lr, b, var) = t?;
            Some((
                lr,
                vec![x, b[0], b[1]],
                vec![f64::NAN, var[0].sqrt(), var[1].sqrt()],
            ))
        })
        .collect();
    let typical = most_sensitive(&trials, |se| se[1].hypot(se[2]) / 2f64.sqrt())
        .map(|(se, t)| Typical::Se { se, at: at(t.1[0]) });
    (best_of(trials, n_rep), typical)
}

/// The amplitude, wavelength and phase (about z = 0) of a sin(k(z − z_ref)) + b cos(k(z − z_ref))
/// fitted at `x` = (k, a, b) with standard errors `se`.
pub fn amplitude_wavelength_phase(x: &[f64], se: &[f64], z_ref: f64) -> [Estimate; 3] {
    let (k, a, b) = (x[0], x[1], x[2]);
    let (sk, sa, sb) = (se[0], se[1], se[2]);
    let amp = a.hypot(b).max(1e-300);
    let amp_se = ((a * sa).powi(2) + (b * sb).powi(2)).sqrt() / amp;
    let phase = (b.atan2(a) - k * z_ref).rem_euclid(TAU);
    let phase_se = (((b * sa).powi(2) + (a * sb).powi(2)).sqrt() / (amp * amp)).hypot(z_ref * sk);
    [
        Estimate::new(amp, amp_se),
        Estimate::new(TAU / k, TAU * sk / (k * k)),
        Estimate::new(phase, phase_se),
    ]
}

/// The words for a wavenumber parameter at the `lower` (longest wavelength) or upper end of its
/// search; None for another parameter.
pub fn bound_note(x: f64, info: &ParamInfo, lower: bool) -> Option<String> {
    (info.name == "k_per_m").then(|| format!(
        "the wavelength ({:.3} mm) is the {} the search allows: the data resolve no {} period, so wavelength and amplitude describe the observed stretch rather than a period",
        1e3 * TAU / x,
        if lower { "longest" } else { "shortest" },
        if lower { "longer" } else { "shorter" }
    ))
}

/// The words for a wavelength that ran to the shortest the search allows (the fine end).
pub fn at_fine_end(x: f64, lower: bool) -> Option<String> {
    (!lower).then(|| {
        format!(
            "its wavelength ran to the shortest the search allows ({:.3} mm)",
            1e3 * TAU / x
        )
    })
}
