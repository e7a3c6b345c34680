//! The command line: outputs of `mesh` and `fdm`, and clean failure (message,
//! exit code 2, no output file) on bad input.

mod common;

use std::path::{Path, PathBuf};

use serde_json::Value;

fn path(dir: &tempfile::TempDir, name: &str) -> PathBuf {
    dir.path().join(name)
}

#[test]
fn mesh_writes_network_and_vtu_and_fdm_solves_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "hex");
    let run = common::ringmesh(&[
        "mesh",
        &common::problem_arg("small-hex.toml"),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(stdout.contains("74 (62 free, 12 fixed)"), "{stdout}");
    assert!(
        stdout.contains("tie 31") && stdout.contains("shortest cable"),
        "{stdout}"
    );
    let vtu = std::fs::read_to_string(out.join("mesh.vtu")).unwrap();
    assert!(vtu.contains("NumberOfPoints=\"74\" NumberOfCells=\"211\""));

    let network = out.join("network.json");
    let json: Value = serde_json::from_str(&std::fs::read_to_string(&network).unwrap()).unwrap();
    assert_eq!(json["nodes"].as_array().unwrap().len(), 74);
    assert_eq!(json["groups"].as_array().unwrap().len(), 211);

    let result = path(&dir, "eq.json");
    let run = common::ringmesh(&[
        "fdm",
        network.to_str().unwrap(),
        "-o",
        result.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let eq: Value = serde_json::from_str(&std::fs::read_to_string(&result).unwrap()).unwrap();
    for (key, len) in [
        ("nodes", 74),
        ("lengths", 211),
        ("forces", 211),
        ("reactions", 12),
    ] {
        assert_eq!(eq[key].as_array().unwrap().len(), len, "{key}");
    }
    let max_force = eq["forces"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .fold(0.0, f64::max);
    assert!(eq["max_residual"].as_f64().unwrap() <= 1e-9 * max_force);
}

fn assert_rejected(args: &[&str], output: &Path, needle: &str) {
    let run = common::ringmesh(args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{args:?}: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected {needle:?} in {stderr}"
    );
    assert!(!output.exists(), "{args:?} left {}", output.display());
}

#[test]
fn bad_scene_fails_with_exit_2_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let scene = path(&dir, "bad.toml");
    let text = std::fs::read_to_string(common::problem_arg("small-hex.toml")).unwrap();
    std::fs::write(
        &scene,
        text.replace(
            "tube_inner_diameter_m = 0.056",
            "tube_inner_diameter_m = 0.07",
        ),
    )
    .unwrap();
    let out = path(&dir, "out");
    let args = ["mesh", scene.to_str().unwrap(), "-o", out.to_str().unwrap()];
    assert_rejected(&args, &out, "truss.tube_inner_diameter_m");
}

#[test]
fn bad_networks_fail_with_exit_2_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let good = r#"{"nodes": [[0,0,0],[1,0,0],[0,1,0],[0.3,0.3,0.2]],
                   "edges": [[3,0],[3,1],[3,2]], "fixed": [0,1,2], "q": [1,2,3]}"#;
    let cases = [
        (good.replace("[3,2]]", "[3,9]]"), "edges[2]"),
        (good.replace("\"q\": [1,2,3]", "\"q\": [1,0,3]"), "q[1]"),
        (good.replace("\"q\": [1,2,3]", "\"q\": [1,-2,3]"), "q[1]"),
        (
            good.replace("\"fixed\": [0,1,2]", "\"fixed\": [0,1,2,7]"),
            "fixed[3]",
        ),
        (
            good.replace("[0.3,0.3,0.2]]", "[0.3,0.3,0.2],[5,5,5]]"),
            "not connected",
        ),
        (
            good.replace("[1,0,0]", "[1,0,1e999]"),
            "number out of range",
        ),
        (
            good.replace("\"q\": [1,2,3]", "\"q\": [1,2]"),
            "`q` has 2 entries",
        ),
        (good.replace("[[3,0]", "[[3,3]"), "edges[0]"),
        (good.replace("\"q\"", "\"qq\""), "qq"),
    ];
    let out = path(&dir, "eq.json");
    let input = path(&dir, "good.json");
    std::fs::write(&input, good).unwrap();
    let run = common::ringmesh(&["fdm", input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    std::fs::remove_file(&out).unwrap();
    for (k, (text, needle)) in cases.iter().enumerate() {
        let input = path(&dir, &format!("bad{k}.json"));
        std::fs::write(&input, text).unwrap();
        assert_rejected(
            &["fdm", input.to_str().unwrap(), "-o", out.to_str().unwrap()],
            &out,
            needle,
        );
    }
}

/// The gradient solver on a network file, without and with a bound `[q]`: a
/// finite design within 5 % of the LP optimum of the prescribed geometry (its
/// geometry is free, so it may also land a little below), every `q` positive
/// and within the bound.
#[test]
fn uniformity_gradient_on_a_network_file_respects_the_bound() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "g.json");
    for bound in [None, Some("1000")] {
        let mut args = vec![
            "uniformity",
            "REF",
            "--solver",
            "gradient",
            "--groups",
            "front,boundary",
            "-o",
            out.to_str().unwrap(),
        ];
        let reference = common::reference_path().display().to_string();
        args[1] = &reference;
        if let Some(b) = bound {
            args.extend(["--max-force-density", b]);
        }
        let run = common::ringmesh(&args);
        assert!(
            run.status.success(),
            "{bound:?}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let json: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let ratio = json["ratio"].as_f64().unwrap();
        assert!((ratio / 20.4503 - 1.0).abs() <= 0.05, "{bound:?}: {ratio}");
        let limit: f64 = bound.map_or(f64::INFINITY, |b| b.parse().unwrap());
        for q in json["q"].as_array().unwrap() {
            let q = q.as_f64().unwrap();
            assert!(q > 0.0 && q <= limit, "{bound:?}: q = {q}");
        }
        std::fs::remove_file(&out).unwrap();
    }
    assert_rejected(
        &[
            "uniformity",
            &common::reference_path().display().to_string(),
            "--max-force-density=-1",
            "-o",
            out.to_str().unwrap(),
        ],
        &out,
        "maximum force density",
    );
}

/// A free node on the straight chord between two fixed nodes: its third cable
/// can only be slack. No solver has a design; the error names the node.
#[test]
fn uniformity_on_an_infeasible_geometry_names_the_slack_node_and_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let input = path(&dir, "chord.json");
    std::fs::write(
        &input,
        r#"{"nodes": [[0,0,0],[2,0,0],[1,1,0],[1,0,0]],
            "edges": [[3,0],[3,1],[3,2]], "fixed": [0,1,2], "q": [1,1,1]}"#,
    )
    .unwrap();
    let out = path(&dir, "q.json");
    for solver in ["lp", "bisection"] {
        let args = [
            "uniformity",
            input.to_str().unwrap(),
            "--solver",
            solver,
            "-o",
            out.to_str().unwrap(),
        ];
        assert_rejected(&args, &out, "cables at nodes 3 can only be slack");
    }
}

