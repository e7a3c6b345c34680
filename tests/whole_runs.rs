//! Whole runs (issue 19): a command's files appear together or not at all.
//! `ringmesh design` killed at any moment of its write phase, interrupted,
//! run twice at once, or out of disk space leaves its folder holding exactly
//! the previous complete set or the new complete set — never a mix, never a
//! temporary file — and says why when it did not write.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use ringmesh::report::{check_manifest, RunRecord};

/// The files of one `design` run.
const SET: [&str; 7] = [
    "cables.csv",
    "convergence.csv",
    "convergence.png",
    "convergence.svg",
    "design.json",
    "model.vtu",
    "surface-error.png",
];

/// The names in a folder.
fn names(dir: &Path) -> Vec<String> {
    common::snapshot(dir).into_iter().map(|(n, _)| n).collect()
}

/// `design` of small-hex into `out`, not waited for.
fn spawn_design(scene: &Path, out: &Path) -> Child {
    Command::new(env!("CARGO_BIN_EXE_ringmesh"))
        .args([
            "design",
            scene.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// A scratch folder with small-hex's scene; `(root, scene, out)`.
fn scratch() -> (tempfile::TempDir, PathBuf, PathBuf) {
    let root = tempfile::tempdir().unwrap();
    let scene = root.path().join("small-hex.toml");
    std::fs::copy(common::problem("small-hex.toml"), &scene).unwrap();
    let out = root.path().join("results").join("small-hex");
    (root, scene, out)
}

/// Asserts that `dir` holds one run's complete set: the seven files, no
/// other entry, every file the one `design.json` records, the SVG and VTU
/// stamped with its run. Returns the run's identifier.
#[track_caller]
fn complete_set(dir: &Path) -> String {
    assert_eq!(names(dir), SET, "not exactly one design's files");
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("design.json")).unwrap()).unwrap();
    let record: RunRecord = serde_json::from_value(json["run"].clone()).unwrap();
    assert_eq!(record.files.len(), SET.len() - 1);
    check_manifest(dir, &record).unwrap();
    for stamped in ["convergence.svg", "model.vtu"] {
        let text = std::fs::read_to_string(dir.join(stamped)).unwrap();
        assert!(
            text.contains(&record.id),
            "{stamped} is not run {}",
            record.id
        );
    }
    record.id
}

/// Staging folders beside `out` (left by a killed run).
fn staging_beside(out: &Path) -> Vec<String> {
    names(out.parent().unwrap())
        .into_iter()
        .filter(|n| n.contains(".staging-"))
        .collect()
}

/// SIGKILL at 24 moments spread over the write phase of a `design` run —
/// before its first file, after each of its files appears in the staging
/// folder, as the set is swapped in, and after — never leaves a mix: the
/// folder holds the previous complete set byte for byte or the new one, and
/// no temporary file. The next run removes what the killed one left beside.
#[test]
fn a_run_killed_while_writing_leaves_the_previous_set_or_the_new_one() {
    let (_root, scene, out) = scratch();
    let first = spawn_design(&scene, &out).wait_with_output().unwrap();
    assert!(first.status.success(), "{first:?}");
    let mut previous = common::snapshot(&out);
    complete_set(&out);
    let (mut kept, mut replaced) = (0, 0);
    for trial in 0..24 {
        // Kill once the staging folder holds `files_seen` entries, then
        // after a further 0–2 ms (within a file's write), or, in the last
        // third, 4–36 ms (the set's stamps, the manifest, the swap, after).
        let files_seen = trial % 8;
        let extra = match trial / 8 {
            2 => Duration::from_millis(4 << (trial % 4)),
            round => Duration::from_micros(500 * (round as u64 + trial as u64 % 3)),
        };
        let mut child = spawn_design(&scene, &out);
        let clock = Instant::now();
        let parent = out.parent().unwrap().to_path_buf();
        let fired = loop {
            if child.try_wait().unwrap().is_some() {
                break false;
            }
            let staged = std::fs::read_dir(&parent)
                .unwrap()
                .flatten()
                .filter(|e| e.file_name().to_string_lossy().contains(".staging-"))
                .map(|e| std::fs::read_dir(e.path()).map_or(0, |d| d.count()))
                .max();
            if staged.is_some_and(|n| n >= files_seen) {
                std::thread::sleep(extra);
                break true;
            }
            assert!(
                clock.elapsed() < Duration::from_secs(60),
                "trial {trial} hung"
            );
        };
        let _ = child.kill();
        let status = child.wait().unwrap();
        let now = common::snapshot(&out);
        if now == previous {
            kept += 1;
        } else {
            complete_set(&out);
            replaced += 1;
            previous = now;
        }
        assert!(
            names(&out).iter().all(|n| !n.starts_with('.')),
            "trial {trial}: temporary file in the folder"
        );
        eprintln!("trial {trial}: kill after {files_seen} staged files (fired {fired}), {status}");
    }
    eprintln!("{kept} kills kept the previous set, {replaced} found the new one");
    assert!(kept >= 8, "the kills missed the write phase: {kept} kept");
    // What the killed runs left beside the folder goes with the next run.
    let last = spawn_design(&scene, &out).wait_with_output().unwrap();
    assert!(last.status.success(), "{last:?}");
    complete_set(&out);
    assert!(
        staging_beside(&out).is_empty(),
        "{:?}",
        staging_beside(&out)
    );
}

/// SIGTERM while writing: the run removes its staging folder and exits;
/// the folder holds one complete set.
#[test]
fn an_interrupted_run_removes_its_staging_folder() {
    let (_root, scene, out) = scratch();
    let first = spawn_design(&scene, &out).wait_with_output().unwrap();
    assert!(first.status.success(), "{first:?}");
    for files_seen in [1, 4] {
        let mut child = spawn_design(&scene, &out);
        loop {
            let staged = staging_beside(&out)
                .iter()
                .map(|n| std::fs::read_dir(out.parent().unwrap().join(n)).map_or(0, |d| d.count()))
                .max();
            if staged.is_some_and(|n| n >= files_seen) || child.try_wait().unwrap().is_some() {
                break;
            }
        }
        let term = Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .unwrap();
        assert!(term.success());
        let status = child.wait().unwrap();
        complete_set(&out);
        assert!(staging_beside(&out).is_empty(), "{status}");
    }
}

/// Two runs into one folder at once: one writes its complete set, the other
/// is refused before computing (exit 2) and says why — into a folder that
/// exists, and into one that neither finds (both create it: the refused one
/// once removed it, empty, from under the other, whose set was then lost).
#[test]
fn of_two_runs_into_one_folder_one_writes_and_the_other_says_why_not() {
    let (_root, scene, existing) = scratch();
    for k in 0..8 {
        let out = match k % 2 {
            0 => existing.clone(),
            _ => existing.with_file_name(format!("fresh-{k}")),
        };
        let a = spawn_design(&scene, &out);
        let b = spawn_design(&scene, &out);
        let outputs: Vec<Output> = [a, b]
            .into_iter()
            .map(|c| c.wait_with_output().unwrap())
            .collect();
        let ok: Vec<&Output> = outputs.iter().filter(|o| o.status.success()).collect();
        let refused: Vec<&Output> = outputs.iter().filter(|o| !o.status.success()).collect();
        let id = complete_set(&out);
        if refused.is_empty() {
            // The first finished before the second began: both wrote.
            continue;
        }
        assert_eq!(ok.len(), 1, "{outputs:?}");
        let why = String::from_utf8_lossy(&refused[0].stderr);
        assert_eq!(refused[0].status.code(), Some(2), "{why}");
        assert!(
            why.contains("another ringmesh run is writing into"),
            "{why}"
        );
        eprintln!("run {id} wrote; the other: {}", why.trim());
    }
    assert!(staging_beside(&existing).is_empty());
}

/// Out of space while writing (a 32 KiB file size limit, `ulimit -f 64` in
/// 512-byte blocks: the first plot is ~46 KiB): the run fails naming the
/// file in the folder it was meant for, the folder keeps the
/// previous set, and nothing is left beside it.
#[test]
fn a_run_out_of_space_fails_and_keeps_the_previous_set() {
    let (_root, scene, out) = scratch();
    let first = spawn_design(&scene, &out).wait_with_output().unwrap();
    assert!(first.status.success(), "{first:?}");
    let before = common::snapshot(&out);
    // SIGXFSZ ignored, so that the write fails with EFBIG instead of the
    // signal killing the process.
    let full = Command::new("sh")
        .args([
            "-c",
            "trap '' XFSZ; ulimit -f 64; exec \"$0\" design \"$1\" -o \"$2\"",
            env!("CARGO_BIN_EXE_ringmesh"),
            scene.to_str().unwrap(),
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let why = String::from_utf8_lossy(&full.stderr);
    assert_eq!(full.status.code(), Some(1), "{why}");
    let named = format!("writing {}", out.join("convergence.png").display());
    assert!(
        why.contains(&named) && why.contains("File too large"),
        "{why}"
    );
    assert!(common::snapshot(&out) == before, "the folder changed");
    assert!(staging_beside(&out).is_empty());
}

/// An output folder that cannot be written is refused before any computing
/// (exit 2, naming it), and a scene name too long for a folder as well.
#[test]
fn an_unwritable_folder_is_refused_before_computing() {
    let (root, scene, _) = scratch();
    let blocker = root.path().join("a-file");
    std::fs::write(&blocker, "not a folder").unwrap();
    let out = blocker.join("results");
    let clock = Instant::now();
    let o = common::ringmesh(&[
        "design",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    let why = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{why}");
    assert!(why.contains("cannot write into the output folder"), "{why}");
    assert!(clock.elapsed() < Duration::from_secs(2), "computed first?");

    let long = root.path().join("long.toml");
    let text = std::fs::read_to_string(&scene).unwrap().replace(
        "name = \"small-hex\"",
        &format!("name = \"{}\"", "x".repeat(300)),
    );
    std::fs::write(&long, text).unwrap();
    let o = common::ringmesh_in(&["design", long.to_str().unwrap()], root.path());
    let why = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{why}");
    assert!(why.contains("name") && why.contains("at most 128"), "{why}");
}

/// A workload beyond the memory limit is refused before anything is computed
/// or written (exit 2), naming the input that sets its size and the estimate
/// (`rings = 815` took 3.5 GB in `mesh` and aborted `optimize`; `front
/// --points 1e9` aborted allocating 8 GB); an input file larger than any
/// input can be is refused without reading it all (`mesh /dev/zero` read 4 GB).
#[test]
fn a_run_beyond_the_memory_limit_is_refused_before_computing() {
    let (_root, scene, out) = scratch();
    let refused = |args: &[&str], needles: &[&str]| {
        let o = common::ringmesh(args);
        let why = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {why}");
        for needle in needles {
            assert!(why.contains(needle), "{args:?}: {why}");
        }
        assert!(!out.exists(), "{args:?} wrote");
    };
    let scene = scene.to_str().unwrap();
    let out_arg = out.to_str().unwrap();
    refused(
        &["design", scene, "-o", out_arg, "--max-memory", "50M"],
        &["front_net.rings = 3", "allowed by --max-memory"],
    );
    refused(
        &["front", scene, "--points", "1000000000", "-o", out_arg],
        &["--points 1000000000", "GB"],
    );
    refused(
        &["mesh", "/dev/zero", "-o", out_arg],
        &["/dev/zero", "larger than 256 MiB"],
    );
    refused(
        &["design", scene, "-o", out_arg, "--max-memory", "lots"],
        &["--max-memory"],
    );
    // A size with an exponent is a size (issue 40 item 9: `1.5e3M` read as
    // an unknown unit): 1.5e-3M is 1.5 kB, far below the design's estimate.
    refused(
        &["design", scene, "-o", out_arg, "--max-memory", "1.5e-3M"],
        &["allowed by --max-memory"],
    );
}

/// The cantilever benchmark with `from` replaced by `to`, run by `frame`
/// in a scratch folder: its exit code, its message, and its output path.
fn cantilever_with(from: &str, to: &str) -> (Option<i32>, String, PathBuf, tempfile::TempDir) {
    let root = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(common::problem("frames/cantilever-moment.toml")).unwrap();
    assert!(text.contains(from), "no {from}");
    let path = root.path().join("frame.toml");
    std::fs::write(&path, text.replace(from, to)).unwrap();
    let out = root.path().join("frame.json");
    let o = common::ringmesh(&["frame", path.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let why = String::from_utf8_lossy(&o.stderr).into_owned();
    (o.status.code(), why, out, root)
}

/// A result that is not finite is an error (exit 1) naming where, never a
/// success: a 1e200 moment on the cantilever gave "converged at the full
/// load" with infinite positions; a section beyond any is refused (exit 2),
/// and so are loads below the force floor of the stiffness.
#[test]
fn a_frame_whose_solution_overflows_is_an_error() {
    let moment = "moment_nm = [0.0, 0.0, 62.83185307179586]";
    let cases = [
        (moment, "moment_nm = [0.0, 0.0, 1e200]", 1, "not finite"),
        // EA = 1e300: its roundoff ε·EA exceeds any load; it 'converged'
        // undeformed.
        ("axial_n = 1e4", "axial_n = 1e300", 2, "rods[0].axial_n"),
        // Within the bound, EA = 1e16 N against EI = 100 N·m²: the force
        // floor of its stiffness (1.4e3 N) exceeds the 62.8 N·m load, and the
        // solve 'converged' undeformed in 0 iterations.
        (
            "axial_n = 1e4",
            "axial_n = 1e16",
            2,
            "resolve forces only to about",
        ),
    ];
    for (from, to, code, needle) in cases {
        let (status, why, out, _root) = cantilever_with(from, to);
        assert_eq!(status, Some(code), "{to}: {why}");
        assert!(why.contains(needle), "{to}: {why}");
        assert!(!out.exists(), "{to} wrote");
    }
}

/// A frame run that ends before the full load writes what it found and
/// exits 3 with the reason (it exited 0): here a section whose stiffness
/// stalls Newton at a load factor of 0.002.
#[test]
fn a_frame_run_that_ends_early_writes_its_state_and_exits_3() {
    let (status, why, out, _root) = cantilever_with("axial_n = 1e4", "axial_n = 1e12");
    assert_eq!(status, Some(3), "{why}");
    assert!(why.contains("ended before the full load"), "{why}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert!(json["load_factor"].as_f64().unwrap() < 1.0);
    assert_ne!(json["termination"], "converged");
    // The path it followed is written too: the start and every step.
    let points = json["path"]["points"].as_array().unwrap();
    assert_eq!(
        points.len() as u64,
        json["load_steps"].as_u64().unwrap() + 1
    );
    let csv = std::fs::read_to_string(out.with_file_name("frame-path.csv")).unwrap();
    assert_eq!(
        csv.lines().filter(|l| l.starts_with("step,")).count(),
        points.len()
    );
    assert!(out.with_file_name("frame-path.png").exists());
}
