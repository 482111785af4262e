//! The truth file of the virtual experiment (TOML): physics, materials, runs, laser and camera.

use crate::physics::{Friction, Groove, Model, PairParams, Restitution, Term};
use crate::recording::{Experiment, Setup};
use serde::{Deserialize, Serialize};

/// Everything `groove synth` needs to make a dataset; see `data/truth/truth.toml` for an example.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Truth {
    /// Seed of every random draw (ChaCha8, one stream per run).
    pub seed: u64,
    pub groove: GrooveSpec,
    #[serde(default)]
    pub physics: PhysicsSpec,
    pub pair: PairSpec,
    pub laser: LaserSpec,
    pub camera: CameraSpec,
    pub materials: Vec<Material>,
    pub runs: Vec<RunGroup>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrooveSpec {
    /// Opening angle θ of the groove (degrees).
    pub theta_deg: f64,
    /// `m R² / I` (5/2 for a solid sphere).
    #[serde(default = "solid_sphere")]
    pub k: f64,
}

fn solid_sphere() -> f64 {
    2.5
}

/// Extra accelerations a(z, v, t) acting on every particle, besides groove friction.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhysicsSpec {
    #[serde(default)]
    pub terms: Vec<Term>,
    /// Give each run its own phase of every `time_periodic_force` (drawn uniformly): a vibration
    /// that is not synchronised with the kick.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub time_phase_per_run: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairSpec {
    /// Particle–particle friction μ_pp.
    pub mu_pp: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaserSpec {
    /// Relative standard deviation of the momentum a pulse gives (0.15 = 15 %).
    pub momentum_scatter: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    pub fps: f64,
    /// Standard deviation of the tracked position (m).
    pub noise_m: f64,
    /// Pixel size in the object plane (m).
    pub pixel_m: f64,
    /// Positions are reported on a grid of `pixel_m / subpixel`.
    pub subpixel: u32,
    /// Probability that a frame is lost.
    pub dropped_frame_rate: f64,
    /// Length of the field of view along the groove (m); positions run from 0 to this.
    pub fov_m: f64,
    /// Probability that a tracked position is an outlier.
    pub outlier_rate: f64,
    /// Standard deviation of an outlier's error (m).
    pub outlier_m: f64,
    /// Range of the (unknown) distance of the kicked particle from the edge of the field of
    /// view it moves away from (m).
    pub start_margin_m: [f64; 2],
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub name: String,
    pub diameter_m: f64,
    pub density_kg_m3: f64,
    /// Particle–groove friction law, e.g. `{ law = "constant", mu = 0.337 }`.
    pub friction: Friction,
    /// C(v_impact) when the striker rolls into a resting target.
    pub restitution_rolling: Restitution,
    /// C(v_impact) when the pair starts in contact.
    pub restitution_contact: Restitution,
}

/// Which way the kicked particle moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Directions {
    /// +z.
    Forward,
    /// −z.
    Backward,
    /// Alternating, starting with +z.
    Both,
}

/// A group of runs of one kind and material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RunGroup {
    pub experiment: Experiment,
    pub material: String,
    pub count: usize,
    /// Range of the nominal (laser-calibrated) kick speed (m/s); spread evenly over the runs.
    pub v0_mps: [f64; 2],
    pub directions: Directions,
    pub duration_s: f64,
    /// Collision runs: `rolling` or `contact`.
    #[serde(default)]
    pub setup: Option<Setup>,
    /// Rolling setup: distance between the surfaces of striker and target at the kick (m).
    #[serde(default)]
    pub gap_m: Option<f64>,
}

impl Truth {
    /// Parse and check a truth file's text.
    pub fn parse(text: &str) -> Result<Truth, String> {
        let truth: Truth =
            toml::from_str(text).map_err(|e| format!("truth file is not valid: {e}"))?;
        truth.check()?;
        Ok(truth)
    }

    fn check(&self) -> Result<(), String> {
        let c = &self.camera;
        if !(c.fps > 0.0 && c.fov_m > 0.0 && c.pixel_m > 0.0 && c.subpixel > 0) {
            return Err("camera: fps, fov_m, pixel_m and subpixel must be positive".into());
        }
        if !(c.start_margin_m[0] >= 0.0 && c.start_margin_m[0] <= c.start_margin_m[1]) {
            return Err("camera.start_margin_m must be [min, max] with 0 ≤ min ≤ max".into());
        }
        for (i, g) in self.runs.iter().enumerate() {
            let twin = self.runs[..i].iter().position(|h| {
                (h.experiment, h.setup, &h.material) == (g.experiment, g.setup, &g.material)
            });
            if let Some(first) = twin {
                return Err(format!(
                    "runs[{i}] repeats the kind and material of runs[{first}]; merge the two groups"
                ));
            }
            if self.material(&g.material).is_none() {
                return Err(format!(
                    "runs[{i}]: material `{}` is not among [[materials]]; add it or fix the name",
                    g.material
                ));
            }
            if !(g.v0_mps[0] > 0.0 && g.v0_mps[0] <= g.v0_mps[1]) {
                return Err(format!(
                    "runs[{i}]: v0_mps must be [min, max] with 0 < min ≤ max"
                ));
            }
            if g.duration_s.is_nan() || g.duration_s <= 0.0 {
                return Err(format!("runs[{i}]: duration_s must be positive"));
            }
            match (g.experiment, g.setup) {
                (Experiment::Collision, None) => {
                    return Err(format!(
                        "runs[{i}]: a collision group needs setup = \"rolling\" or \"contact\""
                    ))
                }
                (Experiment::Single, Some(_)) => {
                    return Err(format!(
                        "runs[{i}]: setup applies to collision runs only; remove it"
                    ))
                }
                (Experiment::Collision, Some(Setup::Rolling)) if g.gap_m.is_none() => {
                    return Err(format!(
                        "runs[{i}]: the rolling setup needs gap_m (e.g. 1.0e-3)"
                    ))
                }
                _ => {}
            }
        }
        Ok(())
    }

    pub fn material(&self, name: &str) -> Option<&Material> {
        self.materials.iter().find(|m| m.name == name)
    }

    pub fn groove(&self) -> Groove {
        Groove {
            s: (0.5 * self.groove.theta_deg).to_radians().sin(),
            k: self.groove.k,
        }
    }

    /// The one-particle model of a material.
    pub fn model(&self, material: &Material) -> Model {
        Model {
            groove: self.groove(),
            friction: material.friction,
            variation: Default::default(),
            terms: self.physics.terms.clone(),
        }
    }

    /// Contact parameters of a pair of `material` in `setup`.
    pub fn pair(&self, material: &Material, setup: Setup) -> PairParams {
        PairParams {
            restitution: match setup {
                Setup::Rolling => material.restitution_rolling,
                Setup::Contact => material.restitution_contact,
            },
            mu_pp: self.pair.mu_pp,
            radius_m: 0.5 * material.diameter_m,
            force: None,
            slip: None,
        }
    }
}
