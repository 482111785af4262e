//! The catalogue of effects the bench draws from: where each enters (force, friction,
//! measurement, particles, pair), how it changes a dataset, and its truth (the form names a
//! finding may carry and the sizes it should report).

use super::dataset::DatasetSpec;
use crate::indsim::effects::{Drag, Force, FrictionLaw};
use crate::indsim::pair::Between;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Every shape: (place, name). The bench cycles through them in this order.
pub const SHAPES: [(&str, &str); 24] = [
    ("force", "quadratic_drag"),
    ("friction", "mu_slip_rising"),
    ("measurement", "scale"),
    ("particles", "mu_spread"),
    ("force", "saturating_drag"),
    ("pair", "pair_force"),
    ("force", "resistance"),
    ("friction", "mu_position"),
    ("force", "tilt"),
    ("measurement", "distortion"),
    ("force", "periodic_z"),
    ("friction", "mu_slip_falling"),
    ("force", "localized_z"),
    ("particles", "size_spread"),
    ("force", "step_z"),
    ("friction", "mu_direction"),
    ("force", "field_z"),
    ("measurement", "time_base"),
    ("force", "time_common_phase"),
    ("friction", "mu_patch"),
    ("force", "time_run_phase"),
    ("friction", "mu_material"),
    ("force", "speed_bump"),
    ("pair", "pair_force_attractive"),
];

/// One drawn effect: its shape, its drawn shape parameters and its size.
#[derive(Clone, Debug)]
pub struct Effect {
    pub shape: usize,
    pub params: Vec<f64>,
    pub size: f64,
}

/// What a finding must say to be right about one effect.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Truth {
    pub place: String,
    pub shape: String,
    /// A finding's form (lowercased) must contain one of these.
    pub forms: Vec<String>,
    /// (parameter name or prefix, true value): every parameter of the finding whose name starts
    /// with it must be within 15 % of the value.
    pub sizes: Vec<(String, f64)>,
    /// The size in units of the detection limit.
    pub multiple: f64,
    /// The size was held at its plausible maximum (see `Effect::plausible_max`), so `multiple`
    /// may lie below 1: the effect is below what these data can show.
    #[serde(default)]
    pub at_plausible_max: bool,
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

fn sign(rng: &mut ChaCha8Rng) -> f64 {
    if rng.random::<bool>() {
        1.0
    } else {
        -1.0
    }
}

fn log_uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi / lo).ln()).exp()
}

