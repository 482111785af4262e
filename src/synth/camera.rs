//! The virtual camera: frames, dropped frames, field of view, noise, sub-pixel grid, outliers.

use super::truth::CameraSpec;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// One tracked position (a row of trajectories.csv).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Row {
    pub particle: u32,
    pub frame: i64,
    pub t_s: f64,
    pub z_m: f64,
}

/// Record true positions `z_true[particle][frame]` as the camera would. Every frame draws the same
/// random numbers whether or not it is kept, so one setting never shifts another's draws.
pub(crate) fn record(cam: &CameraSpec, z_true: &[Vec<f64>], rng: &mut ChaCha8Rng) -> Vec<Row> {
    let grid = cam.pixel_m / f64::from(cam.subpixel);
    let frames = z_true.first().map_or(0, Vec::len);
    let mut rows = Vec::with_capacity(frames * z_true.len());
    for k in 0..frames {
        let dropped = rng.random::<f64>() < cam.dropped_frame_rate;
        for (p, track) in z_true.iter().enumerate() {
            let noise: f64 = StandardNormal.sample(rng);
            let outlier = rng.random::<f64>() < cam.outlier_rate;
            let jump: f64 = StandardNormal.sample(rng);
            let z = track[k];
            if dropped || !(0.0..=cam.fov_m).contains(&z) {
                continue;
            }
            let mut measured = z + cam.noise_m * noise;
            if outlier {
                measured += cam.outlier_m * jump;
            }
            rows.push(Row {
                particle: p as u32,
                frame: k as i64,
                t_s: k as f64 / cam.fps,
                z_m: (measured / grid).round() * grid,
            });
        }
    }
    rows
}
