//! Output safety (issue 7): every result file is written to a temporary file
//! and renamed, so a run killed mid-way leaves the previous results intact
//! and readable.

mod common;

use std::io::{BufRead, BufReader};
use std::path::PathBuf;
use std::process::{Command, Stdio};

/// `ringmesh design` on a copy of realistic-26m (≈ 3 s) writes its results;
/// a second run on the same folder, killed (SIGKILL) as soon as it reports
/// its first outer iteration, leaves every file byte for byte as the first
/// run wrote it — `design.json` parses, `cables.csv` has its header and a
/// row per cable — and no temporary file behind.
#[test]
fn a_design_run_killed_in_its_outer_loop_leaves_the_previous_results_intact() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("realistic-26m.toml");
    std::fs::copy(common::problem("realistic-26m.toml"), &scene).unwrap();
    let out: PathBuf = dir.path().join("results").join("realistic-26m");
    let args = [
        "design",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    let first = Command::new(env!("CARGO_BIN_EXE_ringmesh"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        first.status.success(),
        "{}",
        String::from_utf8_lossy(&first.stderr)
    );
    let before = common::snapshot(&out);
    let names: Vec<&str> = before.iter().map(|(n, _)| n.as_str()).collect();
    for expected in ["design.json", "cables.csv", "convergence.csv", "model.vtu"] {
        assert!(names.contains(&expected), "{names:?}");
    }

    let mut second = Command::new(env!("CARGO_BIN_EXE_ringmesh"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = BufReader::new(second.stderr.take().unwrap());
    let mut line = String::new();
    let mut seen = Vec::new();
    loop {
        line.clear();
        let read = stderr.read_line(&mut line).unwrap();
        assert!(read > 0, "the run ended before its outer loop: {seen:?}");
        seen.push(line.clone());
        if line.contains("boundary change") {
            break;
        }
    }
    second.kill().unwrap();
    let status = second.wait().unwrap();
    assert!(!status.success(), "the run finished before it was killed");

    let after = common::snapshot(&out);
    assert_eq!(
        after.iter().map(|(n, _)| n).collect::<Vec<_>>(),
        before.iter().map(|(n, _)| n).collect::<Vec<_>>(),
        "files appeared or vanished (temporary files left?)"
    );
    for ((name, a), (_, b)) in after.iter().zip(&before) {
        assert!(a == b, "{name} changed");
    }
    let design: serde_json::Value =
        serde_json::from_slice(&after.iter().find(|(n, _)| n == "design.json").unwrap().1).unwrap();
    assert_eq!(design["scene"], "realistic-26m");
    let csv = String::from_utf8(
        after
            .iter()
            .find(|(n, _)| n == "cables.csv")
            .unwrap()
            .1
            .clone(),
    )
    .unwrap();
    assert!(csv.starts_with("id,group,i,j,q,tension_n,length_m,cut_length_m\n"));
    let cables = design["net"]["q"].as_array().unwrap().len();
    assert_eq!(csv.lines().count(), cables + 1);
    eprintln!(
        "killed after: {}; {} files intact",
        seen.last().unwrap().trim(),
        after.len()
    );
}

/// Every file the library writes goes through `report::write_atomic` (whose
/// temporary files `report/pending.rs` creates; the
/// plot backends draw in memory) or `report::OutputSet` (which links or copies the folder's other
/// files into its staging folder): no other place in `src/` creates or
/// writes a file.
#[test]
fn only_the_atomic_writers_touch_the_file_system() {
    let src = common::source_dir();
    let mut stack = vec![src.clone()];
    let mut offenders = Vec::new();
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let relative = path
                .strip_prefix(&src)
                .unwrap()
                .to_string_lossy()
                .replace('\\', "/");
            for (n, line) in text.lines().enumerate() {
                let writes = ["File::create", "fs::write", "OpenOptions", "fs::copy"]
                    .iter()
                    .any(|w| line.contains(w));
                let draws = ["BitMapBackend::new(", "SVGBackend::new("]
                    .iter()
                    .any(|w| line.contains(w))
                    && !line.contains("temporary");
                let writer =
                    ["report/pending.rs", "report/output_set.rs"].contains(&relative.as_str());
                if (writes && !writer) || draws {
                    offenders.push(format!("src/{relative}:{}: {}", n + 1, line.trim()));
                }
            }
        }
    }
    assert!(offenders.is_empty(), "non-atomic writes: {offenders:#?}");
}

/// Under a file-size limit (`ulimit -f`) the write that crosses it fails
/// like a full disk — exit 1 naming the file, nothing left behind — instead
/// of SIGXFSZ killing the run with its staging folder (issue 40 item 12).
#[cfg(unix)]
#[test]
fn a_file_size_limit_fails_like_a_full_disk() {
    let dir = tempfile::tempdir().unwrap();
    let run = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -f 1; exec {} design {} -o out",
            env!("CARGO_BIN_EXE_ringmesh"),
            common::problem_arg("small-hex.toml")
        ))
        .current_dir(dir.path())
        .output()
        .expect("bash runs");
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("error: writing") && stderr.contains("out/"),
        "{stderr}"
    );
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert!(left.is_empty(), "left behind: {left:?}");
}
