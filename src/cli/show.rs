//! `groove show STAGE:OUTPUT`: a stored result in readable form, read from the store through the
//! engine's read API (pipeline.lock names the objects of the last run; nothing is written).
//!
//! A recording item (`ingest:runs`) is shown as a line per run (default: the calibration at a
//! glance — samples, duration, span and mean speed), as interchange CSV (`--csv`) or as JSON
//! (`--json`); a JSON item or file (a fit, the summary) as indented JSON; other text as it is.

use super::args::Project;
use groove::engine::context::lock_path;
use groove::engine::lockfile::PipelineLock;
use groove::engine::stage::Artifact;
use groove::engine::status::{self, State};
use groove::engine::store::Store;
use groove::engine::{Catalog, EngineError};
use groove::recording::{item, Recording};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::process::ExitCode;

/// How to print what is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum As {
    Readable,
    Csv,
    Json,
}

/// `show`: prints `target` (STAGE:OUTPUT), or the one `item` of it.
pub fn show(
    catalog: &Catalog,
    project: &Project,
    target: &str,
    item: Option<&str>,
    how: As,
) -> Result<ExitCode, EngineError> {
    let pipeline = super::load(project, catalog)?;
    let Some((stage, output)) = target.split_once(':') else {
        return Err(EngineError::Usage(format!(
            "`{target}` is not STAGE:OUTPUT; e.g. `groove show ingest:runs` (`groove dag` lists the stages and their outputs)"
        )));
    };
    let Some(spec) = pipeline.stages.get(stage) else {
        return Err(pipeline.no_stage(stage));
    };
    if !spec.outputs.contains_key(output) {
        return Err(EngineError::Usage(format!(
            "stage `{stage}` has no output `{output}`; it writes: {}",
            spec.outputs.keys().cloned().collect::<Vec<_>>().join(", ")
        )));
    }
    let lock = PipelineLock::load(&lock_path(&pipeline));
    let Some(stored) = lock.stages.get(stage).and_then(|s| s.outputs.get(output)) else {
        return Err(EngineError::Usage(format!(
            "`{stage}` has not run in this project yet (pipeline.lock names no result of it); run `groove run {stage}` first"
        )));
    };
    let selected: BTreeSet<String> =
        groove::engine::dag::with_ancestors(&pipeline, &[stage.to_string()]);
    if let Ok(statuses) = status::status(catalog, &pipeline, Some(&selected)) {
        if statuses
            .iter()
            .any(|s| s.stage == stage && s.state == State::Stale)
        {
            eprintln!("groove: `{stage}` is stale: this is the result of its last run (`groove status` says why; `groove run {stage}` brings it up to date)");
        }
    }
    let store = Store::at(&pipeline.root);
    let artifact = store.load(stored)?;
    let text = match artifact {
        Artifact::File(bytes) => {
            if let Some(key) = item {
                return Err(EngineError::Usage(format!(
                    "`{target}` is one file, not items; drop --item {key}"
                )));
            }
            render_one(target, &bytes, how)?
        }
        Artifact::Collection(items) => {
            let items: BTreeMap<String, Vec<u8>> = match item {
                Some(key) => {
                    let Some((name, bytes)) = items.get_key_value(key) else {
                        let some: Vec<&str> = items.keys().take(8).map(String::as_str).collect();
                        return Err(EngineError::Usage(format!(
                            "`{target}` has no item `{key}`; its {} items include: {}",
                            items.len(),
                            some.join(", ")
                        )));
                    };
                    BTreeMap::from([(name.clone(), bytes.clone())])
                }
                None => items,
            };
            render_items(target, &items, how)?
        }
        _ => {
            return Err(EngineError::Usage(format!(
                "`{target}` is not stored as a file or items; this is a bug, please report it"
            )))
        }
    };
    print!("{text}");
    Ok(ExitCode::SUCCESS)
}

/// One file: JSON indented, text as it is, anything else said.
fn render_one(name: &str, bytes: &[u8], how: As) -> Result<String, EngineError> {
    if let Ok(v) = serde_json::from_slice::<serde_json::Value>(bytes) {
        return Ok(format!(
            "{}\n",
            serde_json::to_string_pretty(&v).expect("a JSON value serializes")
        ));
    }
    if let Ok(rec) = item::decode(bytes) {
        return render_recordings(&[(name.to_string(), rec)], how);
    }
    match (std::str::from_utf8(bytes), how) {
        (Ok(text), As::Json) => Err(EngineError::Usage(format!(
            "`{name}` is text, not JSON ({} bytes); drop --json to print it",
            text.len()
        ))),
        (Ok(text), _) => Ok(text.to_string()),
        (Err(_), _) => Err(EngineError::Usage(format!(
            "`{name}` is {} bytes of binary data groove has no readable form for",
            bytes.len()
        ))),
    }
}

