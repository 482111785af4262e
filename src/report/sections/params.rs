//! A fitted term's parameters as text: `name = value ± stderr`, and those that ended at a bound.

use crate::artifacts::estimate::Estimate;
use crate::report::value::sig;
use serde::Deserialize;
use serde_json::Value;
use std::collections::BTreeMap;

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

/// `name = value ± stderr` for each parameter of a finding.
pub fn params_text(ps: &BTreeMap<String, Estimate>) -> String {
    let parts: Vec<String> = ps
        .iter()
        .map(|(k, p)| {
            let v = finite(p.value).map_or("—".into(), |x| sig(x, 4));
            // a zero error marks a value that was set, not estimated (a spline's range)
            match p.se.and_then(finite).filter(|se| *se > 0.0) {
                Some(se) => format!("{k} = {v} ± {}", sig(se, 2)),
                None => format!("{k} = {v}"),
            }
        })
        .collect();
    if parts.is_empty() {
        "—".into()
    } else {
        parts.join(", ")
    }
}

/// The parameters of a finding that ended at a bound of their search, in words (`where.at_bound`).
pub fn at_bound(w: &BTreeMap<String, Value>) -> Vec<String> {
    w.get("at_bound")
        .and_then(|l| Vec::<String>::deserialize(l).ok())
        .unwrap_or_default()
}
