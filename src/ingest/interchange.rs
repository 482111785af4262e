//! Reads the interchange format (see the module docs): runs.csv and trajectories.csv (or `.parquet`).

use super::error::Problem;
use super::samples::{RunRow, Sample, SampleFile};
use super::sanity;
use super::table::{Col, Table};
use crate::recording::{Experiment, RunInfo, Setup};
use std::collections::BTreeMap;
use std::sync::Arc;

/// The columns of runs.csv that groove interprets; any other column is kept as text.
const RUN_COLUMNS: [(&str, &str); 5] = [
    ("run", "the unique id of each run"),
    ("experiment", "single or collision"),
    ("material", "e.g. 316"),
    ("diameter_m", "particle diameter in metres"),
    ("fps", "camera frame rate in frames per second"),
];

const TRAJECTORY_COLUMNS: [(&str, &str); 5] = [
    ("run", "a run id from runs.csv"),
    (
        "particle",
        "0 for a single run, 0 striker and 1 target in a collision run",
    ),
    ("frame", "frame index"),
    ("t_s", "seconds since the run's first frame"),
    ("z_m", "position along the groove in metres"),
];

/// The file holding the table `stem` (`runs` or `trajectories`): its CSV or its Parquet form.
pub fn pick<'a>(
    files: &'a BTreeMap<String, Vec<u8>>,
    stem: &str,
    what: &str,
) -> Result<(&'a str, &'a [u8]), Problem> {
    let csv = format!("{stem}.csv");
    let parquet = format!("{stem}.parquet");
    match (files.get_key_value(&csv), files.get_key_value(&parquet)) {
        (Some((name, bytes)), None) | (None, Some((name, bytes))) => {
            Ok((name.as_str(), bytes.as_slice()))
        }
        (Some(_), Some(_)) => Err(Problem::file(
            &csv,
            format!("both {csv} and {parquet} are in the dataset folder"),
            "keep one of them",
        )),
        (None, None) => Err(Problem::file(
            &csv,
            "is missing from the dataset folder",
            format!("add {csv} ({what}; see README, Using it on your data) or {parquet}"),
        )),
    }
}

/// Reads runs.csv. Rows with problems are left out and their problems returned (belonging to the
/// row's run where the run id is readable).
pub fn read_runs(table: &Table) -> Result<(Vec<RunRow>, Vec<Problem>), Problem> {
    table.require(&RUN_COLUMNS)?;
    table.require_numeric(&["diameter_m", "fps"])?;
    let extra_columns: Vec<&String> = table
        .names
        .iter()
        .filter(|n| n.as_str() != "setup" && !RUN_COLUMNS.iter().any(|(c, _)| c == n))
        .collect();
    let (rows, problems) = rows_by_run(table, |i, run| {
        Ok(RunRow {
            info: run_info(table, i, run, &extra_columns)?,
            file: table.file.clone(),
            row: table.row(i),
        })
    });
    Ok((rows, problems))
}

fn run_info(
    table: &Table,
    i: usize,
    run: &str,
    extra_columns: &[&String],
) -> Result<RunInfo, Problem> {
    let experiment_text = table.string("experiment", i, "write single or collision")?;
    let experiment = experiment_of(table, i, &experiment_text)?;
    let material = table.string("material", i, "write the particle material, e.g. 316")?;
    let diameter_m = positive(table, "diameter_m", i, "the particle diameter in metres")?;
    sanity::diameter(diameter_m).map_err(|(m, fix)| table.problem("diameter_m", i, m, fix))?;
    let fps = positive(
        table,
        "fps",
        i,
        "the camera frame rate in frames per second",
    )?;
    sanity::fps(fps).map_err(|(m, fix)| table.problem("fps", i, m, fix))?;
    let setup = setup_of(table, i)?;
    let extra = extra_of(table, i, extra_columns);
    Ok(RunInfo {
        run: run.to_string(),
        experiment,
        material,
        diameter_m,
        fps,
        setup,
        extra,
    })
}

/// Each row's run id and what `read` makes of the row (a runs table: runs.csv of the
/// interchange format or a tracker manifest). A row without a run id, or that `read` refuses, is
/// left out and its problem kept (belonging to the row's run where the id is readable).
pub fn rows_by_run<T>(
    table: &Table,
    mut read: impl FnMut(usize, &str) -> Result<T, Problem>,
) -> (Vec<T>, Vec<Problem>) {
    let mut rows = Vec::with_capacity(table.height());
    let mut problems = Vec::new();
    for i in 0..table.height() {
        let run = match table.string("run", i, "write the run's id") {
            Ok(r) => r,
            Err(p) => {
                problems.push(p);
                continue;
            }
        };
        if !run_id_ok(&run) {
            problems.push(table.problem(
                "run",
                i,
                format!("run id {run:?} cannot name the run's files (it is `.` or `..`, begins with a dot, or holds a `/`, a `\\` or a control character such as a line break)"),
                "rename the run with letters, digits, `.`, `_` and `-` (e.g. s1 or run_07)",
            ));
            continue;
        }
        match read(i, &run) {
            Ok(row) => rows.push(row),
            Err(p) => problems.push(p.in_run(&run)),
        }
    }
    (rows, problems)
}

