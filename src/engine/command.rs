//! The `command` kind: a user's own program on the DAG, run with `sh -c` in the project folder.
//!
//! Placeholders in `cmd`: `{in.NAME}` (a file, or a folder for a collection), `{out.NAME}` (where
//! the program must write that output: a file, or a folder that becomes a collection),
//! `{params.NAME}`, `{item}` (per-item stages) and `{seed}`. Inputs are copied into a private
//! folder under `.groove/tmp/`, outputs are written there and only taken into the store after
//! the program exited 0 and wrote every output. Other braces (shell `${VAR}`, awk) are left alone.

use super::inputs::dir_files;
use super::pipeline::{InputSpec, Pipeline, StageSpec};
use super::stage::{Artifact, StageOutputs};
use super::store::Store;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One `{ns.name}` / `{item}` / `{seed}` placeholder found in a command.
#[derive(Debug, PartialEq, Eq)]
enum Placeholder<'a> {
    In(&'a str),
    Out(&'a str),
    Param(&'a str),
    Item,
    Seed,
}

/// Split a command into literal text and placeholders.
fn parse(cmd: &str) -> Vec<Result<&str, (Placeholder<'_>, &str)>> {
    let mut parts = Vec::new();
    let mut rest = cmd;
    'outer: while let Some(open) = rest.find('{') {
        let after = &rest[open + 1..];
        if let Some(close) = after.find('}') {
            let inner = &after[..close];
            let ident = |s: &str| {
                !s.is_empty()
                    && s.chars()
                        .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
            };
            let ph = match inner.split_once('.') {
                Some(("in", n)) if ident(n) => Some(Placeholder::In(n)),
                Some(("out", n)) if ident(n) => Some(Placeholder::Out(n)),
                Some(("params", n)) if ident(n) => Some(Placeholder::Param(n)),
                None if inner == "item" => Some(Placeholder::Item),
                None if inner == "seed" => Some(Placeholder::Seed),
                _ => None,
            };
            if let Some(ph) = ph {
                parts.push(Ok(&rest[..open]));
                parts.push(Err((ph, &rest[open..open + close + 2])));
                rest = &after[close + 1..];
                continue 'outer;
            }
        }
        parts.push(Ok(&rest[..open + 1]));
        rest = after;
    }
    parts.push(Ok(rest));
    parts
}

/// Every placeholder names a declared input, output or param.
pub fn check_placeholders(
    cmd: &str,
    inputs: &BTreeMap<String, InputSpec>,
    outputs: &BTreeMap<String, Option<PathBuf>>,
    params: &toml::Table,
) -> Result<(), String> {
    for part in parse(cmd) {
        let Err((ph, text)) = part else { continue };
        let (ok, what, names): (bool, &str, Vec<&String>) = match ph {
            Placeholder::In(n) => (inputs.contains_key(n), "input", inputs.keys().collect()),
            Placeholder::Out(n) => (outputs.contains_key(n), "output", outputs.keys().collect()),
            Placeholder::Param(n) => (params.contains_key(n), "param", params.keys().collect()),
            Placeholder::Item | Placeholder::Seed => (true, "", vec![]),
        };
        if !ok {
            let names: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
            return Err(format!(
                "`{text}` in cmd names no {what} of this stage; declared: {}",
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            ));
        }
    }
    Ok(())
}

/// Quote a value for `sh`.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// The file name an input is given in the private folder (keeps extensions scripts may rely on).
fn input_file_name(
    pipeline: &Pipeline,
    spec: &StageSpec,
    input: &str,
    item: Option<&str>,
) -> String {
    if spec.is_item_input(input) {
        if let Some(item) = item {
            return item.to_string();
        }
    }
    let base = |p: &Path| p.file_name().map(|n| n.to_string_lossy().into_owned());
    match &spec.inputs[input] {
        InputSpec::Path { path, .. } => base(path),
        InputSpec::Stage { stage, output } => pipeline.stages[stage].outputs[output]
            .as_deref()
            .and_then(base),
        InputSpec::Provenance => Some("provenance.json".into()),
    }
    .unwrap_or_else(|| input.to_string())
}

fn write_artifact(path: &Path, artifact: &Artifact) -> Result<(), String> {
    let io = |e: std::io::Error| format!("{}: {e}", path.display());
    match artifact {
        Artifact::File(bytes) => std::fs::write(path, bytes).map_err(io),
        Artifact::Collection(items) => {
            std::fs::create_dir_all(path).map_err(io)?;
            for (name, bytes) in items {
                std::fs::write(path.join(name), bytes)
                    .map_err(|e| format!("{}: {e}", path.join(name).display()))?;
            }
            Ok(())
        }
        Artifact::InStore(_) | Artifact::OnDisk(_) => Err(format!(
            "{}: {}",
            path.display(),
            super::stage::IN_STORE_INPUT
        )),
    }
}

/// Run a command stage once (or for one item). Errors are the stage's failure message.
pub fn run(
    store: &Store,
    pipeline: &Pipeline,
    spec: &StageSpec,
    inputs: &BTreeMap<&str, &Artifact>,
    item: Option<&str>,
    seed: u64,
) -> Result<StageOutputs, String> {
    let work = store
        .tmp_dir(&format!("cmd-{}", spec.name))
        .map_err(|e| e.to_string())?;
    let result = run_in(&work, pipeline, spec, inputs, item, seed);
    let _ = std::fs::remove_dir_all(&work);
    result
}

fn run_in(
    work: &Path,
    pipeline: &Pipeline,
    spec: &StageSpec,
    inputs: &BTreeMap<&str, &Artifact>,
    item: Option<&str>,
    seed: u64,
) -> Result<StageOutputs, String> {
    let io = |p: &Path, e: std::io::Error| format!("{}: {e}", p.display());
    let mut in_paths = BTreeMap::new();
    for (name, artifact) in inputs {
        let dir = work.join("in").join(name);
        std::fs::create_dir_all(&dir).map_err(|e| io(&dir, e))?;
        let path = dir.join(input_file_name(pipeline, spec, name, item));
        write_artifact(&path, artifact)?;
        in_paths.insert(name.to_string(), path);
    }
    let mut out_paths = BTreeMap::new();
    for (name, target) in &spec.outputs {
        let dir = work.join("out").join(name);
        std::fs::create_dir_all(&dir).map_err(|e| io(&dir, e))?;
        let file = target
            .as_deref()
            .and_then(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned());
        out_paths.insert(name.clone(), dir.join(file.unwrap_or_else(|| name.clone())));
    }
    let mut script = String::new();
    for part in parse(spec.cmd.as_deref().unwrap_or("")) {
        match part {
            Ok(text) => script.push_str(text),
            Err((Placeholder::In(n), _)) => match in_paths.get(n) {
                Some(p) => script.push_str(&quote(&p.to_string_lossy())),
                // an absent optional input
                None => script.push_str("''"),
            },
            Err((Placeholder::Out(n), _)) => {
                script.push_str(&quote(&out_paths[n].to_string_lossy()))
            }
            Err((Placeholder::Param(n), _)) => {
                let v = match &spec.params[n] {
                    toml::Value::String(s) => s.clone(),
                    other => other.to_string(),
                };
                script.push_str(&quote(&v));
            }
            Err((Placeholder::Item, _)) => script.push_str(&quote(item.unwrap_or(""))),
            Err((Placeholder::Seed, _)) => script.push_str(&seed.to_string()),
        }
    }
    let output = Command::new("sh")
        .arg("-c")
        .arg(&script)
        .current_dir(&pipeline.root)
        .stdin(std::process::Stdio::null())
        .output()
        .map_err(|e| format!("cannot start `sh`: {e}; install a POSIX shell"))?;
    if !output.status.success() {
        let stderr = String::from_utf8_lossy(&output.stderr);
        let tail: Vec<&str> = stderr.lines().rev().take(20).collect();
        let tail: Vec<&str> = tail.into_iter().rev().collect();
        return Err(format!(
            "command failed ({}){}{}",
            output.status,
            if tail.is_empty() { "" } else { ":\n" },
            tail.join("\n")
        ));
    }
    let mut outputs = StageOutputs::new();
    for (name, path) in out_paths {
        let artifact = if path.is_dir() {
            let mut items = BTreeMap::new();
            for (item_name, p) in dir_files(&path).map_err(|e| e.to_string())? {
                items.insert(item_name, std::fs::read(&p).map_err(|e| io(&p, e))?);
            }
            Artifact::Collection(items)
        } else if path.is_file() {
            Artifact::File(std::fs::read(&path).map_err(|e| io(&path, e))?)
        } else {
            return Err(format!(
                "the command exited 0 but wrote nothing at {{out.{name}}}; write that output to the path the placeholder gives"
            ));
        };
        outputs.insert(name, artifact);
    }
    Ok(outputs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_are_found_and_shell_braces_left_alone() {
        let parts = parse("awk '{print $1}' {in.table} > {out.plot} ${HOME} {item}{seed}");
        let found: Vec<&str> = parts
            .iter()
            .filter_map(|p| p.as_ref().err().map(|(_, t)| *t))
            .collect();
        assert_eq!(found, vec!["{in.table}", "{out.plot}", "{item}", "{seed}"]);
        let literal: String = parts
            .iter()
            .filter_map(|p| p.as_ref().ok().copied())
            .collect();
        assert_eq!(literal, "awk '{print $1}'  >  ${HOME} ");
    }

    #[test]
    fn quoting_survives_single_quotes() {
        assert_eq!(quote("a'b"), "'a'\\''b'");
    }
}
