//! Proposals: from the residuals of the current model, where the named forms that need a
//! starting point should start (periodogram peaks in z and t, a matched-filter scan for a
//! localized bump, the force maps for the spline); the ranges those forms may take are in
//! `ranges.rs`.
//!
//! The same function runs on the data and on every bootstrap replicate, so a candidate started
//! from the best of many trial wavelengths is judged against a null searched the same way.

use super::candidate::{prepare, Extra, ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::forcemap::{force_map, phase_map};
use super::ranges::{bump_column, bump_trials, Proposals, Ranges, Wanted};
use super::response::{dot, Prepared};
use super::spectral::{f_grid, k_grid, t_spectrum, z_spectrum};
use super::time_scan::resolvable;
use crate::physics::Variable;
use rayon::prelude::*;

/// Knot intervals of a force map and of the spline fallback.
pub const MAP_SEGMENTS: usize = 16;

/// Matched-filter scan for a Gaussian bump: widths doubling from the smallest, centres every
/// half width; the two best separated (centre, width) with their least-squares amplitude.
fn bump_scan(prep: &[Prepared], rg: &Ranges) -> Vec<[f64; 3]> {
    let trials = bump_trials(rg, rg.w_lo(), f64::INFINITY);
    let stats: Vec<(f64, f64)> = trials
        .par_iter()
        .map(|&(c, w)| {
            let (mut a, mut b) = (0.0, 0.0);
            for p in prep {
                let Some(x) = bump_column(p, c, w) else {
                    continue;
                };
                a += dot(&x, &x);
                b += dot(&x, &p.y);
            }
            if a > 0.0 {
                (b * b / a, b / a)
            } else {
                (0.0, 0.0)
            }
        })
        .collect();
    let mut order: Vec<usize> = (0..trials.len()).collect();
    order.sort_by(|i, j| stats[*j].0.total_cmp(&stats[*i].0).then(i.cmp(j)));
    let mut out: Vec<[f64; 3]> = Vec::new();
    for i in order {
        let (c, w) = trials[i];
        if out.iter().any(|o| (o[1] - c).abs() < 2.0 * o[2].max(w)) {
            continue;
        }
        out.push([stats[i].1, c, w]);
        if out.len() >= 2 {
            break;
        }
    }
    out
}

/// Proposals from the residuals of (spec, global, local) on `runs`.
#[allow(clippy::too_many_arguments)]
pub fn propose(
    spec: &Spec,
    params: &[ParamInfo],
    global: &[f64],
    local: &[[f64; N_LOCAL]],
    runs: &[RunData],
    rg: &Ranges,
    wanted: Wanted,
    folds: Option<(&[usize], usize)>,
) -> Proposals {
    if !(wanted.z || wanted.t || wanted.bump || wanted.maps) {
        return Proposals::default();
    }
    let no_glob: Vec<ParamInfo> = params
        .iter()
        .map(|p| ParamInfo {
            hi: p.lo,
            ..p.clone()
        })
        .collect();
    let prep = prepare(
        spec,
        if wanted.maps { params } else { &no_glob },
        global,
        local,
        runs,
    );
    let z = wanted
        .z
        .then(|| z_spectrum(&prep, rg.z_ref(), &k_grid(rg.span(), rg.lambda_min_m)));
    let t = wanted.t.then(|| {
        let fs = f_grid(rg.duration_s, rg.f_max_hz);
        t_spectrum(&prep, &fs[..resolvable(&prep, &fs)])
    });
    let bumps = if wanted.bump {
        bump_scan(&prep, rg)
    } else {
        vec![]
    };
    let mut maps = Vec::new();
    if wanted.maps {
        if let Some((fold, k)) = folds {
            let n_obs: usize = runs.iter().map(|r| r.n_used()).sum();
            for var in [Variable::Z, Variable::V, Variable::T] {
                if let Some(m) = force_map(&prep, var, MAP_SEGMENTS, fold, k, n_obs) {
                    maps.push(m);
                }
            }
            if let Some(m) = phase_map(&prep, fold, k, n_obs) {
                maps.push(m);
            }
        }
    }
    Proposals { z, t, bumps, maps }
}

/// The proposals the terms need.
pub fn wanted_for(extras: &[&Extra]) -> Wanted {
    extras
        .iter()
        .fold(Wanted::default(), |w, e| w.or(e.wanted()))
}

/// True when the term's starting values come from the residuals.
pub fn needs_proposal(e: &Extra) -> bool {
    e.wanted().any()
}

/// Starting values of a proposed term's parameters (several: the best peaks), held inside its
/// bounds; where it vanishes when nothing is proposed. A peak that puts a parameter beyond its
/// interval by more than the interval's width is no start: it is something the form cannot be
/// (a residual peak at kHz whose acceleration is hundreds of m/s², from a micrometre of
/// tracker noise), and from its bound the fit of a vibration crawled through a fast force
/// (14 s of a 35 s stage on the bench) to a worse χ² than the screen's start.
pub fn starts(e: &Extra, p: &Proposals) -> Vec<Vec<f64>> {
    let params = e.params();
    let possible = |v: &Vec<f64>| {
        v.iter().zip(&params).all(|(x, q)| {
            let w = q.hi - q.lo;
            *x >= q.lo - w && *x <= q.hi + w
        })
    };
    let clamp = |v: Vec<f64>| -> Vec<f64> {
        v.iter()
            .zip(&params)
            .map(|(x, q)| x.clamp(q.lo, q.hi))
            .collect()
    };
    let out: Vec<Vec<f64>> = e
        .proposed(p)
        .into_iter()
        .filter(possible)
        .map(clamp)
        .collect();
    if out.is_empty() {
        vec![e.params().iter().map(|q| q.start).collect()]
    } else {
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discover::forms::TimePeriodic;
    use crate::discover::spectral::{Peak, Spectrum};
    use std::f64::consts::TAU;

    fn peak(f_hz: f64, amp: f64) -> Peak {
        Peak {
            omega: TAU * f_hz,
            power: 100.0,
            coef: [amp, 0.0],
        }
    }

    /// A vibration proposed within its amplitude's interval, or beyond it by less than the
    /// interval's width, starts clamped inside it; one beyond by more (a kHz peak of tracker
    /// noise read as hundreds of m/s²) is no start, and with nothing else proposed the form
    /// starts where it vanishes.
    #[test]
    fn a_proposal_the_form_cannot_be_is_no_start() {
        let e: Extra = TimePeriodic {
            f_lo: 10.0,
            f_hi: 5000.0,
        }
        .into();
        let spectrum = |peaks: Vec<Peak>| Proposals {
            t: Some(Spectrum {
                variable: "t".into(),
                x: vec![],
                power: vec![],
                noise_power: 2.0,
                peaks,
            }),
            ..Proposals::default()
        };
        let p = spectrum(vec![
            peak(40.0, 0.03),
            peak(3500.0, 8.0),
            peak(3514.0, 490.0),
        ]);
        assert_eq!(starts(&e, &p), vec![vec![40.0, 0.03], vec![3500.0, 5.0]]);
        let default: Vec<f64> = e.params().iter().map(|q| q.start).collect();
        assert_eq!(default[1], 0.0);
        assert_eq!(
            starts(&e, &spectrum(vec![peak(3514.0, 490.0)])),
            vec![default]
        );
    }
}
