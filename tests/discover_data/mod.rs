//! Synthesized single-run data sets with known truth, shared by the discovery tests and bench.
#![allow(dead_code)]

use groove::discover::sim::{Drag, SimModel};
use groove::discover::G_MPS2;
use groove::recording::{Experiment, Recording, RunInfo, Track};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use std::collections::BTreeMap;

pub mod reference;

pub const S: f64 = 0.577_858;

/// The truth of a synthesized data set.
#[derive(Clone)]
pub struct Truth {
    pub mu: [f64; 2],
    pub t_s: f64,
    pub quad_c_per_m: f64,
    pub sat_tp: Option<f64>,
    pub roll_c: f64,
    pub tilt_deg: f64,
    pub vc_mps: Option<f64>,
    /// (amp m/s², wavelength m, phase)
    pub position: Option<(f64, f64, f64)>,
}

impl Truth {
    pub fn baseline() -> Truth {
        Truth {
            mu: [0.337, 0.293],
            t_s: 0.06,
            quad_c_per_m: 0.0,
            sat_tp: None,
            roll_c: 0.0,
            tilt_deg: 0.0,
            vc_mps: None,
            position: None,
        }
    }

    pub fn model(&self, material: usize) -> SimModel {
        SimModel {
            s: S,
            k: 2.5,
            mu: self.mu[material],
            vc_mps: self.vc_mps,
            drag: match self.sat_tp {
                Some(tp) => Drag::Saturating {
                    t0_s: self.t_s,
                    tp_s_per_mps: tp,
                },
                None => Drag::Quadratic {
                    t_s: self.t_s,
                    c_per_m: self.quad_c_per_m,
                },
            },
            roll_c: self.roll_c,
            tilt_mps2: -G_MPS2 * self.tilt_deg.to_radians().sin(),
            position: self
                .position
                .map(|(a, lambda, ph)| vec![(a, 2.0 * std::f64::consts::PI / lambda, ph)])
                .unwrap_or_default(),
            terms: vec![],
            phased_term: None,
            variation: Default::default(),
            distortion: None,
        }
    }
}

/// Shape of a data set.
pub struct Shape {
    pub runs: usize,
    pub frames: usize,
    pub outliers: bool,
    pub shuffle: bool,
}

pub const SMALL: Shape = Shape {
    runs: 24,
    frames: 400,
    outliers: false,
    shuffle: false,
};

pub fn synthesize(truth: &Truth, shape: &Shape, seed: u64) -> Vec<Recording> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let fps = 10_000.0;
    (0..shape.runs)
        .map(|i| {
            let material = i % 2;
            let speed = 0.005 + 0.095 * rng.random::<f64>();
            let dir = if rng.random::<bool>() { 1.0 } else { -1.0 };
            let t0 = rng.random::<f64>() / fps;
            let z0 = (rng.random::<f64>() - 0.5) * 4e-3;
            let mut t: Vec<f64> = (0..shape.frames).map(|k| k as f64 / fps).collect();
            let tt: Vec<f64> = t.iter().map(|x| x + t0).collect();
            let mut z = vec![0.0; t.len()];
            truth
                .model(material)
                .simulate(z0, dir * speed, &tt, &mut z, None, None);
            for zi in z.iter_mut() {
                *zi += 1e-6 * rng.sample::<f64, _>(StandardNormal);
                if shape.outliers && rng.random::<f64>() < 0.005 {
                    let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
                    *zi += sign * (20e-6 + 30e-6 * rng.random::<f64>());
                }
            }
            let mut frame: Vec<i64> = (0..shape.frames as i64).collect();
            if shape.shuffle {
                let mut idx: Vec<usize> = (0..t.len()).collect();
                idx.shuffle(&mut rng);
                frame = idx.iter().map(|k| frame[*k]).collect();
                t = idx.iter().map(|k| t[*k]).collect();
                z = idx.iter().map(|k| z[*k]).collect();
            }
            Recording {
                info: RunInfo {
                    run: format!("r{i:03}"),
                    experiment: Experiment::Single,
                    material: ["316", "440c"][material].into(),
                    diameter_m: 300e-6,
                    fps,
                    setup: None,
                    extra: BTreeMap::new(),
                },
                tracks: vec![Track {
                    particle: 0,
                    frame,
                    t_s: t,
                    z_m: z,
                }],
            }
        })
        .collect()
}
