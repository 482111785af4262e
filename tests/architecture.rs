//! The shape of the code, checked: the engine names no analysis module and its files form no
//! cycle, each kind's compiled code fingerprint covers exactly the modules it uses, and the
//! README's code map names every module and names nothing that does not exist.

#[path = "../src/build/code_deps.rs"]
#[allow(dead_code)]
mod code_deps;

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn rel(root: &Path, p: &Path) -> String {
    p.strip_prefix(root)
        .unwrap_or(p)
        .to_string_lossy()
        .replace('\\', "/")
}

/// Every file the engine reaches (from `src/engine/mod.rs`) that lies outside `src/engine/`.
fn engine_escapes(src: &Path) -> Vec<String> {
    let engine = src.join("engine");
    code_deps::files_used(src, &engine.join("mod.rs"))
        .into_iter()
        .filter(|f| !f.starts_with(&engine))
        .map(|f| rel(src, &f))
        .collect()
}

/// A cycle among sibling files of `dir` (edges: the modules a file names, not its children).
fn find_cycle(src: &Path, dir: &Path) -> Option<Vec<String>> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                files.push(p);
            }
        }
    }
    let graph: BTreeMap<PathBuf, Vec<PathBuf>> = files
        .iter()
        .map(|f| {
            let named = code_deps::direct_uses(src, f).named;
            (f.clone(), named.into_iter().filter(|n| n != f).collect())
        })
        .collect();
    // depth-first search with colours: 1 = on the path, 2 = done
    fn visit(
        f: &PathBuf,
        graph: &BTreeMap<PathBuf, Vec<PathBuf>>,
        colour: &mut BTreeMap<PathBuf, u8>,
        path: &mut Vec<PathBuf>,
    ) -> Option<Vec<PathBuf>> {
        colour.insert(f.clone(), 1);
        path.push(f.clone());
        for n in graph.get(f).into_iter().flatten() {
            match colour.get(n).copied().unwrap_or(0) {
                1 => {
                    let at = path.iter().position(|p| p == n).unwrap();
                    let mut cycle = path[at..].to_vec();
                    cycle.push(n.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(n, graph, colour, path) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        path.pop();
        colour.insert(f.clone(), 2);
        None
    }
    let mut colour = BTreeMap::new();
    for f in graph.keys() {
        if colour.get(f).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(f, &graph, &mut colour, &mut Vec::new()) {
                return Some(c.iter().map(|p| rel(src, p)).collect());
            }
        }
    }
    None
}

fn write(root: &Path, files: &[(&str, &str)]) {
    for (path, text) in files {
        let p = root.join(path);
        fs::create_dir_all(p.parent().unwrap()).unwrap();
        fs::write(p, text).unwrap();
    }
}

#[test]
fn the_engine_names_no_module_outside_it() {
    let escapes = engine_escapes(&repo().join("src"));
    assert!(
        escapes.is_empty(),
        "src/engine reaches {escapes:?}; the engine knows no analysis: let the command line hand it what it needs"
    );
}

#[test]
fn the_engine_check_catches_an_analysis_import() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    write(
        dir.path(),
        &[
            ("src/lib.rs", "pub mod engine;\npub mod fit;\n"),
            ("src/engine/mod.rs", "pub mod catalog;\npub mod store;\n"),
            ("src/engine/store.rs", "//! store\n"),
            (
                "src/engine/catalog.rs",
                "//! catalog\nuse super::store;\npub fn f() { crate::fit::single::run(); }\n",
            ),
            ("src/fit/mod.rs", "pub mod single;\n"),
            ("src/fit/single.rs", "pub fn run() {}\n"),
        ],
    );
    assert_eq!(engine_escapes(&src), ["fit/single.rs"]);
    write(
        dir.path(),
        &[("src/engine/catalog.rs", "use super::store;\n")],
    );
    assert!(engine_escapes(&src).is_empty());
}

#[test]
fn the_engine_files_form_no_cycle() {
    let src = repo().join("src");
    if let Some(cycle) = find_cycle(&src, &src.join("engine")) {
        panic!(
            "engine modules use each other in a cycle: {}",
            cycle.join(" -> ")
        );
    }
}

#[test]
fn the_cycle_check_catches_a_cycle() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    write(
        dir.path(),
        &[
            ("src/engine/mod.rs", "pub mod a;\npub mod b;\npub mod c;\n"),
            ("src/engine/a.rs", "use super::b::X;\n"),
            ("src/engine/b.rs", "use super::{c::Y, a};\n"),
            ("src/engine/c.rs", "pub struct Y;\n"),
        ],
    );
    let cycle = find_cycle(&src, &src.join("engine")).expect("a -> b -> a is a cycle");
    assert_eq!(cycle, ["engine/a.rs", "engine/b.rs", "engine/a.rs"]);
    write(dir.path(), &[("src/engine/b.rs", "use super::c::Y;\n")]);
    assert_eq!(find_cycle(&src, &src.join("engine")), None);
}