impl Effect {
    pub fn place(&self) -> &'static str {
        SHAPES[self.shape].0
    }

    pub fn name(&self) -> &'static str {
        SHAPES[self.shape].1
    }

    /// Draws the shape's parameters (all but the size); `runs` bounds the per-run draws.
    pub fn draw(shape: usize, runs: usize, rng: &mut ChaCha8Rng) -> Effect {
        let tau = std::f64::consts::TAU;
        let params = match SHAPES[shape].1 {
            "periodic_z" => vec![log_uniform(rng, 0.5e-3, 8e-3), tau * rng.random::<f64>()],
            "localized_z" => vec![
                rng.random_range(2e-3..10e-3),
                rng.random_range(0.2e-3..1e-3),
                sign(rng),
            ],
            "step_z" => vec![rng.random_range(3e-3..9e-3), sign(rng)],
            "field_z" => (0..5)
                .flat_map(|_| {
                    [
                        log_uniform(rng, 1e-3, 10e-3),
                        tau * rng.random::<f64>(),
                        normal(rng),
                    ]
                })
                .collect(),
            "time_common_phase" => vec![log_uniform(rng, 20.0, 200.0), tau * rng.random::<f64>()],
            "time_run_phase" => {
                let mut p = vec![log_uniform(rng, 20.0, 200.0)];
                p.extend((0..runs).map(|_| tau * rng.random::<f64>()));
                p
            }
            "speed_bump" => vec![rng.random_range(0.01..0.06), rng.random_range(0.005..0.015)],
            "tilt" => vec![sign(rng)],
            "mu_position" => vec![log_uniform(rng, 1e-3, 8e-3), tau * rng.random::<f64>()],
            "mu_patch" => vec![
                rng.random_range(2e-3..7e-3),
                rng.random_range(1e-3..4e-3),
                sign(rng),
            ],
            "mu_slip_falling" => vec![rng.random_range(0.005..0.03)],
            "mu_direction" => vec![sign(rng)],
            "mu_material" => vec![if rng.random::<bool>() { 1.0 } else { 0.0 }],
            "mu_spread" | "size_spread" => (0..runs).map(|_| normal(rng)).collect(),
            "scale" | "distortion" | "time_base" => vec![sign(rng)],
            "pair_force" | "pair_force_attractive" => vec![rng.random_range(50e-6..300e-6)],
            _ => Vec::new(),
        };
        Effect {
            shape,
            params,
            size: Effect::reference_size(shape),
        }
    }

    /// A size of the right order to start the search for the detection limit.
    pub fn reference_size(shape: usize) -> f64 {
        match SHAPES[shape].1 {
            "quadratic_drag" => 20.0,
            "saturating_drag" => 1.0,
            "resistance" => 0.003,
            "tilt" => 0.1,
            "periodic_z" | "step_z" | "field_z" => 0.05,
            "localized_z" | "time_common_phase" | "time_run_phase" | "speed_bump" => 0.2,
            "mu_position" => 0.02,
            "mu_patch" => 0.01,
            "mu_slip_rising" => 0.002,
            "mu_slip_falling" => 0.05,
            "mu_direction" => 0.01,
            "mu_material" => 0.002,
            "mu_spread" => 0.02,
            "size_spread" => 0.05,
            "scale" | "distortion" | "time_base" => 0.005,
            _ => 0.5,
        }
    }

    /// The largest size the experiment makes plausible, where a calibration bounds it: a length
    /// scale or a time base off by more than 5 %, or a distortion of more than 10 % at the image's
    /// edge, would be seen by anyone who calibrates the camera; a friction that falls with slip
    /// speed is at most twice its sliding value at rest (static against kinetic friction); a
    /// patch of friction changes it by half at most.
    /// On single runs the scale and the
    /// time base are μ, T, z0 and v0 over again, so their detection limit may lie beyond it;
    /// the dataset then carries the effect below its limit (its multiple says so).
    pub fn plausible_max(&self) -> f64 {
        match self.name() {
            "scale" | "time_base" => 0.05,
            "distortion" => 0.1,
            "mu_slip_falling" => 1.0,
            // a patch that changes the sliding friction by more than half of itself is another
            // groove; where the runs barely slide over the patch the size search ran off to a
            // change of 10⁵ and more (beyond the full set: 217, 249)
            "mu_patch" => 0.15,
            _ => f64::INFINITY,
        }
    }

    /// Puts the effect into a dataset.
    pub fn apply(&self, spec: &mut DatasetSpec) {
        let (x, p) = (self.size, &self.params);
        let force = |spec: &mut DatasetSpec, f: &dyn Fn(usize) -> Force| {
            for (i, run) in spec.runs.iter_mut().enumerate() {
                for ph in run.physics.iter_mut() {
                    ph.forces.push(f(i));
                }
            }
        };
        let friction = |spec: &mut DatasetSpec, law: &dyn Fn(usize) -> Option<FrictionLaw>| {
            for run in spec.runs.iter_mut() {
                if let Some(l) = law(run.material) {
                    for ph in run.physics.iter_mut() {
                        ph.friction = l.clone();
                    }
                }
            }
        };
        match self.name() {
            "quadratic_drag" | "saturating_drag" => {
                for run in spec.runs.iter_mut() {
                    for ph in run.physics.iter_mut() {
                        let t_s = ph.drag.t_s();
                        ph.drag = if self.name() == "quadratic_drag" {
                            Drag::Quadratic { t_s, c_per_m: x }
                        } else {
                            Drag::Saturating {
                                t0_s: t_s,
                                tp_s_per_mps: x,
                            }
                        };
                    }
                }
            }
            "resistance" => force(spec, &|_| Force::Resistance { c: x }),
            "tilt" => force(spec, &|_| Force::Tilt {
                alpha_rad: (p[0] * x).to_radians(),
            }),
            "periodic_z" => force(spec, &|_| Force::Periodic {
                amp: x,
                wavelength_m: p[0],
                phase: p[1],
            }),
            "localized_z" => force(spec, &|_| Force::Localized {
                amp: p[2] * x,
                centre_m: p[0],
                width_m: p[1],
            }),
            "step_z" => force(spec, &|_| Force::Step {
                amp: p[1] * x,
                z_m: p[0],
                width_m: 0.1e-3,
            }),
            "field_z" => {
                let modes = self.field_modes();
                force(spec, &|_| Force::Field {
                    modes: modes.clone(),
                })
            }
            "time_common_phase" => force(spec, &|_| Force::Time {
                amp: x,
                freq_hz: p[0],
                phase: p[1],
            }),
            "time_run_phase" => force(spec, &|i| Force::Time {
                amp: x,
                freq_hz: p[0],
                phase: p[1 + i % (p.len() - 1)],
            }),
            "speed_bump" => force(spec, &|_| Force::SpeedBump {
                amp: x,
                v_c: p[0],
                width: p[1],
            }),
            "mu_slip_rising" => friction(spec, &|_| Some(FrictionLaw::SlipRising { v_c: x })),
            "mu_material" => {
                let m = p[0] as usize;
                friction(spec, &|mat| {
                    (mat == m).then_some(FrictionLaw::SlipRising { v_c: x })
                })
            }
            "mu_position" => friction(spec, &|_| {
                Some(FrictionLaw::Position {
                    delta: x,
                    wavelength_m: p[0],
                    phase: p[1],
                })
            }),
            "mu_patch" => friction(spec, &|_| {
                Some(FrictionLaw::Patch {
                    delta_mu: p[2] * x,
                    z_a: p[0],
                    z_b: p[0] + p[1],
                    edge_m: 0.1e-3,
                })
            }),
            "mu_slip_falling" => friction(spec, &|_| {
                Some(FrictionLaw::SlipFalling {
                    delta: x,
                    v_c: p[0],
                })
            }),
            "mu_direction" => friction(spec, &|_| Some(FrictionLaw::Direction { delta: p[0] * x })),
            "scale" => spec.camera.scale_error = p[0] * x,
            "distortion" => spec.camera.distortion = p[0] * x,
            "time_base" => spec.camera.time_error = p[0] * x,
            "mu_spread" => {
                for (i, run) in spec.runs.iter_mut().enumerate() {
                    for ph in run.physics.iter_mut() {
                        ph.mu *= (1.0 + x * p[i % p.len()]).max(0.2);
                    }
                }
            }
            "size_spread" => {
                // a drag time growing as the radius squared (a viscous drag on a larger sphere)
                for (i, run) in spec.runs.iter_mut().enumerate() {
                    for ph in run.physics.iter_mut() {
                        let r = (1.0 + x * p[i % p.len()]).max(0.2);
                        ph.drag = ph.drag.with_t_s(ph.drag.t_s() * r * r);
                    }
                }
            }
            "pair_force" => {
                spec.pair_force = Some(Between::Screened {
                    amp: x,
                    range: p[0],
                })
            }
            "pair_force_attractive" => {
                spec.pair_force = Some(Between::Screened {
                    amp: -x,
                    range: p[0],
                })
            }
            other => unreachable!("no shape {other}"),
        }
    }

    /// The modes of a random field normalised so that its peak over the field of view is the size.
    fn field_modes(&self) -> Vec<(f64, f64, f64)> {
        let raw: Vec<(f64, f64, f64)> = self
            .params
            .chunks(3)
            .map(|c| (c[2], std::f64::consts::TAU / c[0], c[1]))
            .collect();
        let at = |z: f64| {
            raw.iter()
                .map(|(a, k, ph)| a * (k * z + ph).sin())
                .sum::<f64>()
        };
        let peak = (0..=1200)
            .map(|i| at(i as f64 * 1e-5).abs())
            .fold(0.0, f64::max);
        raw.iter()
            .map(|&(a, k, ph)| (a * self.size / peak, k, ph))
            .collect()
    }

    /// The peak of the random field over the stretches of groove that two single runs or more
    /// of `spec` go through (its size is its peak over the whole field of view, much of which,
    /// between the runs that start at either end, no run may reach).
    fn field_peak_where_runs_go(&self, spec: &DatasetSpec) -> f64 {
        let modes = self.field_modes();
        let stretches: Vec<(f64, f64)> = spec
            .render(true)
            .iter()
            .filter(|r| r.experiment == "single")
            .map(|r| {
                let z = r.tracks.iter().flatten().map(|f| f.z_m);
                (
                    z.clone().fold(f64::INFINITY, f64::min),
                    z.fold(f64::NEG_INFINITY, f64::max),
                )
            })
            .collect();
        (0..=1200)
            .map(|i| i as f64 * 1e-5)
            .filter(|&z| {
                stretches
                    .iter()
                    .filter(|(lo, hi)| *lo <= z && z <= *hi)
                    .count()
                    >= 2
            })
            .map(|z| {
                modes
                    .iter()
                    .map(|(a, k, ph)| a * (k * z + ph).sin())
                    .sum::<f64>()
                    .abs()
            })
            .fold(0.0, f64::max)
    }

    /// The spread the particles of each material of `spec` were given, relative to their mean
    /// (sample standard deviation over the material's single runs): the truth of a finding that
    /// "the particles differ by this much" is the spread of these particles, not the width of
    /// the law they were drawn from (with about 30 runs a material the two differ by about 13 %,
    /// nearly the whole size tolerance). For a size the factor is the radius's.
    fn realized_spread(&self, spec: &DatasetSpec) -> Vec<(usize, f64)> {
        let (x, p) = (self.size, &self.params);
        (0..spec.materials.len())
            .filter_map(|m| {
                let f: Vec<f64> = spec
                    .runs
                    .iter()
                    .enumerate()
                    .filter(|(_, r)| r.material == m && r.experiment == "single")
                    .map(|(i, _)| (1.0 + x * p[i % p.len()]).max(0.2))
                    .collect();
                if f.len() < 2 {
                    return None;
                }
                let n = f.len() as f64;
                let mean = f.iter().sum::<f64>() / n;
                let var = f.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
                Some((m, var.sqrt() / mean))
            })
            .collect()
    }

    /// The truth of this effect in dataset `spec` (before the effect is applied, the runs and
    /// materials are the same after).
    pub fn truth(&self, spec: &DatasetSpec, multiple: f64) -> Truth {
        let materials: Vec<&str> = spec.materials.iter().map(|m| m.name).collect();
        let (x, p) = (self.size, &self.params);
        let s = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let v = |k: &str, x: f64| (k.to_string(), x);
        let (forms, sizes): (Vec<String>, Vec<(String, f64)>) = match self.name() {
            "quadratic_drag" => (s(&["quadratic"]), vec![v("c_per_m", x)]),
            "saturating_drag" => (s(&["saturating"]), vec![v("tp_s_per_mps", x)]),
            "resistance" => (s(&["resistance"]), vec![v("coefficient", x)]),
            "tilt" => (s(&["tilt"]), vec![v("alpha_deg", p[0] * x)]),
            "periodic_z" => (
                s(&["periodic in z"]),
                vec![v("amplitude_mps2", x), v("wavelength_m", p[0])],
            ),
            "localized_z" => (
                s(&["localized in z"]),
                vec![
                    v("amplitude_mps2", p[2] * x),
                    v("centre_m", p[0]),
                    v("width_m", p[1]),
                ],
            ),
            "step_z" => (
                s(&["step in z", "map in z", "spline in z"]),
                vec![v("step_mps2", p[1] * x)],
            ),
            "field_z" => (
                s(&["map in z", "spline in z", "field in z"]),
                vec![v("peak_accel_mps2", self.field_peak_where_runs_go(spec))],
            ),
            "time_common_phase" | "time_run_phase" => (
                s(&["periodic in time"]),
                vec![v("amplitude_mps2", x), v("frequency_hz", p[0])],
            ),
            "speed_bump" => (
                s(&["map in v", "spline in v", "in speed"]),
                vec![v(
                    "peak_accel_mps2",
                    speed_bump_beyond_drag(spec, x, p[0], p[1]),
                )],
            ),
            "mu_slip_rising" => (s(&["mu(u)", "slip speed"]), vec![v("v_c_mps", x)]),
            "mu_material" => {
                let m = materials[p[0] as usize];
                (
                    s(&["mu(u)", "slip speed"]),
                    vec![v(&format!("v_c_mps_{m}"), x)],
                )
            }
            "mu_slip_falling" => (s(&["slip speed", "mu(u)"]), vec![v("delta_mu_rel", x)]),
            "mu_position" => (s(&["in z", "mu(z"]), vec![v("delta_mu_rel", x)]),
            "mu_patch" => (
                s(&["in z", "mu(z", "patch"]),
                vec![v("delta_mu_abs", p[2] * x)],
            ),
            "mu_direction" => (s(&["direction"]), vec![v("delta_mu_rel", p[0] * x)]),
            "scale" => (s(&["scale"]), vec![v("scale_error", p[0] * x)]),
            "distortion" => (
                s(&["distortion"]),
                vec![v("peak_shift_m", distortion_shift(spec, p[0] * x))],
            ),
            "time_base" => (
                s(&["time base", "frame rate", "timing"]),
                vec![v("time_error", p[0] * x)],
            ),
            "mu_spread" | "size_spread" => {
                let (forms, key) = if self.name() == "mu_spread" {
                    (s(&["mu", "friction"]), "mu_sd_rel")
                } else {
                    (s(&["size", "drag", "diameter"]), "size_sd_rel")
                };
                let sizes = self
                    .realized_spread(spec)
                    .into_iter()
                    .map(|(m, sd)| v(&format!("{key}_{}", materials[m]), sd))
                    .collect();
                (forms, sizes)
            }
            "pair_force" | "pair_force_attractive" => (
                s(&["between", "separation"]),
                vec![v("pair_amplitude_mps2", x)],
            ),
            other => unreachable!("no shape {other}"),
        };
        Truth {
            place: self.place().to_string(),
            shape: self.name().to_string(),
            forms,
            sizes,
            multiple,
            at_plausible_max: self.size >= self.plausible_max() * (1.0 - 1e-9),
        }
    }
}

