//! The positions' scale: recordings whose tracks move faster, or slow down harder, than steel
//! spheres of ~300 µm kicked by a laser along a groove can, were written in another unit (most
//! often millimetres for metres), and every fit of them would be nonsense.
//!
//! Two measures per track of 5 samples or more, each robust to the odd tracking outlier:
//! - the mean speed, the track's range of position over its duration;
//! - the deceleration, twice the quadratic coefficient of a least-squares parabola z(t).
//!
//! Physically a laser-kicked sphere leaves at well under 1 m/s (the shipped data: about 0.01 m/s)
//! and friction slows it at about g·μ ≈ 5 m/s². The bounds are far wider so that no real
//! recording trips them: the dataset is refused only when the *median* track moves faster than
//! [`SPEED_MAX_MPS`] = 3 m/s or decelerates harder than [`ACCEL_MAX_MPS2`] = 100 m/s² (≈ 10 g).
//! The same data in millimetres is 1000 times over both.

use super::error::Problem;
use crate::recording::Recording;

/// Largest median mean speed of a track accepted, m/s.
pub const SPEED_MAX_MPS: f64 = 3.0;
/// Largest median deceleration (|acceleration| of the fitted parabola) accepted, m/s².
pub const ACCEL_MAX_MPS2: f64 = 100.0;
/// Fewest samples a track needs to be measured.
const MIN_SAMPLES: usize = 5;

/// The mean speed and |acceleration| of one track, or `None` if it is too short to tell.
pub fn kinematics(t: &[f64], z: &[f64]) -> Option<(f64, f64)> {
    let n = t.len().min(z.len());
    if n < MIN_SAMPLES {
        return None;
    }
    let duration = t[n - 1] - t[0];
    if !(duration > 0.0) {
        return None;
    }
    let (lo, hi) = z[..n]
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        });
    let speed = (hi - lo) / duration;
    // least squares z = a + b·u + c·u², u = (t − t̄)/h centred and scaled for conditioning
    let mean_t = t[..n].iter().sum::<f64>() / n as f64;
    let h = duration / 2.0;
    let mut m = [[0.0f64; 3]; 3];
    let mut r = [0.0f64; 3];
    for i in 0..n {
        let u = (t[i] - mean_t) / h;
        let basis = [1.0, u, u * u];
        for a in 0..3 {
            r[a] += basis[a] * z[i];
            for b in 0..3 {
                m[a][b] += basis[a] * basis[b];
            }
        }
    }
    let c = solve3(m, r)?[2];
    Some((speed, (2.0 * c / (h * h)).abs()))
}

/// Solves the 3×3 system by Cramer's rule; `None` if it is singular.
fn solve3(m: [[f64; 3]; 3], r: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: &[[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(&m);
    if !(d.abs() > 0.0) || !d.is_finite() {
        return None;
    }
    let mut out = [0.0; 3];
    for (k, o) in out.iter_mut().enumerate() {
        let mut mk = m;
        for row in 0..3 {
            mk[row][k] = r[row];
        }
        *o = det(&mk) / d;
    }
    Some(out)
}

/// The median of a non-empty list.
fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// The (mean speed, |acceleration|) of each of a recording's tracks long enough to tell.
pub fn measure(r: &Recording) -> Vec<(f64, f64)> {
    r.tracks
        .iter()
        .filter_map(|t| kinematics(&t.t_s, &t.z_m))
        .collect()
}

/// The median speed and |acceleration| of the measured tracks when they are physically
/// impossible in metres, else `None` (also when nothing was measured).
pub fn impossible(measured: &[(f64, f64)]) -> Option<(f64, f64)> {
    if measured.is_empty() {
        return None;
    }
    let speed = median(measured.iter().map(|m| m.0).collect());
    let accel = median(measured.iter().map(|m| m.1).collect());
    (speed > SPEED_MAX_MPS || accel > ACCEL_MAX_MPS2).then_some((speed, accel))
}

/// One problem of the whole dataset (never skipped) when the median track is physically
/// impossible in metres; `file` is the positions' file, `column` its position column.
pub fn check(recordings: &[Recording], file: &str, column: &str) -> Option<Problem> {
    let measured: Vec<(f64, f64)> = recordings.iter().flat_map(measure).collect();
    let (speed, accel) = impossible(&measured)?;
    let mut p = Problem::file(
        file,
        format!(
            "the positions are not in metres, or not of spheres rolling in a groove: over {} tracks the median one moves at {speed:.3} m/s and decelerates at {accel:.3} m/s², where a laser-kicked sphere moves at under 1 m/s and friction slows it at a few m/s² (groove accepts up to {SPEED_MAX_MPS} m/s and {ACCEL_MAX_MPS2} m/s²)",
            measured.len()
        ),
        format!(
            "write {column} in metres (positions in millimetres: divide them by 1000); for tracker exports check the calibration (metres per pixel, the spatial unit)"
        ),
    );
    p.column = Some(column.to_string());
    Some(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decelerating(v0: f64, a: f64, scale: f64) -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..400).map(|i| i as f64 * 1e-4).collect();
        let z = t
            .iter()
            .map(|&t| scale * (1e-3 + v0 * t - 0.5 * a * t * t))
            .collect();
        (t, z)
    }

    #[test]
    fn kinematics_recover_the_deceleration_and_the_mean_speed() {
        // slowing from 0.01 m/s at 0.2 m/s², still moving forward at the last frame
        let (t, z) = decelerating(0.01, 0.2, 1.0);
        let (speed, accel) = kinematics(&t, &z).unwrap();
        assert!((accel - 0.2).abs() < 1e-6, "{accel}");
        // range over duration: (v0·T − a·T²/2)/T with T = 0.0399 s
        let span = 0.01 * 0.0399 - 0.5 * 0.2 * 0.0399f64.powi(2);
        assert!((speed - span / 0.0399).abs() < 1e-9, "{speed}");
    }

    #[test]
    fn millimetres_trip_the_check_and_metres_do_not() {
        let rec = |scale: f64| {
            let (t_s, z_m) = decelerating(0.01, 2.0, scale);
            crate::recording::Recording {
                info: crate::recording::RunInfo {
                    run: "r".into(),
                    experiment: crate::recording::Experiment::Single,
                    material: "316".into(),
                    diameter_m: 3e-4,
                    fps: 1e4,
                    setup: None,
                    extra: Default::default(),
                },
                tracks: vec![crate::recording::Track {
                    particle: 0,
                    frame: (0..400).collect(),
                    t_s,
                    z_m,
                }],
            }
        };
        assert!(check(&[rec(1.0)], "trajectories.csv", "z_m").is_none());
        let p = check(&[rec(1000.0)], "trajectories.csv", "z_m").expect("refused");
        let text = p.to_string();
        assert!(
            text.contains("not in metres") && text.contains("divide them by 1000"),
            "{text}"
        );
        assert!(p.run.is_none(), "a problem of the dataset, never skipped");
    }
}