/// The derivation on a small tree: `use` trees with braces, `super::`, `mod` children,
/// `include_str!`, methods in a sibling file, test-only code ignored, modules passed through
/// not included.
#[test]
fn the_files_a_kind_uses_are_followed_through_its_paths() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    write(
        dir.path(),
        &[
            (
                "src/lib.rs",
                "pub mod engine;\npub mod fit;\npub mod report;\npub mod stages;\n",
            ),
            ("src/engine/mod.rs", "pub mod stage;\npub mod store;\n"),
            (
                "src/engine/stage.rs",
                "use super::super::engine::store as _s;\n",
            ),
            (
                "src/engine/store.rs",
                "//! reached from stage.rs only through super::super\n",
            ),
            (
                "src/fit/mod.rs",
                "pub mod lm;\nmod robust;\nmod robust_impl;\npub use lm::solve;\n",
            ),
            (
                "src/fit/robust_impl.rs",
                "impl super::robust::Huber { pub fn k(&self) {} }\n",
            ),
            (
                "src/fit/lm.rs",
                "pub fn solve() { super::robust::huber(); }\n",
            ),
            (
                "src/fit/robust.rs",
                "pub struct Huber;\npub fn huber() {}\n",
            ),
            ("src/report/mod.rs", "pub mod html;\n"),
            (
                "src/report/html.rs",
                "const T: &str = include_str!(\"templates/page.html\");\n",
            ),
            ("src/report/templates/page.html", "<p></p>\n"),
            (
                "src/stages/mod.rs",
                "pub mod fit;\npub mod fit_io;\npub mod report;\n",
            ),
            (
                "src/stages/fit.rs",
                "use crate::{engine::stage::{self as s}, fit::lm};\nuse super::fit_io::read;\n\
                 #[cfg(test)]\nmod tests {\n    use super::*;\n    use crate::report::html;\n}\n",
            ),
            ("src/stages/fit_io.rs", "pub fn read() {}\n"),
            (
                "src/stages/report.rs",
                "fn f() { crate::report::html::render() }\n",
            ),
        ],
    );
    let used = |kind: &str| -> Vec<String> {
        code_deps::files_used(&src, &src.join(format!("stages/{kind}.rs")))
            .iter()
            .map(|f| rel(&src, f))
            .collect()
    };
    assert_eq!(
        used("fit"),
        [
            "engine/stage.rs",
            "engine/store.rs",
            "fit/lm.rs",
            "fit/robust.rs",
            "fit/robust_impl.rs",
            "stages/fit.rs",
            "stages/fit_io.rs",
        ]
    );
    assert_eq!(
        used("report"),
        [
            "report/html.rs",
            "report/templates/page.html",
            "stages/report.rs"
        ]
    );
    // an edit to a used module changes the fingerprint; an edit elsewhere does not
    let before = code_deps::kind_fingerprints(dir.path());
    write(
        dir.path(),
        &[("src/report/mod.rs", "pub mod html;\n// edited\n")],
    );
    assert_eq!(code_deps::kind_fingerprints(dir.path()), before);
    write(
        dir.path(),
        &[("src/fit/robust_impl.rs", "impl super::robust::Huber {}\n")],
    );
    let after = code_deps::kind_fingerprints(dir.path());
    assert_ne!(after["fit"], before["fit"]);
    assert_eq!(after["report"], before["report"]);
}