/// Whether a run id can name the run's files: not empty, no leading dot (so not `.` or `..`),
/// no separator and no control character.
pub fn run_id_ok(run: &str) -> bool {
    !run.is_empty()
        && !run.starts_with('.')
        && !run.chars().any(|c| c == '/' || c == '\\' || c.is_control())
}

/// The experiment kind `text` written in row `i`'s `experiment` cell.
pub fn experiment_of(table: &Table, i: usize, text: &str) -> Result<Experiment, Problem> {
    match text.to_ascii_lowercase().as_str() {
        "single" => Ok(Experiment::Single),
        "collision" => Ok(Experiment::Collision),
        _ => Err(table.problem(
            "experiment",
            i,
            format!("{text:?} is not a known experiment kind"),
            "write single (one particle) or collision (striker and target)",
        )),
    }
}

/// Row `i`'s optional `setup` cell.
pub fn setup_of(table: &Table, i: usize) -> Result<Option<Setup>, Problem> {
    let Some(s) = table.text("setup", i) else {
        return Ok(None);
    };
    match s.to_ascii_lowercase().as_str() {
        "rolling" => Ok(Some(Setup::Rolling)),
        "contact" => Ok(Some(Setup::Contact)),
        _ => Err(table.problem(
            "setup",
            i,
            format!("{s:?} is not a known setup"),
            "write rolling (the striker rolled in), contact (the pair started touching), or leave it empty",
        )),
    }
}

/// Row `i`'s non-empty cells of the columns groove does not interpret, kept as text.
pub fn extra_of(table: &Table, i: usize, columns: &[&String]) -> BTreeMap<String, String> {
    columns
        .iter()
        .filter_map(|c| table.text(c, i).map(|v| (c.to_string(), v.into_owned())))
        .collect()
}

/// A finite positive number; `what` says what the column holds.
fn positive(table: &Table, column: &str, i: usize, what: &str) -> Result<f64, Problem> {
    let fix = format!("write {what}, a positive number");
    let x = table.float(column, i, &fix)?;
    if x <= 0.0 {
        return Err(table.problem(column, i, format!("{x} is not positive"), fix));
    }
    Ok(x)
}

/// Reads trajectories.csv. Rows with problems are left out and their problems returned.
pub fn read_trajectories(table: &Table) -> Result<(SampleFile, Vec<Problem>), Problem> {
    table.require(&TRAJECTORY_COLUMNS)?;
    table.require_numeric(&["particle", "frame", "t_s", "z_m"])?;
    let cols = TrajectoryColumns {
        run: table.col("run"),
        particle: table.col("particle"),
        frame: table.col("frame"),
        t_s: table.col("t_s"),
        z_m: table.col("z_m"),
    };
    let mut interned: BTreeMap<String, Arc<str>> = BTreeMap::new();
    let mut samples = Vec::with_capacity(table.height());
    let mut problems = Vec::new();
    for i in 0..table.height() {
        let Some(name) = cols.run.text(i) else {
            problems.push(
                cols.run
                    .problem(i, "is empty", "write a run id from runs.csv"),
            );
            continue;
        };
        let run: Arc<str> = match interned.get(name.as_ref()) {
            Some(r) => r.clone(),
            None => {
                let r: Arc<str> = Arc::from(name.as_ref());
                interned.insert(name.into_owned(), r.clone());
                r
            }
        };
        match sample(&cols, i, run.clone(), table.row(i)) {
            Ok(s) => samples.push(s),
            Err(p) => problems.push(p.in_run(&run)),
        }
    }
    Ok((
        SampleFile {
            file: table.file.clone(),
            key_columns: "run, particle, frame",
            frame_column: "frame",
            particle_column: "particle",
            time_column: "t_s",
            position_column: "z_m",
            samples,
        },
        problems,
    ))
}

/// The columns of trajectories.csv, looked up once.
struct TrajectoryColumns<'a> {
    run: Col<'a>,
    particle: Col<'a>,
    frame: Col<'a>,
    t_s: Col<'a>,
    z_m: Col<'a>,
}

fn sample(
    cols: &TrajectoryColumns,
    i: usize,
    run: Arc<str>,
    row: usize,
) -> Result<Sample, Problem> {
    let particle_fix =
        "write 0 for a single run's particle, 0 (striker) or 1 (target) in a collision run";
    let particle = cols.particle.int(i, particle_fix)?;
    let particle = u32::try_from(particle).map_err(|_| {
        cols.particle
            .problem(i, format!("{particle} is not a particle id"), particle_fix)
    })?;
    let frame = cols.frame.int(i, "write the frame index, a whole number")?;
    let t_s = cols.t_s.float(i, "write a finite number in seconds")?;
    let z_m = cols.z_m.float(i, "write a finite number in metres")?;
    Ok(Sample {
        run,
        particle,
        frame,
        t_s,
        z_m,
        row,
    })
}
