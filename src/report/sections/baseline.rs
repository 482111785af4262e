//! Section 7 (only when the report stage is given a baseline): this result against an earlier
//! one, number by number, as `groove diff` says it.

use super::{Block, Table};
use crate::report::diff::{shown, with_se, Row};
use crate::report::inputs::ReportData;

/// How many moved estimates the table shows (the largest moves first).
const ROWS: usize = 25;
/// A move this many combined standard errors or more is called significant.
const SIGNIFICANT: f64 = 2.0;

pub fn block(d: &ReportData) -> Option<Block> {
    let diff = d.baseline.as_ref()?;
    let mut b = Block::new("baseline", "7. Compared with the baseline");
    let changed: Vec<&Row> = diff.numbers.iter().filter(|r| r.changed()).collect();
    let mut moved: Vec<&Row> = changed
        .iter()
        .copied()
        .filter(|r| r.sigma.is_some())
        .collect();
    moved.sort_by(|x, y| {
        let size = |r: &Row| r.sigma.map_or(0.0, f64::abs);
        size(y)
            .total_cmp(&size(x))
            .then_with(|| (&x.file, &x.path).cmp(&(&y.file, &y.path)))
    });
    let significant = moved
        .iter()
        .filter(|r| r.sigma.is_some_and(|s| s.abs() >= SIGNIFICANT))
        .count();
    b.para(format!(
        "This run's summary.json and diagnosis.json against the baseline's: {} of {} numbers changed; {} of the {} estimates with a standard error that changed moved by {SIGNIFICANT} or more combined standard errors √(se_baseline² + se_now²).",
        changed.len(),
        diff.numbers.len(),
        significant,
        moved.len()
    ));
    let list = |v: &[String]| match v {
        [] => "none".to_string(),
        v => v.join(", "),
    };
    b.para(format!(
        "Accepted findings that appeared: {}; that disappeared: {}.",
        list(&diff.findings_appeared),
        list(&diff.findings_disappeared)
    ));
    if moved.is_empty() {
        return Some(b);
    }
    let mut t = Table::new(
        "Estimates that moved, the largest moves first",
        &[
            "file",
            "number",
            "baseline",
            "now",
            "change",
            "σ of the change",
        ],
    );
    for r in moved.iter().take(ROWS) {
        t.push(vec![
            r.file.clone(),
            r.path.clone(),
            with_se(r.a, r.a_se),
            with_se(r.b, r.b_se),
            shown(r.change),
            r.sigma.map_or("—".into(), |s| format!("{s:+.2}")),
        ]);
    }
    b.table(t);
    if moved.len() > ROWS {
        b.para(format!(
            "{} more estimates moved less; `groove diff BASELINE reports` lists every number.",
            moved.len() - ROWS
        ));
    }
    Some(b)
}