#[test]
fn compiled_fingerprints_are_those_of_the_modules_each_kind_uses() {
    let compiled: BTreeMap<&str, &str> = groove::engine::identity::FINGERPRINTS
        .iter()
        .copied()
        .collect();
    let derived = code_deps::kind_fingerprints(repo());
    for kind in groove::stages::registry() {
        let name = kind.kind();
        assert_eq!(
            compiled.get(name).copied(),
            derived.get(name).map(String::as_str),
            "kind `{name}`: the fingerprint compiled in differs from the files it uses now; rebuild"
        );
    }
}

#[test]
fn every_kind_fingerprints_what_it_uses_and_nothing_it_does_not() {
    let src = repo().join("src");
    let used = |kind: &str| -> BTreeSet<String> {
        code_deps::files_used(&src, &src.join(format!("stages/{kind}.rs")))
            .iter()
            .map(|f| rel(&src, f))
            .collect()
    };
    for kind in groove::stages::registry() {
        let files = used(kind.kind());
        // every kind implements the contract in engine/stage.rs and reads recordings or artifacts
        assert!(
            files.contains("engine/stage.rs"),
            "{}: {files:?}",
            kind.kind()
        );
        assert!(
            !files.iter().any(|f| f.starts_with("engine/")
                && f != "engine/stage.rs"
                && f != "engine/error.rs"),
            "kind `{}` reaches engine internals: {files:?}",
            kind.kind()
        );
    }
    assert!(used("validate").contains("recording.rs"));
    assert!(used("validate").contains("synth/truth.rs"));
    let discover = used("discover");
    assert!(discover.contains("discover/mod.rs") && discover.contains("physics/mod.rs"));
    assert!(
        // discovery on pairs fits collision runs itself (fit/collision); it reads no per-run fit
        !discover
            .iter()
            .any(|f| f.starts_with("fit/") && !f.starts_with("fit/collision/")),
        "discover reads no per-run fit, so no such fit module belongs in its fingerprint: {discover:?}"
    );
    let report = used("report");
    assert!(report.contains("report/templates/report.html.jinja"));
    // no hand-kept list is left to drift
    for kind in groove::stages::registry() {
        let text = fs::read_to_string(src.join(format!("stages/{}.rs", kind.kind()))).unwrap();
        assert!(
            !text.contains("groove:uses"),
            "{}: a hand-kept uses list",
            kind.kind()
        );
    }
}

#[test]
fn a_kind_reads_only_the_inputs_it_declares() {
    // `discover` refits every run itself; binding `fits` would rerun it on every fit change
    let kinds = groove::stages::registry();
    let discover = kinds.iter().find(|k| k.kind() == "discover").unwrap();
    assert_eq!(discover.inputs(), ["runs"]);
    let toml = fs::read_to_string(repo().join("pipeline.toml")).unwrap();
    let stage = toml.split("[stages.discover]").nth(1).unwrap();
    let stage = stage.split("[stages.").next().unwrap();
    assert!(!stage.contains("fit:fits"), "{stage}");
}

fn section<'a>(text: &'a str, heading: &str) -> &'a str {
    let start = text
        .find(heading)
        .unwrap_or_else(|| panic!("README has no `{heading}`"));
    let body = &text[start + heading.len()..];
    let level = heading.chars().take_while(|c| *c == '#').count();
    let end = body
        .match_indices('\n')
        .map(|(i, _)| i + 1)
        .find(|&i| {
            let hashes = body[i..].chars().take_while(|c| *c == '#').count();
            hashes > 0 && hashes <= level && body[i + hashes..].starts_with(' ')
        })
        .unwrap_or(body.len());
    &body[..end]
}

