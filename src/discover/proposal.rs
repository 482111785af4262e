//! Proposals: from the residuals of the current model, where the named forms that need a
//! starting point should start (periodogram peaks in z and t, a matched-filter scan for a
//! localized bump, the force maps for the spline), and the ranges those forms may take.
//!
//! The same function runs on the data and on every bootstrap replicate, so a candidate started
//! from the best of many trial wavelengths is judged against a null searched the same way.

use super::candidate::{Extra, ParamInfo, Spec, N_LOCAL};
use super::data::RunData;
use super::forcemap::{force_map, phase_map, ForceMap};
use super::response::{dot, prepare, Prepared};
use super::spectral::{f_grid, k_grid, t_spectrum, z_spectrum, Spectrum};
use crate::physics::Variable;
use rayon::prelude::*;
use std::f64::consts::TAU;

/// Knot intervals of a force map and of the spline fallback.
pub const MAP_SEGMENTS: usize = 16;

/// What the data allow the new forms to take: the observed lab range, wavelengths, frequencies.
#[derive(Clone, Debug)]
pub struct Ranges {
    pub z_lo: f64,
    pub z_hi: f64,
    /// Median distance between consecutive samples (m).
    pub dz_med: f64,
    pub lambda_min_m: f64,
    /// Longest time since the kick (s) and the highest frequency searched (Nyquist, Hz).
    pub duration_s: f64,
    pub f_max_hz: f64,
    /// The runs' median early speed (m/s): the reference of a friction varying with slip speed.
    pub v_ref_mps: f64,
}

impl Ranges {
    pub fn of(runs: &[RunData]) -> Ranges {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut steps = Vec::new();
        let mut duration: f64 = 0.0;
        let mut fps = f64::INFINITY;
        let mut speeds = Vec::new();
        for r in runs {
            let kept: Vec<(f64, f64)> = r
                .t_s
                .iter()
                .zip(&r.z_m)
                .zip(&r.keep)
                .filter(|(_, k)| **k)
                .map(|((t, z), _)| (*t, *z))
                .collect();
            for w in kept.windows(2) {
                steps.push((w[1].1 - w[0].1).abs());
            }
            // the run's early speed: over its first few kept samples
            if let (Some(a), Some(b)) =
                (kept.first(), kept.get(5.min(kept.len().saturating_sub(1))))
            {
                if b.0 > a.0 {
                    speeds.push(((b.1 - a.1) / (b.0 - a.0)).abs());
                }
            }
            for (t, z) in &kept {
                lo = lo.min(*z);
                hi = hi.max(*z);
                duration = duration.max(*t);
            }
            if r.fps > 0.0 {
                fps = fps.min(r.fps);
            }
        }
        steps.sort_by(f64::total_cmp);
        let dz_med = steps.get(steps.len() / 2).copied().unwrap_or(1e-6);
        let span = (hi - lo).max(1e-6);
        speeds.sort_by(f64::total_cmp);
        let v_ref = speeds.get(speeds.len() / 2).copied().unwrap_or(0.0);
        Ranges {
            z_lo: lo,
            z_hi: hi,
            dz_med,
            lambda_min_m: (2.0 * dz_med).max(span / 100.0),
            duration_s: duration.max(1e-3),
            f_max_hz: if fps.is_finite() { 0.5 * fps } else { 5e3 },
            v_ref_mps: if v_ref > 0.0 { v_ref } else { 0.01 },
        }
    }

    pub fn span(&self) -> f64 {
        (self.z_hi - self.z_lo).max(1e-6)
    }

    pub fn z_ref(&self) -> f64 {
        0.5 * (self.z_lo + self.z_hi)
    }

    /// The new named forms with their ranges.
    pub fn periodic_z(&self) -> Extra {
        Extra::PeriodicZ {
            z_ref_m: self.z_ref(),
            k_lo: 0.5 * TAU / self.span(),
            k_hi: 1.5 * TAU / self.lambda_min_m,
        }
    }

    /// μ varying along the observed stretch of groove.
    pub fn friction_position(&self) -> Extra {
        Extra::FrictionPosition {
            z_mid_m: self.z_ref(),
            half_span_m: 0.5 * self.span(),
        }
    }

    /// μ varying with the slip speed, about the runs' median early speed.
    pub fn friction_slip(&self) -> Extra {
        Extra::FrictionSlip {
            u_ref_mps: self.v_ref_mps,
        }
    }

    /// The camera's positions distorted over the observed stretch.
    pub fn distortion(&self) -> Extra {
        Extra::Distortion {
            z_mid_m: self.z_ref(),
            half_span_m: 0.5 * self.span(),
        }
    }

    pub fn localized(&self) -> Extra {
        Extra::Localized {
            z_lo: self.z_lo,
            z_hi: self.z_hi,
            w_lo: self.w_lo(),
            w_hi: 0.5 * self.span(),
        }
    }

    fn w_lo(&self) -> f64 {
        (2.0 * self.dz_med).max(self.span() / 200.0)
    }