#[test]
fn uniformity_on_the_reference_network_reproduces_its_optimum() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "u.json");
    for solver in ["lp", "bisection"] {
        let run = common::ringmesh(&[
            "uniformity",
            &common::reference_path().display().to_string(),
            "--solver",
            solver,
            "--groups",
            "front,boundary",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        let json: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let ratio = json["ratio"].as_f64().unwrap();
        assert!((ratio - 20.4503).abs() <= 5e-4, "{solver}: {ratio}");
        let forces: Vec<f64> = json["tensions"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        let max_force = forces.iter().copied().fold(0.0, f64::max);
        assert!(json["max_residual"].as_f64().unwrap() <= 1e-8 * max_force);
        assert_eq!(json["q"].as_array().unwrap().len(), 325);
        for key in ["solver", "termination", "iterations", "time_s"] {
            assert!(!json[key].is_null(), "{key}");
        }
        std::fs::remove_file(&out).unwrap();
    }
    assert_rejected(
        &[
            "uniformity",
            &common::reference_path().display().to_string(),
            "--groups",
            "front,cable",
            "-o",
            out.to_str().unwrap(),
        ],
        &out,
        "`cable`",
    );
}

#[test]
fn optimize_writes_design_and_cut_lengths() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "opt");
    let run = common::ringmesh(&[
        "optimize",
        &common::problem_arg("small-hex.toml"),
        "--solver",
        "lp",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    // The printout names the status as design.json does, not as Rust does.
    let printed = String::from_utf8_lossy(&run.stdout);
    assert!(printed.contains("termination: converged"), "{printed}");
    let design: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("design.json")).unwrap()).unwrap();
    assert_eq!(design["scene"], "small-hex");
    assert_eq!(design["termination"], "converged");
    let csv = std::fs::read_to_string(out.join("cables.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("id,group,i,j,q,tension_n,length_m,cut_length_m")
    );
    // Cut length L0 = ℓ/(1 + T/EA), EA = 50 GPa · π (5 mm)²/4.
    let ea = 50e9 * std::f64::consts::PI * 0.005f64.powi(2) / 4.0;
    let mut rows = 0;
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        // Plain decimals, as a spreadsheet or a cutting sheet wants them.
        assert!(f[4..].iter().all(|v| !v.contains(['e', 'E'])), "{line}");
        let (q, t, l, l0): (f64, f64, f64, f64) = (
            f[4].parse().unwrap(),
            f[5].parse().unwrap(),
            f[6].parse().unwrap(),
            f[7].parse().unwrap(),
        );
        assert!((t - q * l).abs() <= 1e-9 * t);
        assert!((l0 - l / (1.0 + t / ea)).abs() <= 1e-12 * l);
        assert!(l0 < l);
        rows += 1;
    }
    assert_eq!(rows, 211);
}

