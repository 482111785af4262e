//! Writes a dataset in the interchange format: runs.csv and trajectories.csv in one folder.

use super::camera::Frame;
use std::fmt::Write as _;
use std::path::Path;

/// One recorded run and its tracks (one for a single run, striker then target for a collision).
#[derive(Clone, Debug)]
pub struct RecordedRun {
    pub run: String,
    /// `single` or `collision`.
    pub experiment: String,
    pub material: String,
    pub diameter_m: f64,
    pub fps: f64,
    /// `rolling` or `contact` for collisions, empty for single runs.
    pub setup: String,
    pub tracks: Vec<Vec<Frame>>,
}

/// Writes `runs.csv` and `trajectories.csv` into `dir` (created if missing).
pub fn write_dataset(dir: &Path, runs: &[RecordedRun]) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut r = String::from("run,experiment,material,diameter_m,fps,setup\n");
    let mut t = String::from("run,particle,frame,t_s,z_m\n");
    for run in runs {
        let _ = writeln!(
            r,
            "{},{},{},{:.6e},{},{}",
            run.run, run.experiment, run.material, run.diameter_m, run.fps, run.setup
        );
        for (p, track) in run.tracks.iter().enumerate() {
            for f in track {
                let _ = writeln!(
                    t,
                    "{},{},{},{:.8},{:.10}",
                    run.run, p, f.frame, f.t_s, f.z_m
                );
            }
        }
    }
    std::fs::write(dir.join("runs.csv"), r)?;
    std::fs::write(dir.join("trajectories.csv"), t)
}
