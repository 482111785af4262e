//! The validation step: raw config → typed [`Pipeline`], every error located at its TOML line.

use super::raw::{Foreach, RawInput, RawPipeline, RawStage};
use super::span::Source;
use super::Overrides;
use crate::engine::catalog::Catalog;
use crate::engine::command;
use crate::engine::dag;
use crate::engine::error::{EngineError, IoContext};
use crate::engine::pipeline::{InputSpec, Pipeline, StageSpec};
use crate::engine::stage::StageKind;
use std::collections::BTreeMap;
use std::path::{Component, Path, PathBuf};
use toml::Spanned;

/// A folder given on the command line (`flag` is `--data` or `--out`, `given` as typed, `whole`
/// its absolute form): a file there is an error, and so is nothing there when it must exist.
/// Blamed on the flag, not on the pipeline line that would otherwise name the folder.
fn check_folder_flag(
    flag: &str,
    given: &Path,
    whole: &Path,
    must_exist: bool,
) -> Result<(), EngineError> {
    let shown = given.display();
    if whole.is_file() {
        let parent = given
            .parent()
            .filter(|p| !p.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        return Err(EngineError::Usage(format!(
            "{flag} {shown} is a file, not a folder; pass the folder that holds it: {flag} {}",
            parent.display()
        )));
    }
    if must_exist && !whole.exists() {
        return Err(EngineError::Usage(format!(
            "{flag} {shown}: there is no folder {}; pass the dataset folder (the one that holds runs.csv and trajectories.csv, or the tracker exports)",
            whole.display()
        )));
    }
    Ok(())
}

/// Turn the serde mirror into a validated pipeline.
pub fn validate(
    raw: RawPipeline,
    file: &Source,
    overrides: &Overrides,
    catalog: &Catalog,
) -> Result<Pipeline, EngineError> {
    let root = file.path.parent().unwrap_or(Path::new(".")).to_path_buf();
    let (seed, data, reports) = match &raw.project {
        Some(p) => {
            let p = p.get_ref();
            (
                p.seed,
                p.data.as_ref().map(|d| d.get_ref().clone()),
                p.reports.as_ref().map(|r| r.get_ref().clone()),
            )
        }
        None => (0, None, None),
    };
    let shared = SharedParams::of(raw.project.as_ref().map(|p| &p.get_ref().params), file);
    if let Some(p) = &raw.project {
        let p = p.get_ref();
        for (key, value) in [("data", &p.data), ("reports", &p.reports)] {
            let Some(value) = value else { continue };
            let text = value.get_ref();
            if text.contains("${") {
                return Err(file.error(
                    file.line_of(value.span().start),
                    format!(
                        "[project] {key} = \"{text}\": the project's folders take no variables (`${{data}}` and `${{reports}}` are these folders); write a path such as \"{key}\""
                    ),
                ));
            }
        }
    }
    let from_cli = |p: &Option<PathBuf>| -> Result<Option<PathBuf>, EngineError> {
        p.as_ref()
            .map(|p| std::path::absolute(p).at(p).map(|a| normalize(&a)))
            .transpose()
    };
    let data_dir = match from_cli(&overrides.data)? {
        Some(d) => {
            check_folder_flag("--data", overrides.data.as_deref().unwrap_or(&d), &d, true)?;
            d
        }
        None => normalize(&root.join(data.as_deref().unwrap_or("data"))),
    };
    let reports_dir = match from_cli(&overrides.reports)? {
        Some(d) => {
            check_folder_flag(
                "--out",
                overrides.reports.as_deref().unwrap_or(&d),
                &d,
                false,
            )?;
            d
        }
        None => normalize(&root.join(reports.as_deref().unwrap_or("reports"))),
    };
    let mut pipeline = Pipeline {
        config_path: file.path.clone(),
        root: root.clone(),
        seed,
        data_dir,
        reports_dir,
        stages: BTreeMap::new(),
    };
    let mut lines = Lines::default();
    // in file order, so the first error reported is the first in the file
    let mut stages: Vec<_> = raw.stages.into_iter().collect();
    stages.sort_by_key(|(name, _)| name.span().start);
    for (name, stage) in stages {
        let line = file.line_of(name.span().start);
        let name = name.into_inner();
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        {
            return Err(file.error(
                line,
                format!("stage name `{name}` may use only letters, digits, `_` and `-`; rename it"),
            ));
        }
        let spec = validate_stage(
            &pipeline,
            &name,
            line,
            stage.into_inner(),
            file,
            catalog,
            &shared,
            &mut lines,
        )?;
        pipeline.stages.insert(name, spec);
    }
    if pipeline.stages.is_empty() {
        return Err(file.error(
            1,
            "defines no stages (is the file empty?); add [stages.NAME] tables, see README.md",
        ));
    }
    shared.check_taken(&pipeline, file)?;
    check_references(&pipeline, file, &lines)?;
    check_outputs(&pipeline, file)?;
    if let Err(cycle) = dag::order(&pipeline) {
        let line = pipeline.stages[&cycle[0]].line;
        return Err(file.error(
            line,
            format!(
                "the stages form a cycle: {}; remove one of these inputs",
                cycle.join(" -> ")
            ),
        ));
    }
    Ok(pipeline)
}

/// Lines of input bindings, for errors found after all stages are read.
#[derive(Default)]
struct Lines {
    inputs: BTreeMap<(String, String), usize>,
    outputs: BTreeMap<(String, String), usize>,
}

fn validate_stage(
    pipeline: &Pipeline,
    name: &str,
    line: usize,
    raw: RawStage,
    file: &Source,
    catalog: &Catalog,
    shared: &SharedParams,
    lines: &mut Lines,
) -> Result<StageSpec, EngineError> {
    let kind_line = file.line_of(raw.kind.span().start);
    let kind = raw.kind.into_inner();
    let builtin = catalog.kind(&kind);
    if builtin.is_none() && kind != "command" {
        return Err(file.error(kind_line, format!(
            "stage `{name}`: unknown kind `{kind}`; known kinds: {}; fix the spelling or use `command` for your own program",
            catalog.kind_names().join(", ")
        )));
    }
    let here = |s: &Spanned<String>| file.line_of(s.span().start);
    let inputs = stage_inputs(pipeline, name, raw.inputs, file, lines)?;
    let mut outputs = stage_outputs(pipeline, name, raw.outputs, file, lines)?;
    let params_lines: BTreeMap<String, usize> = raw
        .params
        .keys()
        .map(|k| (k.get_ref().clone(), here(k)))
        .collect();
    let mut params_lines = params_lines;
    let mut params: toml::Table = raw
        .params
        .into_iter()
        .map(|(k, v)| (k.into_inner(), v.into_inner()))
        .collect();
    if let Some(kind_impl) = builtin {
        shared.inherit(kind_impl, &mut params, &mut params_lines);
    }
    // a NaN or an infinity would reach the stage (or its key, as JSON null) unchecked
    if let Some((key, value)) = params.iter().find(|(_, v)| !finite(v)) {
        return Err(file.error(
            params_lines.get(key).copied().unwrap_or(line),
            format!(
                "stage `{name}`: param `{key}` = {value} is not a finite number; write a number such as 0.5 (or remove the param)"
            ),
        ));
    }
    let cmd = raw.cmd.map(|c| (here(&c), c.into_inner()));
    let at = Place {
        file,
        name,
        kind: &kind,
        line,
    };
    let (canonical_params, cmd) = if let Some(kind_impl) = builtin {
        if let Some((cmd_line, _)) = cmd {
            return Err(file.error(
                cmd_line,
                format!("stage `{name}`: `cmd` is only for kind `command`; remove it"),
            ));
        }
        check_builtin_bindings(&at, kind_impl, &inputs, &mut outputs, lines)?;
        let canonical = kind_impl.canonical_params(&params).map_err(|e| {
            let at = params_lines.get(&e.key).copied().unwrap_or(line);
            file.error(
                at,
                format!("stage `{name}` (kind `{kind}`): {e}; fix or remove this param"),
            )
        })?;
        (super::super::key::canonical_json(canonical), None)
    } else {
        let (json, cmd) = command_stage(&at, cmd, &inputs, &outputs, &params)?;
        (super::super::key::canonical_json(json), Some(cmd))
    };
    let (foreach, foreach_with) = match raw.foreach {
        Some(f) => stage_foreach(file, name, f, &inputs)?,
        None => (None, Vec::new()),
    };
    Ok(StageSpec {
        name: name.to_string(),
        kind,
        line,
        foreach,
        foreach_with,
        inputs,
        outputs,
        params,
        canonical_params,
        cmd,
    })
}

/// Where a stage stands, for its errors.
struct Place<'a> {
    file: &'a Source,
    name: &'a str,
    kind: &'a str,
    line: usize,
}

