//! The source files a stage kind uses, found by following its module paths, and their fingerprint.
//!
//! Shared by the build script (which compiles each kind's fingerprint into the binary) and by
//! `tests/architecture.rs` (which checks that the compiled fingerprints are these). Starting from
//! `src/stages/<kind>.rs`, every `crate::…`, `super::…` and `self::…` path (including `use`
//! trees with braces) is resolved to the deepest module file it names (`src/a/b.rs` or
//! `src/a/b/mod.rs`); a module reached this way brings its `mod x;` children, its
//! `include_str!`/`include_bytes!` files, and whatever its own paths name. Modules only passed
//! through (`crate::engine` on the way to `crate::engine::stage`) are not included, and neither
//! is the crate root (`src/lib.rs`, a list of modules). Paths in comments count too: that can
//! only add files, never miss one.

use sha2::{Digest, Sha256};
use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Every file the module in `entry` uses, itself included, sorted. A file that defines a type
/// brings the files beside it with an `impl` block for a type of that name (methods can live
/// in a sibling file that no path names).
pub fn files_used(src: &Path, entry: &Path) -> BTreeSet<PathBuf> {
    let impls = impl_index(src);
    let mut seen = BTreeSet::new();
    let mut todo = vec![entry.to_path_buf()];
    while let Some(file) = todo.pop() {
        if seen.insert(file.clone()) {
            let uses = direct_uses(src, &file);
            todo.extend(uses.children);
            todo.extend(uses.named);
            if file.extension().is_some_and(|e| e == "rs") {
                let text = without_tests(&fs::read_to_string(&file).unwrap_or_default());
                for ty in defined_types(&text) {
                    let siblings = impls.get(&ty).into_iter().flatten();
                    todo.extend(siblings.filter(|f| f.parent() == file.parent()).cloned());
                }
            }
        }
    }
    seen
}

/// Type name → the files holding an `impl` block for a type of that name, over all of `src`.
fn impl_index(src: &Path) -> BTreeMap<String, Vec<PathBuf>> {
    let mut files = Vec::new();
    collect_files(src, &mut files);
    let mut index: BTreeMap<String, Vec<PathBuf>> = BTreeMap::new();
    for f in files
        .into_iter()
        .filter(|f| f.extension().is_some_and(|e| e == "rs"))
    {
        let text = without_tests(&fs::read_to_string(&f).unwrap_or_default());
        for line in text.lines() {
            if let Some(ty) = impl_target(line.trim_start()) {
                index.entry(ty).or_default().push(f.clone());
            }
        }
    }
    index
}

/// The type an `impl` line is for: `impl<T> Trait for a::Name<T> {` → `Name`.
fn impl_target(line: &str) -> Option<String> {
    let mut rest = line.strip_prefix("impl")?;
    if rest.starts_with('<') {
        let mut depth = 0;
        let end = rest.char_indices().find_map(|(i, c)| {
            match c {
                '<' => depth += 1,
                '>' => depth -= 1,
                _ => {}
            }
            (depth == 0).then_some(i + 1)
        })?;
        rest = &rest[end..];
    } else if !rest.starts_with(' ') {
        return None;
    }
    if let Some(at) = rest.rfind(" for ") {
        rest = &rest[at + 5..];
    }
    let path: String = rest
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
        .collect();
    path.rsplit("::")
        .next()
        .filter(|n| !n.is_empty())
        .map(str::to_string)
}

/// The names of the structs, enums, unions, traits and type aliases a file defines.
fn defined_types(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in text.lines() {
        let mut words = line.split_whitespace().skip_while(|w| w.starts_with("pub"));
        if let (Some("struct" | "enum" | "union" | "trait" | "type"), Some(name)) =
            (words.next(), words.next())
        {
            let name: String = name
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            out.push(name);
        }
    }
    out
}

/// What one file brings in directly.
#[derive(Debug, Default)]
pub struct Uses {
    /// The files of its `mod x;` children.
    pub children: Vec<PathBuf>,
    /// The module files its paths name and the files it includes.
    pub named: Vec<PathBuf>,
}

