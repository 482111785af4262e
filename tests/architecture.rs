//! The shape of the code, checked: the engine names no analysis module and its files form no
//! cycle, each kind's compiled code fingerprint covers exactly the modules it uses, every folder's
//! module docs open with a map of exactly its files, and the README names every top-level module.

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

/// Every folder of code directly under `src/` (each checked with the folders below it).
fn top_folders(src: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = fs::read_dir(src)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    out.sort();
    out
}

/// Imports that run back up: a file of `from/` naming a file of `to/`.
fn arrows_back_up(src: &Path, from: &str, to: &str) -> Vec<String> {
    let (from, to) = (src.join(from), src.join(to));
    folders(&from)
        .iter()
        .flat_map(|d| fs::read_dir(d).unwrap().flatten().map(|e| e.path()))
        .filter(|f| f.extension().is_some_and(|x| x == "rs"))
        .flat_map(|f| {
            code_deps::direct_uses(src, &f)
                .named
                .into_iter()
                .filter(|n| n.starts_with(&to))
                .map(move |n| format!("{} -> {}", rel(src, &f), rel(src, &n)))
        })
        .collect()
}

#[test]
fn no_folder_of_src_has_an_import_cycle() {
    let src = repo().join("src");
    let cycles: Vec<String> = top_folders(&src)
        .iter()
        .filter_map(|d| find_cycle(&src, d))
        .map(|c| c.join(" -> "))
        .collect();
    assert!(
        cycles.is_empty(),
        "modules use each other in a cycle (move what both need to where it belongs): {cycles:#?}"
    );
}

#[test]
fn the_artifact_contract_imports_nothing_from_the_fits() {
    let arrows = arrows_back_up(&repo().join("src"), "artifacts", "fit");
    assert!(
        arrows.is_empty(),
        "artifacts/ is the contract the fits write; it names no fit module: {arrows:#?}"
    );
}

#[test]
fn the_back_up_check_catches_an_artifact_importing_a_fit() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path().join("src");
    write(
        dir.path(),
        &[
            ("src/lib.rs", "pub mod artifacts;\npub mod fit;\n"),
            ("src/artifacts/mod.rs", "pub mod summary;\n"),
            (
                "src/artifacts/summary.rs",
                "pub use crate::fit::collision::summary::MuPp;\n",
            ),
            ("src/fit/mod.rs", "pub mod collision;\n"),
            ("src/fit/collision/mod.rs", "pub mod summary;\n"),
            (
                "src/fit/collision/summary.rs",
                "use crate::artifacts::summary::X;\npub struct MuPp;\n",
            ),
        ],
    );
    assert_eq!(
        arrows_back_up(&src, "artifacts", "fit"),
        ["artifacts/summary.rs -> fit/collision/summary.rs"]
    );
    write(
        dir.path(),
        &[("src/artifacts/summary.rs", "pub struct MuPp;\n")],
    );
    assert!(arrows_back_up(&src, "artifacts", "fit").is_empty());
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
    // a cycle through a nested folder, seen from its top folder, through `crate::` paths
    write(
        dir.path(),
        &[
            ("src/lib.rs", "pub mod discover;\n"),
            ("src/discover/mod.rs", "pub mod pairs;\npub mod forcemap;\n"),
            (
                "src/discover/pairs.rs",
                "use crate::discover::forcemap::grid::G;\n",
            ),
            ("src/discover/forcemap/mod.rs", "pub mod grid;\n"),
            (
                "src/discover/forcemap/grid.rs",
                "pub struct G;\nfn f() { crate::discover::pairs::run(); }\n",
            ),
        ],
    );
    let cycle = find_cycle(&src, &src.join("discover")).expect("pairs -> grid -> pairs");
    assert_eq!(cycle.first(), cycle.last());
    assert!(
        cycle.contains(&"discover/forcemap/grid.rs".to_string()),
        "{cycle:?}"
    );
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
        // discovery on pairs fits collision runs itself (fit/collision: whole runs, and each
        // run's own impacts); it reads no per-run fit of the fit stage
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

/// Whether `dir` or a folder below it holds Rust code.
fn holds_code(dir: &Path) -> bool {
    folders(dir).iter().any(|d| {
        fs::read_dir(d)
            .unwrap()
            .flatten()
            .any(|e| e.path().extension().is_some_and(|x| x == "rs"))
    })
}

/// The file whose module docs map the folder `dir`: its `mod.rs`, or the `dir.rs` beside it.
fn map_file(dir: &Path) -> PathBuf {
    let inside = dir.join("mod.rs");
    if inside.exists() {
        inside
    } else {
        dir.with_extension("rs")
    }
}