/// The stage's input bindings parsed, their lines noted.
fn stage_inputs(
    pipeline: &Pipeline,
    name: &str,
    raw: BTreeMap<Spanned<String>, Spanned<RawInput>>,
    file: &Source,
    lines: &mut Lines,
) -> Result<BTreeMap<String, InputSpec>, EngineError> {
    let mut inputs = BTreeMap::new();
    for (input_name, binding) in raw {
        let input_line = file.line_of(input_name.span().start);
        let input_name = input_name.into_inner();
        let spec = parse_binding(pipeline, binding.into_inner()).map_err(|m| {
            file.error(
                input_line,
                format!("stage `{name}` input `{input_name}`: {m}"),
            )
        })?;
        lines
            .inputs
            .insert((name.to_string(), input_name.clone()), input_line);
        inputs.insert(input_name, spec);
    }
    Ok(inputs)
}

/// The stage's output paths with `${…}` substituted, their lines noted.
fn stage_outputs(
    pipeline: &Pipeline,
    name: &str,
    raw: BTreeMap<Spanned<String>, Spanned<String>>,
    file: &Source,
    lines: &mut Lines,
) -> Result<BTreeMap<String, Option<PathBuf>>, EngineError> {
    let mut outputs = BTreeMap::new();
    for (output_name, path) in raw {
        let output_line = file.line_of(output_name.span().start);
        let output_name = output_name.into_inner();
        let path = substitute(pipeline, path.get_ref()).map_err(|m| {
            file.error(
                output_line,
                format!("stage `{name}` output `{output_name}`: {m}"),
            )
        })?;
        lines
            .outputs
            .insert((name.to_string(), output_name.clone()), output_line);
        outputs.insert(output_name, Some(path));
    }
    Ok(outputs)
}

