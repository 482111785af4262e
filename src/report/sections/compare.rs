//! Section 3.4.1: the compare stage's residuals of the per-run collision fits by phase and by
//! time since the last impact (where an impact model that misses something leaves structure).

use super::{Block, Table};
use crate::artifacts::comparison::GroupStats;
use crate::artifacts::residuals::Phase;
use crate::report::inputs::ReportData;

fn cells(group: String, s: &GroupStats) -> Vec<String> {
    let opt = |x: Option<f64>, digits: usize| x.map_or("—".into(), |x| format!("{x:.digits$}"));
    vec![
        group,
        s.n.to_string(),
        format!("{:.2}", s.rms_m * 1e6),
        format!("{:+.2}", s.mean_m * 1e6),
        opt(s.lag1_autocorr, 2),
        opt(s.runs_test_z, 1),
    ]
}

fn ms(x: f64) -> String {
    format!("{:.0}", x * 1e3)
}

/// The block, or None when the dataset has no compared collision runs.
pub fn block(d: &ReportData) -> Option<Block> {
    let pairs = d.comparison.as_ref()?.pairs.as_ref()?;
    let mut b = Block::new(
        "pair-residuals",
        "3.4.1 Residuals of the collision fits by phase and by time since impact",
    );
    b.para(format!(
        "The compare stage pools the residuals of the piecewise fits of {} (both particles, each piece re-simulated from its fitted start state; outlier frames left out) by the phase of the fitted motion and by the time since the last fitted impact. A group whose RMS or autocorrelation stands out is where the pieces and the impact rule miss something.",
        crate::report::value::count(pairs.n_runs, "collision run")
    ));
    let mut t = Table::new(
        "Residuals of the per-run collision fits (compare stage): by phase, then by time since the last impact",
        &[
            "group",
            "frames",
            "RMS (µm)",
            "mean (µm)",
            "lag-1 autocorrelation",
            "runs-test z",
        ],
    );
    for (phase, s) in &pairs.by_phase {
        let name = match phase {
            Phase::Sliding => "sliding",
            Phase::Rolling => "rolling",
            Phase::Rest => "at rest",
        };
        t.push(cells(format!("phase: {name}"), s));
    }
    if pairs.before_first_impact.n > 0 {
        t.push(cells(
            "before the first impact".into(),
            &pairs.before_first_impact,
        ));
    }
    for bin in &pairs.by_time_since_impact {
        let label = match bin.hi {
            Some(hi) => format!("{}–{} ms after an impact", ms(bin.lo), ms(hi)),
            None => format!("≥ {} ms after an impact", ms(bin.lo)),
        };
        t.push(cells(label, &bin.stats));
    }
    t.folded = true;
    b.table(t);
    Some(b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::artifacts::comparison::{Bin, Comparison, PairResiduals};
    use crate::report::sections::Item;
    use std::collections::BTreeMap;

    fn stats(n: usize, rms_m: f64) -> GroupStats {
        GroupStats {
            n,
            mean_m: 0.0,
            rms_m,
            lag1_autocorr: Some(0.1),
            runs_test_z: None,
        }
    }

    #[test]
    fn the_table_lists_phases_then_times_since_impact() {
        let mut d = ReportData::default();
        assert!(block(&d).is_none(), "no comparison: no block");
        let pairs = PairResiduals {
            n_runs: 3,
            by_phase: BTreeMap::from([(Phase::Sliding, stats(10, 2e-6))]),
            before_first_impact: stats(4, 1e-6),
            by_time_since_impact: vec![
                Bin {
                    lo: 0.0,
                    hi: Some(1e-3),
                    stats: stats(5, 3e-6),
                },
                Bin {
                    lo: 20e-3,
                    hi: None,
                    stats: stats(7, 1.5e-6),
                },
            ],
        };
        d.comparison = Some(Comparison {
            n_runs: 3,
            skipped: BTreeMap::new(),
            n_frames: 26,
            n_outliers: 0,
            overall: stats(26, 2e-6),
            by_phase: BTreeMap::new(),
            by_speed: vec![],
            by_position: vec![],
            by_direction: BTreeMap::new(),
            by_material: BTreeMap::new(),
            by_experiment: BTreeMap::new(),
            by_run: BTreeMap::new(),
            pairs: Some(pairs),
        });
        let b = block(&d).unwrap();
        let t = b
            .items
            .iter()
            .find_map(|i| match i {
                Item::Table(t) => Some(t),
                _ => None,
            })
            .unwrap();
        let firsts: Vec<&str> = t.rows.iter().map(|r| r[0].as_str()).collect();
        assert_eq!(
            firsts,
            [
                "phase: sliding",
                "before the first impact",
                "0–1 ms after an impact",
                "≥ 20 ms after an impact"
            ]
        );
        assert_eq!(t.rows[2][1], "5");
        assert_eq!(t.rows[2][2], "3.00");
        assert_eq!(t.rows[0][4], "0.10");
        assert_eq!(t.rows[0][5], "—");
    }
}