/// The names a module's map lists: the first backticked name of each item of the first list in
/// the file's opening `//!` docs.
fn map_names(text: &str) -> Vec<String> {
    let docs = text
        .lines()
        .take_while(|l| l.starts_with("//!"))
        .map(|l| l.trim_start_matches("//!").trim_start());
    let mut names = Vec::new();
    let mut in_list = false;
    for line in docs {
        if let Some(item) = line.strip_prefix("- ") {
            in_list = true;
            if let Some(name) = backticked(item).first() {
                names.push(name.to_string());
            }
        } else if in_list && !line.is_empty() && !line.starts_with("- ") {
            // a continuation line of the item before
            continue;
        } else if in_list {
            break;
        }
    }
    names
}

/// What is wrong with the module map of the folder `dir`, both ways: a file or folder of code it
/// does not name, and a name it lists that does not exist there.
fn module_map_problems(dir: &Path) -> Vec<String> {
    let file = map_file(dir);
    let shown = |p: &Path| p.file_name().unwrap().to_string_lossy().into_owned();
    let Ok(text) = fs::read_to_string(&file) else {
        return vec![format!(
            "{}: no mod.rs or {}.rs to hold its map",
            dir.display(),
            shown(dir)
        )];
    };
    let names = map_names(&text);
    let mut problems = Vec::new();
    if names.is_empty() {
        problems.push(format!(
            "{}: its docs open with no map of the folder",
            shown(&file)
        ));
    }
    let mut entries: Vec<PathBuf> = fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .collect();
    entries.sort();
    for p in entries {
        let name = if p.is_dir() {
            if !holds_code(&p) {
                continue;
            }
            format!("{}/", shown(&p))
        } else if p.extension().is_some_and(|x| x == "rs") && shown(&p) != "mod.rs" {
            shown(&p)
        } else {
            continue;
        };
        if !names.contains(&name) {
            problems.push(format!("the map of {} does not name {name}", dir.display()));
        }
    }
    for name in &names {
        let path = dir.join(name.trim_end_matches('/'));
        if !path.exists() || name.ends_with('/') != path.is_dir() {
            problems.push(format!(
                "the map of {} names `{name}`, which does not exist",
                dir.display()
            ));
        }
    }
    problems
}

#[test]
fn every_folder_of_code_opens_with_a_map_of_its_files() {
    let src = repo().join("src");
    let problems: Vec<String> = folders(&src)
        .into_iter()
        .skip(1)
        .filter(|d| holds_code(d))
        .flat_map(|d| module_map_problems(&d))
        .collect();
    assert!(
        problems.is_empty(),
        "module maps (the `//! - `name.rs`: …` list each folder's mod.rs opens with): {problems:#?}"
    );
}

#[test]
fn the_module_map_check_catches_a_missing_file_and_a_stale_name() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        &[
            (
                "src/fit/mod.rs",
                "//! Fits.\n//!\n//! - `lm.rs`: the driver\n//! - `collision/`: collisions,\n//!   over two lines\n//!\n//! - `later.rs`: another list\n",
            ),
            ("src/fit/lm.rs", "//! lm\n"),
            ("src/fit/collision/mod.rs", "//! Collisions.\n//!\n//! - `mod.rs`: all of it\n"),
            ("src/fit/templates/page.html", "<p></p>\n"),
            ("src/recording.rs", "//! One run.\n//!\n//! - `item.rs`: its bytes\n"),
            ("src/recording/item.rs", "//! item\n"),
        ],
    );
    let src = dir.path().join("src");
    for d in ["fit", "fit/collision", "recording"] {
        assert_eq!(
            module_map_problems(&src.join(d)),
            Vec::<String>::new(),
            "{d}"
        );
    }
    // a file the map forgets, and a name it keeps after the file went
    write(dir.path(), &[("src/fit/robust.rs", "//! robust\n")]);
    fs::remove_file(src.join("fit/lm.rs")).unwrap();
    let problems = module_map_problems(&src.join("fit"));
    assert_eq!(problems.len(), 2, "{problems:?}");
    assert!(
        problems[0].ends_with("does not name robust.rs"),
        "{problems:?}"
    );
    assert!(
        problems[1].ends_with("names `lm.rs`, which does not exist"),
        "{problems:?}"
    );
    // docs with no map at all
    write(dir.path(), &[("src/recording.rs", "//! One run.\n")]);
    let problems = module_map_problems(&src.join("recording"));
    assert!(
        problems.iter().any(|p| p.contains("no map")),
        "{problems:?}"
    );
}

