//! The crate's structure (docs/ARCHITECTURE.md): no import cycles, counted
//! file to file. A file's dependencies are the items its code names —
//! `use` items, inline `crate::`/`super::`/`self::` paths, and in a `mod.rs`
//! or `lib.rs` paths through its own child modules (`sizing::SizingError`) —
//! each followed through the re-exports (`pub use`, `pub(crate) use`,
//! `pub(super) use`) to the file that defines it. A re-export is not itself
//! a dependency; everything else counts, a `mod.rs` and the crate root
//! (`lib.rs`) included: a `mod.rs` whose own code uses a child file that uses
//! an item defined in that `mod.rs` is a cycle. Unit tests (which may use any
//! layer) are left out.
//!
//! The analysis runs on the crate and, to show that it sees each kind of
//! cycle the project has had, on small synthetic trees that reintroduce them.

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

/// The module path of a file under `root`: `a/b.rs` → `a::b`, `a/mod.rs` → `a`,
/// `lib.rs` → the root (empty path).
fn module_of(root: &Path, path: &Path) -> Vec<String> {
    let rel = path.strip_prefix(root).unwrap();
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

/// A file's `use` items, split into re-exports (`pub use`, `pub(crate) use`,
/// `pub(super) use`, `pub(in …) use`) and private imports, each as its
/// expanded paths (`as` renames dropped, a trailing `self` dropped); and the
/// code with every `use` item blanked out.
struct Imports {
    exports: Vec<String>,
    imports: Vec<String>,
    rest: String,
}

fn imports_of(code: &str) -> Imports {
    let (mut exports, mut imports, mut rest) = (Vec::new(), Vec::new(), String::new());
    let mut text = code;
    while let Some(i) = text.find("use ") {
        let boundary = i == 0 || !text.as_bytes()[i - 1].is_ascii_alphanumeric();
        let after = &text[i + 4..];
        let end = after.find(';').unwrap_or(after.len());
        if !boundary {
            rest.push_str(&text[..i + 4]);
            text = after;
            continue;
        }
        let before = text[..i].trim_end();
        let visibility = before
            .rfind([';', '}', '{', ']'])
            .map_or(before, |k| &before[k + 1..])
            .trim();
        let paths = expand(&after[..end]).into_iter().map(|p| {
            let p = p.split(" as ").next().unwrap().to_string();
            p.strip_suffix("::self").map(str::to_string).unwrap_or(p)
        });
        if visibility.starts_with("pub") {
            exports.extend(paths);
        } else {
            imports.extend(paths);
        }
        rest.push_str(&text[..i]);
        text = &after[end.min(after.len())..];
    }
    rest.push_str(text);
    Imports {
        exports,
        imports,
        rest,
    }
}

/// Every occurrence of `prefix::a::b…` in `code` (not preceded by an
/// identifier character or `::`), as the text from `prefix`.
fn inline_paths(code: &str, prefix: &str) -> Vec<String> {
    let key = format!("{prefix}::");
    let mut found = Vec::new();
    let mut start = 0;
    while let Some(i) = code[start..].find(&key) {
        let at = start + i;
        let before = code[..at].chars().next_back();
        let free = !before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':');
        let tail = &code[at..];
        let end = tail
            .find(|c: char| !(c.is_alphanumeric() || c == '_' || c == ':'))
            .unwrap_or(tail.len());
        if free {
            found.push(tail[..end].trim_end_matches(':').to_string());
        }
        start = at + end.max(key.len());
    }
    found
}

/// Module paths → defining files, re-exports, and each file's uses.
struct Crate {
    /// Module path → file.
    files: BTreeMap<Vec<String>, PathBuf>,
    /// (module, item) → the absolute path a re-export in that module names.
    exports: BTreeMap<(Vec<String>, String), Vec<String>>,
    /// File → absolute paths its code names.
    uses: BTreeMap<PathBuf, Vec<Vec<String>>>,
}

impl Crate {
    fn read() -> Crate {
        Crate::read_tree(&common::source_dir())
    }

