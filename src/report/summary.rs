//! Aggregates per material from summary.json, with the same numbers computed from the per-run fits
//! as a fallback so the report always shows a value (and says where it came from).

use super::figures::common::ols;
use super::inputs::ReportData;
use crate::artifacts::summary::{Estimate, MaterialSummary, Summary};
use crate::recording::Setup;

/// An aggregate value, its interval if known, and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Agg {
    pub est: Estimate,
    pub interval: Option<(f64, f64)>,
    /// "summary.json" or "per-run fits".
    pub source: &'static str,
}

fn finite_pair(lo: f64, hi: f64) -> Option<(f64, f64)> {
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// An estimate of summary.json (value and bootstrap interval); None when it could not be computed.
fn agg(e: &Estimate) -> Option<Agg> {
    e.value.is_finite().then(|| Agg {
        est: Estimate::with_interval(e.value, None),
        interval: finite_pair(e.lo(), e.hi()),
        source: "summary.json",
    })
}

/// summary.json's aggregates of one material's single runs.
pub fn material<'a>(summary: &'a Summary, material: &str) -> Option<&'a MaterialSummary> {
    summary.single.as_ref()?.materials.get(material)
}

fn mean_se(xs: &[f64]) -> Option<Estimate> {
    let n = xs.len();
    if n == 0 {
        return None;
    }
    let m = xs.iter().sum::<f64>() / n as f64;
    let se = (n > 1).then(|| {
        let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
        (var / n as f64).sqrt()
    });
    Some(Estimate {
        value: m,
        se,
        interval: None,
    })
}

/// μ_pg mean of runs with |v0| > 0.03 m/s (the chapter's definition).
pub fn mu_fast(d: &ReportData, m: &str) -> Option<Agg> {
    let from_summary = d
        .summary
        .as_ref()
        .and_then(|s| material(s, m))
        .and_then(|o| agg(&o.mu_fast));
    from_summary.or_else(|| {
        let xs: Vec<f64> = d
            .singles_of(m)
            .filter(|r| r.v0_mps.value.abs() > super::chapter::MU_MEAN_V0_MIN_MPS)
            .map(|r| r.mu.value)
            .collect();
        mean_se(&xs).map(|e| Agg {
            est: e,
            interval: None,
            source: "per-run fits",
        })
    })
}

/// μ_pg over all runs (weighted mean in summary.json; plain mean of the fits otherwise).
pub fn mu_all(d: &ReportData, m: &str) -> Option<Agg> {
    let from_summary = d
        .summary
        .as_ref()
        .and_then(|s| material(s, m))
        .and_then(|o| agg(&o.mu_weighted));
    from_summary.or_else(|| {
        let xs: Vec<f64> = d.singles_of(m).map(|r| r.mu.value).collect();
        mean_se(&xs).map(|e| Agg {
            est: e,
            interval: None,
            source: "per-run fits",
        })
    })
}

/// The T-vs-v0 line of one material (or of all runs when `material` is None): (intercept, slope).
pub fn t_line(d: &ReportData, m: Option<&str>) -> Option<(Agg, Agg)> {
    let obj = d.summary.as_ref().and_then(|s| match m {
        Some(m) => material(s, m),
        None => s.single.as_ref().map(|s| &s.pooled),
    });
    if let Some(l) = obj.map(|o| &o.t_vs_v0) {
        if let (Some(a), Some(b)) = (agg(&l.intercept_s), agg(&l.slope_s_per_mps)) {
            return Some((a, b));
        }
    }
    let pts: Vec<(f64, f64)> = d
        .singles
        .iter()
        .filter(|r| r.converged() && m.is_none_or(|m| r.material == m))
        .map(|r| (r.v0_mps.value.abs(), r.t_drag_s.value))
        .collect();
    let (a, b) = ols(&pts)?;
    let mk = |v| Agg {
        est: Estimate {
            value: v,
            se: None,
            interval: None,
        },
        interval: None,
        source: "per-run fits",
    };
    Some((mk(a), mk(b)))
}

/// μ_pp of the collision runs: summary.json's `collisions.mu_pp` (the headline value, else the
/// slip slope, else the impulse fit), or the slope of Δv_a vs Δv_z of the target over slip
/// impacts (through the origin) divided by k.
pub fn mu_pp(d: &ReportData, k: f64) -> Option<Agg> {
    let from_summary = d
        .summary
        .as_ref()
        .and_then(|s| s.collisions.as_ref())
        .and_then(|c| {
            let m = &c.mu_pp;
            m.value.and_then(|v| agg(&v)).or_else(|| {
                m.from_slip_slope
                    .or(m.from_impulse_fit)
                    .and_then(|v| agg(&v))
            })
        });
    from_summary.or_else(|| {
        let (sxy, sxx) = d
            .collisions
            .iter()
            .flat_map(|c| &c.impacts)
            .filter(|i| i.slip != Some(false))
            .filter_map(|i| Some((i.dvz_target_mps?, i.dva_target_mps?)))
            .fold((0.0, 0.0), |(sxy, sxx), (x, y)| (sxy + x * y, sxx + x * x));
        (sxx > 0.0).then(|| Agg {
            est: Estimate {
                value: (sxy / sxx).abs() / k,
                se: None,
                interval: None,
            },
            interval: None,
            source: "impacts (slip)",
        })
    })
}

/// summary.json's lower bound on μ_pp from stick impacts, when there is one.
pub fn mu_pp_stick_lower_bound(d: &ReportData) -> Option<f64> {
    d.summary
        .as_ref()?
        .collisions
        .as_ref()?
        .mu_pp
        .stick_lower_bound
        .filter(|x| x.is_finite())
}

/// The fitted restitution curve of one material and setup from summary.json's
/// `collisions.restitution`: (a in C = 1 − a·v, its interval, impacts).
pub fn restitution_curve(d: &ReportData, material: &str, contact: bool) -> Option<(Agg, usize)> {
    let list = &d.summary.as_ref()?.collisions.as_ref()?.restitution;
    let setup = if contact {
        Setup::Contact
    } else {
        Setup::Rolling
    };
    let c = list
        .iter()
        .find(|c| c.material == material && c.setup.unwrap_or(Setup::Rolling) == setup)?;
    Some((agg(&c.a_per_mps)?, c.n_impacts))
}