/// Items: recordings as one table, JSON items as one object keyed by item, text per item.
fn render_items(
    name: &str,
    items: &BTreeMap<String, Vec<u8>>,
    how: As,
) -> Result<String, EngineError> {
    if items.is_empty() {
        return Ok(format!("`{name}` has no items\n"));
    }
    let recordings: Option<Vec<(String, Recording)>> = items
        .iter()
        .map(|(k, b)| item::decode(b).ok().map(|r| (k.clone(), r)))
        .collect();
    if let Some(recs) = recordings {
        return render_recordings(&recs, how);
    }
    let json: Option<BTreeMap<&String, serde_json::Value>> = items
        .iter()
        .map(|(k, b)| serde_json::from_slice(b).ok().map(|v| (k, v)))
        .collect();
    if let Some(json) = json {
        if how == As::Csv {
            return Err(EngineError::Usage(format!(
                "`{name}` holds JSON items; drop --csv (fits as CSV: aggregate:fits_csv)"
            )));
        }
        let v = if json.len() == 1 {
            json.into_values().next().expect("one item")
        } else {
            serde_json::to_value(json).expect("a JSON map serializes")
        };
        return Ok(format!(
            "{}\n",
            serde_json::to_string_pretty(&v).expect("a JSON value serializes")
        ));
    }
    let mut out = String::new();
    for (k, b) in items {
        out.push_str(&render_one(&format!("{name} item {k}"), b, how)?);
    }
    Ok(out)
}

/// Recordings as a table (readable), interchange CSV, or JSON.
fn render_recordings(recs: &[(String, Recording)], how: As) -> Result<String, EngineError> {
    let mut out = String::new();
    match how {
        As::Json => {
            let all: Vec<&Recording> = recs.iter().map(|(_, r)| r).collect();
            let v = match all.as_slice() {
                [one] => serde_json::to_string_pretty(one),
                _ => serde_json::to_string_pretty(&all),
            };
            out = v.expect("a recording serializes");
            out.push('\n');
        }
        As::Csv => {
            out.push_str("run,particle,frame,t_s,z_m\n");
            for (_, r) in recs {
                for t in &r.tracks {
                    for i in 0..t.frame.len() {
                        let _ = writeln!(
                            out,
                            "{},{},{},{:?},{:?}",
                            r.info.run, t.particle, t.frame[i], t.t_s[i], t.z_m[i]
                        );
                    }
                }
            }
        }
        As::Readable => {
            out.push_str("run  experiment  material  diameter_m  fps  particle  samples  duration_s  span_m  mean_speed_mps\n");
            for (_, r) in recs {
                for t in &r.tracks {
                    let n = t.z_m.len();
                    let duration = match n {
                        0 => 0.0,
                        _ => t.t_s[n - 1] - t.t_s[0],
                    };
                    let (lo, hi) = t
                        .z_m
                        .iter()
                        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &z| {
                            (lo.min(z), hi.max(z))
                        });
                    let span = if n == 0 { 0.0 } else { hi - lo };
                    let speed = if duration > 0.0 { span / duration } else { 0.0 };
                    let experiment = match r.info.experiment {
                        groove::recording::Experiment::Single => "single",
                        groove::recording::Experiment::Collision => "collision",
                    };
                    let _ = writeln!(
                        out,
                        "{}  {experiment}  {}  {:e}  {}  {}  {n}  {duration:.4}  {span:.4e}  {speed:.4e}",
                        r.info.run, r.info.material, r.info.diameter_m, r.info.fps, t.particle
                    );
                }
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use groove::recording::{Experiment, RunInfo, Track};

    fn rec() -> Recording {
        Recording {
            info: RunInfo {
                run: "single-1".into(),
                experiment: Experiment::Single,
                material: "316".into(),
                diameter_m: 3e-4,
                fps: 1e4,
                setup: None,
                extra: Default::default(),
            },
            tracks: vec![Track {
                particle: 0,
                frame: vec![0, 1, 3],
                t_s: vec![0.0, 1e-4, 3e-4],
                z_m: vec![1e-3, 1.5e-3, 2e-3],
            }],
        }
    }

    #[test]
    fn recordings_print_as_interchange_csv_and_a_readable_line() {
        let recs = [("single-1".to_string(), rec())];
        let csv = render_recordings(&recs, As::Csv).unwrap();
        assert_eq!(
            csv,
            "run,particle,frame,t_s,z_m\nsingle-1,0,0,0.0,0.001\nsingle-1,0,1,0.0001,0.0015\nsingle-1,0,3,0.0003,0.002\n"
        );
        let table = render_recordings(&recs, As::Readable).unwrap();
        let line = table.lines().nth(1).unwrap();
        assert!(
            line.starts_with("single-1  single  316  3e-4  10000  0  3  0.0003"),
            "{line}"
        );
        // span 1 mm over 0.3 ms
        assert!(line.ends_with("3.3333e0"), "{line}");
    }
}