#[test]
fn front_rms_total_draws_against_the_total_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "front");
    let args = |rms: &str| {
        common::ringmesh(&[
            "front",
            &common::problem_arg("small-hex.toml"),
            "--solvers",
            "lp",
            "--rms",
            rms,
            "-o",
            out.to_str().unwrap(),
        ])
    };
    let run = args("total");
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(stdout.contains("drawn against total RMS"), "{stdout}");
    let csv = std::fs::read_to_string(out.join("front.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("solver,knob,ratio,rms_mm,time_s"));
    let svg = std::fs::read_to_string(out.join("front.svg")).unwrap();
    assert!(svg.contains("total surface RMS"));
    let bad = args("facets");
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("design, total"));
}

#[test]
fn front_writes_csv_and_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "front");
    let run = common::ringmesh(&[
        "front",
        &common::problem_arg("small-hex.toml"),
        "--solvers",
        "bisection",
        "--points",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(out.join("front.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("solver,knob,ratio,rms_mm,time_s"));
    assert_eq!(csv.lines().count(), 4);
    let png = std::fs::read(out.join("front.png")).unwrap();
    assert_eq!(&png[..4], b"\x89PNG");
    let svg = std::fs::read_to_string(out.join("front.svg")).unwrap();
    assert!(svg.contains("<svg") && svg.contains("bisection"));
    assert!(!svg.contains("total surface RMS"));
    // The strategies' cost: the same points, wall time against RMS (a
    // logarithmic axis: every point's time positive).
    let time = std::fs::read_to_string(out.join("front-time.svg")).unwrap();
    assert!(time.contains("bisection") && time.contains("wall time of the design (s)"));
    let times: Vec<f64> = csv
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
        .collect();
    assert!(times.iter().all(|&t| t > 0.0), "times {times:?}");
    assert_eq!(
        &std::fs::read(out.join("front-time.png")).unwrap()[..4],
        b"\x89PNG"
    );
    let leftovers: Vec<_> = std::fs::read_dir(&out)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with('.')
        })
        .collect();
    assert!(leftovers.is_empty(), "temporary files left: {leftovers:?}");
}

/// The README's main command (run with the built binary) in a fresh clone of
/// the repository leaves `git status` clean: its outputs go where git
/// ignores them.
#[test]
fn the_readme_main_command_leaves_a_clean_checkout() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let command = readme
        .lines()
        .map(str::trim)
        .find_map(|l| l.strip_prefix("cargo run --release -- design "))
        .expect("README names the main command");
    let args: Vec<&str> = std::iter::once("design")
        .chain(command.split_whitespace())
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let Some(clone) = fresh_clone(dir.path()) else {
        return;
    };
    let out = common::ringmesh_in(&args, &clone);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let status = git(&["status", "--porcelain"], &clone);
    assert!(status.status.success());
    assert_eq!(
        String::from_utf8_lossy(&status.stdout),
        "",
        "git status after {args:?}"
    );
}