/// A built-in kind's inputs and outputs against what the stage binds: every required input
/// bound, nothing the kind does not take; the kind's undeclared outputs added (not materialized).
fn check_builtin_bindings(
    at: &Place,
    kind_impl: &dyn StageKind,
    inputs: &BTreeMap<String, InputSpec>,
    outputs: &mut BTreeMap<String, Option<PathBuf>>,
    lines: &Lines,
) -> Result<(), EngineError> {
    let Place {
        file,
        name,
        kind,
        line,
    } = *at;
    for input in kind_impl.inputs() {
        if !inputs.contains_key(*input) {
            return Err(file.error(line, format!(
                "stage `{name}` (kind `{kind}`) is missing input `{input}`; add `{input} = \"<stage>:<output>\"` or a path to its inputs"
            )));
        }
    }
    for input_name in inputs.keys() {
        let known = kind_impl.inputs().contains(&input_name.as_str())
            || kind_impl.optional_inputs().contains(&input_name.as_str());
        if !known {
            let takes: Vec<&str> = kind_impl
                .inputs()
                .iter()
                .chain(kind_impl.optional_inputs())
                .copied()
                .collect();
            return Err(file.error(
                lines.inputs[&(name.to_string(), input_name.clone())],
                format!(
                    "stage `{name}`: kind `{kind}` has no input `{input_name}`; it takes: {}",
                    takes.join(", ")
                ),
            ));
        }
    }
    for output_name in outputs.keys() {
        if !kind_impl.outputs().contains(&output_name.as_str()) {
            return Err(file.error(
                lines.outputs[&(name.to_string(), output_name.clone())],
                format!(
                    "stage `{name}`: kind `{kind}` has no output `{output_name}`; it writes: {}",
                    kind_impl.outputs().join(", ")
                ),
            ));
        }
    }
    for o in kind_impl.outputs() {
        outputs.entry(o.to_string()).or_insert(None);
    }
    Ok(())
}

/// A `command` stage: its `cmd` (required), at least one output, placeholders that name
/// something; returns the params as JSON and the command.
fn command_stage(
    at: &Place,
    cmd: Option<(usize, String)>,
    inputs: &BTreeMap<String, InputSpec>,
    outputs: &BTreeMap<String, Option<PathBuf>>,
    params: &toml::Table,
) -> Result<(serde_json::Value, String), EngineError> {
    let Place {
        file, name, line, ..
    } = *at;
    let Some((cmd_line, cmd)) = cmd else {
        return Err(file.error(
            line,
            format!(
                "stage `{name}` (kind `command`) needs `cmd = \"...\"`, the shell command to run"
            ),
        ));
    };
    if outputs.is_empty() {
        return Err(file.error(line, format!("stage `{name}` (kind `command`) declares no outputs; add `outputs = {{ NAME = \"path\" }}`")));
    }
    command::check_placeholders(&cmd, inputs, outputs, params)
        .map_err(|m| file.error(cmd_line, format!("stage `{name}`: {m}")))?;
    let json = serde_json::to_value(params)
        .map_err(|e| file.error(line, format!("stage `{name}`: params: {e}")))?;
    Ok((json, cmd))
}

