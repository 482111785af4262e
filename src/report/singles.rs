//! Per-run fits of single runs, read from fits.csv (the fixed output contract) and the per-run fit JSON.

use super::value::{est, num, text, Est};
use serde_json::Value;
use std::collections::BTreeMap;

/// One single run's baseline fit, as the report shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct SingleRow {
    pub run: String,
    pub material: String,
    pub v0_mps: Est,
    pub mu: Est,
    pub t_drag_s: Est,
    pub t1_s: Option<f64>,
    pub rms_m: Option<f64>,
    pub status: String,
    /// Nuisance parameters (from the fit JSON only).
    pub z0_m: Option<f64>,
    pub t0_s: Option<f64>,
}

impl SingleRow {
    /// A fit counts as usable unless its status says it failed or is suspect.
    pub fn converged(&self) -> bool {
        let s = self.status.to_ascii_lowercase();
        !(s.contains("fail")
            || s.contains("diverge")
            || s.contains("error")
            || s.contains("nan")
            || s.contains("suspect"))
    }
}

/// Parse fits.csv: `run, material, v0_mps, v0_se, mu, mu_se, T_s, T_se, t1_s, rms_m, status`.
/// Columns are found by name; rows that lack a number for v0, mu or T are skipped.
pub fn parse_fits_csv(csv: &str) -> Result<Vec<SingleRow>, String> {
    let mut lines = csv.lines().filter(|l| !l.trim().is_empty());
    let header: Vec<&str> = match lines.next() {
        Some(h) => h.split(',').map(str::trim).collect(),
        None => return Ok(Vec::new()),
    };
    let col = |name: &str| header.iter().position(|h| *h == name);
    let need = |name: &str| {
        col(name).ok_or_else(|| {
            format!("fits.csv has no column `{name}`; regenerate it with the aggregate stage")
        })
    };
    let (c_run, c_mat) = (need("run")?, need("material")?);
    let (c_v0, c_mu, c_t) = (need("v0_mps")?, need("mu")?, need("T_s")?);
    let (c_v0se, c_muse, c_tse) = (col("v0_se"), col("mu_se"), col("T_se"));
    let (c_t1, c_rms, c_status) = (col("t1_s"), col("rms_m"), col("status"));
    let mut rows = Vec::new();
    for line in lines {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        let get = |c: Option<usize>| -> Option<f64> {
            c.and_then(|i| cells.get(i))
                .and_then(|s| s.parse::<f64>().ok())
                .filter(|x| x.is_finite())
        };
        let (Some(v0), Some(mu), Some(t)) = (get(Some(c_v0)), get(Some(c_mu)), get(Some(c_t)))
        else {
            continue;
        };
        rows.push(SingleRow {
            run: cells.get(c_run).unwrap_or(&"").to_string(),
            material: cells.get(c_mat).unwrap_or(&"").to_string(),
            v0_mps: Est {
                value: v0,
                stderr: get(c_v0se),
            },
            mu: Est {
                value: mu,
                stderr: get(c_muse),
            },
            t_drag_s: Est {
                value: t,
                stderr: get(c_tse),
            },
            t1_s: get(c_t1),
            rms_m: get(c_rms),
            status: c_status
                .and_then(|i| cells.get(i))
                .unwrap_or(&"")
                .to_string(),
            z0_m: None,
            t0_s: None,
        });
    }
    rows.sort_by(|a, b| a.run.cmp(&b.run));
    Ok(rows)
}

/// Read one single-run fit JSON (`{"experiment": "single", ...}`), tolerant of field naming.
pub fn from_fit_json(run: &str, material: &str, fit: &Value) -> Option<SingleRow> {
    let body = fit.get("fit").filter(|b| b.is_object()).unwrap_or(fit);
    let params = body.get("params").filter(|p| p.is_object()).unwrap_or(body);
    let v0 = est(params, &["v0_mps", "v0"])?;
    let mu = est(params, &["mu", "mu_pg"])?;
    let t = est(params, &["T_s", "t_drag_s", "T", "t_s"])?;
    let status = text(body, &["status", "termination", "reason"])
        .map(str::to_string)
        .or_else(|| {
            body.get("status")
                .map(|s| s.to_string().trim_matches('"').to_string())
        })
        .unwrap_or_default();
    Some(SingleRow {
        run: text(fit, &["run"]).unwrap_or(run).to_string(),
        material: text(fit, &["material"]).unwrap_or(material).to_string(),
        v0_mps: v0,
        mu,
        t_drag_s: t,
        t1_s: num(body, &["t1_s", "switch_time_s", "t1"]),
        rms_m: num(body, &["rms_m", "rms"]),
        status,
        z0_m: num(params, &["z0_m", "z0"]),
        t0_s: num(params, &["t0_s", "t0"]),
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
    fn reads_fits_csv_by_column_name() {
        let csv = "run,material,v0_mps,v0_se,mu,mu_se,T_s,T_se,t1_s,rms_m,status\n\
                   b,440c,-0.05,1e-4,0.29,0.01,0.11,0.004,0.01,1.1e-6,converged\n\
                   a,316,0.02,1e-4,0.34,0.01,0.07,0.003,0.004,9e-7,converged\n";
        let rows = parse_fits_csv(csv).unwrap();
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].run, "a");
        assert_eq!(rows[1].v0_mps.value, -0.05);
        assert_eq!(rows[1].t_drag_s.stderr, Some(0.004));
        assert!(parse_fits_csv("run,material\n").is_err());
    }
}