    /// The crate whose root (`lib.rs`) is in `root`; the binary (`main.rs`,
    /// `cli.rs`) and unit-test files (`tests.rs`) are left out.
    fn read_tree(root: &Path) -> Crate {
        let mut paths = Vec::new();
        rust_files(root, &mut paths);
        paths.retain(|p| {
            let binary = root.join("main.rs") == *p || root.join("cli.rs") == *p;
            !(binary || p.ends_with("tests.rs"))
        });
        let files: BTreeMap<Vec<String>, PathBuf> = paths
            .iter()
            .map(|p| (module_of(root, p), p.clone()))
            .collect();
        let mut exports = BTreeMap::new();
        let mut uses = BTreeMap::new();
        for path in &paths {
            let module = module_of(root, path);
            let children: BTreeSet<String> = files
                .keys()
                .filter(|m| m.len() == module.len() + 1 && m.starts_with(&module))
                .map(|m| m.last().unwrap().clone())
                .collect();
            let absolute = |p: &str| absolute(&module, &children, p);
            let imports = imports_of(&code(&std::fs::read_to_string(path).unwrap()));
            for p in &imports.exports {
                if let Some(target) = absolute(p) {
                    let name = p.rsplit("::").next().unwrap().to_string();
                    exports.insert((module.clone(), name), target);
                }
            }
            let mut named: Vec<Vec<String>> = Vec::new();
            let mut aliases = Vec::new();
            for p in &imports.imports {
                let Some(target) = absolute(p) else { continue };
                if files.contains_key(&target) {
                    // A module imported by name: its items are named through it.
                    aliases.push((p.rsplit("::").next().unwrap().to_string(), target));
                } else {
                    named.push(target);
                }
            }
            let mut prefixes = vec!["crate".to_string(), "super".to_string(), "self".to_string()];
            prefixes.extend(children.iter().cloned());
            for prefix in &prefixes {
                for p in inline_paths(&imports.rest, prefix) {
                    named.extend(absolute(&p));
                }
            }
            for (alias, target) in &aliases {
                for p in inline_paths(&imports.rest, alias) {
                    let mut full = target.clone();
                    full.extend(p.split("::").skip(1).map(str::to_string));
                    named.push(full);
                }
            }
            uses.insert(path.clone(), named);
        }
        Crate {
            files,
            exports,
            uses,
        }
    }

    /// The file that defines what `path` names: the longest module prefix,
    /// followed through that module's re-export of the next segment.
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

    /// File → the files whose items it names.
    fn graph(&self) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
        let mut graph = BTreeMap::new();
        for (file, paths) in &self.uses {
            let edges: &mut BTreeSet<PathBuf> = graph.entry(file.clone()).or_default();
            for p in paths {
                // A path that only names a module (`crate::truss`) names no item.
                if self.files.contains_key(p) {
                    continue;
                }
                if let Some(target) = self.resolve(p, 0) {
                    if target != *file {
                        edges.insert(target);
                    }
                }
            }
        }
        graph
    }
}