    pub fn time_periodic(&self) -> Extra {
        Extra::TimePeriodic {
            // three periods in the longest run at least: slower, a force in time is one smooth
            // push per run, which drag, tilt or a force in z explain as well
            f_lo: 3.0 / self.duration_s,
            f_hi: 1.05 * self.f_max_hz,
        }
    }

    /// The spline fallback in `var` on the map's knots.
    pub fn spline(&self, map: &ForceMap, var: Variable) -> Option<Extra> {
        let (lo, dx, segments, _) = map.spline.clone()?;
        Some(Extra::Spline {
            variable: var,
            lo,
            dx,
            segments,
        })
    }
}

/// Everything the current model's residuals propose.
#[derive(Clone, Debug, Default)]
pub struct Proposals {
    pub z: Option<Spectrum>,
    pub t: Option<Spectrum>,
    /// (amplitude m/s², centre m, width m), best first.
    pub bumps: Vec<[f64; 3]>,
    pub maps: Vec<ForceMap>,
}

/// What is needed from the residuals.
#[derive(Clone, Copy, Debug)]
pub struct Wanted {
    pub z: bool,
    pub t: bool,
    pub bump: bool,
    /// Force maps (with the folds of the cross-validation).
    pub maps: bool,
}

/// Trial (centre, width) of a Gaussian bump: widths doubling from `w_lo` (at least 1/160 of the
/// span) up to a quarter of the span (and `w_hi`), centres every half width over the range.
pub fn bump_trials(rg: &Ranges, w_lo: f64, w_hi: f64) -> Vec<(f64, f64)> {
    let mut trials = Vec::new();
    let mut w = w_lo.max(0.05 * rg.span() / 8.0);
    while w <= (0.25 * rg.span()).min(w_hi) {
        let mut c = rg.z_lo;
        while c <= rg.z_hi {
            trials.push((c, w));
            c += 0.5 * w;
        }
        w *= 2.0;
    }
    trials
}

/// A run's response to a unit Gaussian bump at (c, w) in lab z, in noise units with its locals
/// projected out; None when the run never comes within three widths of it.
pub fn bump_column(p: &Prepared, c: f64, w: f64) -> Option<Vec<f64>> {
    let z = p.track.variable(Variable::Z);
    if !z.iter().any(|zz| (zz - c).abs() < 3.0 * w) {
        return None;
    }
    let f: Vec<f64> = z
        .iter()
        .map(|zz| {
            let u = (zz - c) / w;
            (-0.5 * u * u).exp()
        })
        .collect();
    Some(p.column(p.track.respond_values(&f)))
}

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
    let t = wanted
        .t
        .then(|| t_spectrum(&prep, &f_grid(rg.duration_s, rg.f_max_hz)));
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

/// The proposals a term needs.
pub fn wanted_for(extras: &[&Extra]) -> Wanted {
    Wanted {
        z: extras.iter().any(|e| matches!(e, Extra::PeriodicZ { .. })),
        t: extras
            .iter()
            .any(|e| matches!(e, Extra::TimePeriodic { .. })),
        bump: extras.iter().any(|e| matches!(e, Extra::Localized { .. })),
        maps: false,
    }
}

/// True when the term's starting values come from the residuals.
pub fn needs_proposal(e: &Extra) -> bool {
    matches!(
        e,
        Extra::PeriodicZ { .. } | Extra::Localized { .. } | Extra::TimePeriodic { .. }
    )
}

/// Starting values of a proposed term's parameters (several: the best peaks).
pub fn starts(e: &Extra, p: &Proposals) -> Vec<Vec<f64>> {
    let clamp = |v: Vec<f64>| -> Vec<f64> {
        v.iter()
            .zip(e.params())
            .map(|(x, q)| x.clamp(q.lo, q.hi))
            .collect()
    };
    let out: Vec<Vec<f64>> = match e {
        Extra::PeriodicZ { .. } => {
            p.z.iter()
                .flat_map(|s| s.peaks.iter())
                .map(|pk| clamp(vec![pk.omega, pk.coef[0], pk.coef[1]]))
                .collect()
        }
        Extra::Localized { .. } => p.bumps.iter().map(|b| clamp(b.to_vec())).collect(),
        Extra::TimePeriodic { .. } => {
            p.t.iter()
                .flat_map(|s| s.peaks.iter())
                .map(|pk| clamp(vec![pk.omega / TAU, pk.coef[0].max(1e-3)]))
                .collect()
        }
        Extra::Spline { variable, .. } => {
            let name = match variable {
                Variable::Z => "z",
                Variable::V => "v",
                Variable::T => "t",
            };
            p.maps
                .iter()
                .filter(|m| m.variable == name)
                .filter_map(|m| m.spline.as_ref().map(|s| s.3.clone()))
                .collect()
        }
        _ => vec![],
    };
    if out.is_empty() {
        vec![e.params().iter().map(|q| q.start).collect()]
    } else {
        out
    }
}