/// The backticked names of a text (`src/fit/`, `stage.rs`, `stages::registry()`, …).
fn backticked(text: &str) -> Vec<&str> {
    text.split('`').skip(1).step_by(2).collect()
}

/// A backticked name that names a file or folder: under the repository root (`src/…`,
/// `tests/…`, `data/…`, `reports/…`) or relative to its entry's folders (`stage.rs`, `config/`).
fn is_path(name: &str) -> bool {
    !name.contains([' ', ':', '(', '['])
        && (name.ends_with(".rs")
            || name.ends_with('/')
            || ["src/", "tests/", "data/", "reports/"]
                .iter()
                .any(|p| name.starts_with(p)))
}

/// Every folder at or below `dir`.
fn folders(dir: &Path) -> Vec<PathBuf> {
    let mut out = vec![dir.to_path_buf()];
    let mut i = 0;
    while i < out.len() {
        if let Ok(entries) = fs::read_dir(&out[i]) {
            out.extend(entries.flatten().map(|e| e.path()).filter(|p| p.is_dir()));
        }
        i += 1;
    }
    out.sort();
    out
}

/// What is wrong with the code map `map` of the tree at `root`, both ways: a module of
/// `src/lib.rs`, a folder of `src/` holding code, or a file of `src/engine/` it does not name,
/// and a path it names that does not exist (a relative name is looked up below the folders its
/// entry names, or below `src/`).
fn code_map_problems(root: &Path, map: &str) -> Vec<String> {
    let src = root.join("src");
    let mut problems = Vec::new();
    let names = backticked(map);
    let lib = fs::read_to_string(src.join("lib.rs")).unwrap_or_default();
    for line in lib.lines() {
        let Some(name) = line.trim().strip_prefix("pub mod ") else {
            continue;
        };
        let name = name.trim_end_matches(';');
        let (dir, file) = (format!("src/{name}/"), format!("src/{name}.rs"));
        if !names.contains(&dir.as_str()) && !names.contains(&file.as_str()) {
            problems.push(format!("does not name module {name}"));
        }
    }
    for top in [
        "src/main.rs",
        "src/cli/",
        "src/build.rs",
        "src/build/code_deps.rs",
    ] {
        if !names.contains(&top) {
            problems.push(format!("does not name {top}"));
        }
    }
    // every folder of code, by its name (`sections/`) or a path through it (`fit/collision/`)
    for dir in folders(&src).into_iter().skip(1) {
        let holds_code = fs::read_dir(&dir)
            .unwrap()
            .flatten()
            .any(|e| e.path().extension().is_some_and(|x| x == "rs"));
        let shown = format!("{}/", dir.file_name().unwrap().to_string_lossy());
        if holds_code && !names.iter().any(|n| n.contains(&shown)) {
            problems.push(format!("does not name folder src/{}", rel(&src, &dir)));
        }
    }
    // the engine's files one by one (the folder a newcomer reads first)
    for e in fs::read_dir(src.join("engine"))
        .into_iter()
        .flatten()
        .flatten()
    {
        let name = e.file_name().to_string_lossy().into_owned();
        let shown = if e.path().is_dir() {
            format!("{name}/")
        } else {
            name.clone()
        };
        if name != "mod.rs" && !names.contains(&shown.as_str()) {
            problems.push(format!("does not name src/engine/{name}"));
        }
    }
    // the other way: every path it names exists; an entry is a top-level `- ` line with its
    // continuation and sub-entries
    let mut entries: Vec<String> = Vec::new();
    for line in map.lines() {
        if line.starts_with("- ") || entries.is_empty() {
            entries.push(String::new());
        }
        let last = entries.last_mut().unwrap();
        last.push_str(line);
        last.push('\n');
    }
    for entry in &entries {
        let names: Vec<&str> = backticked(entry)
            .into_iter()
            .filter(|n| is_path(n))
            .collect();
        let mut bases: Vec<PathBuf> = names
            .iter()
            .filter(|n| n.starts_with("src/") && n.ends_with('/'))
            .flat_map(|n| folders(&root.join(n)))
            .collect();
        bases.push(src.clone());
        for name in names {
            let rooted = ["src/", "tests/", "data/", "reports/"]
                .iter()
                .any(|p| name.starts_with(p));
            let found = if rooted {
                root.join(name).exists()
            } else {
                bases.iter().any(|b| b.join(name).exists())
            };
            if !found {
                problems.push(format!("names `{name}`, which does not exist"));
            }
        }
    }
    problems
}

