//! fits.csv: one row per single run, sorted by run, fixed float formatting (the output contract).

use super::single::SingleFit;
use rayon::prelude::*;
use std::fmt::Write;

pub use crate::artifacts::fits_table::HEADER;

/// Render fits.csv. Numbers are written as `{:.6e}`; an unknown standard error is an empty field.
pub fn render(fits: &[SingleFit]) -> String {
    let mut rows: Vec<&SingleFit> = fits.iter().collect();
    rows.sort_by(|a, b| a.run.cmp(&b.run));
    // the rows written a thousand at a time on every core, then joined in order
    let parts: Vec<String> = rows.par_chunks(1024).map(lines).collect();
    let mut out = String::with_capacity(parts.iter().map(String::len).sum::<usize>() + 128);
    out.push_str(HEADER);
    out.push('\n');
    for part in parts {
        out.push_str(&part);
    }
    out
}

/// The lines of some rows.
fn lines(rows: &[&SingleFit]) -> String {
    let mut out = String::with_capacity(128 * rows.len());
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::options::FitOptions;

    #[test]
    fn rows_written_in_parallel_parts_are_the_rows_in_run_order() {
        // 2,500 fits (three parts), given out of order, one with a comma in its name
        let fit = |k: usize| SingleFit {
            run: if k == 7 {
                "r,7".into()
            } else {
                format!("r{k:05}")
            },
            material: "316".into(),
            groove: FitOptions::default().groove(),
            v0_mps: 1e-3 * k as f64,
            v0_se: (!k.is_multiple_of(3)).then_some(1e-5),
            mu: 0.3,
            mu_se: Some(0.01),
            t_drag_s: 0.05,
            t_drag_se: None,
            z0_m: 1e-3,
            z0_se: None,
            t0_s: 0.0,
            t0_se: None,
            t1_s: f64::NAN,
            rms_m: 1e-6,
            scale_m: 1e-6,
            outlier_cut_m: 5e-6,
            n_frames: 600,
            n_used: 600,
            n_outliers: 0,
            iterations: 9,
            termination: crate::fit::Termination::SmallStep,
            status: crate::artifacts::run_fit::FitStatus::Converged,
            suspect: Vec::new(),
            restarted: false,
        };
        let fits: Vec<SingleFit> = (0..2500).rev().map(fit).collect();
        let csv = render(&fits);
        let mut sorted: Vec<&SingleFit> = fits.iter().collect();
        sorted.sort_by(|a, b| a.run.cmp(&b.run));
        assert_eq!(csv, format!("{HEADER}\n{}", lines(&sorted)));
        let body: Vec<&str> = csv.lines().skip(1).collect();
        assert_eq!(body.len(), 2500);
        assert!(
            body[0].starts_with("\"r,7\",316,7.000000e-3,"),
            "{}",
            body[0]
        );
        assert!(
            body[1].starts_with("r00000,316,0.000000e0,,"),
            "{}",
            body[1]
        );
        assert!(body[2499].starts_with("r02499,"));
    }
}
