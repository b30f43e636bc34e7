//! The flight crate's module graph, read from its source: no two modules (at any depth: `plan`, `plan::abit`,
//! `plan::abit::queue`) import each other through a chain of `crate::` / `super::` paths, and no flight file names
//! the benchmark workloads. Paths in comments and in test code (`tests.rs` files and `#[cfg(test)] mod tests`
//! blocks) are not imports of the flight code and are skipped. The same check runs on the board crate.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Module path of a source file below `root` (`plan/abit/mod.rs` -> `["plan", "abit"]`).
fn module_of(root: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(root).expect("file below root").with_extension("");
    let mut parts: Vec<String> = rel.iter().map(|p| p.to_string_lossy().into_owned()).collect();
    if matches!(parts.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        parts.pop();
    }
    parts
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = fs::read_dir(dir).expect("readable dir").map(|e| e.expect("entry").path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// The flight part of a file: up to its `#[cfg(test)] mod tests` block, comment lines dropped.
fn flight_lines(text: &str) -> Vec<&str> {
    let mut lines = Vec::new();
    let mut prev_cfg_test = false;
    for line in text.lines() {
        let t = line.trim_start();
        if prev_cfg_test && t.starts_with("mod tests") && t.ends_with('{') {
            break;
        }
        prev_cfg_test = t.starts_with("#[cfg(test)]");
        if !t.starts_with("//") {
            lines.push(t);
        }
    }
    lines
}

/// `a::b::c` segments after each `crate::` in a line.
fn crate_paths(line: &str) -> Vec<Vec<String>> {
    line.match_indices("crate::")
        .filter(|(i, _)| !line[..*i].ends_with(|c: char| c.is_alphanumeric() || c == '_'))
        .map(|(i, m)| {
            line[i + m.len()..]
                .split("::")
                .map(|s| s.chars().take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_').collect())
                .take_while(|s: &String| !s.is_empty())
                .collect()
        })
        .collect()
}

/// Module-to-module edges at `depth` (a module's path cut to `depth` segments); an edge into one's own ancestor
/// or descendant is a parent/child relation, not an import between peers, and is left out.
fn edges(root: &Path, depth: usize) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut files = Vec::new();
    rust_files(root, &mut files);
    let mut g: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for f in files {
        let me = module_of(root, &f);
        if me.last().is_some_and(|m| m == "tests") {
            continue;
        }
        let text = fs::read_to_string(&f).expect("readable source");
        for line in flight_lines(&text) {
            let mut targets = crate_paths(line);
            if let Some(rest) = line.strip_prefix("use super::").or_else(|| line.strip_prefix("pub use super::")) {
                let name: String = rest.chars().take_while(|c| c.is_ascii_lowercase() || *c == '_').collect();
                // `super` is the module that holds this one (a `mod.rs` file's module is its directory).
                if !name.is_empty() {
                    let mut target = me.clone();
                    target.pop();
                    target.push(name);
                    targets.push(target);
                }
            }
            for t in targets {
                let (a, b): (Vec<String>, Vec<String>) =
                    (me.iter().take(depth).cloned().collect(), t.iter().take(depth).cloned().collect());
                let related = a.starts_with(&b) || b.starts_with(&a);
                if !a.is_empty() && !b.is_empty() && !related {
                    g.entry(a).or_default().insert(b);
                }
            }
        }
    }
    g
}

/// A cycle in `g`, if there is one (depth-first search, deterministic order).
fn find_cycle(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Option<Vec<Vec<String>>> {
    fn visit(
        v: &Vec<String>,
        g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        state: &mut BTreeMap<Vec<String>, u8>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<Vec<String>>> {
        state.insert(v.clone(), 1);
        stack.push(v.clone());
        for w in g.get(v).into_iter().flatten() {
            match state.get(w).copied().unwrap_or(0) {
                1 => {
                    let from = stack.iter().position(|x| x == w).unwrap_or(0);
                    return Some(stack[from..].to_vec());
                }
                0 => {
                    if let Some(c) = visit(w, g, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(v.clone(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for v in g.keys() {
        if state.get(v).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(v, g, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn assert_acyclic(root: &Path) {
    for depth in 1..=4 {
        let g = edges(root, depth);
        assert!(!g.is_empty() || depth > 1, "no imports found below {}", root.display());
        if let Some(c) = find_cycle(&g) {
            let names: Vec<String> = c.iter().map(|m| m.join("::")).collect();
            panic!("import circle in {} at depth {depth}: {}", root.display(), names.join(" -> "));
        }
    }
}

#[test]
fn the_flight_crate_has_no_import_circle() {
    assert_acyclic(&repo().join("firmware/src"));
}

#[test]
fn the_board_crate_has_no_import_circle() {
    assert_acyclic(&repo().join("firmware/boards/mps2-an500/src"));
}

#[test]
fn no_flight_module_names_the_workloads() {
    let mut files = Vec::new();
    rust_files(&repo().join("firmware/src"), &mut files);
    assert!(files.len() > 50, "the flight crate's files were not found");
    for f in files {
        let text = fs::read_to_string(&f).expect("readable source");
        for line in flight_lines(&text) {
            assert!(!line.contains("workloads::"), "{} uses the workloads crate: {line}", f.display());
        }
    }
}

#[test]
fn the_cycle_finder_finds_a_planted_circle() {
    let m = |s: &str| s.split("::").map(String::from).collect::<Vec<_>>();
    let mut g: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    g.entry(m("plan::abit::graph")).or_default().insert(m("plan::abit::queue"));
    g.entry(m("plan::abit::queue")).or_default().insert(m("plan::abit::node"));
    assert_eq!(find_cycle(&g), None);
    g.entry(m("plan::abit::node")).or_default().insert(m("plan::abit::graph"));
    assert_eq!(find_cycle(&g).map(|c| c.len()), Some(3));
    assert_eq!(
        crate_paths("use crate::plan::heap::{HeapItems, IndexedHeap};"),
        vec![vec!["plan".to_string(), "heap".to_string()]]
    );
}
