//! A dataset's specification (materials, runs, camera, noise, pair model) and its rendering into
//! recorded runs by the independent simulator.

use crate::indsim::camera::{Camera, Frame};
use crate::indsim::model::Physics;
use crate::indsim::noise::Noise;
use crate::indsim::pair::{simulate_pair, Between, Law, PairModel};
use crate::indsim::run::{simulate, DT_S};
use crate::indsim::writer::RecordedRun;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// One material: its name, size and restitution laws (rolling-in and in-contact collisions).
#[derive(Clone, Debug)]
pub struct Material {
    pub name: &'static str,
    pub diameter_m: f64,
    pub restitution_rolling: (f64, f64),
    pub restitution_contact: (f64, f64),
}

/// One run to simulate: the kicked particle (and the target of a collision).
#[derive(Clone, Debug)]
pub struct RunSpec {
    pub id: String,
    /// `single` or `collision`.
    pub experiment: &'static str,
    /// `rolling`, `contact` or empty.
    pub setup: &'static str,
    pub material: usize,
    pub physics: [Physics; 2],
    pub z0: [f64; 2],
    pub v0: f64,
    /// The first frame comes this fraction of a frame after the kick.
    pub frac: f64,
    pub duration_s: f64,
}

/// Everything a dataset is made from.
#[derive(Clone, Debug)]
pub struct DatasetSpec {
    pub seed: u64,
    pub materials: Vec<Material>,
    pub runs: Vec<RunSpec>,
    pub camera: Camera,
    pub noise: Noise,
    pub mu_pp: f64,
    /// A force between the two particles of a collision run.
    pub pair_force: Option<Between>,
    /// A restitution law for every collision other than the materials' saturating ones.
    pub restitution_law: Option<Law>,
    /// μ_pp falling with the slip speed at the contact (its scale u0, m/s).
    pub mu_pp_weakening_mps: Option<f64>,
}

impl DatasetSpec {
    fn pair_model(&self, run: &RunSpec) -> PairModel {
        let m = &self.materials[run.material];
        let (c0, v_ref_mps) = if run.setup == "contact" {
            m.restitution_contact
        } else {
            m.restitution_rolling
        };
        PairModel {
            radius_m: 0.5 * m.diameter_m,
            mu_pp: self.mu_pp,
            c0,
            v_ref_mps,
            force: self.pair_force,
            law: self.restitution_law,
            mu_pp_weakening_mps: self.mu_pp_weakening_mps,
        }
    }

    /// Simulates and films every run; noise-free (no noise, drops or outliers) when `clean`.
    pub fn render(&self, clean: bool) -> Vec<RecordedRun> {
        self.runs
            .iter()
            .enumerate()
            .map(|(i, run)| {
                // a little past the last frame: a time base error or the kick's fraction of a
                // frame may put the last true frame time beyond the nominal duration
                let span = run.duration_s * 1.1 + 2.0 / self.camera.fps;
                let fines = if run.experiment == "collision" {
                    let (f, _) = simulate_pair(
                        [&run.physics[0], &run.physics[1]],
                        &self.pair_model(run),
                        run.z0,
                        run.v0,
                        span,
                        DT_S,
                    );
                    f.to_vec()
                } else {
                    vec![simulate(&run.physics[0], run.z0[0], run.v0, span, DT_S)]
                };
                let mut rng = ChaCha8Rng::seed_from_u64(
                    self.seed ^ (0x9e37_79b9_7f4a_7c15u64.wrapping_mul(i as u64 + 1)),
                );
                let tracks: Vec<Vec<Frame>> = fines
                    .iter()
                    .map(|f| {
                        let noise = if clean {
                            None
                        } else {
                            Some((&self.noise, &mut rng))
                        };
                        self.camera.film(f, run.frac, run.duration_s, noise)
                    })
                    .collect();
                let m = &self.materials[run.material];
                RecordedRun {
                    run: run.id.clone(),
                    experiment: run.experiment.to_string(),
                    material: m.name.to_string(),
                    diameter_m: m.diameter_m,
                    fps: self.camera.fps,
                    setup: run.setup.to_string(),
                    tracks,
                }
            })
            .collect()
    }
}
