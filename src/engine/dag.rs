//! The stage graph: waves of independent stages in topological order, cycles, ancestors, rendering.

use super::pipeline::{InputSpec, Pipeline};
use std::collections::{BTreeMap, BTreeSet};

/// Stages grouped in waves: every stage's inputs come from earlier waves, so the stages of one
/// wave can run in parallel. On a cycle, returns its path (first stage repeated at the end).
pub fn order(pipeline: &Pipeline) -> Result<Vec<Vec<String>>, Vec<String>> {
    if let Some(cycle) = find_cycle(pipeline) {
        return Err(cycle);
    }
    let mut level: BTreeMap<&str, usize> = BTreeMap::new();
    fn depth<'a>(p: &'a Pipeline, s: &'a str, level: &mut BTreeMap<&'a str, usize>) -> usize {
        if let Some(&l) = level.get(s) {
            return l;
        }
        let l = p
            .deps(s)
            .into_iter()
            .map(|d| depth(p, d, level) + 1)
            .max()
            .unwrap_or(0);
        level.insert(s, l);
        l
    }
    for name in pipeline.stages.keys() {
        depth(pipeline, name, &mut level);
    }
    let mut waves: Vec<Vec<String>> = Vec::new();
    for (name, l) in level {
        if waves.len() <= l {
            waves.resize(l + 1, Vec::new());
        }
        waves[l].push(name.to_string());
    }
    Ok(waves)
}

fn find_cycle(pipeline: &Pipeline) -> Option<Vec<String>> {
    // 0 = unseen, 1 = on the current path, 2 = done
    let mut mark: BTreeMap<&str, u8> = BTreeMap::new();
    let mut path: Vec<&str> = Vec::new();
    fn visit<'a>(
        p: &'a Pipeline,
        s: &'a str,
        mark: &mut BTreeMap<&'a str, u8>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        match mark.get(s).copied().unwrap_or(0) {
            2 => return None,
            1 => {
                let start = path.iter().position(|&x| x == s).unwrap_or(0);
                let mut cycle: Vec<String> = path[start..].iter().map(|x| x.to_string()).collect();
                cycle.push(s.to_string());
                return Some(cycle);
            }
            _ => {}
        }
        mark.insert(s, 1);
        path.push(s);
        for d in p.deps(s) {
            if let Some(c) = visit(p, d, mark, path) {
                return Some(c);
            }
        }
        path.pop();
        mark.insert(s, 2);
        None
    }
    for name in pipeline.stages.keys() {
        if let Some(mut cycle) = visit(pipeline, name, &mut mark, &mut path) {
            // deps point upstream; show the data flow direction (producer -> consumer)
            cycle.reverse();
            return Some(cycle);
        }
    }
    None
}

/// The named stages and everything they need.
pub fn with_ancestors(pipeline: &Pipeline, names: &[String]) -> BTreeSet<String> {
    let mut out = BTreeSet::new();
    let mut todo: Vec<String> = names.to_vec();
    while let Some(s) = todo.pop() {
        if out.insert(s.clone()) {
            todo.extend(pipeline.deps(&s).into_iter().map(str::to_string));
        }
    }
    out
}

/// Output format of `groove dag`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Text,
    Dot,
    Mermaid,
}

/// One edge per bound stage input: (producer, output, consumer, input).
fn edges(pipeline: &Pipeline) -> Vec<(&str, &str, &str, &str)> {
    let mut out = Vec::new();
    for stage in pipeline.stages.values() {
        for (input, spec) in &stage.inputs {
            if let InputSpec::Stage { stage: up, output } = spec {
                out.push((
                    up.as_str(),
                    output.as_str(),
                    stage.name.as_str(),
                    input.as_str(),
                ));
            }
        }
    }
    out
}

/// Render the graph as text, Graphviz dot, or Mermaid.
pub fn render(pipeline: &Pipeline, format: Format) -> String {
    render_with_state(pipeline, format, &BTreeMap::new(), false)
}

/// A stage's state, for colouring the graph: `fresh`, `stale`, or none when not known.
fn state_of<'a>(states: &'a BTreeMap<String, String>, stage: &str) -> Option<&'a str> {
    states.get(stage).map(String::as_str)
}