#[test]
fn the_readme_code_map_names_every_module_and_only_what_exists() {
    let readme = fs::read_to_string(repo().join("README.md")).unwrap();
    let map = section(&readme, "### Code map");
    let problems = code_map_problems(repo(), map);
    assert!(problems.is_empty(), "README's code map: {problems:#?}");
}

#[test]
fn the_code_map_check_catches_a_missing_module_and_a_stale_path() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        &[
            ("src/lib.rs", "pub mod engine;\npub mod fit;\n"),
            ("src/main.rs", ""),
            ("src/build.rs", ""),
            ("src/build/code_deps.rs", ""),
            ("src/cli/mod.rs", ""),
            ("src/engine/mod.rs", "pub mod store;\n"),
            ("src/engine/store.rs", ""),
            ("src/fit/mod.rs", "pub mod lm;\n"),
            ("src/fit/lm.rs", ""),
            ("src/fit/collision/mod.rs", ""),
        ],
    );
    let top = "- `src/main.rs`, `src/cli/`, `src/build.rs`, `src/build/code_deps.rs`: top\n";
    let good = format!(
        "{top}- `src/engine/`: engine\n  - `store.rs`: store\n- `src/fit/`: `lm.rs`, `fit/collision/`\n"
    );
    assert_eq!(code_map_problems(dir.path(), &good), Vec::<String>::new());
    // a module and a folder the map forgets
    let forgets = format!("{top}- `src/engine/`: `store.rs`\n");
    assert_eq!(
        code_map_problems(dir.path(), &forgets),
        [
            "does not name module fit",
            "does not name folder src/fit",
            "does not name folder src/fit/collision"
        ]
    );
    // a path the map names that is gone: relative to its entry and rooted
    let stale = format!("{good}- `src/fit/`: `robust.rs`; `tests/gone.rs`\n");
    assert_eq!(
        code_map_problems(dir.path(), &stale),
        [
            "names `robust.rs`, which does not exist",
            "names `tests/gone.rs`, which does not exist"
        ]
    );
}

#[test]
fn the_readme_keeps_its_set_up_and_reference_sections() {
    let readme = fs::read_to_string(repo().join("README.md")).unwrap();
    for line in [
        "    cargo run --release -- run",
        "    cargo test --locked --features s3",
        "## What `groove run` writes",
        "## Dependencies and why",
        "### Invariants",
        "### Data flow",
    ] {
        assert!(readme.contains(line), "README lost `{line}`");
    }
    // the invariants are stated once
    for phrase in [
        "knows no analysis",
        "byte-identical report",
        "only by `validate`",
    ] {
        assert_eq!(
            readme.matches(phrase).count(),
            1,
            "`{phrase}` is stated more than once"
        );
    }
    // every dependency is explained
    let deps = section(&readme, "## Dependencies and why");
    let cargo = fs::read_to_string(repo().join("Cargo.toml")).unwrap();
    for table in ["[dependencies]", "[dev-dependencies]"] {
        let body = cargo
            .split(table)
            .nth(1)
            .unwrap()
            .split("\n[")
            .next()
            .unwrap();
        for line in body.lines() {
            let Some((name, _)) = line.split_once(" = ") else {
                continue;
            };
            assert!(
                deps.contains(name.trim()),
                "README does not say why `{name}` is a dependency"
            );
        }
    }
}
