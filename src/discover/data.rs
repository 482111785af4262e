//! The runs discovery works on: single-particle tracks, sorted, with the run's material and noise weight.

use crate::recording::{Experiment, Recording, T_MAX_S, Z_MAX_M};

/// Number of per-run parameters: z0 (m), t0 (s, kick before the first frame), v0 (m/s).
pub const N_LOCAL: usize = 3;

/// One single-particle run prepared for joint fitting.
#[derive(Clone, Debug)]
pub struct RunData {
    pub run: String,
    /// Index into the sorted list of materials.
    pub material: usize,
    pub fps: f64,
    /// Sample times since the first frame, sorted ascending.
    pub t_s: Vec<f64>,
    /// Observed positions in the lab frame.
    pub z_m: Vec<f64>,
    /// False for samples flagged as tracking outliers (left out of every fit).
    pub keep: Vec<bool>,
    /// Noise scale of the run (metres), from its own baseline fit; 1 µm until measured.
    pub sigma_m: f64,
    /// The shape of the run's fast noise (`noise.rs`): white until measured.
    pub fast: super::noise_model::Fast,
    /// The fast noise's σ at each kept sample over `sigma_m` when it grows with speed
    /// (`blur.rs`); empty is 1 everywhere.
    pub scale: Vec<f64>,
    /// The dataset's slow tracking noise (`slow_noise.rs`); none until measured.
    pub slow: super::noise_model::Slow,
}

impl RunData {
    /// The noise the run carries, as every test's null draws it.
    pub fn noise(&self) -> super::noise_model::RunNoise<'_> {
        super::noise_model::RunNoise {
            fast: self.fast,
            slow: self.slow,
            scale: &self.scale,
        }
    }

    /// Number of samples used in fits.
    pub fn n_used(&self) -> usize {
        self.keep.iter().filter(|k| **k).count()
    }
}

/// The single-particle runs of `recordings` with at least `min_frames` samples, sorted by run id,
/// and the sorted list of materials. Rows are sorted by time here, so input order never matters.
pub fn prepare_runs(recordings: &[Recording], min_frames: usize) -> (Vec<RunData>, Vec<String>) {
    let mut materials: Vec<String> = recordings
        .iter()
        .filter(|r| r.info.experiment == Experiment::Single)
        .map(|r| r.info.material.clone())
        .collect();
    materials.sort();
    materials.dedup();
    let mut runs = Vec::new();
    for rec in recordings {
        if rec.info.experiment != Experiment::Single {
            continue;
        }
        let Some(track) = rec.track(0).or_else(|| rec.tracks.first()) else {
            continue;
        };
        let mut rows: Vec<(f64, f64)> = track
            .t_s
            .iter()
            .zip(&track.z_m)
            // only what ingest lets through: finite, and within its plausible range
            .filter(|(t, z)| t.abs() <= T_MAX_S && z.abs() <= Z_MAX_M)
            .map(|(t, z)| (*t, *z))
            .collect();
        if rows.len() < min_frames {
            continue;
        }
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        rows.dedup_by(|a, b| a.0 == b.0);
        let t0 = rows[0].0;
        let material = materials
            .binary_search(&rec.info.material)
            .expect("material collected above");
        runs.push(RunData {
            run: rec.info.run.clone(),
            material,
            fps: rec.info.fps,
            t_s: rows.iter().map(|r| r.0 - t0).collect(),
            z_m: rows.iter().map(|r| r.1).collect(),
            keep: vec![true; rows.len()],
            sigma_m: 1e-6,
            fast: Default::default(),
            scale: Vec::new(),
            slow: Default::default(),
        });
    }
    runs.sort_by(|a, b| a.run.cmp(&b.run));
    (runs, materials)
}