/// `foreach`: the first input named, and the others stepped through with it.
fn stage_foreach(
    file: &Source,
    name: &str,
    f: Spanned<Foreach>,
    inputs: &BTreeMap<String, InputSpec>,
) -> Result<(Option<String>, Vec<String>), EngineError> {
    let f_line = file.line_of(f.span().start);
    let mut names = match f.into_inner() {
        Foreach::One(one) => vec![one],
        Foreach::Many(many) => many,
    };
    if names.is_empty() {
        return Err(file.error(f_line, format!("stage `{name}`: foreach = [] names no input; name the collection input to map over")));
    }
    for f in &names {
        if !inputs.contains_key(f) {
            return Err(file.error(f_line, format!("stage `{name}`: foreach = \"{f}\" names no input of this stage; name one of its inputs")));
        }
        if matches!(inputs[f], InputSpec::Provenance) {
            return Err(file.error(f_line, format!("stage `{name}`: foreach cannot step through `{f}`, the provenance record; name a collection input")));
        }
    }
    let first = names.remove(0);
    Ok((Some(first), names))
}

/// What is wrong with a path of pipeline.toml (the caller says it at the path's line).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
enum PathError {
    /// `${name}` other than `${data}` and `${reports}`; holds the variable as written.
    #[error("unknown variable `{0}`; use `${{data}}` or `${{reports}}`")]
    UnknownVariable(String),
    #[error("empty path; write a file or folder path")]
    Empty,
}

/// `"engine:provenance"`, `"stage:output"`, a path, or `{ path, optional }`.
fn parse_binding(pipeline: &Pipeline, raw: RawInput) -> Result<InputSpec, PathError> {
    match raw {
        RawInput::Text(text) => {
            if text == "engine:provenance" {
                return Ok(InputSpec::Provenance);
            }
            let ident = |s: &str| {
                !s.is_empty()
                    && s.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            };
            if let Some((stage, output)) = text.split_once(':') {
                if ident(stage) && ident(output) {
                    return Ok(InputSpec::Stage {
                        stage: stage.to_string(),
                        output: output.to_string(),
                    });
                }
            }
            Ok(InputSpec::Path {
                path: substitute(pipeline, &text)?,
                optional: false,
            })
        }
        RawInput::Table(t) => Ok(InputSpec::Path {
            path: substitute(pipeline, &t.path)?,
            optional: t.optional,
        }),
    }
}

/// Whether a param holds no NaN or infinity (in arrays and tables too).
fn finite(value: &toml::Value) -> bool {
    match value {
        toml::Value::Float(x) => x.is_finite(),
        toml::Value::Array(a) => a.iter().all(finite),
        toml::Value::Table(t) => t.values().all(finite),
        _ => true,
    }
}

/// Expand `${data}` and `${reports}`, resolve against the project root, normalize.
fn substitute(pipeline: &Pipeline, text: &str) -> Result<PathBuf, PathError> {
    let mut out = text.to_string();
    for (var, value) in [
        ("${data}", &pipeline.data_dir),
        ("${reports}", &pipeline.reports_dir),
    ] {
        out = out.replace(var, &value.to_string_lossy());
    }
    if let Some(start) = out.find("${") {
        let var: String = out[start..].chars().take_while(|&c| c != '}').collect();
        return Err(PathError::UnknownVariable(format!("{var}}}")));
    }
    if out.is_empty() {
        return Err(PathError::Empty);
    }
    Ok(normalize(&pipeline.root.join(out)))
}

/// Lexically remove `.` and `..` components.
pub fn normalize(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    out.push("..");
                }
            }
            other => out.push(other),
        }
    }
    out
}

