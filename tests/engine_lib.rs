//! The engine as a library with fake stage kinds: code fingerprints, params errors, per-item
//! keys, provenance. Fake kinds count their calls so a test sees exactly what ran.

use groove::engine::config::{self, Overrides};
use groove::engine::run::{run, RunOptions};
use groove::engine::stage::{
    typed_params, Artifact, ParamError, StageError, StageInput, StageKind, StageOutputs,
};
use groove::engine::status::{status, State};
use groove::engine::{Catalog, EngineError, Pipeline};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

#[derive(Default, Clone)]
struct Calls(Arc<BTreeMap<&'static str, AtomicUsize>>);

impl Calls {
    fn new() -> Calls {
        Calls(Arc::new(
            ["square", "total", "stamp"]
                .into_iter()
                .map(|k| (k, AtomicUsize::new(0)))
                .collect(),
        ))
    }
    fn hit(&self, kind: &str) {
        self.0[kind].fetch_add(1, Ordering::SeqCst);
    }
    /// Calls per kind since the last take.
    fn take(&self) -> BTreeMap<&'static str, usize> {
        self.0
            .iter()
            .map(|(k, v)| (*k, v.swap(0, Ordering::SeqCst)))
            .collect()
    }
}

fn text(a: &Artifact) -> String {
    match a {
        Artifact::File(b) => String::from_utf8(b.clone()).unwrap(),
        Artifact::Collection(_) | Artifact::InStore(_) | Artifact::OnDisk(_) => {
            panic!("expected a file")
        }
    }
}

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct NoParams {}

/// Per item: the square of the number in the file.
struct Square(Calls);
impl StageKind for Square {
    fn kind(&self) -> &'static str {
        "square"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["values"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["squared"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        typed_params::<NoParams>(params).map(|(_, v)| v)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        self.0.hit("square");
        let x: f64 = text(input.inputs["values"])
            .trim()
            .parse()
            .map_err(|_| StageError("not a number".into()))?;
        Ok(BTreeMap::from([(
            "squared".to_string(),
            Artifact::File(format!("{}", x * x).into_bytes()),
        )]))
    }
}

#[derive(Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
struct TotalParams {
    offset: f64,
}

/// The sum of all squares plus an offset.
struct Total(Calls);
impl StageKind for Total {
    fn kind(&self) -> &'static str {
        "total"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["squared"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["total"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        typed_params::<TotalParams>(params).map(|(_, v)| v)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        self.0.hit("total");
        let (p, _) =
            typed_params::<TotalParams>(input.params).map_err(|e| StageError(e.to_string()))?;
        let Artifact::Collection(items) = input.inputs["squared"] else {
            return Err(StageError("squared must be a collection".into()));
        };
        let sum: f64 = items
            .values()
            .map(|b| std::str::from_utf8(b).unwrap().parse::<f64>().unwrap())
            .sum();
        Ok(BTreeMap::from([(
            "total".to_string(),
            Artifact::File(format!("{}", sum + p.offset).into_bytes()),
        )]))
    }
}

/// Copies the provenance record (and the total) into its output.
struct Stamp(Calls);
impl StageKind for Stamp {
    fn kind(&self) -> &'static str {
        "stamp"
    }
    fn inputs(&self) -> &'static [&'static str] {
        &["total"]
    }
    fn optional_inputs(&self) -> &'static [&'static str] {
        &["provenance"]
    }
    fn outputs(&self) -> &'static [&'static str] {
        &["record"]
    }
    fn canonical_params(&self, params: &toml::Table) -> Result<serde_json::Value, ParamError> {
        typed_params::<NoParams>(params).map(|(_, v)| v)
    }
    fn run(&self, input: &StageInput) -> Result<StageOutputs, StageError> {
        self.0.hit("stamp");
        let record = input
            .inputs
            .get("provenance")
            .map(|a| text(a))
            .unwrap_or_default();
        Ok(BTreeMap::from([(
            "record".to_string(),
            Artifact::File(record.into_bytes()),
        )]))
    }
}

