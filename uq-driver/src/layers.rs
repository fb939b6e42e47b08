//! The layering of the library, checked: the modules in the order of [`LAYERS`] (bottom first)
//! use only modules below them or themselves, and no two files import each other, directly or
//! through others.
//!
//! An edge is a path `crate::a::b…` or `super::…` in a file's code (its `#[cfg(test)] mod
//! tests` at the bottom not counted), resolved to the longest module prefix that is a file of
//! `src/`. A module's `mod` declarations and `pub use` of its own children are not edges.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The top-level modules, bottom first: each may use those before it in the list.
pub(crate) const LAYERS: &[&str] = &[
    "text", "suggest", "sys", "fmu", "uq", "qoi", "spec", "results", "report", "study", "prelude",
    "cli",
];

/// Every `.rs` file below `dir`, by module path (`study::run::point`).
fn module_files(root: &Path, dir: &Path, out: &mut BTreeMap<String, PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a folder entry").path();
        if path.is_dir() {
            module_files(root, &path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            let rel = path
                .strip_prefix(root)
                .expect("below src/")
                .with_extension("");
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
            out.insert(parts.join("::"), path);
        }
    }
}

/// A file's code without its tests module and comments.
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths after `prefix` (`crate::` or `super::`) in `code`, each expanded over one level
/// of braces: `crate::a::{b, c::d}` gives `a::b` and `a::c::d`.
fn paths_after(code: &str, prefix: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find(prefix) {
        let before = rest[..i].chars().last();
        rest = &rest[i + prefix.len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(rest.len());
        let base = rest[..end].trim_end_matches(':').to_owned();
        if rest[end..].starts_with('{') && rest[..end].ends_with("::") {
            let close = rest[end..].find('}').map_or(rest.len(), |j| end + j);
            for item in rest[end + 1..close].split(',') {
                let item = item.split(" as ").next().unwrap_or("").trim();
                let item = item.split('{').next().unwrap_or("").trim_end_matches(':');
                if item.is_empty() || item == "self" {
                    out.push(base.clone());
                } else {
                    out.push(format!("{base}::{item}"));
                }
            }
        } else {
            out.push(base);
        }
    }
    out
}

/// The module of `path` (longest prefix that is a file), if any.
fn resolve(files: &BTreeMap<String, PathBuf>, path: &str) -> Option<String> {
    let segs: Vec<&str> = path.split("::").collect();
    (1..=segs.len())
        .rev()
        .map(|k| segs[..k].join("::"))
        .find(|m| files.contains_key(m))
}

/// File → the files it uses.
fn edges(src: &Path) -> BTreeMap<String, BTreeSet<String>> {
    let mut files = BTreeMap::new();
    module_files(src, src, &mut files);
    let mut edges = BTreeMap::new();
    for (module, path) in &files {
        let code = code_of(&std::fs::read_to_string(path).expect("a source file"));
        let mut targets = BTreeSet::new();
        for p in paths_after(&code, "crate::") {
            targets.extend(resolve(&files, &p));
        }
        // `super::` from `a::b::c` is `a::b` in both `a/b/c.rs` and `a/b/c/mod.rs`.
        let parent: Vec<&str> = module.split("::").collect();
        let parent = parent[..parent.len().saturating_sub(1)].join("::");
        for p in paths_after(&code, "super::") {
            let full = if parent.is_empty() {
                p
            } else {
                format!("{parent}::{p}")
            };
            targets.extend(resolve(&files, &full));
        }
        targets.remove(module);
        edges.insert(module.clone(), targets);
    }
    edges
}

/// The groups of files that import each other (strongly connected components of more than
/// one file), by Tarjan's algorithm.
fn circles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct Walk<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        found: Vec<Vec<String>>,
    }
    impl<'a> Walk<'a> {
        fn visit(&mut self, v: &'a str) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on_stack.insert(v);
            for w in self.edges.get(v).into_iter().flatten() {
                if !self.index.contains_key(w.as_str()) {
                    self.visit(w);
                    let lw = self.low[w.as_str()];
                    let lv = self.low.get_mut(v).expect("visited");
                    *lv = (*lv).min(lw);
                } else if self.on_stack.contains(w.as_str()) {
                    let iw = self.index[w.as_str()];
                    let lv = self.low.get_mut(v).expect("visited");
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut group = Vec::new();
                while let Some(w) = self.stack.pop() {
                    self.on_stack.remove(w);
                    group.push(w.to_owned());
                    if w == v {
                        break;
                    }
                }
                if group.len() > 1 {
                    group.sort();
                    self.found.push(group);
                }
            }
        }
    }
    let mut walk = Walk {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for v in edges.keys() {
        if !walk.index.contains_key(v.as_str()) {
            walk.visit(v);
        }
    }
    walk.found
}

/// The edges from a module to one above it in [`LAYERS`].
fn upward(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<(String, String)> {
    let top = |m: &str| m.split("::").next().unwrap_or("").to_owned();
    let rank = |m: &str| LAYERS.iter().position(|l| *l == top(m));
    let mut bad = Vec::new();
    for (a, targets) in edges {
        for b in targets {
            if let (Some(ra), Some(rb)) = (rank(a), rank(b)) {
                if rb > ra {
                    bad.push((a.clone(), b.clone()));
                }
            }
        }
    }
    bad
}

#[cfg(test)]
mod tests {
    use super::*;

    fn src() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
    }

    #[test]
    fn no_module_uses_one_above_it_in_the_declared_layers() {
        let e = edges(&src());
        let bad = upward(&e);
        assert!(
            bad.is_empty(),
            "upward imports (layers bottom first: {LAYERS:?}): {bad:?}"
        );
        // Every top-level module is placed in the order.
        for m in e.keys() {
            let top = m.split("::").next().unwrap_or("");
            assert!(
                top.is_empty() || top == "layers" || LAYERS.contains(&top),
                "module '{top}' is not in LAYERS"
            );
        }
    }

    #[test]
    fn no_two_files_import_each_other() {
        let found = circles(&edges(&src()));
        assert!(found.is_empty(), "import circles between files: {found:?}");
    }

    #[test]
    fn the_checks_see_edges_circles_and_upward_imports() {
        // The reader itself: braces, `super::` from a nested file, comments and tests left out.
        let code = code_of(
            "use crate::a::{b, c::d as e};\nuse super::f; // crate::x\n#[cfg(test)]\nmod tests { use crate::z; }",
        );
        assert_eq!(paths_after(&code, "crate::"), ["a::b", "a::c::d"]);
        assert_eq!(paths_after(&code, "super::"), ["f"]);
        let mut e: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        e.insert("fmu".into(), ["study::run".to_owned()].into());
        e.insert("study::run".into(), ["fmu".to_owned()].into());
        assert_eq!(
            circles(&e),
            [vec!["fmu".to_owned(), "study::run".to_owned()]]
        );
        assert_eq!(upward(&e), [("fmu".to_owned(), "study::run".to_owned())]);
    }
}
