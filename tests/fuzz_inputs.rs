//! Fuzzing the input files (issue 7): scenes and frame files mutated one key
//! at a time — a value replaced by one of every kind (zero, negative, huge,
//! NaN, infinite, string, array, table), a key deleted, an unknown key added
//! — and scene text corrupted byte by byte. No input panics; every rejected
//! structured mutation is an error that names a key; accepted inputs go on
//! through the pipeline (mesh and forward solve, frame analysis and solve)
//! without a panic.

mod common;

use std::path::Path;

use proptest::prelude::*;
use ringmesh::fdm::solve_network;
use ringmesh::frame::FrameFile;
use ringmesh::geometry::build_mesh;
use ringmesh::mechanics::StaticSolver;
use ringmesh::scene::Scene;
use toml::{Table, Value};

fn read(relative: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)).unwrap()
}

/// A step into a TOML document.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    Key(String),
    Index(usize),
}

/// Every value's path in `v` (tables and arrays too, so whole sections can
/// be replaced or deleted).
fn paths(v: &Value, here: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    if !here.is_empty() {
        out.push(here.clone());
    }
    match v {
        Value::Table(t) => {
            for (k, child) in t {
                here.push(Step::Key(k.clone()));
                paths(child, here, out);
                here.pop();
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                here.push(Step::Index(i));
                paths(child, here, out);
                here.pop();
            }
        }
        _ => {}
    }
}

/// The last key of a path: what an error about that value should name.
fn leaf(path: &[Step]) -> String {
    path.iter()
        .rev()
        .find_map(|s| match s {
            Step::Key(k) => Some(k.clone()),
            Step::Index(_) => None,
        })
        .expect("a path starts with a key")
}

fn at<'a>(v: &'a mut Value, path: &[Step]) -> &'a mut Value {
    path.iter().fold(v, |v, s| match s {
        Step::Key(k) => v.get_mut(k.as_str()).expect("path exists"),
        Step::Index(i) => v.get_mut(*i).expect("path exists"),
    })
}

/// Values of every kind, the nasty ones first.
fn nasty(k: usize) -> Value {
    let mut table = Table::new();
    table.insert("x".into(), Value::Integer(1));
    let values = [
        Value::Integer(0),
        Value::Integer(-1),
        Value::Integer(1),
        Value::Integer(2),
        Value::Integer(7),
        Value::Integer(64),
        Value::Integer(1000),
        Value::Integer(i64::MAX),
        Value::Float(0.0),
        Value::Float(-1.0),
        Value::Float(0.5),
        Value::Float(1e-300),
        Value::Float(1e300),
        Value::Float(f64::NAN),
        Value::Float(f64::INFINITY),
        Value::Float(f64::NEG_INFINITY),
        Value::String(String::new()),
        Value::String("tip".into()),
        Value::Boolean(true),
        Value::Array(vec![]),
        Value::Array(vec![
            Value::Float(1.0),
            Value::Float(2.0),
            Value::Float(3.0),
        ]),
        Value::Array(vec![Value::Float(f64::NAN); 3]),
        Value::Table(table),
    ];
    values[k % values.len()].clone()
}

/// One structured mutation of a document.
#[derive(Debug, Clone)]
enum Mutation {
    Replace { path: usize, value: usize },
    Delete { path: usize },
    Unknown { path: usize },
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        4 => (any::<usize>(), any::<usize>()).prop_map(|(path, value)| Mutation::Replace { path, value }),
        1 => any::<usize>().prop_map(|path| Mutation::Delete { path }),
        1 => any::<usize>().prop_map(|path| Mutation::Unknown { path }),
    ]
}

