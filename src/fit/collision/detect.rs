//! Finding impacts in noisy tracks: the noise level, the target's departure from rest, local
//! velocities, and contacts in the gap between the particles (secondary collisions).
//!
//! An impact is a jump in velocity (a kink in z), equal and opposite in the two tracks, and it
//! happens only where the gap is back at the contact distance; a switch from sliding to rolling
//! only changes the acceleration. All detectors use robust statistics so
//! that rare tracking outliers and dropped frames do not create or hide impacts.

use super::model::TrackData;
use crate::lsq::dense::ScaledCholesky;

/// Robust position noise (m) from second differences: for equally spaced samples
/// `var(z[i+1] − 2 z[i] + z[i−1]) = 6 σ²`; uneven spacing uses the interpolating form.
pub fn noise_scale_m(track: &TrackData) -> f64 {
    let (t, z) = (&track.t_s, &track.z_m);
    let mut d: Vec<f64> = Vec::with_capacity(t.len());
    for i in 1..t.len().saturating_sub(1) {
        let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
        if h0 <= 0.0 || h1 <= 0.0 {
            continue;
        }
        let interp = (z[i - 1] * h1 + z[i + 1] * h0) / (h0 + h1);
        // residual of the middle point from the chord; its variance is σ²(1 + (h0² + h1²)/(h0 + h1)²)
        let f = 1.0 + (h0 * h0 + h1 * h1) / ((h0 + h1) * (h0 + h1));
        d.push((z[i] - interp) / f.sqrt());
    }
    if d.is_empty() {
        return f64::NAN;
    }
    crate::stats::abs_scale(&d)
}

pub use crate::stats::upper_median as median;

/// Theil–Sen line through the samples `lo..hi`: (slope m/s, value at `t_ref`).
pub fn robust_line(track: &TrackData, lo: usize, hi: usize, t_ref: f64) -> Option<(f64, f64)> {
    if hi <= lo + 1 || hi > track.t_s.len() {
        return None;
    }
    let (t, z) = (&track.t_s[lo..hi], &track.z_m[lo..hi]);
    let mut slopes = Vec::with_capacity(t.len() * t.len() / 2);
    for i in 0..t.len() {
        for j in i + 1..t.len() {
            if t[j] > t[i] {
                slopes.push((z[j] - z[i]) / (t[j] - t[i]));
            }
        }
    }
    if slopes.is_empty() {
        return None;
    }
    let slope = median(&mut slopes);
    let mut icpt: Vec<f64> = t
        .iter()
        .zip(z)
        .map(|(t, z)| z - slope * (t - t_ref))
        .collect();
    Some((slope, median(&mut icpt)))
}

/// First time the target leaves rest toward +z (striker-forward frame): the time where a robust
/// line through the first moving samples crosses the rest position. None if it never moves.
pub fn departure_time_s(target: &TrackData, sigma_m: f64) -> Option<f64> {
    let n = target.t_s.len();
    if n < 12 {
        return None;
    }
    let n_rest = (n / 4).clamp(5, 15);
    let mut head: Vec<f64> = target.z_m[..n_rest].to_vec();
    let z_rest = median(&mut head);
    let thr = 8.0 * sigma_m.max(1e-12);
    let moved = |i: usize| target.z_m[i] - z_rest > thr;
    let i = (n_rest..n.saturating_sub(3)).find(|&i| moved(i) && moved(i + 1) && moved(i + 2))?;
    let hi = (i + 6).min(n);
    let (slope, z_at) = robust_line(target, i, hi, target.t_s[i])?;
    if slope <= 0.0 {
        return Some(target.t_s[i - 1]);
    }
    // the threshold is crossed a few frames after the start at low speed: extrapolate back
    let t_cross = target.t_s[i] - (z_at - z_rest) / slope;
    Some(t_cross.clamp(target.t_s[n_rest - 1], target.t_s[i]))
}

/// Index of the first sample at or after `t`.
pub fn index_at(track: &TrackData, t_s: f64) -> usize {
    track.t_s.partition_point(|&x| x < t_s)
}

/// A contact found in the gap between the particles.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    pub t_s: f64,
    /// Rate of change of the gap just before (< 0, closing) and just after (> 0, opening).
    pub gap_rate_before_mps: f64,
    pub gap_rate_after_mps: f64,
    /// Jump of the gap rate over its standard error.
    pub z_score: f64,
}

/// The gap z_target − z_striker at the times both particles were recorded (same frame time).
pub fn gap_series(tracks: &[TrackData; 2]) -> TrackData {
    let (a, b) = (&tracks[0], &tracks[1]);
    let (mut i, mut j) = (0, 0);
    let mut out = TrackData::default();
    while i < a.t_s.len() && j < b.t_s.len() {
        let (ta, tb) = (a.t_s[i], b.t_s[j]);
        if (ta - tb).abs() <= 1e-9 * ta.abs().max(1.0) {
            out.t_s.push(ta);
            out.z_m.push(b.z_m[j] - a.z_m[i]);
            i += 1;
            j += 1;
        } else if ta < tb {
            i += 1;
        } else {
            j += 1;
        }
    }
    out
}

