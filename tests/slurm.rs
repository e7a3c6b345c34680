//! The README's Slurm recipe, run for real: `scripts/slurm/local-check.sh`
//! brings up a one-node Slurm cluster (munge, slurmctld, slurmd; `.ci/run`
//! installs Debian's `slurm-wlm` and `munge`), submits a sharded sweep as a
//! job array through `scripts/slurm/submit.sh` with the merge as a dependent
//! job, and checks the merged table against the unsharded run. Where Slurm
//! cannot be started (not installed, not root) the script exits 77 and the
//! test says so instead of failing.

use std::path::Path;
use std::process::Command;
use std::sync::Mutex;

/// One throw-away cluster at a time.
static CLUSTER: Mutex<()> = Mutex::new(());

/// Runs the check on `args` (a sweep command and its arguments) in `shards`
/// array tasks; `None` when Slurm cannot be started here.
fn slurm_check(shards: usize, args: &[&str]) -> Option<String> {
    let _one = CLUSTER.lock().unwrap_or_else(|e| e.into_inner());
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = Command::new("bash")
        .arg(root.join("scripts/slurm/local-check.sh"))
        .arg(shards.to_string())
        .args(args)
        .current_dir(root)
        .env("RINGMESH", env!("CARGO_BIN_EXE_ringmesh"))
        .output()
        .expect("bash runs");
    let stdout = String::from_utf8_lossy(&run.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&run.stderr);
    if run.status.code() == Some(77) {
        eprintln!("Slurm cannot be started here, check skipped: {stderr}");
        return None;
    }
    assert!(
        run.status.success(),
        "local-check.sh {args:?} failed:\n{stdout}\n{stderr}"
    );
    Some(stdout)
}

#[test]
fn a_front_sharded_as_a_slurm_job_array_merges_to_the_unsharded_table() {
    let Some(out) = slurm_check(
        3,
        &[
            "front",
            "problems/small-hex.toml",
            "--solvers",
            "bisection,gradient",
            "--points",
            "4",
        ],
    ) else {
        return;
    };
    assert!(out.contains("COMPLETED"), "{out}");
    assert!(
        out.contains("front.csv: 8 rows equal to the unsharded run"),
        "{out}"
    );
}

#[test]
fn a_budget_monte_carlo_sharded_as_a_slurm_job_array_merges_to_the_unsharded_budget() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/small-hex.toml"),
    )
    .unwrap()
        + r#"
[surface]
frequency_ghz = 8.0

[tolerances]
cable_length_sigma_m = 5e-6
rod_length_sigma_m = 2e-5
hinge_position_sigma_m = 2e-5
seed = 3
"#;
    let scene = dir.path().join("small-hex-budget.toml");
    std::fs::write(&scene, text).unwrap();
    let Some(out) = slurm_check(3, &["budget", scene.to_str().unwrap(), "--samples", "8"]) else {
        return;
    };
    // budget.csv (the table) and budget-samples.csv (facets, design and the
    // 8 samples), value for value.
    assert!(out.contains("budget.csv: "), "{out}");
    assert!(
        out.contains("budget-samples.csv: 10 rows equal to the unsharded run"),
        "{out}"
    );
}
