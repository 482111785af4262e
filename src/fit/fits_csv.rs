//! fits.csv: one row per single run, sorted by run, fixed float formatting (the output contract).

use super::single::SingleFit;
use std::fmt::Write;

pub use crate::artifacts::fits_table::HEADER;

/// Render fits.csv. Numbers are written as `{:.6e}`; an unknown standard error is an empty field.
pub fn render(fits: &[SingleFit]) -> String {
    let mut rows: Vec<&SingleFit> = fits.iter().collect();
    rows.sort_by(|a, b| a.run.cmp(&b.run));
    let mut out = String::with_capacity(64 * (rows.len() + 1));
    out.push_str(HEADER);
    out.push('\n');
    for f in rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{}",
            field(&f.run),
            field(&f.material),
            num(f.v0_mps),
            opt(f.v0_se),
            num(f.mu),
            opt(f.mu_se),
            num(f.t_drag_s),
            opt(f.t_drag_se),
            num(f.t1_s),
            num(f.rms_m),
            f.status
        );
    }
    out
}

fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.6e}")
    } else {
        String::new()
    }
}

fn opt(x: Option<f64>) -> String {
    x.map_or(String::new(), num)
}

/// Quote a text field if it holds a comma, quote or line break (RFC 4180).
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
