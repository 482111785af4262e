//! The camera: frames a random fraction of a frame after the kick, a field of view fixed in the
//! lab, dropped frames, rare tracking outliers, and what the optics and clock do to positions and
//! times (a length scale and a distortion about the image centre, a time base).

use super::noise::Noise;
use super::run::Fine;
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// The camera of one dataset.
#[derive(Clone, Debug)]
pub struct Camera {
    /// Frame rate written to runs.csv.
    pub fps: f64,
    /// The true frame rate is fps (1 + time_error): the written times are off by that factor.
    pub time_error: f64,
    /// Field of view [0, fov_m] in the lab (z_m is written in these coordinates).
    pub fov_m: f64,
    pub dropped_rate: f64,
    /// Rare tracking outliers of the camera itself: (rate per frame, size m).
    pub outliers: (f64, f64),
    /// Length scale error about the image centre: z → c + (1 + scale_error)(z − c).
    pub scale_error: f64,
    /// Distortion about the image centre: z → c + (z − c)(1 + κ ((z − c)/(fov/2))²).
    pub distortion: f64,
}

/// One measured frame.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub frame: usize,
    pub t_s: f64,
    pub z_m: f64,
}

impl Camera {
    /// Where the image puts a particle at lab position `z`.
    pub fn image(&self, z: f64) -> f64 {
        let c = 0.5 * self.fov_m;
        let x = (z - c) / c;
        c + (z - c) * (1.0 + self.scale_error + self.distortion * x * x)
    }

    /// The true times (since the kick) of the frames of a recording starting `frac` of a frame
    /// after the kick and lasting `duration_s`.
    pub fn times(&self, frac: f64, duration_s: f64) -> Vec<f64> {
        let true_fps = self.fps * (1.0 + self.time_error);
        let n = (duration_s * self.fps).floor() as usize;
        (0..n).map(|i| (i as f64 + frac) / true_fps).collect()
    }

    /// The recorded frames of one track: noise-free when `noise` is None (no drops, no outliers).
    pub fn film(
        &self,
        fine: &Fine,
        frac: f64,
        duration_s: f64,
        noise: Option<(&Noise, &mut ChaCha8Rng)>,
    ) -> Vec<Frame> {
        let times = self.times(frac, duration_s);
        let (z, v): (Vec<f64>, Vec<f64>) = times.iter().map(|&t| fine.at(t)).unzip();
        let image: Vec<f64> = z.iter().map(|&z| self.image(z)).collect();
        let seen = |i: usize| z[i] >= 0.0 && z[i] <= self.fov_m;
        match noise {
            None => (0..times.len())
                .filter(|&i| seen(i))
                .map(|i| Frame {
                    frame: i,
                    t_s: i as f64 / self.fps,
                    z_m: image[i],
                })
                .collect(),
            Some((model, rng)) => {
                let measured = model.apply(&image, &v, self.fps, rng);
                let mut out = Vec::new();
                for i in 0..times.len() {
                    let drop = rng.random::<f64>() < self.dropped_rate;
                    let outlier = rng.random::<f64>() < self.outliers.0;
                    let jump = self.outliers.1 * (rng.random::<f64>() - 0.5) * 2.0;
                    if seen(i) && !drop {
                        let z_m = if outlier {
                            image[i] + jump
                        } else {
                            measured[i]
                        };
                        out.push(Frame {
                            frame: i,
                            t_s: i as f64 / self.fps,
                            z_m,
                        });
                    }
                }
                out
            }
        }
    }
}