#[test]
fn cantilever_writes_its_table_where_asked() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "cantilever");
    let run = common::ringmesh(&["cantilever", "--json", "-o", out.to_str().unwrap()]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let printed: Value = serde_json::from_slice(&run.stdout).unwrap();
    let written: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("cantilever.json")).unwrap())
            .unwrap();
    assert_eq!(printed, written);
    assert_eq!(written["rows"].as_array().unwrap().len(), 7);
}

/// A pretension level near the top of double precision (issue 19): the
/// design's numbers stay finite — the residual was written as `null` and
/// printed `inf`, with termination "converged".
#[test]
fn uniformity_at_a_huge_level_writes_finite_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "hex");
    let mesh = common::ringmesh(&[
        "mesh",
        &common::problem_arg("small-hex.toml"),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(mesh.status.success());
    let json = path(&dir, "u.json");
    let run = common::ringmesh(&[
        "uniformity",
        out.join("network.json").to_str().unwrap(),
        "--groups",
        "front",
        "--mean-tension",
        "1e300",
        "-o",
        json.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let design: Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let residual = design["max_residual"].as_f64().expect("a number, not null");
    let largest = design["tensions"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(Value::as_f64)
        .fold(0.0, f64::max);
    assert!(largest > 1e299 && largest.is_finite(), "{largest:e}");
    assert!(residual <= 1e-12 * largest, "{residual:e} of {largest:e}");
}

/// A design loop stopped by its iteration budget before its tolerance is not
/// a plain success (issue 40): exit 3, the reason on stderr, and its files
/// written, as `frame` does short of its full load.
#[test]
fn a_design_loop_stopped_before_its_tolerance_exits_3_with_its_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "short");
    let out_arg = out.to_str().unwrap();
    let run = common::ringmesh(&[
        "design",
        &common::problem_arg("small-hex.toml"),
        "--max-iterations",
        "1",
        "-o",
        out_arg,
    ]);
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("the design loop ended before its tolerance: max_iterations after 1"),
        "{stderr}"
    );
    let report: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("design.json")).unwrap()).unwrap();
    assert_eq!(report["termination"], "max_iterations");
    // Converged, the same scene exits 0.
    let full = common::ringmesh(&[
        "design",
        &common::problem_arg("small-hex.toml"),
        "-o",
        path(&dir, "full").to_str().unwrap(),
    ]);
    assert_eq!(full.status.code(), Some(0));
}

