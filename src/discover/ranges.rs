//! What the data allow the forms to take (`Ranges`: the observed lab range, wavelengths,
//! frequencies), what the residuals propose for their starts (`Proposals`), and the bump trials
//! and columns a localized force is searched with.

use super::data::RunData;
use super::forcemap::ForceMap;
use super::response::Prepared;
use super::spectral::Spectrum;
use crate::physics::Variable;

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

    /// The narrowest bump searched: two sample steps, or 1/200 of the span.
    pub fn w_lo(&self) -> f64 {
        (2.0 * self.dz_med).max(self.span() / 200.0)
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
#[derive(Clone, Copy, Debug, Default)]
pub struct Wanted {
    pub z: bool,
    pub t: bool,
    pub bump: bool,
    /// Force maps (with the folds of the cross-validation).
    pub maps: bool,
}

impl Wanted {
    /// What either needs.
    pub fn or(self, o: Wanted) -> Wanted {
        Wanted {
            z: self.z || o.z,
            t: self.t || o.t,
            bump: self.bump || o.bump,
            maps: self.maps || o.maps,
        }
    }

    /// True when anything is needed.
    pub fn any(self) -> bool {
        self.z || self.t || self.bump || self.maps
    }
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
