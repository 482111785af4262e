//! Aggregates per material from summary.json, with the same numbers computed from the per-run fits
//! as a fallback so the report always shows a value (and says where it came from).

use super::figures::common::ols;
use super::inputs::ReportData;
use super::value::{est, field, interval, num, Est};
use serde_json::Value;

/// An aggregate value, its interval if known, and where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct Agg {
    pub est: Est,
    pub interval: Option<(f64, f64)>,
    /// "summary.json" or "per-run fits".
    pub source: &'static str,
}

/// summary.json's object for one material: `single.materials.<m>` (the fit stage's layout), or
/// `materials`/`per_material` (map or list), or top level.
pub fn material_obj<'a>(summary: &'a Value, material: &str) -> Option<&'a Value> {
    let roots = [
        summary.get("single").filter(|v| v.is_object()),
        Some(summary),
    ];
    for root in roots.into_iter().flatten() {
        for key in ["materials", "per_material"] {
            match root.get(key) {
                Some(Value::Object(m)) => {
                    if let Some(v) = m.get(material) {
                        return Some(v);
                    }
                }
                Some(Value::Array(a)) => {
                    let found = a
                        .iter()
                        .find(|o| o.get("material").and_then(Value::as_str) == Some(material));
                    if found.is_some() {
                        return found;
                    }
                }
                _ => {}
            }
        }
    }
    summary.get(material).filter(|v| v.is_object())
}

/// summary.json's pooled (all materials) object.
pub fn pooled_obj(summary: &Value) -> Option<&Value> {
    summary
        .get("single")
        .and_then(|s| field(s, &["pooled", "all"]))
        .or_else(|| field(summary, &["pooled", "all"]))
}

/// `{lo, hi}` of a value object, or of its `value` when that is an object (`{value: {value, lo, hi}}`).
fn lo_hi(v: &Value) -> Option<(f64, f64)> {
    match (
        num(v, &["lo", "low", "lower"]),
        num(v, &["hi", "high", "upper"]),
    ) {
        (Some(lo), Some(hi)) => Some((lo, hi)),
        _ => v.get("value").filter(|x| x.is_object()).and_then(lo_hi),
    }
}

fn agg(obj: &Value, names: &[&str]) -> Option<Agg> {
    let e = est(obj, names)?;
    let iv = field(obj, names)
        .and_then(|v| {
            interval(v, &["interval", "ci", "ci95", "bootstrap_interval"]).or_else(|| lo_hi(v))
        })
        .or_else(|| {
            let cands: Vec<String> = names.iter().map(|n| format!("{n}_interval")).collect();
            let refs: Vec<&str> = cands.iter().map(String::as_str).collect();
            interval(obj, &refs)
        });
    Some(Agg {
        est: e,
        interval: iv,
        source: "summary.json",
    })
}

fn mean_se(xs: &[f64]) -> Option<Est> {
    let n = xs.len();
    if n == 0 {
        return None;
    }
    let m = xs.iter().sum::<f64>() / n as f64;
    let se = (n > 1).then(|| {
        let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
        (var / n as f64).sqrt()
    });
    Some(Est {
        value: m,
        stderr: se,
    })
}

