//! `groove init [DIR]`: a new project: the built-in pipeline.toml, an empty dataset folder with
//! the interchange headers, and a .gitignore for the store. Refuses to overwrite anything.

use groove::engine::EngineError;
use std::path::Path;

/// The headers of the interchange format's two files (README, "Dataset format").
const RUNS_HEADER: &str = "run,experiment,material,diameter_m,fps,setup,v0_laser_mps\n";
const TRAJECTORIES_HEADER: &str = "run,particle,frame,t_s,z_m\n";

/// Writes the project's files into `dir` (made if missing); lists what it wrote.
pub fn init(dir: &Path, pipeline: &str) -> Result<Vec<String>, EngineError> {
    let files: [(&str, &str); 4] = [
        ("pipeline.toml", pipeline),
        ("data/runs.csv", RUNS_HEADER),
        ("data/trajectories.csv", TRAJECTORIES_HEADER),
        (".gitignore", ".groove/\n"),
    ];
    let present: Vec<String> = files
        .iter()
        .map(|(f, _)| dir.join(f))
        .filter(|p| p.exists())
        .map(|p| p.display().to_string())
        .collect();
    if !present.is_empty() {
        return Err(EngineError::Usage(format!(
            "not initialised: {} already exist{}; groove init overwrites nothing (move them away, or init another folder)",
            present.join(", "),
            if present.len() == 1 { "s" } else { "" }
        )));
    }
    let io = |p: &Path, e: std::io::Error| {
        EngineError::Usage(format!("cannot write {}: {e}", p.display()))
    };
    let data = dir.join("data");
    std::fs::create_dir_all(&data).map_err(|e| io(&data, e))?;
    let mut wrote = Vec::new();
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(|e| io(&path, e))?;
        wrote.push(name.to_string());
    }
    Ok(wrote)
}
