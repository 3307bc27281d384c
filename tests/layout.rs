//! The source tree's layout rules: no module cycles in any crate (modules
//! that use each other, directly or through others, at any level of the
//! tree), and no source file over 700 lines.
//!
//! A module's paths into its crate outside its unit tests (`crate::...`,
//! and `super::...` and `self::...`, brace groups included) are its
//! dependencies. A folder is one
//! unit to the modules outside it, so a dependency counts between the two
//! siblings under the deepest module that contains both ends:
//! `maps::albedo_map` using `model::file` makes `maps` depend on `model`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const MAX_LINES: usize = 700;

/// The crates' source roots, relative to the workspace (the Python
/// package's crate too, though it is outside the workspace); every crate
/// under `crates/` must be here ([`every_crate_is_checked`]).
const ROOTS: &[&str] = &[
    "src",
    "crates/core/src",
    "crates/pictures/src",
    "crates/atomic/src",
    "crates/mapguard/src",
    "crates/merl/src",
    "crates/analytic/src",
    "crates/ffi/src",
    "crates/hostile/src",
    "python/src",
];

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// `a/b/mod.rs` and `a/b.rs` are module `a::b`; `lib.rs` and `main.rs` the root.
fn module_of(root: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(root).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// Every path of `text` that names a module of the crate, resolved to
/// segments from the crate root: `crate::a::b`, and `super::x` or
/// `self::x` relative to `module` (the file's own module; in a `mod.rs` or
/// a plain file alike, `super` is its parent), with brace groups
/// (`use super::{a, b::c}`) taken apart. Comments are skipped.
fn module_paths(text: &str, module: &[String]) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    for line in text.lines() {
        let code = line.split("//").next().unwrap_or("");
        let bytes = code.as_bytes();
        let mut i = 0;
        while i < code.len() {
            let starts_word = i == 0
                || !(bytes[i - 1].is_ascii_alphanumeric()
                    || bytes[i - 1] == b'_'
                    || bytes[i - 1] == b':');
            let rest = &code[i..];
            let base: Option<(Vec<String>, usize)> = if !starts_word {
                None
            } else if rest.starts_with("crate::") {
                Some((Vec::new(), "crate::".len()))
            } else if rest.starts_with("super::") || rest.starts_with("self::") {
                // super::super::... climbs once a `super`.
                let mut base = module.to_vec();
                let mut at = 0;
                loop {
                    if code[i + at..].starts_with("super::") {
                        base.pop();
                        at += "super::".len();
                    } else if code[i + at..].starts_with("self::") {
                        at += "self::".len();
                    } else {
                        break;
                    }
                }
                Some((base, at))
            } else {
                None
            };
            let Some((base, skip)) = base else {
                i += rest.chars().next().map_or(1, char::len_utf8);
                continue;
            };
            let tail = &code[i + skip..];
            for segs in tree_paths(tail) {
                let mut path = base.clone();
                path.extend(segs);
                out.push(path);
            }
            i += skip;
        }
    }
    out
}

/// The paths a use tree starting at `tail` names: `a::b::C` gives one,
/// `{a, b::{c, d}}` one per leaf (each as far as its identifiers go).
fn tree_paths(tail: &str) -> Vec<Vec<String>> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect()
    };
    let mut prefix = Vec::new();
    let mut rest = tail.trim_start();
    loop {
        if let Some(group) = rest.strip_prefix('{') {
            // Split the group at its top-level commas.
            let (mut depth, mut start, mut items) = (0usize, 0usize, Vec::new());
            let mut end = group.len();
            for (k, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        end = k;
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        items.push(&group[start..k]);
                        start = k + 1;
                    }
                    _ => {}
                }
            }
            items.push(&group[start..end]);
            let mut out = Vec::new();
            for item in items {
                for p in tree_paths(item) {
                    let mut full = prefix.clone();
                    full.extend(p);
                    out.push(full);
                }
            }
            return out;
        }
        let seg = ident(rest);
        if seg.is_empty() {
            return vec![prefix];
        }
        rest = &rest[seg.len()..];
        prefix.push(seg);
        match rest.strip_prefix("::") {
            Some(r) => rest = r,
            None => return vec![prefix],
        }
    }
}

