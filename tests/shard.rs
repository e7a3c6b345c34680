//! Sweeps split across machines: `front` and `study` run as shards
//! (`--shard I/N`) and joined by `merge` give exactly the rows of the
//! unsharded run; shards of different sweeps are refused.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

fn succeed(args: &[&str]) -> Output {
    let run = common::ringmesh(args);
    assert!(
        run.status.success(),
        "ringmesh {args:?}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    run
}

/// `merge` refuses with exit code 2 and a message containing `needle`, and
/// writes nothing to `output`.
fn refused(paths: &[&Path], output: &Path, needle: &str) {
    let mut args = vec!["merge".to_string()];
    args.extend(paths.iter().map(|p| p.display().to_string()));
    args.extend(["-o".to_string(), output.display().to_string()]);
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let run = common::ringmesh(&args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(stderr.contains(needle), "{args:?}: {stderr}");
    assert!(!output.exists(), "{args:?} wrote {}", output.display());
}

/// The header and rows of a CSV with the named columns left out (the wall
/// times, which differ from run to run).
fn table_without(path: &Path, left_out: &[&str]) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&i| !left_out.contains(&header[i]))
        .collect();
    assert_eq!(keep.len() + left_out.len(), header.len(), "{header:?}");
    std::iter::once(header.join(","))
        .chain(lines.map(str::to_string))
        .map(|line| {
            let fields: Vec<&str> = line.split(',').collect();
            keep.iter().map(|&i| fields[i].to_string()).collect()
        })
        .collect()
}

fn shard_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files
}

/// Runs `args` unsharded into `whole`, as shards `0/3 … 2/3` into `parts`,
/// merges `parts` into `merged`, and returns the names of the shard files.
fn whole_sharded_merged(args: &[&str], whole: &Path, parts: &Path, merged: &Path) -> Vec<String> {
    let with = |extra: &[&str]| -> Vec<String> {
        args.iter()
            .chain(extra)
            .map(|s| s.to_string())
            .collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| succeed(&a.iter().map(String::as_str).collect::<Vec<_>>());
    run(with(&["-o", whole.to_str().unwrap()]));
    for i in 0..3 {
        run(with(&[
            "--shard",
            &format!("{i}/3"),
            "-o",
            parts.to_str().unwrap(),
        ]));
    }
    succeed(&[
        "merge",
        parts.to_str().unwrap(),
        "-o",
        merged.to_str().unwrap(),
    ]);
    shard_files(parts)
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect()
}

#[test]
fn front_in_three_shards_merges_to_the_unsharded_rows() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, parts, merged) = (
        dir.path().join("whole"),
        dir.path().join("parts"),
        dir.path().join("merged"),
    );
    let scene = common::problem_arg("small-hex.toml");
    let args = [
        "front",
        &scene,
        // gradient warm-starts each point from its neighbour: a shard takes
        // its chain whole, or its points would start elsewhere and end a
        // hair apart (1e-6 in the RMS) from the unsharded ones.
        "--solvers",
        "bisection,least-squares,gradient",
        "--points",
        "4",
    ];
    let names = whole_sharded_merged(&args, &whole, &parts, &merged);
    assert_eq!(
        names,
        [
            "front.shard-0-of-3.csv",
            "front.shard-1-of-3.csv",
            "front.shard-2-of-3.csv"
        ],
        "a shard writes its CSV only"
    );
    let expected = table_without(&whole.join("front.csv"), &["time_s"]);
    assert_eq!(expected.len(), 1 + 12, "{expected:?}");
    assert_eq!(
        table_without(&merged.join("front.csv"), &["time_s"]),
        expected
    );
    let png = std::fs::read(merged.join("front.png")).unwrap();
    assert_eq!(&png[..4], b"\x89PNG");
    assert!(std::fs::read_to_string(merged.join("front.svg"))
        .unwrap()
        .contains("least-squares"));
}