/// `optimize` holds both nets' mean tensions, as `design` does (issue 40
/// item 6: the rear net was at 138.5 N for small-hex's 140 N), whatever the
/// solver.
#[test]
fn optimize_holds_the_scene_mean_tensions_of_both_nets() {
    let dir = tempfile::tempdir().unwrap();
    let scene = common::scene("small-hex");
    for solver in ["lp", "least-squares"] {
        let out = path(&dir, solver);
        let run = common::ringmesh(&[
            "optimize",
            &common::problem_arg("small-hex.toml"),
            "--solver",
            solver,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(run.status.success(), "{solver}: {run:?}");
        let csv = std::fs::read_to_string(out.join("cables.csv")).unwrap();
        let mean = |group: &str| {
            let t: Vec<f64> = csv
                .lines()
                .skip(1)
                .filter(|l| l.split(',').nth(1) == Some(group))
                .map(|l| l.split(',').nth(5).unwrap().parse::<f64>().unwrap())
                .collect();
            t.iter().sum::<f64>() / t.len() as f64
        };
        for (group, target) in [
            ("front", scene.front_net.mean_tension_n),
            ("rear", scene.rear_net.mean_tension_n),
        ] {
            let m = mean(group);
            assert!(
                (m - target).abs() <= 1e-9 * target,
                "{solver}: {group} {m} N"
            );
        }
    }
}

/// A refusal after the output folder is locked leaves no empty folder the
/// run created (issue 40 item 12), and keeps a folder that was there.
#[test]
fn a_refused_run_leaves_no_folder_it_created() {
    let dir = tempfile::tempdir().unwrap();
    let fresh = path(&dir, "S");
    let refuse = |out: &Path| {
        common::ringmesh(&[
            "size",
            &common::problem_arg("small-hex.toml"),
            "--margin",
            "0",
            "-o",
            out.to_str().unwrap(),
        ])
    };
    let run = refuse(&fresh);
    assert_eq!(run.status.code(), Some(2), "{run:?}");
    assert!(!fresh.exists(), "an empty {} was left", fresh.display());
    let existing = path(&dir, "kept");
    std::fs::create_dir(&existing).unwrap();
    assert_eq!(refuse(&existing).status.code(), Some(2));
    assert!(existing.is_dir());
    let leftovers: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers, vec![std::ffi::OsString::from("kept")]);
}

/// An aperture given twice is refused, naming `apertures`, before any work
/// (issue 40 item 8: it was sized and designed twice).
#[test]
fn an_aperture_given_twice_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "ap");
    let run = common::ringmesh(&[
        "apertures",
        &common::problem_arg("small-hex.toml"),
        "--apertures",
        "6,6",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("`apertures`: 6 m is given twice"),
        "{stderr}"
    );
    assert!(!out.exists());
}

/// A study's rings too many for the machine are refused up front, naming
/// them, like the scene's own (issue 40 item 8: a failed row and exit 0).
#[test]
fn a_study_of_rings_beyond_memory_is_refused_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let out = path(&dir, "st");
    let run = common::ringmesh(&[
        "study",
        &common::problem_arg("small-hex.toml"),
        "--knobs",
        "rings",
        "--rings",
        "100000",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("front_net.rings = 100000"), "{stderr}");
    assert!(!out.exists());
}

/// A study refused for its `--jobs` names them beside the net (issue 40
/// item 9: the refusal blamed the net alone).
#[test]
fn a_study_refused_for_its_jobs_names_them() {
    let dir = tempfile::tempdir().unwrap();
    let run = common::ringmesh(&[
        "study",
        &common::problem_arg("small-hex.toml"),
        "--jobs",
        "1024",
        "--max-memory",
        "1G",
        "-o",
        path(&dir, "st").to_str().unwrap(),
    ]);
    let stderr = String::from_utf8(run.stderr).unwrap();
    assert_eq!(run.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("and --jobs 1024"), "{stderr}");
}

/// A fresh clone of the repository, in `dir/clone`, or `None` when the
/// sources are not a git checkout (a source tarball: nothing to keep clean).
fn fresh_clone(dir: &std::path::Path) -> Option<PathBuf> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let cloned = git(
        &[
            "clone",
            "--quiet",
            "--local",
            &root.display().to_string(),
            "clone",
        ],
        dir,
    );
    cloned.status.success().then(|| dir.join("clone"))
}

/// `git ARGS` in `cwd`.
fn git(args: &[&str], cwd: &std::path::Path) -> std::process::Output {
    std::process::Command::new("git")
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("git runs")
}

