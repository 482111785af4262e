//! The bench's results file (one JSON record per dataset, appended) and its tables: per place,
//! per shape and per noise model.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One dataset's result.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Record {
    pub index: usize,
    pub quick: bool,
    pub noise: String,
    /// Empty for a null.
    pub places: Vec<String>,
    pub shapes: Vec<String>,
    /// Each effect's size in units of its detection limit.
    pub multiples: Vec<f64>,
    /// Each effect's true sizes (parameter, value).
    #[serde(default)]
    pub sizes: Vec<Vec<(String, f64)>>,
    /// `ok`, or why the pipeline did not complete.
    pub status: String,
    pub named: bool,
    pub sized: bool,
    pub false_accept: bool,
    /// The accepted findings: `place/effect: form`.
    pub accepted: Vec<String>,
    /// Each accepted finding's parameters (name, value), in the order of `accepted`: what the
    /// sizes are read from, kept to see the estimates' bias and scatter beside the truths.
    #[serde(default)]
    pub estimates: Vec<Vec<(String, f64)>>,
    /// The discover stage's time (s), when the run reported it.
    pub discover_s: Option<f64>,
    /// The whole pipeline's time (s).
    pub run_s: f64,
}

#[derive(Default)]
struct Tally {
    n: usize,
    named: usize,
    sized: usize,
    strong: usize,
    strong_named: usize,
    strong_sized: usize,
    nulls: usize,
    false_accepts: usize,
    failed: usize,
    times: Vec<f64>,
}

impl Tally {
    fn add(&mut self, r: &Record) {
        if r.status != "ok" {
            self.failed += 1;
        }
        if let Some(t) = r.discover_s {
            self.times.push(t);
        }
        if r.shapes.is_empty() {
            self.nulls += 1;
            self.false_accepts += r.false_accept as usize;
            return;
        }
        self.n += 1;
        self.named += r.named as usize;
        self.sized += r.sized as usize;
        if r.multiples.iter().all(|&m| m >= 3.0) {
            self.strong += 1;
            self.strong_named += r.named as usize;
            self.strong_sized += r.sized as usize;
        }
    }

    fn row(&self, key: &str) -> String {
        let frac = |a: usize, b: usize| {
            if b == 0 {
                "–".to_string()
            } else {
                format!("{a}/{b}")
            }
        };
        let mut t = self.times.clone();
        t.sort_by(f64::total_cmp);
        let med = if t.is_empty() {
            "–".to_string()
        } else {
            format!("{:.1}", t[t.len() / 2])
        };
        let max = t.last().map_or("–".to_string(), |m| format!("{m:.1}"));
        format!(
            "| {key} | {} | {} | {} | {} | {} | {} | {} | {med} | {max} |",
            frac(self.named, self.n),
            frac(self.sized, self.n),
            frac(self.strong_named, self.strong),
            frac(self.strong_sized, self.strong),
            frac(self.false_accepts, self.nulls),
            self.failed,
            self.n + self.nulls,
        )
    }
}

const HEADER: &str = "| named right | sized within 15 % | named right at ≥ 3× limit | sized at ≥ 3× limit | false accepts (nulls) | failed | datasets | discover s median | discover s max |\n";

fn table(title: &str, key: &str, groups: &BTreeMap<String, Tally>) -> String {
    let mut s = format!("\n{title}\n\n| {key} {HEADER}|---|---|---|---|---|---|---|---|---|---|\n");
    for (k, t) in groups {
        let _ = writeln!(s, "{}", t.row(k));
    }
    s
}

/// The tables of a set of records (the last record of each index counts).
pub fn tables(records: &[Record]) -> String {
    let mut last: BTreeMap<(bool, usize), &Record> = BTreeMap::new();
    for r in records {
        last.insert((r.quick, r.index), r);
    }
    let (mut all, mut place, mut shape, mut noise) = (
        Tally::default(),
        BTreeMap::new(),
        BTreeMap::new(),
        BTreeMap::new(),
    );
    for r in last.values() {
        all.add(r);
        let (p, s) = match r.shapes.len() {
            0 => ("null".to_string(), "null".to_string()),
            1 => (
                r.places[0].clone(),
                format!("{}: {}", r.places[0], r.shapes[0]),
            ),
            _ if r.places[0] == r.places[1] => (
                "two effects, one place".to_string(),
                "two effects".to_string(),
            ),
            _ => (
                "two effects, two places".to_string(),
                "two effects".to_string(),
            ),
        };
        place.entry(p).or_insert_with(Tally::default).add(r);
        shape.entry(s).or_insert_with(Tally::default).add(r);
        noise
            .entry(r.noise.clone())
            .or_insert_with(Tally::default)
            .add(r);
    }
    let mut total = BTreeMap::new();
    total.insert("all".to_string(), all);
    let mut s = table("All datasets", "set", &total);
    s += &table("Per place", "place", &place);
    s += &table("Per shape", "shape", &shape);
    s += &table("Per noise model", "noise", &noise);
    s
}

/// Reads a results file (missing: no records); a line that does not parse is an error naming it.
pub fn read(path: &std::path::Path) -> Result<Vec<Record>, String> {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(Vec::new()),
        Err(e) => return Err(format!("cannot read {}: {e}", path.display())),
    };
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(i, l)| {
            serde_json::from_str(l).map_err(|e| {
                format!(
                    "{} line {}: {e}; delete the line to rerun that dataset",
                    path.display(),
                    i + 1
                )
            })
        })
        .collect()
}