/// The files `file` brings in by itself (not transitively); none for a file that is not Rust.
pub fn direct_uses(src: &Path, file: &Path) -> Uses {
    let mut uses = Uses::default();
    if file.extension().is_none_or(|e| e != "rs") {
        return uses;
    }
    let text = without_tests(&fs::read_to_string(file).unwrap_or_default());
    let dir = children_dir(file);
    for child in mod_decls(&text) {
        uses.children.extend(module_file(&dir, &child));
    }
    for rel in includes(&text) {
        uses.named.push(file.parent().unwrap_or(src).join(rel));
    }
    for path in paths(&text) {
        uses.named.extend(resolve(src, &dir, &path));
    }
    uses.named.sort();
    uses.named.dedup();
    uses
}

/// Fingerprint of every file in `src/stages/` except `mod.rs`: stem → sha256 of the files it uses.
pub fn kind_fingerprints(root: &Path) -> BTreeMap<String, String> {
    let src = root.join("src");
    let mut stage_files: Vec<PathBuf> = fs::read_dir(src.join("stages"))
        .map(|entries| entries.filter_map(|e| e.ok().map(|e| e.path())).collect())
        .unwrap_or_default();
    stage_files.sort();
    let mut out = BTreeMap::new();
    for file in stage_files {
        let stem = file.file_stem().and_then(|s| s.to_str()).unwrap_or("");
        if file.extension().is_some_and(|e| e == "rs") && stem != "mod" {
            let files: Vec<PathBuf> = files_used(&src, &file).into_iter().collect();
            out.insert(stem.to_string(), fingerprint(root, &files));
        }
    }
    out
}

/// sha256 over (relative path, contents) of every file under `paths` (folders: every file below
/// them), sorted and deduplicated.
pub fn fingerprint(root: &Path, paths: &[PathBuf]) -> String {
    let mut files = Vec::new();
    for p in paths {
        collect_files(p, &mut files);
    }
    files.sort();
    files.dedup();
    let mut h = Sha256::new();
    for f in files {
        let rel = f
            .strip_prefix(root)
            .unwrap_or(&f)
            .to_string_lossy()
            .replace('\\', "/");
        let bytes = fs::read(&f).unwrap_or_default();
        h.update((rel.len() as u64).to_le_bytes());
        h.update(rel.as_bytes());
        h.update((bytes.len() as u64).to_le_bytes());
        h.update(&bytes);
    }
    h.finalize().iter().map(|b| format!("{b:02x}")).collect()
}

fn collect_files(p: &Path, out: &mut Vec<PathBuf>) {
    if p.is_dir() {
        if let Ok(entries) = fs::read_dir(p) {
            for e in entries.flatten() {
                collect_files(&e.path(), out);
            }
        }
    } else if p.is_file() {
        out.push(p.to_path_buf());
    }
}

/// The folder holding the child modules of the module in `file`.
fn children_dir(file: &Path) -> PathBuf {
    let parent = file.parent().unwrap_or(Path::new("")).to_path_buf();
    match file.file_name().and_then(|n| n.to_str()) {
        Some("mod.rs" | "lib.rs" | "main.rs") => parent,
        _ => parent.join(file.file_stem().unwrap_or_default()),
    }
}

/// The file of module `name` whose parent keeps its children in `dir`.
fn module_file(dir: &Path, name: &str) -> Option<PathBuf> {
    [
        dir.join(format!("{name}.rs")),
        dir.join(name).join("mod.rs"),
    ]
    .into_iter()
    .find(|f| f.is_file())
}

/// The file of the module whose children are in `dir` (not the crate root).
fn module_of_dir(src: &Path, dir: &Path) -> Option<PathBuf> {
    if dir == src {
        return None;
    }
    [dir.join("mod.rs"), dir.with_extension("rs")]
        .into_iter()
        .find(|f| f.is_file())
}

/// The deepest module file a path names, starting with `crate`, `self` or `super`.
fn resolve(src: &Path, here: &Path, path: &[String]) -> Option<PathBuf> {
    let mut segs = path.iter().map(String::as_str).peekable();
    let mut dir = match segs.next()? {
        "crate" => src.to_path_buf(),
        "self" => here.to_path_buf(),
        "super" => here.parent()?.to_path_buf(),
        _ => return None,
    };
    while segs.peek() == Some(&"super") {
        segs.next();
        dir = dir.parent()?.to_path_buf();
    }
    let mut found = None;
    for seg in segs {
        if seg == "self" {
            continue;
        }
        match module_file(&dir, seg) {
            Some(f) => {
                dir = dir.join(seg);
                found = Some(f);
            }
            None => break,
        }
    }
    found.or_else(|| module_of_dir(src, &dir))
}