/// The cycles among the sibling modules of one crate, as readable strings.
fn cycles(root: &Path) -> Vec<String> {
    let mut files = Vec::new();
    rust_files(root, &mut files);
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_of(root, f)).collect();
    // Edges between siblings: parent module -> (child -> children it uses).
    let mut edges: BTreeMap<Vec<String>, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for file in &files {
        let from = module_of(root, file);
        let text = std::fs::read_to_string(file).unwrap();
        // Unit tests are consumers of the modules they test, not part of
        // their layering: the scan stops at the test module.
        let text = text.split("#[cfg(test)]\nmod tests").next().unwrap_or("");
        for path in module_paths(text, &from) {
            // The longest prefix of the path that is a module of the crate.
            let to = (0..=path.len())
                .rev()
                .map(|k| path[..k].to_vec())
                .find(|p| modules.contains(p))
                .unwrap_or_default();
            let common = from.iter().zip(&to).take_while(|(a, b)| a == b).count();
            if common < from.len() && common < to.len() {
                edges
                    .entry(from[..common].to_vec())
                    .or_default()
                    .entry(from[common].clone())
                    .or_default()
                    .insert(to[common].clone());
            }
        }
    }
    let mut found = Vec::new();
    for (parent, graph) in &edges {
        // Depth-first search for a back edge.
        fn visit(
            node: &str,
            graph: &BTreeMap<String, BTreeSet<String>>,
            stack: &mut Vec<String>,
            done: &mut BTreeSet<String>,
            found: &mut Vec<Vec<String>>,
        ) {
            if let Some(i) = stack.iter().position(|s| s == node) {
                let mut cycle = stack[i..].to_vec();
                cycle.push(node.to_string());
                found.push(cycle);
                return;
            }
            if !done.insert(node.to_string()) {
                return;
            }
            stack.push(node.to_string());
            for next in graph.get(node).into_iter().flatten() {
                visit(next, graph, stack, done, found);
            }
            stack.pop();
        }
        let mut done = BTreeSet::new();
        let mut local = Vec::new();
        for node in graph.keys() {
            visit(node, graph, &mut Vec::new(), &mut done, &mut local);
        }
        for c in local {
            let at = if parent.is_empty() {
                "crate".to_string()
            } else {
                parent.join("::")
            };
            found.push(format!("{}: in {at}: {}", root.display(), c.join(" -> ")));
        }
    }
    found
}

#[test]
fn every_crate_is_checked() {
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(workspace().join("crates")).unwrap() {
        let src = entry.unwrap().path().join("src");
        let rel = src.strip_prefix(workspace()).unwrap();
        if src.is_dir() && !ROOTS.iter().any(|r| Path::new(r) == rel) {
            missing.push(rel.display().to_string());
        }
    }
    assert!(missing.is_empty(), "not in ROOTS: {missing:?}");
}

#[test]
fn no_crate_has_a_module_cycle() {
    let found: Vec<String> = ROOTS
        .iter()
        .flat_map(|r| cycles(&workspace().join(r)))
        .collect();
    assert!(found.is_empty(), "module cycles:\n{}", found.join("\n"));
}

#[test]
fn the_cycle_check_finds_a_planted_cycle() {
    let tmp = tempfile::tempdir().unwrap();
    let src = tmp.path();
    std::fs::create_dir_all(src.join("query")).unwrap();
    std::fs::write(src.join("lib.rs"), "mod model;\nmod query;\n").unwrap();
    std::fs::write(src.join("model.rs"), "use crate::query::map::Basis;\n").unwrap();
    std::fs::write(src.join("query/mod.rs"), "pub mod map;\n").unwrap();
    std::fs::write(src.join("query/map.rs"), "use crate::model::Model;\n").unwrap();
    let found = cycles(src);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(
        found[0].contains("model -> query -> model")
            || found[0].contains("query -> model -> query")
    );
    // The same cycle through `super::` paths and a brace group.
    std::fs::write(
        src.join("model.rs"),
        "use crate::{io, query::{map::Basis}};\n",
    )
    .unwrap();
    std::fs::write(
        src.join("query/map.rs"),
        "use super::super::model::Model;\n",
    )
    .unwrap();
    let found = cycles(src);
    assert_eq!(found.len(), 1, "{found:?}");
    std::fs::write(src.join("model.rs"), "").unwrap();
    // Siblings of a folder using each other by `super::`.
    std::fs::create_dir_all(src.join("report")).unwrap();
    std::fs::write(src.join("lib.rs"), "mod model;\nmod query;\nmod report;\n").unwrap();
    std::fs::write(src.join("report/mod.rs"), "mod csv;\nmod measure;\n").unwrap();
    std::fs::write(src.join("report/csv.rs"), "use super::measure::Results;\n").unwrap();
    std::fs::write(
        src.join("report/measure.rs"),
        "use super::{csv::e, Plan};\n",
    )
    .unwrap();
    std::fs::write(src.join("query/map.rs"), "").unwrap();
    let found = cycles(src);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].contains("in report: "), "{found:?}");
    std::fs::write(src.join("report/measure.rs"), "use super::Plan;\n").unwrap();
    assert!(cycles(src).is_empty(), "{:?}", cycles(src));
    // Within a folder, a child using its parent's re-exports is no cycle.
    std::fs::write(src.join("model.rs"), "").unwrap();
    std::fs::write(src.join("query/map.rs"), "use crate::query::Thing;\n").unwrap();
    assert!(cycles(src).is_empty());
}

#[test]
fn no_source_file_is_over_700_lines() {
    let mut files = Vec::new();
    for r in ROOTS {
        rust_files(&workspace().join(r), &mut files);
    }
    for extra in [
        "tests",
        "benches",
        "crates/core/tests",
        "crates/pictures/tests",
        "crates/ffi/tests",
    ] {
        rust_files(&workspace().join(extra), &mut files);
    }
    let long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let lines = std::fs::read_to_string(f).unwrap().lines().count();
            (lines > MAX_LINES).then(|| format!("{}: {lines} lines", f.display()))
        })
        .collect();
    assert!(
        long.is_empty(),
        "files over {MAX_LINES} lines:\n{}",
        long.join("\n")
    );
}
