//! One run of the virtual experiment: its random draws, its simulation, its recording.

use super::camera::{record, Row};
use super::truth::{Directions, RunGroup, Truth};
use crate::physics::{simulate, simulate_pair, State};
use crate::recording::{Experiment, Setup};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// A simulated and recorded run.
pub(crate) struct SynthRun {
    pub id: String,
    pub experiment: Experiment,
    pub material: String,
    pub diameter_m: f64,
    pub setup: Option<Setup>,
    /// The kick speed the laser calibration promises (the actual one scatters around it).
    pub v0_laser_mps: f64,
    /// Time of the first frame after the kick (s), within the first frame period.
    pub t_first_frame_s: f64,
    /// True initial state of each particle at the kick, in camera coordinates.
    pub init: Vec<State>,
    pub rows: Vec<Row>,
}

/// Simulate run `j` of group `group` (global index `index` picks the random stream).
pub(crate) fn synth_run(truth: &Truth, group: &RunGroup, j: usize, index: usize) -> SynthRun {
    let mut rng = ChaCha8Rng::seed_from_u64(truth.seed);
    rng.set_stream(index as u64);
    let material = truth
        .material(&group.material)
        .expect("checked by Truth::parse");
    let cam = &truth.camera;
    // draws, always in this order
    let u_speed: f64 = rng.random();
    let scatter: f64 = StandardNormal.sample(&mut rng);
    let u_margin: f64 = rng.random();
    let u_first: f64 = rng.random();

    let [lo, hi] = group.v0_mps;
    let v0_laser = lo + (j as f64 + u_speed) / group.count as f64 * (hi - lo);
    let v0 = v0_laser * (1.0 + truth.laser.momentum_scatter * scatter).max(0.2);
    let forward = match group.directions {
        Directions::Forward => true,
        Directions::Backward => false,
        Directions::Both => j.is_multiple_of(2),
    };
    let dir = if forward { 1.0 } else { -1.0 };
    let margin = cam.start_margin_m[0] + u_margin * (cam.start_margin_m[1] - cam.start_margin_m[0]);
    let z_kick = if forward { margin } else { cam.fov_m - margin };
    let t_first = u_first / cam.fps;
    let frames = (group.duration_s * cam.fps).round() as usize;
    let t: Vec<f64> = (0..frames).map(|k| t_first + k as f64 / cam.fps).collect();
    let mut model = truth.model(material);
    if truth.physics.time_phase_per_run {
        // drawn only when asked for, after the other draws, so other datasets keep their streams
        let u_phase: f64 = rng.random();
        for term in &mut model.terms {
            if let crate::physics::Term::TimePeriodicForce { phase_rad, .. } = term {
                *phase_rad += std::f64::consts::TAU * u_phase;
            }
        }
    }
    let striker = State {
        z_m: z_kick,
        v_mps: dir * v0,
        va_mps: 0.0,
    };
    let (init, z_true) = match group.setup {
        None => {
            let tr = simulate(&model, striker, &t);
            (vec![striker], vec![tr.z_m])
        }
        Some(setup) => {
            let pair = truth.pair(material, setup);
            let gap = match setup {
                Setup::Rolling => group.gap_m.unwrap_or(0.0),
                Setup::Contact => 0.0,
            };
            let target = State {
                z_m: z_kick + dir * (material.diameter_m + gap),
                v_mps: 0.0,
                va_mps: 0.0,
            };
            let tr = simulate_pair(&model, &pair, [striker, target], &t);
            let [a, b] = tr.particles;
            (vec![striker, target], vec![a.z_m, b.z_m])
        }
    };
    let rows = record(cam, &z_true, &mut rng);
    let kind = match (group.experiment, group.setup) {
        (Experiment::Single, _) => "single".to_string(),
        (_, Some(Setup::Rolling)) => "rolling".to_string(),
        (_, Some(Setup::Contact)) => "contact".to_string(),
        (_, None) => "collision".to_string(),
    };
    SynthRun {
        id: format!("{kind}-{}-{:03}", group.material, j + 1),
        experiment: group.experiment,
        material: group.material.clone(),
        diameter_m: material.diameter_m,
        setup: group.setup,
        v0_laser_mps: dir * v0_laser,
        t_first_frame_s: t_first,
        init,
        rows,
    }
}
