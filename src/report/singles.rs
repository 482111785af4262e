//! Per-run fits of single runs, read from fits.csv (the fixed output contract) and the per-run fit JSON.

use crate::artifacts::fits_table;
use crate::artifacts::Estimate;
use crate::artifacts::{FitStatus, SingleFit};
use std::collections::BTreeMap;

/// One single run's baseline fit, as the report shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct SingleRow {
    pub run: String,
    pub material: String,
    pub v0_mps: Estimate,
    pub mu: Estimate,
    pub t_drag_s: Estimate,
    pub t1_s: Option<f64>,
    pub rms_m: Option<f64>,
    pub status: FitStatus,
    /// Nuisance parameters (from the fit JSON only).
    pub z0_m: Option<f64>,
    pub t0_s: Option<f64>,
}

impl SingleRow {
    /// A fit counts as usable unless it failed or is suspect (one stopped at its iteration
    /// limit is shown; the aggregates leave it out).
    pub fn converged(&self) -> bool {
        !matches!(self.status, FitStatus::Failed | FitStatus::Suspect)
    }
}

/// Parse fits.csv (`artifacts::fits_table`); rows that lack a number for v0, mu or T are skipped.
pub fn parse_fits_csv(csv: &str) -> Result<Vec<SingleRow>, String> {
    let mut rows: Vec<SingleRow> = fits_table::parse(csv)?
        .into_iter()
        .filter_map(|r| {
            Some(SingleRow {
                v0_mps: Estimate {
                    value: r.v0_mps?,
                    se: r.v0_se,
                    interval: None,
                },
                mu: Estimate {
                    value: r.mu?,
                    se: r.mu_se,
                    interval: None,
                },
                t_drag_s: Estimate {
                    value: r.t_s?,
                    se: r.t_se,
                    interval: None,
                },
                t1_s: r.t1_s,
                rms_m: r.rms_m,
                status: FitStatus::from_word(&r.status)?,
                z0_m: None,
                t0_s: None,
                run: r.run,
                material: r.material,
            })
        })
        .collect();
    rows.sort_by(|a, b| a.run.cmp(&b.run));
    Ok(rows)
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

fn est(value: f64, se: Option<f64>) -> Option<Estimate> {
    Some(Estimate {
        value: finite(value)?,
        se: se.and_then(finite),
        interval: None,
    })
}

/// One single run's fit (the `fit` stage's item); None when v0, μ or T is not a number.
pub fn from_fit(fit: &SingleFit) -> Option<SingleRow> {
    Some(SingleRow {
        run: fit.run.clone(),
        material: fit.material.clone(),
        v0_mps: est(fit.v0_mps, fit.v0_se)?,
        mu: est(fit.mu, fit.mu_se)?,
        t_drag_s: est(fit.t_drag_s, fit.t_drag_se)?,
        t1_s: finite(fit.t1_s),
        rms_m: finite(fit.rms_m),
        status: fit.status,
        z0_m: finite(fit.z0_m),
        t0_s: finite(fit.t0_s),
    })
}

/// Fill in z0 and t0 (absent from fits.csv) from the per-run fit JSON, by run id.
pub fn add_nuisance(rows: &mut [SingleRow], from_json: &BTreeMap<String, SingleRow>) {
    for r in rows.iter_mut() {
        if let Some(j) = from_json.get(&r.run) {
            r.z0_m = r.z0_m.or(j.z0_m);
            r.t0_s = r.t0_s.or(j.t0_s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_fits_csv_rows() {
        let csv = "run,material,v0_mps,v0_se,mu,mu_se,T_s,T_se,t1_s,rms_m,status\n\
                   b,440c,-0.05,1e-4,0.29,0.01,0.11,0.004,0.01,1.1e-6,converged\n\
                   a,316,0.02,1e-4,0.34,0.01,0.07,0.003,0.004,9e-7,converged\n\
                   c,316,,,0.34,0.01,0.07,0.003,0.004,9e-7,failed\n";
        let rows = parse_fits_csv(csv).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].run, "a");
        assert_eq!(rows[1].v0_mps.value, -0.05);
        assert_eq!(rows[1].t_drag_s.se, Some(0.004));
        assert!(parse_fits_csv("run,material\n").is_err());
    }
}
