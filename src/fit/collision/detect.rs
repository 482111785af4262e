//! Finding impacts in noisy tracks: the noise level, the target's departure from rest, local
//! velocities, and the kink scan that proposes a missed (secondary) impact from fit residuals.
//!
//! An impact is a jump in velocity (a kink in z), equal and opposite in the two tracks; a switch
//! from sliding to rolling only changes the acceleration. All detectors use robust statistics so
//! that rare tracking outliers and dropped frames do not create or hide impacts.

use super::model::TrackData;

/// Robust position noise (m) from second differences: for equally spaced samples
/// var(z[i+1] − 2 z[i] + z[i−1]) = 6 σ²; uneven spacing uses the interpolating form.
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
    median_abs(&mut d) * 1.4826
}

pub fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b));
    v[mid]
}

fn median_abs(v: &mut [f64]) -> f64 {
    v.iter_mut().for_each(|x| *x = x.abs());
    median(v)
}

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
    let t_cross = target.t_s[i] - (z_at - z_rest) / slope;
    Some(t_cross.clamp(target.t_s[i - 1], target.t_s[i]))
}

/// Index of the first sample at or after `t`.
pub fn index_at(track: &TrackData, t_s: f64) -> usize {
    track.t_s.partition_point(|&x| x < t_s)
}

/// A proposed impact from the residual kink scan.
#[derive(Debug, Clone, Copy)]
pub struct KinkProposal {
    pub t_s: f64,
    /// Velocity jump of the striker and of the target (m/s, striker-forward frame).
    pub jump_mps: [f64; 2],
    /// Impulse estimate over its standard error.
    pub z_score: f64,
}

/// Kink (change of slope at `tb`) of residuals in a window: regress r on 1, (t − tb), (t − tb)₊.
fn hinge(t: &[f64], r: &[f64], tb: f64, half_window_s: f64) -> Option<(f64, f64)> {
    let mut xtx = [[0.0f64; 3]; 3];
    let mut xty = [0.0f64; 3];
    let (mut n_left, mut n_right) = (0, 0);
    let mut rows: Vec<([f64; 3], f64)> = Vec::new();
    for (ti, ri) in t.iter().zip(r) {
        let dt = ti - tb;
        if dt.abs() > half_window_s {
            continue;
        }
        if dt < 0.0 {
            n_left += 1;
        } else {
            n_right += 1;
        }
        let x = [1.0, dt, dt.max(0.0)];
        rows.push((x, *ri));
        for a in 0..3 {
            xty[a] += x[a] * ri;
            for b in 0..3 {
                xtx[a][b] += x[a] * x[b];
            }
        }
    }
    if n_left < 5 || n_right < 5 {
        return None;
    }
    let inv = invert3(&xtx)?;
    let beta: Vec<f64> = (0..3)
        .map(|a| (0..3).map(|b| inv[a][b] * xty[b]).sum())
        .collect();
    let mut res: Vec<f64> = rows
        .iter()
        .map(|(x, y)| y - (0..3).map(|a| x[a] * beta[a]).sum::<f64>())
        .collect();
    let s = 1.4826 * median_abs(&mut res);
    Some((beta[2], s * inv[2][2].max(0.0).sqrt()))
}

fn invert3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let c = |i: usize, j: usize| {
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    };
    let det = m[0][0] * c(0, 0) + m[0][1] * c(0, 1) + m[0][2] * c(0, 2);
    if det.abs() < 1e-300 || !det.is_finite() {
        return None;
    }
    let mut inv = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            inv[j][i] = c(i, j) / det;
        }
    }
    Some(inv)
}

/// Scan the residuals of both tracks for the strongest pair of opposite kinks (striker slows,
/// target speeds up) away from the known impacts; `allowed(t)` gates candidate times (contact).
pub fn kink_scan(
    tracks: &[TrackData; 2],
    residuals: [&[f64]; 2],
    known_impacts_s: &[f64],
    min_separation_s: f64,
    half_window_s: f64,
    allowed: &dyn Fn(f64) -> bool,
) -> Option<KinkProposal> {
    let ts = &tracks[0].t_s;
    let mut best: Option<KinkProposal> = None;
    for i in 1..ts.len() {
        let tb = 0.5 * (ts[i - 1] + ts[i]);
        if known_impacts_s
            .iter()
            .any(|&k| (k - tb).abs() < min_separation_s)
            || !allowed(tb)
        {
            continue;
        }
        let Some((k0, s0)) = hinge(ts, residuals[0], tb, half_window_s) else {
            continue;
        };
        let Some((k1, s1)) = hinge(&tracks[1].t_s, residuals[1], tb, half_window_s) else {
            continue;
        };
        // residual = model − data, so a missed jump ΔV in the data shows as a kink −ΔV
        let (j0, j1) = (-k0, -k1);
        let impulse = 0.5 * (j1 - j0);
        let se = 0.5 * (s0 * s0 + s1 * s1).sqrt();
        if !(se > 0.0) || j1 <= 0.0 || j0 >= 0.0 {
            continue;
        }
        let z = impulse / se;
        if best.is_none_or(|b| z > b.z_score) {
            best = Some(KinkProposal {
                t_s: tb,
                jump_mps: [j0, j1],
                z_score: z,
            });
        }
    }
    best
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