/// μ_pg mean of runs with |v0| > 0.03 m/s (the chapter's definition).
pub fn mu_fast(d: &ReportData, material: &str) -> Option<Agg> {
    let from_summary = d
        .summary
        .as_ref()
        .and_then(|s| material_obj(s, material))
        .and_then(|o| {
            agg(
                o,
                &[
                    "mu_fast",
                    "mu_v0_gt_0_03",
                    "mu_above_0_03",
                    "mu_chapter",
                    "mu_v0_above",
                ],
            )
        });
    from_summary.or_else(|| {
        let xs: Vec<f64> = d
            .singles_of(material)
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
pub fn mu_all(d: &ReportData, material: &str) -> Option<Agg> {
    let from_summary = d
        .summary
        .as_ref()
        .and_then(|s| material_obj(s, material))
        .and_then(|o| agg(o, &["mu", "mu_weighted", "mu_pg"]));
    from_summary.or_else(|| {
        let xs: Vec<f64> = d.singles_of(material).map(|r| r.mu.value).collect();
        mean_se(&xs).map(|e| Agg {
            est: e,
            interval: None,
            source: "per-run fits",
        })
    })
}

/// The T-vs-v0 line of one material (or of all runs when `material` is None): (intercept, slope).
pub fn t_line(d: &ReportData, material: Option<&str>) -> Option<(Agg, Agg)> {
    let obj = match material {
        Some(m) => d.summary.as_ref().and_then(|s| material_obj(s, m)),
        None => d.summary.as_ref().and_then(pooled_obj),
    };
    let line = obj.and_then(|o| {
        field(
            o,
            &[
                "t_line",
                "T_line",
                "t_vs_v0",
                "T_vs_v0",
                "drag_line",
                "T_v0",
            ],
        )
    });
    if let Some(l) = line {
        let a = agg(l, &["intercept_s", "intercept", "t0_s", "T0_s"]);
        let b = agg(
            l,
            &[
                "slope_s_per_mps",
                "slope",
                "t_prime_s_per_mps",
                "Tp_s_per_mps",
            ],
        );
        if let (Some(a), Some(b)) = (a, b) {
            return Some((a, b));
        }
    }
    let pts: Vec<(f64, f64)> = d
        .singles
        .iter()
        .filter(|r| r.converged() && material.is_none_or(|m| r.material == m))
        .map(|r| (r.v0_mps.value.abs(), r.t_drag_s.value))
        .collect();
    let (a, b) = ols(&pts)?;
    let mk = |v| Agg {
        est: Est {
            value: v,
            stderr: None,
        },
        interval: None,
        source: "per-run fits",
    };
    Some((mk(a), mk(b)))
}

/// μ_pp of the collision runs: summary.json's `collisions.mu_pp`, or the slope of Δv_a vs Δv_z of the
/// target over slip impacts (through the origin) divided by k.
pub fn mu_pp(d: &ReportData, k: f64) -> Option<Agg> {
    let from_summary = d
        .summary
        .as_ref()
        .and_then(|s| field(s, &["collisions", "collision"]))
        .and_then(|c| {
            agg(c, &["mu_pp", "mu_pp_slope", "mu_pp_fit"]).or_else(|| {
                let m = c.get("mu_pp")?;
                agg(m, &["from_slip_slope", "from_impulse_fit"])
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
            est: Est {
                value: (sxy / sxx).abs() / k,
                stderr: None,
            },
            interval: None,
            source: "impacts (slip)",
        })
    })
}

/// A number from summary.json at a path of keys, for the tables (e.g. `["collisions", "n_runs"]`).
pub fn at(summary: Option<&Value>, path: &[&str]) -> Option<f64> {
    let mut v = summary?;
    for (i, k) in path.iter().enumerate() {
        if i + 1 == path.len() {
            return num(v, &[k]);
        }
        v = v.get(*k)?;
    }
    None
}

/// The fitted restitution curve of one material and setup from summary.json's
/// `collisions.restitution`: (a in C = 1 − a·v, its interval, impacts).
pub fn restitution_curve(d: &ReportData, material: &str, contact: bool) -> Option<(Agg, usize)> {
    let list = d
        .summary
        .as_ref()?
        .get("collisions")?
        .get("restitution")?
        .as_array()?;
    let setup = if contact { "contact" } else { "rolling" };
    let c = list.iter().find(|c| {
        c.get("material").and_then(Value::as_str) == Some(material)
            && c.get("setup").and_then(Value::as_str).unwrap_or("rolling") == setup
    })?;
    let a = agg(c, &["a_per_mps"])?;
    Some((a, num(c, &["n_impacts"]).unwrap_or(0.0) as usize))
}
