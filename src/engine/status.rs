//! `groove status`: every stage fresh or stale, with the reasons.

use super::catalog::Catalog;
use super::context::{Context, Evaluated};
use super::dag;
use super::error::EngineError;
use super::evaluate::{evaluate, Action};
use super::pipeline::Pipeline;
use super::progress::Progress;
use super::reasons::reasons;
use serde::Serialize;
use std::collections::{BTreeMap, BTreeSet};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum State {
    Fresh,
    Stale,
}

/// One line of `groove status`; the JSON form is `{stage, state, reasons}`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct StageStatus {
    pub stage: String,
    pub state: State,
    pub reasons: Vec<String>,
}

/// The status of the selected stages (all when `None`), in topological order.
pub fn status(
    catalog: &Catalog,
    pipeline: &Pipeline,
    selected: Option<&BTreeSet<String>>,
) -> Result<Vec<StageStatus>, EngineError> {
    let ctx = Context::new(catalog, pipeline, Progress::new(0, true));
    let all: BTreeSet<String> = pipeline.stages.keys().cloned().collect();
    let selected = selected.unwrap_or(&all);
    let (done, errors) = evaluate(&ctx, selected, |_| Action::Check, |_, _| {});
    if let Some(e) = errors.into_iter().next() {
        return Err(e);
    }
    // the hash cache only spares a later command work: a store that cannot be written (read
    // only, full) costs that, never the answer
    let _ = ctx.hashes.save();
    Ok(describe(&ctx, &done))
}

/// Statuses of evaluated stages in topological order.
pub fn describe(ctx: &Context, done: &BTreeMap<String, Evaluated>) -> Vec<StageStatus> {
    let order = dag::order(ctx.pipeline).expect("validated pipelines have no cycle");
    order
        .into_iter()
        .flatten()
        .filter_map(|name| {
            let ev = done.get(&name)?;
            let spec = &ctx.pipeline.stages[&name];
            let reasons = reasons(ctx.pipeline, spec, ev, ctx.lock().stages.get(&name));
            let state = if reasons.is_empty() {
                State::Fresh
            } else {
                State::Stale
            };
            Some(StageStatus {
                stage: name,
                state,
                reasons,
            })
        })
        .collect()
}

/// Human-readable status lines.
pub fn render(statuses: &[StageStatus]) -> String {
    let mut s = String::new();
    for st in statuses {
        match st.state {
            State::Fresh => s.push_str(&format!("fresh  {}\n", st.stage)),
            State::Stale => {
                s.push_str(&format!("stale  {}\n", st.stage));
                for r in &st.reasons {
                    s.push_str(&format!("         {r}\n"));
                }
            }
        }
    }
    s
}