/// Fill colours of the states in dot and Mermaid (light green, light orange).
const FRESH_FILL: &str = "#c8e6c9";
const STALE_FILL: &str = "#ffcc80";

/// [`render`] with each stage marked by its state (stage → `fresh` or `stale`, as `groove
/// status` says): in text a `[fresh]`/`[stale]` tag (green or
/// yellow with `ansi`, for a terminal), in dot and Mermaid a fill colour and a legend.
pub fn render_with_state(
    pipeline: &Pipeline,
    format: Format,
    states: &BTreeMap<String, String>,
    ansi: bool,
) -> String {
    let waves = order(pipeline).unwrap_or_default();
    let mut s = String::new();
    match format {
        Format::Text => {
            for stage in waves.iter().flatten() {
                let spec = &pipeline.stages[stage];
                let each = spec
                    .foreach
                    .iter()
                    .chain(&spec.foreach_with)
                    .map(String::as_str)
                    .collect::<Vec<_>>()
                    .join(", ");
                let each = if each.is_empty() {
                    each
                } else {
                    format!(" foreach {each}")
                };
                let tag = match (state_of(states, stage), ansi) {
                    (None, _) => String::new(),
                    (Some(st), false) => format!(" [{st}]"),
                    (Some(st), true) => {
                        let colour = if st == "fresh" { 32 } else { 33 };
                        format!(" \x1b[{colour}m[{st}]\x1b[0m")
                    }
                };
                s.push_str(&format!("{stage} ({}{each}){tag}\n", spec.kind));
                for (input, bound) in &spec.inputs {
                    let from = match bound {
                        InputSpec::Stage { stage, output } => format!("{stage}:{output}"),
                        InputSpec::Path { path, optional } => {
                            format!(
                                "{}{}",
                                pipeline.show(path),
                                if *optional { " (optional)" } else { "" }
                            )
                        }
                        InputSpec::Provenance => "engine:provenance".into(),
                    };
                    s.push_str(&format!("  <- {input} = {from}\n"));
                }
                for (output, path) in &spec.outputs {
                    let to = path
                        .as_ref()
                        .map(|p| format!(" -> {}", pipeline.show(p)))
                        .unwrap_or_default();
                    s.push_str(&format!("  => {output}{to}\n"));
                }
            }
        }
        Format::Dot => {
            s.push_str("digraph groove {\n  rankdir=LR;\n  node [shape=box];\n");
            for stage in pipeline.stages.values() {
                let fill = match state_of(states, &stage.name) {
                    Some("fresh") => format!(", style=filled, fillcolor=\"{FRESH_FILL}\""),
                    Some(_) => format!(", style=filled, fillcolor=\"{STALE_FILL}\""),
                    None => String::new(),
                };
                let st = state_of(states, &stage.name)
                    .map(|st| format!(", {st}"))
                    .unwrap_or_default();
                s.push_str(&format!(
                    "  \"{}\" [label=\"{}\\n({}{st})\"{fill}];\n",
                    stage.name, stage.name, stage.kind
                ));
            }
            for (up, output, down, input) in edges(pipeline) {
                s.push_str(&format!(
                    "  \"{up}\" -> \"{down}\" [label=\"{output} → {input}\"];\n"
                ));
            }
            s.push_str("}\n");
        }
        Format::Mermaid => {
            s.push_str("graph LR\n");
            for stage in pipeline.stages.values() {
                s.push_str(&format!(
                    "  {}[\"{} ({})\"]\n",
                    stage.name, stage.name, stage.kind
                ));
            }
            for (up, output, down, input) in edges(pipeline) {
                s.push_str(&format!("  {up} -->|{output} → {input}| {down}\n"));
            }
            if !states.is_empty() {
                s.push_str(&format!(
                    "  classDef fresh fill:{FRESH_FILL}\n  classDef stale fill:{STALE_FILL}\n"
                ));
                for st in ["fresh", "stale"] {
                    let names: Vec<&str> = pipeline
                        .stages
                        .keys()
                        .filter(|n| state_of(states, n) == Some(st))
                        .map(String::as_str)
                        .collect();
                    if !names.is_empty() {
                        s.push_str(&format!("  class {} {st}\n", names.join(",")));
                    }
                }
            }
        }
    }
    s
}