/// Stage references exist; required paths exist; no input reads a materialized output by path.
fn check_references(pipeline: &Pipeline, file: &Source, lines: &Lines) -> Result<(), EngineError> {
    let materialized: BTreeMap<&PathBuf, (&str, &str)> = pipeline
        .stages
        .values()
        .flat_map(|s| {
            s.outputs
                .iter()
                .filter_map(move |(o, p)| p.as_ref().map(|p| (p, (s.name.as_str(), o.as_str()))))
        })
        .collect();
    for stage in pipeline.stages.values() {
        for (input_name, spec) in &stage.inputs {
            let line = lines.inputs[&(stage.name.clone(), input_name.clone())];
            let fail = |m: String| {
                file.error(
                    line,
                    format!("stage `{}` input `{input_name}`: {m}", stage.name),
                )
            };
            match spec {
                InputSpec::Stage { stage: up, output } => {
                    let Some(up_spec) = pipeline.stages.get(up) else {
                        return Err(fail(format!(
                            "no stage `{up}`; stages: {}; or, for a file whose name holds `:`, write {{ path = \"{up}:{output}\" }}",
                            pipeline.stages.keys().cloned().collect::<Vec<_>>().join(", ")
                        )));
                    };
                    if !up_spec.outputs.contains_key(output) {
                        return Err(fail(format!(
                            "stage `{up}` has no output `{output}`; it writes: {}",
                            up_spec
                                .outputs
                                .keys()
                                .cloned()
                                .collect::<Vec<_>>()
                                .join(", ")
                        )));
                    }
                }
                InputSpec::Path { path, optional } => {
                    if let Some((s, o)) = path
                        .ancestors()
                        .find_map(|a| materialized.get(&a.to_path_buf()))
                    {
                        return Err(fail(format!(
                            "{} is written by stage `{s}`; bind it as \"{s}:{o}\" instead of a path",
                            pipeline.show(path)
                        )));
                    }
                    if !optional && !path.exists() {
                        return Err(fail(format!(
                            "{} does not exist; create it, fix the path, or mark it {{ path = \"...\", optional = true }}",
                            pipeline.show(path)
                        )));
                    }
                }
                InputSpec::Provenance => {}
            }
        }
    }
    Ok(())
}

/// Why an output may not be written at `path`, if it may not: outputs stay inside the project
/// folder or the reports folder, and never land on (or in, or around) the config, the lock, the
/// store, the dataset or any path input.
fn forbidden_output(pipeline: &Pipeline, inputs: &PathInputs, path: &Path) -> Option<String> {
    let inside = |base: &Path| path.starts_with(base) && path != base;
    if !inside(&pipeline.root) && !inside(&pipeline.reports_dir) {
        return Some("outside the project folder and the reports folder".into());
    }
    let protected = [
        (pipeline.config_path.clone(), "the pipeline config"),
        (pipeline.root.join("pipeline.lock"), "pipeline.lock"),
        (pipeline.root.join(".groove"), "the store"),
    ];
    for (p, what) in &protected {
        if path.starts_with(p) || p.starts_with(path) {
            return Some(format!("which would replace {what}"));
        }
    }
    if path.starts_with(&pipeline.data_dir) || pipeline.data_dir.starts_with(path) {
        return Some(format!(
            "inside or around the dataset folder {} (is the reports folder the dataset folder?)",
            pipeline.show(&pipeline.data_dir)
        ));
    }
    // the first stage (and its first input) in config order that `path` is at or inside
    let (_, name, stage) = path.ancestors().filter_map(|a| inputs.get(a)).min()?;
    Some(format!("onto or inside input `{name}` of stage `{stage}`"))
}

/// Every path input of the pipeline, each with its first reader (stage and input, in the order
/// the stages and their inputs are kept): an output's ancestors are looked up here, one
/// search each, not every input of every stage per output (10,000 stages took 7 s).
type PathInputs<'p> = BTreeMap<&'p Path, ((usize, usize), &'p str, &'p str)>;

fn path_inputs(pipeline: &Pipeline) -> PathInputs<'_> {
    let mut all = PathInputs::new();
    for (i, stage) in pipeline.stages.values().enumerate() {
        for (j, (name, input)) in stage.inputs.iter().enumerate() {
            if let InputSpec::Path { path: input, .. } = input {
                all.entry(input.as_path())
                    .or_insert(((i, j), name.as_str(), stage.name.as_str()));
            }
        }
    }
    all
}