#[test]
fn study_in_three_shards_merges_to_the_unsharded_rows() {
    let dir = tempfile::tempdir().unwrap();
    let (whole, parts, merged) = (
        dir.path().join("whole"),
        dir.path().join("parts"),
        dir.path().join("merged"),
    );
    let scene = common::problem_arg("small-hex.toml");
    let args = [
        "study",
        &scene,
        "--knobs",
        "tolerance,elements,truss",
        "--tolerances",
        "1e-3,1e-6",
        "--elements",
        "1,4",
        "--trusses",
        "rigid,exact",
    ];
    let names = whole_sharded_merged(&args, &whole, &parts, &merged);
    assert_eq!(names.len(), 3, "{names:?}");
    assert!(names
        .iter()
        .all(|n| n.starts_with("accuracy-vs-time.shard-")));
    let expected = table_without(&whole.join("accuracy-vs-time.csv"), &["time_s"]);
    assert_eq!(
        table_without(&merged.join("accuracy-vs-time.csv"), &["time_s"]),
        expected
    );
    let png = std::fs::read(merged.join("accuracy-vs-time.png")).unwrap();
    assert_eq!(&png[..4], b"\x89PNG");

    // The reference, then tolerance ×2, elements ×2, truss ×2.
    let column = |name: &str| expected[0].iter().position(|c| c == name).unwrap();
    let (knob, value) = (column("knob"), column("value"));
    let points: Vec<(&str, &str)> = expected[1..]
        .iter()
        .map(|r| (r[knob].as_str(), r[value].as_str()))
        .collect();
    assert_eq!(
        points,
        [
            ("reference", ""),
            ("tolerance", "1e-3"),
            ("tolerance", "1e-6"),
            ("elements", "1"),
            ("elements", "4"),
            ("truss", "rigid"),
            ("truss", "exact"),
        ]
    );
    let number = |row: usize, name: &str| -> f64 { expected[row][column(name)].parse().unwrap() };
    assert_eq!(
        number(1, "ratio_error"),
        0.0,
        "the reference against itself"
    );
    // The conventional (rigid-truss) design, built on the flexible truss,
    // misses the reference's uniformity and tensions by orders of magnitude
    // more than the design made for the exact truss.
    let (rigid, exact) = (6, 7);
    for name in ["ratio_error", "tension_change_pct", "cut_length_error_mm"] {
        assert!(
            number(rigid, name) > 100.0 * number(exact, name),
            "{name}: rigid {} vs exact {}",
            number(rigid, name),
            number(exact, name)
        );
    }
}

#[test]
fn merging_mismatched_shards_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let at = |name: &str| dir.path().join(name);
    let hex = common::problem_arg("small-hex.toml");
    let front = |scene: &str, shard: &str, points: &str, out: &Path| {
        succeed(&[
            "front",
            scene,
            "--solvers",
            "least-squares",
            "--points",
            points,
            "--shard",
            shard,
            "-o",
            out.to_str().unwrap(),
        ]);
        out.join(format!("front.shard-{}.csv", shard.replace('/', "-of-")))
    };
    let out = at("merged");

    let a = front(&hex, "0/2", "3", &at("a"));
    let settings = front(&hex, "1/2", "2", &at("b"));
    refused(&[&a, &settings], &out, "settings differ");

    let other_scene = front(
        &common::problem_arg("small-offset.toml"),
        "1/2",
        "3",
        &at("c"),
    );
    refused(&[&a, &other_scene], &out, "scenes differ");

    // The same name with other values is another scene.
    let text = std::fs::read_to_string(&hex).unwrap();
    let changed = text.replace("mean_tension_n = 70.0", "mean_tension_n = 71.0");
    assert_ne!(text, changed);
    std::fs::create_dir_all(at("edited")).unwrap();
    let edited_scene = at("edited").join("small-hex.toml");
    std::fs::write(&edited_scene, changed).unwrap();
    let edited = front(edited_scene.to_str().unwrap(), "1/2", "3", &at("d"));
    refused(&[&a, &edited], &out, "both named `small-hex`");

    let counts = front(&hex, "1/3", "3", &at("e"));
    refused(&[&a, &counts], &out, "shard counts differ");

    refused(&[&a], &out, "shards [1] of 2 are missing");
    let copy = at("f").join("front.shard-0-of-2.csv");
    std::fs::create_dir_all(at("f")).unwrap();
    std::fs::copy(&a, &copy).unwrap();
    refused(&[&a, &copy], &out, "given twice");

    let not_a_shard = at("plain.csv");
    std::fs::write(&not_a_shard, "solver,knob\n").unwrap();
    refused(&[&not_a_shard], &out, "not a ringmesh shard");

    // A truncated row is its own shard's fault (it blamed the first shard),
    // and a path that does not exist is bad input (it exited 1).
    let b = front(&hex, "1/2", "3", &at("b2"));
    std::fs::create_dir_all(at("g")).unwrap();
    let broken = at("g").join("front.shard-1-of-2.csv");
    let text = std::fs::read_to_string(&b).unwrap();
    let (kept, _) = text.trim_end().rsplit_once(',').unwrap();
    std::fs::write(&broken, format!("{kept}\n")).unwrap();
    refused(&[&a, &broken], &out, &broken.display().to_string());
    refused(&[&a, &at("missing.csv")], &out, "no such file or folder");

    // The matching pair merges.
    succeed(&[
        "merge",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(out.join("front.csv").exists());
}

#[test]
fn bad_shard_specifications_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    for (spec, needle) in [
        ("3/3", "numbered from 0 to 2"),
        ("0/0", "at least 1"),
        ("1", "expected I/N"),
    ] {
        let run = common::ringmesh(&[
            "front",
            &common::problem_arg("small-hex.toml"),
            "--shard",
            spec,
            "-o",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(2), "{spec}: {stderr}");
        assert!(stderr.contains(needle), "{spec}: {stderr}");
        assert!(!out.exists());
    }
}