fn catalog(calls: &Calls, square_code: &str) -> Catalog {
    Catalog {
        kinds: vec![
            Box::new(Square(calls.clone())),
            Box::new(Total(calls.clone())),
            Box::new(Stamp(calls.clone())),
        ],
        fingerprints: [
            ("square", square_code),
            ("total", "t1"),
            ("stamp", "s1"),
            ("command", "c1"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect(),
        code_commit: "test-commit".into(),
        version: "0.0.0-test".into(),
    }
}

const PIPELINE: &str = r#"[project]
seed = 11

[stages.square]
kind = "square"
foreach = "values"
inputs = { values = "data/values" }

[stages.total]
kind = "total"
inputs = { squared = "square:squared" }
params = { offset = 0.5 }
outputs = { total = "reports/total.txt" }

[stages.stamp]
kind = "stamp"
inputs = { total = "total:total", provenance = "engine:provenance" }
outputs = { record = "reports/provenance.json" }
"#;

fn project(pipeline: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("pipeline.toml"), pipeline).unwrap();
    std::fs::create_dir_all(dir.path().join("data/values")).unwrap();
    for (name, v) in [("a.txt", "1"), ("b.txt", "2"), ("c.txt", "3")] {
        std::fs::write(dir.path().join("data/values").join(name), v).unwrap();
    }
    dir
}

fn load(dir: &tempfile::TempDir, catalog: &Catalog) -> Result<Pipeline, EngineError> {
    config::load(
        &dir.path().join("pipeline.toml"),
        &Overrides::default(),
        catalog,
    )
}

fn quiet() -> RunOptions {
    RunOptions {
        quiet: true,
        ..RunOptions::default()
    }
}

fn stale(catalog: &Catalog, pipeline: &Pipeline) -> Vec<(String, String)> {
    status(catalog, pipeline, None)
        .unwrap()
        .into_iter()
        .filter(|s| s.state == State::Stale)
        .map(|s| (s.stage, s.reasons.join("; ")))
        .collect()
}

#[test]
fn per_item_stage_computes_each_item_and_the_aggregate_is_right() {
    let calls = Calls::new();
    let dir = project(PIPELINE);
    let cat = catalog(&calls, "q1");
    let p = load(&dir, &cat).unwrap();
    run(&cat, &p, &quiet()).unwrap();
    assert_eq!(
        calls.take(),
        BTreeMap::from([("square", 3), ("stamp", 1), ("total", 1)])
    );
    // 1 + 4 + 9 + 0.5, exact in binary floating point
    assert_eq!(
        std::fs::read_to_string(dir.path().join("reports/total.txt")).unwrap(),
        "14.5"
    );
}

#[test]
fn a_changed_code_fingerprint_makes_that_stage_and_its_descendants_stale() {
    let calls = Calls::new();
    let dir = project(PIPELINE);
    let before = catalog(&calls, "q1");
    let p = load(&dir, &before).unwrap();
    run(&before, &p, &quiet()).unwrap();
    calls.take();

    let after = catalog(&calls, "q2");
    let stale = stale(&after, &p);
    let names: Vec<&str> = stale.iter().map(|s| s.0.as_str()).collect();
    assert_eq!(names, vec!["square", "total", "stamp"]);
    assert!(
        stale[0]
            .1
            .contains("code of kind `square` changed (fingerprint q1 → q2)"),
        "{}",
        stale[0].1
    );
    assert!(stale[1].1.contains("waits on `square`"));

    // square reruns every item; its output is identical, so total is not rerun (early cutoff);
    // stamp reruns because the provenance it reads names the new code
    run(&after, &p, &quiet()).unwrap();
    assert_eq!(
        calls.take(),
        BTreeMap::from([("square", 3), ("stamp", 1), ("total", 0)])
    );
    assert!(status(&after, &p, None)
        .unwrap()
        .iter()
        .all(|s| s.state == State::Fresh));
}

#[test]
fn one_changed_item_reruns_only_that_item() {
    let calls = Calls::new();
    let dir = project(PIPELINE);
    let cat = catalog(&calls, "q1");
    let p = load(&dir, &cat).unwrap();
    run(&cat, &p, &quiet()).unwrap();
    calls.take();
    std::fs::write(dir.path().join("data/values/b.txt"), "4").unwrap();
    let stale = stale(&cat, &p);
    assert!(
        stale[0]
            .1
            .contains("input `values` changed (data/values): items `b.txt`"),
        "{}",
        stale[0].1
    );
    run(&cat, &p, &quiet()).unwrap();
    assert_eq!(
        calls.take(),
        BTreeMap::from([("square", 1), ("stamp", 1), ("total", 1)])
    );
    assert_eq!(
        std::fs::read_to_string(dir.path().join("reports/total.txt")).unwrap(),
        "26.5"
    );
}

#[test]
fn provenance_lists_code_inputs_and_upstream_keys_and_is_location_independent() {
    let calls = Calls::new();
    let cat = catalog(&calls, "q1");
    let records: Vec<String> = (0..2)
        .map(|_| {
            let dir = project(PIPELINE);
            let p = load(&dir, &cat).unwrap();
            run(&cat, &p, &quiet()).unwrap();
            let lock: serde_json::Value =
                serde_json::from_slice(&std::fs::read(dir.path().join("pipeline.lock")).unwrap())
                    .unwrap();
            let record =
                std::fs::read_to_string(dir.path().join("reports/provenance.json")).unwrap();
            let v: serde_json::Value = serde_json::from_str(&record).unwrap();
            assert_eq!(v["groove_version"], "0.0.0-test");
            assert_eq!(v["code_commit"], "test-commit");
            assert_eq!(v["fingerprints"]["square"], "q1");
            assert_eq!(v["seed"], 11);
            assert_eq!(v["inputs"][1]["path"], "${data}/values/b.txt");
            assert_eq!(
                v["inputs"][1]["sha256"],
                groove::engine::hashing::sha256_hex(b"2")
            );
            assert_eq!(v["stages"][0]["stage"], "square");
            assert_eq!(v["stages"][1]["key"], lock["stages"]["total"]["key"]);
            assert!(
                !record.contains(dir.path().to_str().unwrap()),
                "no absolute paths"
            );
            record
        })
        .collect();
    assert_eq!(records[0], records[1]);
}

/// (pipeline text, marker of the expected line, phrase)
#[test]
fn param_and_input_errors_name_the_line() {
    let cases = [
        (
            PIPELINE.replace("offset = 0.5", "offest = 0.5"),
            "offest",
            "unknown field `offest`",
        ),
        (
            PIPELINE.replace("offset = 0.5", "offset = \"half\""),
            "offset",
            "invalid type",
        ),
        (
            PIPELINE.replace("inputs = { squared = \"square:squared\" }", "inputs = { }"),
            "[stages.total]",
            "missing input `squared`",
        ),
        (
            PIPELINE.replace(
                "squared = \"square:squared\"",
                "squared = \"square:sqared\"",
            ),
            "square:sqared",
            "stage `square` has no output `sqared`; it writes: squared",
        ),
        (
            PIPELINE.replace("foreach = \"values\"", "foreach = \"vals\""),
            "foreach",
            "names no input",
        ),
    ];
    let calls = Calls::new();
    let cat = catalog(&calls, "q1");
    for (text, marker, phrase) in cases {
        let dir = project(&text);
        let line = text.lines().position(|l| l.contains(marker)).unwrap() + 1;
        let err = load(&dir, &cat).expect_err("an error").to_string();
        assert!(
            err.starts_with(&format!("pipeline.toml:{line}: ")),
            "{marker}: want line {line}: {err}"
        );
        assert!(err.contains(phrase), "{marker}: want `{phrase}`: {err}");
    }
}

/// `[project] params` reach every stage whose kind takes the param, unless the stage sets its
/// own; a shared param no kind takes is an error at its line.
#[test]
fn project_params_are_inherited_by_the_kinds_that_take_them() {
    let calls = Calls::new();
    let cat = catalog(&calls, "q1");
    let offset_of = |text: &str| -> serde_json::Value {
        let dir = project(text);
        let p = load(&dir, &cat).unwrap();
        p.stages["total"].canonical_params["offset"].clone()
    };
    let shared = PIPELINE.replace("seed = 11\n", "seed = 11\nparams = { offset = 2.5 }\n");
    // the stage's own value wins; without it the project's; the kinds without it get nothing
    assert_eq!(offset_of(&shared), serde_json::json!(0.5));
    let inherited = shared.replace("params = { offset = 0.5 }\n", "");
    assert_eq!(offset_of(&inherited), serde_json::json!(2.5));
    assert_eq!(
        offset_of(&PIPELINE.replace("params = { offset = 0.5 }\n", "")),
        serde_json::json!(0.0)
    );
    let dir = project(&inherited);
    let p = load(&dir, &cat).unwrap();
    assert!(!p.stages["square"].params.contains_key("offset"));
    // the inherited value is the stage's param: it runs with it
    run(&cat, &p, &quiet()).unwrap();
    let total = std::fs::read_to_string(dir.path().join("reports/total.txt")).unwrap();
    assert_eq!(total.trim(), "16.5");
    // a misspelt shared param
    let text = PIPELINE.replace("seed = 11\n", "seed = 11\nparams = { ofset = 2.5 }\n");
    let err = load(&project(&text), &cat)
        .expect_err("no kind takes `ofset`")
        .to_string();
    let line = text.lines().position(|l| l.contains("ofset")).unwrap() + 1;
    assert!(err.starts_with(&format!("pipeline.toml:{line}: ")), "{err}");
    assert!(err.contains("no stage's kind takes `ofset`"), "{err}");
}

#[test]
fn optional_absent_input_is_missing_and_appearing_makes_it_stale() {
    let calls = Calls::new();
    let cat = catalog(&calls, "q1");
    let text = PIPELINE.replace(
        "inputs = { total = \"total:total\", provenance = \"engine:provenance\" }",
        "inputs = { total = \"total:total\", provenance = { path = \"extra.json\", optional = true } }",
    );
    let dir = project(&text);
    let p = load(&dir, &cat).unwrap();
    run(&cat, &p, &quiet()).unwrap();
    assert_eq!(
        std::fs::read_to_string(dir.path().join("reports/provenance.json")).unwrap(),
        ""
    );
    std::fs::write(dir.path().join("extra.json"), "{}").unwrap();
    let stale = stale(&cat, &p);
    assert_eq!(stale.len(), 1);
    assert!(
        stale[0].1.contains("input `provenance` added"),
        "{}",
        stale[0].1
    );
}