/// No two outputs write one path, nor one inside another.
fn check_outputs(pipeline: &Pipeline, file: &Source) -> Result<(), EngineError> {
    let mut all: Vec<(&PathBuf, &str, &str, usize)> = Vec::new();
    let inputs = path_inputs(pipeline);
    for stage in pipeline.stages.values() {
        for (output, path) in &stage.outputs {
            let Some(path) = path else { continue };
            if let Some(why) = forbidden_output(pipeline, &inputs, path) {
                return Err(file.error(stage.line, format!(
                    "stage `{}` output `{output}` would write {}, {why}; choose a path inside the reports folder",
                    stage.name,
                    pipeline.show(path)
                )));
            }
            all.push((path, &stage.name, output, stage.line));
        }
    }
    // sorted by components, a path and everything inside it are neighbours
    all.sort();
    for pair in all.windows(2) {
        let ((a, a_stage, a_output, a_line), (b, b_stage, b_output, b_line)) = (pair[0], pair[1]);
        if b.starts_with(a) {
            let (first, second) = if a_line <= b_line {
                ((a_stage, a_output, a_line), (b_stage, b_output, b_line))
            } else {
                ((b_stage, b_output, b_line), (a_stage, a_output, a_line))
            };
            let what = if a == b {
                format!("both write {}", pipeline.show(a))
            } else {
                format!(
                    "write {} and {} inside it",
                    pipeline.show(a),
                    pipeline.show(b)
                )
            };
            return Err(file.error(second.2, format!(
                "stages `{}` (line {}, output `{}`) and `{}` (output `{}`) {what}; give one of them another path",
                first.0, first.2, first.1, second.0, second.1
            )));
        }
    }
    Ok(())
}

/// `[project] params`: params every stage whose kind takes them inherits unless it sets its own
/// (a kind takes a param when its defaults name it), so a setting shared by several stages
/// (`min_frames`) is written once.
struct SharedParams {
    params: Vec<(String, toml::Value, usize)>,
}

impl SharedParams {
    fn of(raw: Option<&BTreeMap<Spanned<String>, Spanned<toml::Value>>>, file: &Source) -> Self {
        let params = raw
            .into_iter()
            .flatten()
            .map(|(k, v)| {
                let line = file.line_of(k.span().start);
                (k.get_ref().clone(), v.get_ref().clone(), line)
            })
            .collect();
        SharedParams { params }
    }

    /// The names a kind's params take, from its defaults.
    fn taken_by(kind: &dyn StageKind) -> Vec<String> {
        match kind.canonical_params(&toml::Table::new()) {
            Ok(serde_json::Value::Object(defaults)) => defaults.keys().cloned().collect(),
            _ => Vec::new(),
        }
    }

    /// Adds to `params` each shared param the kind takes and the stage does not set.
    fn inherit(
        &self,
        kind: &dyn StageKind,
        params: &mut toml::Table,
        lines: &mut BTreeMap<String, usize>,
    ) {
        let taken = Self::taken_by(kind);
        for (name, value, line) in &self.params {
            if taken.contains(name) && !params.contains_key(name) {
                params.insert(name.clone(), value.clone());
                lines.insert(name.clone(), *line);
            }
        }
    }

    /// A shared param that no stage's kind takes is a spelling mistake, said at its line.
    fn check_taken(&self, pipeline: &Pipeline, file: &Source) -> Result<(), EngineError> {
        for (name, _, line) in &self.params {
            let used = pipeline
                .stages
                .values()
                .any(|s| s.cmd.is_none() && s.canonical_params.get(name).is_some());
            if !used {
                return Err(file.error(
                    *line,
                    format!("[project] params: no stage's kind takes `{name}`; fix the spelling or remove it"),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pipeline() -> Pipeline {
        Pipeline {
            config_path: PathBuf::from("/p/pipeline.toml"),
            root: PathBuf::from("/p"),
            seed: 1,
            data_dir: PathBuf::from("data"),
            reports_dir: PathBuf::from("reports"),
            stages: BTreeMap::new(),
        }
    }

    #[test]
    fn a_bad_path_is_a_typed_error_that_says_the_fix() {
        let p = pipeline();
        assert_eq!(
            substitute(&p, "${data}/../x.csv"),
            Ok(PathBuf::from("/p/x.csv"))
        );
        let unknown = substitute(&p, "${dta}/runs.csv").unwrap_err();
        assert_eq!(unknown, PathError::UnknownVariable("${dta}".into()));
        assert_eq!(
            unknown.to_string(),
            "unknown variable `${dta}`; use `${data}` or `${reports}`"
        );
        assert_eq!(substitute(&p, ""), Err(PathError::Empty));
        assert_eq!(
            parse_binding(&p, RawInput::Text("${out}/x".into())).unwrap_err(),
            PathError::UnknownVariable("${out}".into())
        );
    }
}