/// `p` as a path from the crate root, for a file of module `module` whose
/// child modules are `children`; `None` for a path outside the crate. (A
/// file's `super` is its module's parent, whether it is `a/b.rs` or
/// `a/b/mod.rs`.)
fn absolute(module: &[String], children: &BTreeSet<String>, p: &str) -> Option<Vec<String>> {
    let segments: Vec<String> = p.split("::").map(str::to_string).collect();
    match segments.first().map(String::as_str) {
        Some("crate") => Some(segments[1..].to_vec()),
        Some("self") => Some([module, &segments[1..]].concat()),
        Some("super") => {
            let mut base = module.to_vec();
            let mut s = segments.as_slice();
            while s.first().is_some_and(|x| x == "super") {
                base.pop();
                s = &s[1..];
            }
            Some([base.as_slice(), s].concat())
        }
        Some(first) if children.contains(first) => Some([module, segments.as_slice()].concat()),
        _ => None,
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

/// The file cycles of the crate in `root`, each as paths relative to it.
fn file_cycles(root: &Path) -> Vec<Vec<String>> {
    cycles(&Crate::read_tree(root).graph())
        .into_iter()
        .map(|c| {
            c.iter()
                .map(|p| p.strip_prefix(root).unwrap().display().to_string())
                .collect()
        })
        .collect()
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
    let root = common::source_dir();
    let krate = Crate::read();
    let mut modules: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (file, targets) in krate.graph() {
        let from = module_of(&root, &file);
        let Some(top) = from.first() else { continue };
        let entry = modules.entry(top.clone()).or_default();
        for t in targets {
            let Some(to) = module_of(&root, &t).first().cloned() else {
                continue;
            };
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

/// Only the crate root and the command layer name `crate::Error`: every
/// other module returns its own error.
#[test]
fn only_the_command_layer_returns_the_crate_error() {
    let root = common::source_dir();
    let krate = Crate::read();
    let lib = root.join("lib.rs");
    let users: Vec<String> = krate
        .graph()
        .into_iter()
        .filter(|(file, targets)| targets.contains(&lib) && !file.starts_with(root.join("run")))
        .map(|(file, _)| file.strip_prefix(&root).unwrap().display().to_string())
        .collect();
    assert!(
        users.is_empty(),
        "files below run/ that use lib.rs: {users:?}"
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

/// A synthetic crate: `(path under src/, code)` pairs written to a fresh
/// folder.
fn tree(name: &str, files: &[(&str, &str)]) -> PathBuf {
    let root = std::env::temp_dir().join(format!(
        "ringmesh-architecture-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&root);
    for (path, text) in files {
        let path = root.join(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    root
}

/// Asserts that the crate in `root` has exactly one cycle, through `files`.
fn assert_one_cycle(root: &Path, files: &[&str]) {
    let found = file_cycles(root);
    let _ = std::fs::remove_dir_all(root);
    let mut expected: Vec<String> = files.iter().map(|f| f.to_string()).collect();
    expected.sort();
    assert_eq!(found, vec![expected]);
}

/// `report/mod.rs ↔ report/output_set.rs`: a `mod.rs` whose code calls a
/// child that uses the error the `mod.rs` defines.
#[test]
fn the_guard_sees_a_mod_rs_and_its_child_using_each_other() {
    let root = tree(
        "mod-child",
        &[
            ("lib.rs", "pub mod report;\n"),
            (
                "report/mod.rs",
                "mod output_set;\npub use output_set::OutputSet;\n\
                 pub enum ReportError { Io }\n\
                 pub fn shown() -> String { output_set::name() }\n",
            ),
            (
                "report/output_set.rs",
                "use super::ReportError;\npub struct OutputSet;\n\
                 pub fn name() -> String { String::new() }\n\
                 pub fn fail() -> ReportError { ReportError::Io }\n",
            ),
        ],
    );
    assert_one_cycle(&root, &["report/mod.rs", "report/output_set.rs"]);
}

/// The same child, with the error moved down into a base file, is no cycle:
/// the guard does not count a re-export as a use.
#[test]
fn the_guard_does_not_count_re_exports() {
    let root = tree(
        "re-export",
        &[
            ("lib.rs", "pub mod report;\n"),
            (
                "report/mod.rs",
                "mod error;\nmod output_set;\npub use error::ReportError;\n\
                 pub use output_set::OutputSet;\n",
            ),
            ("report/error.rs", "pub enum ReportError { Io }\n"),
            (
                "report/output_set.rs",
                "use super::ReportError;\npub struct OutputSet;\n\
                 pub fn fail() -> ReportError { ReportError::Io }\n",
            ),
        ],
    );
    let found = file_cycles(&root);
    let _ = std::fs::remove_dir_all(&root);
    assert!(found.is_empty(), "{found:?}");
}

/// `lib.rs ↔ sizing/catalogue.rs ↔ sizing/mod.rs`: the crate's error joins a
/// module's error, and that module returns the crate's error.
#[test]
fn the_guard_sees_a_module_returning_the_crate_error() {
    let root = tree(
        "crate-error",
        &[
            (
                "lib.rs",
                "pub mod sizing;\n\
                 pub enum Error { Sizing(sizing::SizingError) }\n",
            ),
            (
                "sizing/mod.rs",
                "mod catalogue;\npub use catalogue::Section;\n\
                 pub enum SizingError { Empty }\n\
                 pub fn size() -> Result<catalogue::Section, crate::Error> { catalogue::read() }\n",
            ),
            (
                "sizing/catalogue.rs",
                "use crate::Error;\npub struct Section;\n\
                 pub fn read() -> Result<Section, Error> { Ok(Section) }\n",
            ),
        ],
    );
    // catalogue.rs → lib.rs → sizing/mod.rs → catalogue.rs, and lib.rs.
    assert_one_cycle(&root, &["lib.rs", "sizing/catalogue.rs", "sizing/mod.rs"]);
}

/// `ipm/status.rs → normal.rs → data.rs → status.rs`, through `pub(crate)
/// use` re-exports of the module.
#[test]
fn the_guard_follows_crate_visible_re_exports() {
    let root = tree(
        "crate-visible",
        &[
            ("lib.rs", "pub mod ipm;\n"),
            (
                "ipm/mod.rs",
                "mod data;\nmod normal;\nmod status;\n\
                 pub(crate) use data::Data;\npub(super) use normal::Normal;\n\
                 pub use status::Status;\n",
            ),
            (
                "ipm/status.rs",
                "use super::Normal;\npub struct Status(Normal);\n",
            ),
            (
                "ipm/normal.rs",
                "use super::Data;\npub struct Normal(Data);\n",
            ),
            ("ipm/data.rs", "pub struct Data(crate::ipm::Status);\n"),
        ],
    );
    assert_one_cycle(&root, &["ipm/data.rs", "ipm/normal.rs", "ipm/status.rs"]);
}

/// `gradient/finish ↔ lbfgs ↔ mod ↔ objective`: a module imported by name
/// (`use super::objective;`) and used through it.
#[test]
fn the_guard_follows_a_module_imported_by_name() {
    let root = tree(
        "by-name",
        &[
            ("lib.rs", "pub mod gradient;\n"),
            (
                "gradient/mod.rs",
                "mod finish;\nmod lbfgs;\nmod objective;\n\
                 pub struct Gradient;\n\
                 pub fn solve() { finish::run() }\n",
            ),
            (
                "gradient/finish/mod.rs",
                "use super::lbfgs;\npub fn run() { lbfgs::minimise() }\n",
            ),
            (
                "gradient/lbfgs.rs",
                "use super::objective;\npub fn minimise() { objective::value(); }\n",
            ),
            (
                "gradient/objective.rs",
                "pub fn value() -> super::Gradient { super::Gradient }\n",
            ),
        ],
    );
    assert_one_cycle(
        &root,
        &[
            "gradient/finish/mod.rs",
            "gradient/lbfgs.rs",
            "gradient/mod.rs",
            "gradient/objective.rs",
        ],
    );
}

/// The top-level modules in the order of docs/ARCHITECTURE.md's layer table
/// (its first column's names, `a.rs`/`a/` → `a`), lowest first.
fn documented_layers() -> Vec<String> {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/ARCHITECTURE.md"))
            .unwrap();
    let table = doc
        .split("## Layers")
        .nth(1)
        .and_then(|s| s.split("\n## ").next())
        .expect("docs/ARCHITECTURE.md has a Layers section");
    let mut layers = Vec::new();
    for line in table.lines().filter(|l| l.starts_with("| `")) {
        let first = line.split('|').nth(1).unwrap();
        for name in first.split('`').skip(1).step_by(2) {
            let name = name.trim_end_matches('/').trim_end_matches(".rs");
            if !layers.iter().any(|l| l == name) {
                layers.push(name.to_string());
            }
        }
    }
    layers
}

/// docs/ARCHITECTURE.md's claim: a module uses only the modules listed
/// before it (the layer table runs from the bottom up), and the table names
/// every top-level module.
#[test]
fn every_module_uses_only_the_layers_the_architecture_lists_below_it() {
    let root = common::source_dir();
    let layers = documented_layers();
    let rank = |m: &str| layers.iter().position(|l| l == m);
    let mut unlisted = BTreeSet::new();
    let mut upward = Vec::new();
    for (file, targets) in Crate::read().graph() {
        let Some(from) = module_of(&root, &file).first().cloned() else {
            continue;
        };
        for t in targets {
            let Some(to) = module_of(&root, &t).first().cloned() else {
                continue;
            };
            match (rank(&from), rank(&to)) {
                (Some(a), Some(b)) if b > a => upward.push(format!(
                    "{} uses {}",
                    file.strip_prefix(&root).unwrap().display(),
                    t.strip_prefix(&root).unwrap().display()
                )),
                (None, _) => drop(unlisted.insert(from.clone())),
                (_, None) => drop(unlisted.insert(to)),
                _ => {}
            }
        }
    }
    assert!(
        unlisted.is_empty(),
        "modules the table does not list: {unlisted:?}"
    );
    assert!(upward.is_empty(), "uses of a higher layer: {upward:#?}");
}