/// Least-squares quadratic through the samples `lo..hi` (outlier-flagged ones skipped):
/// its slope at `tb` and the standard error of that slope for noise `sigma_m`.
pub fn quadratic_slope(
    g: &TrackData,
    keep: &[bool],
    lo: usize,
    hi: usize,
    tb: f64,
    sigma_m: f64,
) -> Option<(f64, f64)> {
    let mut xtx = [[0.0f64; 3]; 3];
    let mut xty = [0.0f64; 3];
    let mut n = 0;
    for i in lo..hi {
        if !keep[i] {
            continue;
        }
        let x = g.t_s[i] - tb;
        let row = [1.0, x, x * x];
        for a in 0..3 {
            xty[a] += row[a] * g.z_m[i];
            for b in 0..3 {
                xtx[a][b] += row[a] * row[b];
            }
        }
        n += 1;
    }
    if n < 6 {
        return None;
    }
    // scaled to unit diagonal for conditioning (times are ~1e-3 s)
    let flat: Vec<f64> = xtx.iter().flatten().copied().collect();
    let f = ScaledCholesky::new(&flat, 3, 0.0, 1e-14)?;
    let slope = f.solve(&xty)[1];
    Some((slope, sigma_m * f.inverse()[4].max(0.0).sqrt()))
}

/// Contacts after `after_s`: samples where the gap is within `tol_m` of the contact distance
/// `contact_m`, the gap rate jumps from closing to opening by more than `min_z` standard errors
/// (one-sided quadratic fits over `window` samples), and the jump is a local maximum.
pub fn gap_contacts(
    gap: &TrackData,
    sigma_m: f64,
    contact_m: f64,
    tol_m: f64,
    after_s: f64,
    window: usize,
    min_z: f64,
) -> Vec<Contact> {
    let n = gap.t_s.len();
    // flag outliers: far from the median of their 5 neighbours
    let keep: Vec<bool> = (0..n)
        .map(|i| {
            let lo = i.saturating_sub(2);
            let hi = (i + 3).min(n);
            let mut w: Vec<f64> = gap.z_m[lo..hi].to_vec();
            (gap.z_m[i] - median(&mut w)).abs() < 8.0 * sigma_m
        })
        .collect();
    let mut found: Vec<Contact> = Vec::new();
    let mut scores: Vec<Option<Contact>> = vec![None; n];
    for i in window..n.saturating_sub(window) {
        let tb = gap.t_s[i];
        if !keep[i] || (gap.z_m[i] - contact_m).abs() > tol_m {
            continue;
        }
        let Some((before, se_b)) = quadratic_slope(gap, &keep, i + 1 - window, i + 1, tb, sigma_m)
        else {
            continue;
        };
        let Some((after, se_a)) = quadratic_slope(gap, &keep, i, i + window, tb, sigma_m) else {
            continue;
        };
        let z = (after - before) / (se_a * se_a + se_b * se_b).sqrt();
        if before < 0.0 && after > 0.0 && z > 0.0 {
            scores[i] = Some(Contact {
                t_s: tb,
                gap_rate_before_mps: before,
                gap_rate_after_mps: after,
                z_score: z,
            });
        }
    }
    let half = (window / 2).max(2);
    for i in 0..n {
        let Some(c) = scores[i] else { continue };
        let lo = i.saturating_sub(half);
        let hi = (i + half + 1).min(n);
        let is_max = (lo..hi).all(|k| {
            k == i
                || scores[k]
                    .is_none_or(|o| o.z_score < c.z_score || (o.z_score == c.z_score && k > i))
        });
        // a contact's own tail must not pass as a later one: select maxima first, then by time
        if is_max && c.z_score >= min_z && c.t_s > after_s {
            found.push(c);
        }
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(f: impl Fn(f64) -> f64, n: usize, dt: f64) -> TrackData {
        let t: Vec<f64> = (0..n).map(|i| i as f64 * dt).collect();
        let z = t
            .iter()
            .enumerate()
            .map(|(i, &t)| f(t) + 1e-6 * (((i * 37) % 11) as f64 / 5.0 - 1.0))
            .collect();
        TrackData { t_s: t, z_m: z }
    }

    #[test]
    fn noise_scale_sees_micrometres_not_motion() {
        let tr = track(|t| 0.1 * t - 3.0 * t * t, 500, 1e-4);
        let s = noise_scale_m(&tr);
        assert!(s > 2e-7 && s < 2e-6, "{s}");
    }

    #[test]
    fn departure_is_found_within_a_frame() {
        let tr = track(
            |t| {
                if t < 0.02 {
                    1e-3
                } else {
                    1e-3 + 0.08 * (t - 0.02)
                }
            },
            400,
            1e-4,
        );
        let t = departure_time_s(&tr, noise_scale_m(&tr)).unwrap();
        assert!((t - 0.02).abs() < 1e-4, "{t}");
    }
}