/// Every command that writes, run with no `-o` in a fresh clone (the small
/// scene, few points), writes under `runs/` — which git ignores — and leaves
/// `git status` clean: no command writes over the committed `results/`
/// unless `-o` names them (issue 37). `fdm` and `uniformity` take a required
/// `-o`; `cantilever` writes nothing without it.
#[test]
fn every_command_without_an_output_folder_leaves_a_clean_checkout() {
    let dir = tempfile::tempdir().unwrap();
    let Some(clone) = fresh_clone(dir.path()) else {
        return;
    };
    // A one-section catalogue, outside the clone: one sizing design.
    let catalogue = dir.path().join("one-tube.csv");
    std::fs::write(
        &catalogue,
        "outer_diameter_m,inner_diameter_m\n0.05,0.046\n",
    )
    .unwrap();
    let scene = "problems/small-hex.toml";
    let runs: &[&[&str]] = &[
        &["init"],
        &["mesh", scene],
        &["optimize", scene],
        &["design", scene],
        &["truss", scene],
        &["size", scene, "--sections", catalogue.to_str().unwrap()],
        &["apertures", scene, "--apertures", "4"],
        &["front", scene, "--solvers", "bisection", "--points", "2"],
        &[
            "front",
            scene,
            "--solvers",
            "bisection",
            "--points",
            "2",
            "--shard",
            "0/1",
        ],
        &["merge", "runs/small-hex"],
        &[
            "study",
            scene,
            "--knobs",
            "tolerance",
            "--tolerances",
            "1e-3",
        ],
        &["frame", "problems/frames/cantilever-moment.toml"],
        &["cantilever", "--elements", "2"],
    ];
    for args in runs {
        let out = common::ringmesh_in(args, &clone);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let status = git(&["status", "--porcelain", "--untracked-files=all"], &clone);
        assert!(status.status.success());
        assert_eq!(
            String::from_utf8_lossy(&status.stdout),
            "",
            "git status after {args:?}"
        );
    }
    for written in [
        "runs/small-hex/design.json",
        "runs/small-hex/sizing.csv",
        "runs/small-hex/apertures/apertures.csv",
        "runs/small-hex/front.csv",
        "runs/small-hex/accuracy-vs-time.csv",
        "runs/cantilever-moment/frame.json",
    ] {
        assert!(clone.join(written).is_file(), "{written} not written");
    }
}

/// `ringmesh init PATH` writes a commented scene named after the file that
/// designs as it is; a second `init` on the same path is refused (exit 2)
/// and leaves the file as it was.
#[test]
fn init_writes_a_commented_scene_that_designs_and_never_overwrites() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("new-dish.toml");
    let run = common::ringmesh(&["init", scene.to_str().unwrap()]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("name = \"new-dish\""), "{text}");
    assert!(text.contains("# elements_per_rod = 4"), "{text}");

    std::fs::write(&scene, format!("# mine\n{text}")).unwrap();
    let again = common::ringmesh(&["init", scene.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&again.stderr).contains("exists"),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    assert!(std::fs::read_to_string(&scene)
        .unwrap()
        .starts_with("# mine\n"));

    let out = dir.path().join("out");
    let design = common::ringmesh(&[
        "design",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        design.status.success(),
        "{}",
        String::from_utf8_lossy(&design.stderr)
    );
    assert!(out.join("design.json").is_file());
    // Off a terminal, one line per stage after the loop as it begins; the
    // iterations name Tmax/Tmin and write their numbers plainly from 1e-3.
    let stderr = String::from_utf8_lossy(&design.stderr);
    let iterations: Vec<&str> = stderr
        .lines()
        .filter(|l| l.contains("boundary change"))
        .collect();
    assert!(!iterations.is_empty(), "{stderr}");
    for line in iterations {
        assert!(
            line.contains(" Tmax/Tmin 1.") && !line.contains(" ratio "),
            "{line}"
        );
        let elapsed = line.split_whitespace().rev().nth(1).unwrap();
        assert!(!elapsed.contains('e'), "{line}");
    }
    let stages: Vec<&str> = stderr.lines().filter(|l| l.starts_with("stage ")).collect();
    assert_eq!(stages.len(), 4, "{stderr}");
    assert!(
        stages[0].starts_with("stage 1/4 at ")
            && stages[0].ends_with("limit margin: the truss's limit load under the design's pull"),
        "{stderr}"
    );
}
