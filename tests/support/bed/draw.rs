//! Drawing the bench's datasets from one seed: the base experiment, the noise model, and for
//! effect datasets one or two effects sized at 1–10× their detection limit.
//!
//! Index i of the full set: every fourth (i % 4 == 3) is a null (nothing missing), the others
//! cycle through the shapes of [`SHAPES`] in order, so any prefix of the indices is stratified
//! over places, shapes and noise models; every fifth effect dataset holds a second effect.

use super::dataset::{DatasetSpec, Material, RunSpec};
use super::limit::{snr2, Basis, LIMIT_SNR2};
use super::shapes::{Effect, Truth, SHAPES};
use crate::indsim::camera::Camera;
use crate::indsim::model::Physics;
use crate::indsim::noise::Noise;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The bench's master seed.
pub const MASTER_SEED: u64 = 20_261_127;
/// Indices of the full set: 150 with effects, 50 nulls.
pub const FULL: usize = 200;
/// The noise models every dataset draws from.
pub const NOISES: [&str; 7] = [
    "white", "ar1", "drift", "blur", "locked", "outliers", "mixture",
];

/// One drawn case: its dataset, its noise model and the truth of each effect (none: a null).
pub struct Case {
    pub index: usize,
    pub noise: String,
    pub spec: DatasetSpec,
    pub truths: Vec<Truth>,
}

/// How big a dataset is.
#[derive(Clone, Copy, Debug)]
pub struct Size {
    /// Single runs per material.
    pub singles_per_material: usize,
    pub duration_s: f64,
}

/// The size: 60 single runs of 60 ms.
pub const FULL_SIZE: Size = Size {
    singles_per_material: 30,
    duration_s: 0.06,
};
/// The quick subset's size.
pub const QUICK_SIZE: Size = Size {
    singles_per_material: 8,
    duration_s: 0.04,
};

fn noise(label: &str, rng: &mut ChaCha8Rng) -> Noise {
    let sigma = rng.random_range(0.5e-6..2e-6);
    let mut n = Noise {
        label: label.to_string(),
        white_m: sigma,
        ..Noise::default()
    };
    let ar1 = |rng: &mut ChaCha8Rng| Some((sigma, rng.random_range(0.5..0.9)));
    let blur = |rng: &mut ChaCha8Rng| Some((sigma, rng.random_range(0.02..0.05)));
    let lock = |rng: &mut ChaCha8Rng| {
        Some((
            5e-6,
            rng.random_range(0.2..0.6),
            if rng.random::<bool>() {
                0.25e-6
            } else {
                0.5e-6
            },
        ))
    };
    let outliers = |rng: &mut ChaCha8Rng| {
        Some((
            rng.random_range(0.002..0.01),
            rng.random_range(10e-6..50e-6),
        ))
    };
    match label {
        "white" => {}
        "ar1" => {
            n.white_m = 0.3 * sigma;
            n.ar1 = ar1(rng);
        }
        "drift" => {
            n.drift = Some((
                sigma * rng.random_range(0.5..1.5),
                rng.random_range(5e-3..30e-3),
            ))
        }
        "blur" => n.blur = blur(rng),
        "locked" => n.lock = lock(rng),
        "outliers" => n.outliers = outliers(rng),
        _ => {
            n.ar1 = ar1(rng);
            n.blur = blur(rng);
            if rng.random::<bool>() {
                n.lock = lock(rng);
            }
            n.outliers = outliers(rng);
        }
    }
    n
}

/// The base experiment: two materials, single runs both ways, and collision runs if asked.
fn base(
    seed: u64,
    size: Size,
    collisions: bool,
    noise: Noise,
    rng: &mut ChaCha8Rng,
) -> DatasetSpec {
    let materials = vec![
        Material {
            name: "316",
            diameter_m: 3e-4,
            restitution_rolling: (0.45, 0.06),
            restitution_contact: (0.7, 0.1),
        },
        Material {
            name: "440c",
            diameter_m: 3e-4,
            restitution_rolling: (0.3, 0.05),
            restitution_contact: (0.8, 0.15),
        },
    ];
    let mus = [0.337, 0.293];
    let ts = [
        rng.random_range(0.045..0.065),
        rng.random_range(0.045..0.065),
    ];
    let fov = 12e-3;
    let mut runs = Vec::new();
    for m in 0..2 {
        for i in 0..size.singles_per_material {
            let dir = if rng.random::<bool>() { 1.0 } else { -1.0 };
            let v0 = dir * rng.random_range(0.005..0.1);
            let margin = rng.random_range(0.5e-3..1.5e-3);
            let z0 = if dir > 0.0 { margin } else { fov - margin };
            let ph = Physics::baseline(mus[m], ts[m]);
            runs.push(RunSpec {
                id: format!("single-{}-{:03}", materials[m].name, i + 1),
                experiment: "single",
                setup: "",
                material: m,
                physics: [ph.clone(), ph],
                z0: [z0, z0],
                v0,
                frac: rng.random::<f64>(),
                duration_s: size.duration_s,
            });
        }
    }
    if collisions {
        for i in 0..12 {
            let (m, setup, gap, (lo, hi)) = if i < 6 {
                (0, "rolling", 1e-3, (0.06, 0.12))
            } else {
                (1, "contact", 0.0, (0.03, 0.3))
            };
            let dir = if rng.random::<bool>() { 1.0 } else { -1.0 };
            let margin = rng.random_range(0.5e-3..1.5e-3);
            let z0 = if dir > 0.0 { margin } else { fov - margin };
            let z1 = z0 + dir * (materials[m].diameter_m + gap);
            let ph = Physics::baseline(mus[m], ts[m]);
            runs.push(RunSpec {
                id: format!("{setup}-{}-{:03}", materials[m].name, i + 1),
                experiment: "collision",
                setup,
                material: m,
                physics: [ph.clone(), ph],
                z0: [z0, z1],
                v0: dir * rng.random_range(lo..hi),
                frac: rng.random::<f64>(),
                duration_s: size.duration_s,
            });
        }
    }
    let camera = Camera {
        fps: 10_000.0,
        time_error: 0.0,
        fov_m: fov,
        dropped_rate: rng.random_range(0.001..0.005),
        outliers: (5e-4, 30e-6),
        scale_error: 0.0,
        distortion: 0.0,
    };
    DatasetSpec {
        seed,
        materials,
        runs,
        camera,
        noise,
        mu_pp: 1.4,
        pair_force: None,
        restitution_law: None,
        mu_pp_weakening_mps: None,
    }
}

