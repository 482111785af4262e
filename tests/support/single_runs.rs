//! Synthetic single runs with known truth for the fit tests and the fit benchmark: the physics
//! closed form sampled at a camera's frames, plus noise, tracking outliers, dropped frames, an
//! unknown kick time within the first frame and an unknown offset along the groove.

use groove::physics::{Baseline, Groove};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// The truth of one synthetic run.
#[derive(Clone, Copy, Debug)]
pub struct Truth {
    pub v0_mps: f64,
    pub mu: f64,
    pub t_drag_s: f64,
    pub t0_s: f64,
    pub z0_m: f64,
}

/// How the camera sees a run.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub fps: f64,
    pub n_frames: usize,
    pub noise_m: f64,
    pub outlier_rate: f64,
    pub dropped_rate: f64,
}

impl Camera {
    /// 10,000 fps, 600 frames (60 ms), 1 µm noise, 0.5 % outliers, 1 % dropped frames.
    pub const CHAPTER: Camera = Camera {
        fps: 10_000.0,
        n_frames: 600,
        noise_m: 1e-6,
        outlier_rate: 0.005,
        dropped_rate: 0.01,
    };
}

/// A synthetic run: frames, positions, and which frames are injected outliers.
pub struct Run {
    pub truth: Truth,
    pub t_s: Vec<f64>,
    pub z_m: Vec<f64>,
    pub outlier: Vec<bool>,
}

/// The chapter's drag line T = 0.052 + 1.10·|v0|.
pub fn chapter_t_drag(v0_mps: f64) -> f64 {
    0.052 + 1.10 * v0_mps.abs()
}

/// Sample `truth` with `cam`; noise, outliers (10–50 µm jumps) and dropped frames from `rng`.
/// The noise draws do not depend on `outlier_rate`, so the same seed with and without outliers
/// gives the same noise.
pub fn sample(truth: Truth, cam: Camera, rng: &mut ChaCha8Rng) -> Run {
    let model = Baseline {
        mu: truth.mu,
        t_drag_s: truth.t_drag_s,
        groove: Groove::CHAPTER,
    };
    let normal = Normal::new(0.0, cam.noise_m).unwrap();
    let mut run = Run {
        truth,
        t_s: Vec::with_capacity(cam.n_frames),
        z_m: Vec::with_capacity(cam.n_frames),
        outlier: Vec::with_capacity(cam.n_frames),
    };
    for i in 0..cam.n_frames {
        let t = i as f64 / cam.fps;
        let noise = normal.sample(rng);
        let (u_drop, u_out, jump): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
        if i > 0 && u_drop < cam.dropped_rate {
            continue;
        }
        let (dz, _, _) = model.state(truth.v0_mps, t + truth.t0_s);
        let bad = u_out < cam.outlier_rate;
        let sign = if jump < 0.5 { -1.0 } else { 1.0 };
        let off = if bad {
            sign * (10e-6 + 80e-6 * (jump - 0.5).abs())
        } else {
            0.0
        };
        run.t_s.push(t);
        run.z_m.push(truth.z0_m + dz + noise + off);
        run.outlier.push(bad);
    }
    run
}

/// A random truth: |v0| uniform in `speed`, random direction, T on the chapter's line, kick
/// within the first frame, offset within ±5 mm.
pub fn random_truth(rng: &mut ChaCha8Rng, speed: (f64, f64), mu: f64, fps: f64) -> Truth {
    let v: f64 = rng.random_range(speed.0..speed.1);
    let dir = if rng.random::<bool>() { 1.0 } else { -1.0 };
    Truth {
        v0_mps: dir * v,
        mu,
        t_drag_s: chapter_t_drag(v),
        t0_s: rng.random_range(0.0..1.0 / fps),
        z0_m: rng.random_range(-5e-3..5e-3),
    }
}

/// A reproducible set of runs.
pub fn runs(seed: u64, n: usize, speed: (f64, f64), mu: f64, cam: Camera) -> Vec<Run> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| {
            let truth = random_truth(&mut rng, speed, mu, cam.fps);
            sample(truth, cam, &mut rng)
        })
        .collect()
}
