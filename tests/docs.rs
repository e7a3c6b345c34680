//! The documentation against the code it describes: every key the scene
//! reader accepts has a row in `docs/scene.md`; `docs/solvers.md` and
//! `--help` give each solver the same text; the README stays a page.

mod common;

use std::collections::BTreeSet;

use ringmesh::Scene;

/// `docs/scene.md`'s text.
fn scene_reference() -> String {
    std::fs::read_to_string(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/scene.md"))
        .expect("docs/scene.md")
}

/// The keys a table accepts, as the reader itself lists them: a scene with
/// an unknown key added to `table` (dotted; "" for the top level) is refused
/// by `deny_unknown_fields` with the list of the fields it expects.
fn accepted_keys(base: &toml::Table, table: &str) -> Vec<String> {
    let mut scene = base.clone();
    let mut at = &mut scene;
    for part in table.split('.').filter(|p| !p.is_empty()) {
        at = at
            .get_mut(part)
            .and_then(toml::Value::as_table_mut)
            .unwrap_or_else(|| panic!("{table} is not a table of the full scene"));
    }
    at.insert("not_a_scene_key".into(), toml::Value::Integer(0));
    let error = toml::from_str::<Scene>(&toml::to_string(&scene).unwrap())
        .expect_err("an unknown key is refused")
        .to_string();
    let expected = error
        .split_once("expected")
        .unwrap_or_else(|| panic!("no list of fields in: {error}"))
        .1;
    let keys: Vec<String> = expected
        .split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_string)
        .collect();
    assert!(!keys.is_empty(), "no fields in: {error}");
    keys
}

/// Every key of the scene format — found by asking the reader, table by
/// table, from a scene with every optional table present — has a row
/// `` | `table.key` | `` in docs/scene.md; a key added to the schema without
/// its row fails here.
#[test]
fn every_scene_key_has_an_entry_in_the_scene_reference() {
    // Every optional table present, so that its keys are asked for too.
    let mut full: toml::Table = toml::from_str(&ringmesh::scene::template("full")).unwrap();
    let extra: toml::Table = toml::from_str(
        "[uniformity]\ngroups = [\"front\"]\n\
         [effects]\ntruss = \"exact\"\n\
         [effects.gravity]\nacceleration_m_per_s2 = 9.81\ndirection = [0.0, 0.0, -1.0]\n\
         [surface]\nrms_mm = 1.5\n\
         [tolerances]\ncable_length_sigma_m = 1e-5\n\
         [effects.thermal]\ncable_expansion_per_k = 1e-6\ntube_expansion_per_k = 1e-6\n\
         [[effects.thermal.cases]]\nname = \"a\"\n",
    )
    .unwrap();
    full.extend(extra);
    let reference = scene_reference();
    let mut tables = vec![String::new()];
    let mut seen = BTreeSet::new();
    while let Some(table) = tables.pop() {
        for key in accepted_keys(&full, &table) {
            let dotted = if table.is_empty() {
                key.clone()
            } else {
                format!("{table}.{key}")
            };
            let is_table = dotted
                .split('.')
                .try_fold(&full, |t, part| t.get(part)?.as_table())
                .is_some();
            if is_table {
                tables.push(dotted.clone());
            }
            seen.insert(dotted);
        }
    }
    // The walk reached the nested tables and the optional keys.
    for key in [
        "truss.elements_per_rod",
        "effects.gravity.direction",
        "surface.frequency_ghz",
        "front_net.membrane_stress_n_per_m",
        "tolerances.seed",
        "effects.thermal.tie_expansion_per_k",
    ] {
        assert!(seen.contains(key), "{key} not found: {seen:?}");
    }
    let missing: Vec<&String> = seen
        .iter()
        .filter(|k| !reference.contains(&format!("| `{k}` |")))
        .collect();
    assert!(
        missing.is_empty(),
        "scene keys without a row in docs/scene.md: {missing:?}"
    );
}

/// `docs/solvers.md`, word for word what `--help` says of each solver: both
/// are [`SolverKind::description`] (the help through clap's possible values).
#[test]
fn the_solver_page_and_the_help_say_the_same_of_every_solver() {
    use ringmesh::uniformity::SolverKind;
    let page = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/solvers.md"),
    )
    .expect("docs/solvers.md");
    let help = common::ringmesh(&["design", "--help"]);
    let help = String::from_utf8_lossy(&help.stdout);
    for solver in SolverKind::ALL {
        let text = solver.description();
        assert!(
            page.contains(&format!("## `{}`\n\n{text}\n", solver.name())),
            "docs/solvers.md does not quote {}'s description",
            solver.name()
        );
        assert!(
            help.contains(&format!("- {}:", solver.name())) && help.contains(text),
            "--help does not give {}'s description:\n{help}",
            solver.name()
        );
    }
}

/// The README stays a page: the details live in docs/.
#[test]
fn the_readme_fits_on_a_page_and_links_every_doc() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(
        readme.lines().count() <= 200,
        "README: {} lines",
        readme.lines().count()
    );
    for doc in [
        "docs/scene.md",
        "docs/commands.md",
        "docs/solvers.md",
        "docs/results.md",
        "docs/benchmarks.md",
        "docs/ARCHITECTURE.md",
    ] {
        assert!(
            readme.contains(&format!("]({doc})")),
            "README does not link {doc}"
        );
        assert!(root.join(doc).is_file(), "{doc} missing");
    }
}