/// The shift a distortion κ about the image centre makes beyond a length scale and an offset,
/// over the stretch of groove the single runs of `spec` are seen on: its peak (signed). The
/// camera puts lab z at c + (z − c)(1 + κu²), u = (z − c)/c, c the image centre; the recordings
/// say neither c nor the field of view, and on the observed stretch z = z_mid + h·x the shift
/// κc·u³ is a cubic in x whose constant and linear parts are each run's offset and a length
/// scale (μ, T, z0 and v0 take them exactly). What is left, a₂P₂(x) + a₃P₃(x) with
/// a₂ = 2κcαβ², a₃ = 2κcβ³/5 (α = (z_mid − c)/c, β = h/c), is all the data can show of κ.
fn distortion_shift(spec: &DatasetSpec, kappa: f64) -> f64 {
    let c = 0.5 * spec.camera.fov_m;
    let image = |z: f64| {
        let u = (z - c) / c;
        c + (z - c) * (1.0 + kappa * u * u)
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for run in spec
        .render(true)
        .iter()
        .filter(|r| r.experiment == "single")
    {
        for f in run.tracks.iter().flatten() {
            lo = lo.min(image(f.z_m));
            hi = hi.max(image(f.z_m));
        }
    }
    let (alpha, beta) = ((0.5 * (lo + hi) - c) / c, 0.5 * (hi - lo) / c);
    let (a2, a3) = (
        2.0 * kappa * c * alpha * beta * beta,
        0.4 * kappa * c * beta.powi(3),
    );
    (0..=400)
        .map(|j| {
            let x = -1.0 + j as f64 / 200.0;
            a2 * 0.5 * (3.0 * x * x - 1.0) + a3 * 0.5 * (5.0 * x.powi(3) - 3.0 * x)
        })
        .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a })
}

