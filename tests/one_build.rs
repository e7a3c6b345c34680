//! `cargo test --release` after `cargo run --release` compiles only the test
//! targets (issue 20): every crate the normal build compiles has the same
//! features when the dev-dependencies join, so Cargo builds it once. A
//! dev-dependency that turns a new feature on in a crate under faer,
//! nalgebra or clarabel would recompile the numerical stack (77 crates,
//! 156 s on 2 cores, before `Cargo.toml` asked for those features).

use std::collections::BTreeMap;
use std::process::Command;

/// `package version` → its features, as `cargo tree` resolves them with the
/// dependency kinds `edges`.
fn features(edges: &str) -> BTreeMap<String, String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "tree",
            "--offline",
            "--prefix",
            "none",
            "-f",
            "{p}|{f}",
            "-e",
            edges,
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .filter_map(|l| {
            let (package, features) = l.trim_end_matches(" (*)").split_once('|')?;
            // `name vX.Y.Z` (a path dependency adds its folder).
            let key = package.split(' ').take(2).collect::<Vec<_>>().join(" ");
            Some((key, features.to_string()))
        })
        .collect()
}

#[test]
fn the_dev_dependencies_change_no_feature_of_the_normal_build() {
    let normal = features("normal,build");
    let with_dev = features("normal,build,dev");
    assert!(normal.len() > 100, "{} packages", normal.len());
    let changed: Vec<String> = normal
        .iter()
        .filter_map(|(package, f)| {
            let g = with_dev.get(package)?;
            (g != f).then(|| format!("{package}: [{f}] → [{g}]"))
        })
        .collect();
    assert!(
        changed.is_empty(),
        "ask for these features in [dependencies] too:\n{}",
        changed.join("\n")
    );
}
