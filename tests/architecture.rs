//! The crate's structure (docs/ARCHITECTURE.md): no import cycles, between
//! the top-level modules or between the files of one module. A file's
//! dependencies are read from its `crate::…` and `super::…` paths, items
//! re-exported by a `mod.rs` followed to the file that defines them; the
//! crate root (`lib.rs`, which joins every module's error), the edges
//! between a `mod.rs` and the files below it (declarations, re-exports) and
//! unit tests (which may use any layer) are left out.

mod common;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`.
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

/// The module path of a file: `src/a/b.rs` → `a::b`, `src/a/mod.rs` → `a`.
fn module_of(path: &Path) -> Vec<String> {
    let rel = path.strip_prefix(common::source_dir()).unwrap();
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
        parts.pop();
    }
    parts
}

/// The code of a file without comments and without its unit tests.
fn code(text: &str) -> String {
    let text = match text.find("#[cfg(test)]") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Expands `a::{b, c::{d, e}}` into `a::b`, `a::c::d`, `a::c::e`.
fn expand(path: &str) -> Vec<String> {
    let path: String = path.chars().filter(|c| !c.is_whitespace()).collect();
    let Some(open) = path.find('{') else {
        return vec![path];
    };
    let (prefix, rest) = (&path[..open], &path[open + 1..path.len() - 1]);
    let mut items = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in rest.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&rest[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    items.push(&rest[start..]);
    items
        .into_iter()
        .filter(|s| !s.is_empty())
        .flat_map(|s| expand(&format!("{prefix}{s}")))
        .collect()
}

/// Every path of a file's `use` items and inline `crate::`/`super::` paths,
/// made absolute (segments from the crate root), `as` renames dropped.
fn paths_of(module: &[String], is_root: bool, code: &str) -> Vec<Vec<String>> {
    let mut raw = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("use ") {
        let boundary = i == 0 || !rest.as_bytes()[i - 1].is_ascii_alphanumeric();
        let after = &rest[i + 4..];
        let end = after.find(';').unwrap_or(after.len());
        if boundary {
            raw.extend(expand(&after[..end]));
        }
        rest = &after[end.min(after.len())..];
    }
    for key in ["crate::", "super::"] {
        let mut rest = code;
        while let Some(i) = rest.find(key) {
            let tail = &rest[i..];
            let end = tail
                .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
                .unwrap_or(tail.len());
            raw.push(tail[..end].trim_end_matches(':').to_string());
            rest = &tail[end..];
        }
    }
    // `super` of a file is its parent module; of a mod.rs, the grandparent.
    let parent: Vec<String> = if is_root {
        module[..module.len().saturating_sub(1)].to_vec()
    } else {
        module[..module.len() - 1].to_vec()
    };
    raw.into_iter()
        .filter_map(|p| {
            let p = p.split(" as ").next().unwrap().to_string();
            let segments: Vec<String> = p.split("::").map(str::to_string).collect();
            match segments.first().map(String::as_str) {
                Some("crate") => Some(segments[1..].to_vec()),
                Some("super") => {
                    let mut base = parent.clone();
                    let mut s = &segments[1..];
                    while s.first().is_some_and(|x| x == "super") {
                        base.pop();
                        s = &s[1..];
                    }
                    base.extend(s.iter().cloned());
                    Some(base)
                }
                _ => None,
            }
        })
        .collect()
}

struct Crate {
    /// Module path → file.
    files: BTreeMap<Vec<String>, PathBuf>,
    /// (module, item) → the absolute path a `pub use` in that module names.
    exports: BTreeMap<(Vec<String>, String), Vec<String>>,
    /// File → absolute paths it uses.
    uses: BTreeMap<PathBuf, Vec<Vec<String>>>,
}

impl Crate {
    fn read() -> Crate {
        let mut paths = Vec::new();
        rust_files(&common::source_dir(), &mut paths);
        let mut files = BTreeMap::new();
        let mut exports = BTreeMap::new();
        let mut uses = BTreeMap::new();
        for path in paths {
            // The binary, and unit-test modules kept in a file of their own.
            if path.ends_with("main.rs") || path.ends_with("tests.rs") {
                continue;
            }
            let module = module_of(&path);
            let is_root = path.ends_with("mod.rs") || path.ends_with("lib.rs");
            let text = code(&std::fs::read_to_string(&path).unwrap());
            // Re-exports, relative paths made absolute.
            for line in text.split(';') {
                let Some(i) = line.find("pub use ") else {
                    continue;
                };
                for p in expand(&line[i + 8..]) {
                    let p = p.split(" as ").next().unwrap().to_string();
                    let segments: Vec<String> = p.split("::").map(str::to_string).collect();
                    let absolute = match segments[0].as_str() {
                        "crate" => segments[1..].to_vec(),
                        "super" => {
                            let mut b = module[..module.len() - 1].to_vec();
                            b.extend(segments[1..].iter().cloned());
                            b
                        }
                        _ => {
                            let mut b = module.clone();
                            b.extend(segments.iter().cloned());
                            b
                        }
                    };
                    let name = absolute.last().unwrap().clone();
                    exports.insert((module.clone(), name), absolute);
                }
            }
            uses.insert(path.clone(), paths_of(&module, is_root, &text));
            files.insert(module, path);
        }
        Crate {
            files,
            exports,
            uses,
        }
    }

    /// The file that defines what `path` names.
    fn resolve(&self, path: &[String], depth: usize) -> Option<PathBuf> {
        let mut k = path.len();
        while k > 0 && !self.files.contains_key(&path[..k]) {
            k -= 1;
        }
        let module = path[..k].to_vec();
        if depth < 8 {
            if let Some(item) = path.get(k) {
                if let Some(target) = self.exports.get(&(module.clone(), item.clone())) {
                    if target.as_slice() != path {
                        return self.resolve(target, depth + 1);
                    }
                }
            }
        }
        self.files.get(&module).cloned()
    }

    /// File → files it depends on (parent–child edges and the root left out).
    fn graph(&self) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
        let module_of_file: BTreeMap<&PathBuf, &Vec<String>> =
            self.files.iter().map(|(m, f)| (f, m)).collect();
        let mut graph = BTreeMap::new();
        for (file, paths) in &self.uses {
            let from = module_of_file[file];
            let edges: &mut BTreeSet<PathBuf> = graph.entry(file.clone()).or_default();
            for p in paths {
                let Some(target) = self.resolve(p, 0) else {
                    continue;
                };
                let to = module_of_file[&target];
                let related = from.starts_with(to) || to.starts_with(from);
                if target != *file && !to.is_empty() && !related {
                    edges.insert(target);
                }
            }
        }
        graph
    }
}

/// The cycles of `graph` (one per strongly connected component of more than
/// one node).
fn cycles<T: Ord + Clone>(graph: &BTreeMap<T, BTreeSet<T>>) -> Vec<Vec<T>> {
    // Nodes that reach each other both ways.
    let reach = |start: &T| {
        let mut seen = BTreeSet::new();
        let mut stack = vec![start.clone()];
        while let Some(n) = stack.pop() {
            for m in graph.get(&n).into_iter().flatten() {
                if seen.insert(m.clone()) {
                    stack.push(m.clone());
                }
            }
        }
        seen
    };
    let reachable: BTreeMap<T, BTreeSet<T>> = graph.keys().map(|n| (n.clone(), reach(n))).collect();
    let mut done = BTreeSet::new();
    let mut found = Vec::new();
    for n in graph.keys() {
        if done.contains(n) || !reachable[n].contains(n) {
            continue;
        }
        let component: Vec<T> = graph
            .keys()
            .filter(|m| reachable[n].contains(*m) && reachable[*m].contains(n))
            .cloned()
            .collect();
        done.extend(component.iter().cloned());
        found.push(component);
    }
    found
}

#[test]
fn no_two_files_import_each_other_even_through_others() {
    let krate = Crate::read();
    let graph = krate.graph();
    assert!(graph.len() > 40, "{} files read", graph.len());
    let found = cycles(&graph);
    assert!(found.is_empty(), "import cycles between files: {found:#?}");
}

#[test]
fn no_two_top_level_modules_import_each_other() {
    let krate = Crate::read();
    let mut modules: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (file, targets) in krate.graph() {
        let from = module_of(&file);
        let Some(top) = from.first() else { continue };
        let entry = modules.entry(top.clone()).or_default();
        for t in targets {
            let to = module_of(&t)[0].clone();
            if to != *top {
                entry.insert(to);
            }
        }
    }
    // The design pipeline uses the lower layers, never the reverse.
    assert!(modules["design"].contains("truss") && modules["design"].contains("uniformity"));
    let found = cycles(&modules);
    assert!(
        found.is_empty(),
        "import cycles between modules: {found:#?}"
    );
}

/// The reader: the dependency analysis sees through a `mod.rs` re-export.
#[test]
fn a_re_exported_item_resolves_to_its_defining_file() {
    let krate = Crate::read();
    let path: Vec<String> = ["design", "TiedNets"].map(String::from).to_vec();
    assert_eq!(
        krate.resolve(&path, 0),
        Some(common::source_dir().join("design/tied_nets.rs"))
    );
}