/// The text without the items marked `#[cfg(test)]` (not compiled into the kind; their
/// `use super::*` would otherwise name the whole parent module).
fn without_tests(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let item = &rest[at..];
        let end = match (item.find('{'), item.find(';')) {
            (Some(open), semi) if semi.is_none_or(|s| open < s) => {
                let mut depth = 0usize;
                let mut end = item.len();
                for (i, c) in item[open..].char_indices() {
                    match c {
                        '{' => depth += 1,
                        '}' => {
                            depth -= 1;
                            if depth == 0 {
                                end = open + i + 1;
                                break;
                            }
                        }
                        _ => {}
                    }
                }
                end
            }
            (_, Some(semi)) => semi + 1,
            _ => item.len(),
        };
        rest = &item[end..];
    }
    out.push_str(rest);
    out
}

/// The names of `mod x;` declarations (file modules; inline `mod x { … }` has no file).
fn mod_decls(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in text.lines() {
        let mut words = line.trim().trim_end_matches(';').split_whitespace();
        let mut w = words.next();
        if w.is_some_and(|w| w.starts_with("pub")) {
            w = words.next();
        }
        if w == Some("mod") && line.trim_end().ends_with(';') {
            if let Some(name) = words.next() {
                out.push(name.to_string());
            }
        }
    }
    out
}

/// The relative paths of `include_str!("…")` and `include_bytes!("…")`.
fn includes(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for mac in ["include_str!(\"", "include_bytes!(\""] {
        for (at, _) in text.match_indices(mac) {
            let rest = &text[at + mac.len()..];
            if let Some(end) = rest.find('"') {
                out.push(rest[..end].to_string());
            }
        }
    }
    out
}

/// Every path beginning with `crate::`, `super::` or `self::`, `use` trees expanded.
fn paths(text: &str) -> Vec<Vec<String>> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    for head in ["crate::", "super::", "self::"] {
        for (at, _) in text.match_indices(head) {
            let glued = at > 0 && (b[at - 1].is_ascii_alphanumeric() || b[at - 1] == b'_');
            // `super::super::x` and `self::super::x` are read from their first keyword
            let inner = at >= 2 && &text[at - 2..at] == "::";
            if glued || inner {
                continue;
            }
            let mut pos = at;
            tree(b, &mut pos, Vec::new(), &mut out);
        }
    }
    out
}

/// Parse a path or `use` tree at `pos`, appending each full path (prefix + segments) to `out`.
fn tree(b: &[u8], pos: &mut usize, mut prefix: Vec<String>, out: &mut Vec<Vec<String>>) {
    loop {
        skip_ws(b, pos);
        if *pos < b.len() && b[*pos] == b'{' {
            *pos += 1;
            loop {
                skip_ws(b, pos);
                if *pos >= b.len() || b[*pos] == b'}' {
                    *pos += 1;
                    return;
                }
                tree(b, pos, prefix.clone(), out);
                // skip `as name` up to the next `,` or the closing brace
                while *pos < b.len() && b[*pos] != b',' && b[*pos] != b'}' {
                    *pos += 1;
                }
                if *pos < b.len() && b[*pos] == b',' {
                    *pos += 1;
                }
            }
        }
        let start = *pos;
        while *pos < b.len() && (b[*pos].is_ascii_alphanumeric() || b[*pos] == b'_') {
            *pos += 1;
        }
        if *pos == start {
            out.push(prefix);
            return;
        }
        prefix.push(String::from_utf8_lossy(&b[start..*pos]).into_owned());
        skip_ws(b, pos);
        if b[*pos..].starts_with(b"::") {
            *pos += 2;
        } else {
            out.push(prefix);
            return;
        }
    }
}

fn skip_ws(b: &[u8], pos: &mut usize) {
    while *pos < b.len() && b[*pos].is_ascii_whitespace() {
        *pos += 1;
    }
}