/// The peak of a speed bump (amplitude `amp` at speed `v_c`, width `w`) beyond a linear drag,
/// over the speeds two single runs or more of `spec` go through (down to rest from the second
/// fastest kick, both ways). A part proportional to v is a change of the drag time T, which each material's own T
/// takes exactly, so no finding can size it: the truth is the bump less its least-squares line
/// through zero over those speeds, as a map in v is sized.
fn speed_bump_beyond_drag(spec: &DatasetSpec, amp: f64, v_c: f64, w: f64) -> f64 {
    // speeds two runs or more go through: down to the second fastest kick each way
    let mut v0: Vec<f64> = spec
        .runs
        .iter()
        .filter(|r| r.experiment == "single")
        .map(|r| r.v0)
        .collect();
    v0.sort_by(f64::total_cmp);
    let lo = v0.get(1).copied().unwrap_or(0.0).min(0.0);
    let hi = v0.iter().rev().nth(1).copied().unwrap_or(0.0).max(0.0);
    let points: Vec<(f64, f64)> = (0..=200)
        .map(|j| {
            let v = lo + (hi - lo) * j as f64 / 200.0;
            let x = (v.abs() - v_c) / w;
            (v, -amp * v.signum() * (-0.5 * x * x).exp())
        })
        .collect();
    let sxx: f64 = points.iter().map(|(v, _)| v * v).sum();
    let k = points.iter().map(|(v, a)| v * a).sum::<f64>() / sxx;
    points
        .iter()
        .map(|(v, a)| (a - k * v).abs())
        .fold(0.0, f64::max)
}