#[test]
fn the_readme_names_every_top_level_module() {
    let readme = fs::read_to_string(repo().join("README.md")).unwrap();
    let modules = section(&readme, "### Modules");
    let names = backticked(modules);
    let lib = fs::read_to_string(repo().join("src/lib.rs")).unwrap();
    let mut missing = Vec::new();
    for line in lib.lines() {
        let Some(name) = line.trim().strip_prefix("pub mod ") else {
            continue;
        };
        let name = name.trim_end_matches(';');
        let (dir, file) = (format!("src/{name}/"), format!("src/{name}.rs"));
        if !names.contains(&dir.as_str()) && !names.contains(&file.as_str()) {
            missing.push(name.to_string());
        }
    }
    for top in ["src/main.rs", "src/cli/", "src/build.rs"] {
        if !names.contains(&top) {
            missing.push(top.to_string());
        }
    }
    assert!(
        missing.is_empty(),
        "README's modules do not name {missing:?}"
    );
    for name in names.iter().filter(|n| n.starts_with("src/")) {
        assert!(
            repo().join(name).exists(),
            "README names `{name}`, which does not exist"
        );
    }
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

/// Every file below `dir` whose text names a document that is not in the repository (the notes
/// the code was first written from), as `path: name`.
fn outside_documents(dir: &Path) -> Vec<String> {
    const NAMES: [&str; 5] = [
        "physics.md",
        "data-format.md",
        "engine-lessons.md",
        "scaleout.md",
        "../shared/",
    ];
    let mut found = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if let Ok(text) = fs::read_to_string(&path) {
                for name in NAMES.iter().filter(|n| text.contains(**n)) {
                    found.push(format!("{}: {name}", rel(repo(), &path)));
                }
            }
        }
    }
    found.sort();
    found
}

#[test]
fn no_code_template_or_test_names_a_document_outside_the_repository() {
    let mut found = outside_documents(&repo().join("src"));
    found.extend(
        outside_documents(&repo().join("tests"))
            .into_iter()
            .filter(|f| !f.starts_with("tests/architecture.rs")),
    );
    assert!(found.is_empty(), "names outside the repository: {found:?}");
}

#[test]
fn the_outside_document_check_catches_a_template_naming_one() {
    let tmp = tempfile::tempdir().unwrap();
    write(
        tmp.path(),
        &[(
            "src/report/templates/page.md.jinja",
            "Each defect listed in physics.md.\n",
        )],
    );
    let found = outside_documents(tmp.path());
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].ends_with("page.md.jinja: physics.md"), "{found:?}");
}

/// The test files (outside `tests/support/` and the benches) that start the groove binary
/// themselves instead of through the helpers of `tests/support/` (`files::groove`,
/// `cli::command`, `project::Project`).
fn own_spawns(tests: &Path) -> Vec<String> {
    let mut found = Vec::new();
    for entry in fs::read_dir(tests).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|x| x != "rs") {
            continue;
        }
        let text = fs::read_to_string(&path).unwrap();
        let n = text.matches("Command::new(GROOVE)").count()
            + text
                .matches("Command::new(env!(\"CARGO_BIN_EXE_groove\"))")
                .count();
        if n > 0 {
            found.push(path.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    found.sort();
    found
}

#[test]
fn the_test_binaries_start_groove_through_the_shared_helpers() {
    // each of these starts it in a way no helper offers, said beside the name
    let own = [
        "architecture.rs",    // this check's own example
        "engine.rs",          // `--help` of every verb, outside any project
        "hostile_project.rs", // a timed spawn it kills when it hangs
        "ingest.rs",          // `synth` of a truth made in the test, output silenced
        "ingest_campaign.rs", // the same, in Parquet too
        "reports_current.rs", // the shipped project, exactly as a user runs it
    ];
    let found = own_spawns(&repo().join("tests"));
    let extra: Vec<&String> = found
        .iter()
        .filter(|f| !own.contains(&f.as_str()))
        .collect();
    assert!(
        extra.is_empty(),
        "start groove through tests/support (files::groove, cli::command, project::Project): {extra:?}"
    );
}

#[test]
fn the_own_spawn_check_catches_a_test_starting_the_binary_itself() {
    let tmp = tempfile::tempdir().unwrap();
    write(
        tmp.path(),
        &[
            (
                "mine.rs",
                "fn groove() { Command::new(env!(\"CARGO_BIN_EXE_groove\")).output(); }\n",
            ),
            ("helped.rs", "fn groove() { files::groove(dir, &[]); }\n"),
        ],
    );
    assert_eq!(own_spawns(tmp.path()), ["mine.rs"]);
}
