//! A trajectories.csv table written as Parquet (for the suites that feed the Parquet reader):
//! `run` as text, `particle` and `frame` as int64, `t_s` and `z_m` as float64 or, to spoil the
//! file, as text.
#![allow(dead_code)]

use polars::prelude::*;

/// The Parquet bytes of a trajectories.csv text (`run,particle,frame,t_s,z_m`); with
/// `numbers_as_text` the `t_s` and `z_m` columns hold their CSV text instead of float64.
pub fn trajectories_parquet(csv: &str, numbers_as_text: bool) -> Vec<u8> {
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let text = |k: usize| rows.iter().map(|r| r[k].to_string()).collect::<Vec<_>>();
    let int = |k: usize| {
        rows.iter()
            .map(|r| r[k].parse::<i64>().unwrap())
            .collect::<Vec<_>>()
    };
    let number = |name: &str, k: usize| {
        if numbers_as_text {
            Column::new(name.into(), text(k))
        } else {
            let x: Vec<f64> = rows.iter().map(|r| r[k].parse().unwrap()).collect();
            Column::new(name.into(), x)
        }
    };
    let mut df = DataFrame::new(
        rows.len(),
        vec![
            Column::new("run".into(), text(0)),
            Column::new("particle".into(), int(1)),
            Column::new("frame".into(), int(2)),
            number("t_s", 3),
            number("z_m", 4),
        ],
    )
    .unwrap();
    let mut bytes = Vec::new();
    ParquetWriter::new(&mut bytes).finish(&mut df).unwrap();
    bytes
}