/// Applies `m` to the TOML `text`: the mutated text and the key an error
/// about it must name.
fn apply(text: &str, m: &Mutation) -> (String, String) {
    let mut doc: Value = toml::from_str(text).unwrap();
    let mut all = Vec::new();
    paths(&doc, &mut Vec::new(), &mut all);
    let named = match m {
        Mutation::Replace { path, value } => {
            let p = &all[path % all.len()];
            *at(&mut doc, p) = nasty(*value);
            leaf(p)
        }
        Mutation::Delete { path } => {
            let p = &all[path % all.len()];
            let (last, parent) = p.split_last().unwrap();
            match (at(&mut doc, parent), last) {
                (Value::Table(t), Step::Key(k)) => {
                    t.remove(k);
                }
                (Value::Array(a), Step::Index(i)) => {
                    a.remove(*i);
                }
                _ => unreachable!(),
            }
            leaf(p)
        }
        Mutation::Unknown { path } => {
            let tables: Vec<&Vec<Step>> = all
                .iter()
                .filter(|p| {
                    let mut d = doc.clone();
                    at(&mut d, p).is_table()
                })
                .collect();
            let p = tables[path % tables.len()].clone();
            if let Value::Table(t) = at(&mut doc, &p) {
                t.insert("unknown_fuzz_key".into(), Value::Integer(1));
            }
            "unknown_fuzz_key".to_string()
        }
    };
    (toml::to_string(&doc).unwrap(), named)
}

proptest! {
    #![proptest_config(common::proptest_config(160, 0x5eed_1001))]

    /// A mutated scene is accepted and builds (and its net solves) without a
    /// panic, or is refused naming the mutated key or the key at fault.
    #[test]
    fn mutated_scenes_never_panic_and_name_the_key(m in mutation()) {
        let (text, named) = apply(&read("problems/small-hex.toml"), &m);
        match Scene::from_toml(&text, "fuzz") {
            Ok(scene) => {
                if let Ok(mesh) = build_mesh(&scene) {
                    if mesh.network.n_nodes() <= 50_000 {
                        let _ = solve_network(&mesh.network);
                    }
                } else if let Err(e) = build_mesh(&scene) {
                    prop_assert!(e.key().is_some(), "{m:?}: {e}");
                }
            }
            Err(e) => {
                let message = e.to_string();
                prop_assert!(
                    message.contains(&named) || e.key().is_some(),
                    "{:?} (key `{}`): {}", m, named, message
                );
            }
        }
    }

    /// A mutated frame file is accepted, analysed and (when small and its
    /// solver settings untouched) solved without a panic, or is refused
    /// naming the mutated key or the item at fault.
    #[test]
    fn mutated_frame_files_never_panic_and_name_the_key(
        m in mutation(),
        which in 0usize..2,
    ) {
        let base = ["problems/frames/cantilever-moment.toml", "problems/frames/ring-truss-frame.toml"];
        let (text, named) = apply(&read(base[which]), &m);
        match FrameFile::from_toml(&text) {
            Ok(file) => {
                let small = file.model.node_count() <= 200;
                if let Ok(solver) = StaticSolver::new(file.model.clone()) {
                    if small && !text.contains("unknown_fuzz_key") && named != "solver" {
                        let _ = solver.solve(&file.settings);
                    }
                }
            }
            Err(e) => {
                let message = e.to_string();
                prop_assert!(
                    message.contains(&named) || e.key().is_some(),
                    "{:?} (key `{}`): {}", m, named, message
                );
            }
        }
    }

    /// Scene text corrupted at random bytes (or cut short) is parsed without
    /// a panic.
    #[test]
    fn corrupted_scene_text_never_panics(
        edits in prop::collection::vec((any::<usize>(), any::<u8>()), 1..8),
        cut in any::<usize>(),
    ) {
        let mut bytes = read("problems/small-hex.toml").into_bytes();
        for (at, byte) in edits {
            let i = at % bytes.len();
            bytes[i] = byte;
        }
        let keep = cut % (bytes.len() + 1);
        bytes.truncate(keep.max(bytes.len() / 2));
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(scene) = Scene::from_toml(&text, "fuzz") {
            let _ = build_mesh(&scene);
        }
    }
}