/// Sizes `effect` to `multiple` × its detection limit in `base` (a few passes: the change is
/// nearly linear in the size), within its plausible range, and returns the multiple reached.
fn size_to(effect: &mut Effect, base: &DatasetSpec, basis: &Basis, multiple: f64) -> f64 {
    let target = LIMIT_SNR2.sqrt() * multiple;
    let clean = base.render(true);
    for _ in 0..3 {
        let mut with = base.clone();
        effect.apply(&mut with);
        let snr = snr2(basis, base, &clean, &with).sqrt();
        if !(snr > 0.0) {
            return 0.0;
        }
        effect.size = (effect.size * target / snr).min(effect.plausible_max());
    }
    let mut with = base.clone();
    effect.apply(&mut with);
    snr2(basis, base, &clean, &with).sqrt() / LIMIT_SNR2.sqrt()
}

/// Draws case `index` at dataset size `size`.
pub fn draw(index: usize, size: Size) -> Case {
    let seed = MASTER_SEED
        .wrapping_mul(1_000_003)
        .wrapping_add(index as u64);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let null = index % 4 == 3;
    let e = index - (index + 1) / 4; // the effect counter (for nulls: the effects before it)
    let k = index / 4; // the null counter
    let shape = e % SHAPES.len();
    let label = if null {
        NOISES[k % NOISES.len()]
    } else {
        NOISES[(e + e / SHAPES.len()) % NOISES.len()]
    };
    let noise = noise(label, &mut rng);
    let mut shapes = Vec::new();
    if !null {
        shapes.push(shape);
        if e % 5 == 4 {
            // a second effect that does not replace the first (one friction law, one drag law)
            let slot = |s: usize| match SHAPES[s] {
                ("friction", _) => "friction",
                ("pair", _) => "pair",
                (_, "quadratic_drag" | "saturating_drag" | "size_spread") => "drag",
                _ => SHAPES[s].1,
            };
            loop {
                let second = (shape + 1 + rng.random_range(0..SHAPES.len() - 1)) % SHAPES.len();
                if slot(second) != slot(shape) {
                    shapes.push(second);
                    break;
                }
            }
        }
    }
    let pair = shapes.iter().any(|&s| SHAPES[s].0 == "pair") || (null && k % 3 == 2);
    let drawn: Vec<(usize, Option<f64>)> = shapes.into_iter().map(|s| (s, None)).collect();
    build(index, label, noise, size, pair, &drawn, &mut rng, seed)
}

/// A case made to order (for tests): `shapes` are (index in [`SHAPES`], multiple of the
/// detection limit), the noise model one of [`NOISES`]; collision runs when a shape is a pair's
/// or `collisions`.
pub fn case(
    seed: u64,
    size: Size,
    noise_label: &str,
    shapes: &[(usize, f64)],
    collisions: bool,
) -> Case {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let noise = noise(noise_label, &mut rng);
    let pair = collisions || shapes.iter().any(|&(s, _)| SHAPES[s].0 == "pair");
    let given: Vec<(usize, Option<f64>)> = shapes.iter().map(|&(s, m)| (s, Some(m))).collect();
    build(
        seed as usize,
        noise_label,
        noise,
        size,
        pair,
        &given,
        &mut rng,
        seed,
    )
}

#[allow(clippy::too_many_arguments)]
fn build(
    index: usize,
    label: &str,
    noise: Noise,
    size: Size,
    pair: bool,
    shapes: &[(usize, Option<f64>)],
    rng: &mut ChaCha8Rng,
    seed: u64,
) -> Case {
    let base = base(seed, size, pair, noise, rng);
    let mut spec = base.clone();
    let mut truths = Vec::new();
    let basis = if shapes.is_empty() {
        None
    } else {
        Some(Basis::new(&base))
    };
    for &(s, want) in shapes {
        let mut effect = Effect::draw(s, base.runs.len(), rng);
        // drawn log-uniformly in 1–10× unless given
        let want = want.unwrap_or_else(|| (10f64.ln() * rng.random::<f64>()).exp());
        let got = size_to(
            &mut effect,
            &base,
            basis.as_ref().expect("an effect dataset has a basis"),
            want,
        );
        effect.apply(&mut spec);
        truths.push(effect.truth(&base, got));
    }
    Case {
        index,
        noise: label.to_string(),
        spec,
        truths,
    }
}
