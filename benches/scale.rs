//! The whole design at growing scale (issue 15): `ringmesh design` on
//! realistic-26m (≈ 10³ nodes), super-60m (≈ 3·10⁴) and super-100m (≈ 10⁵),
//! each run once in a process of its own, so that its peak resident memory
//! is its own. Prints one row per scene: nodes, the wall time of each stage
//! (`design.json`'s `timings`), the total and the peak RSS, then the growth
//! exponents of the total time and of the memory between successive sizes,
//! `log(t₂/t₁)/log(n₂/n₁)`.
//!
//! A whole design at 10⁵ nodes takes minutes, so this is not a criterion
//! bench (ten samples each): one run per size, on a quiet machine.
//!
//!     cargo bench --bench scale                       # all three
//!     cargo bench --bench scale -- realistic-26m super-60m
//!
//! Linux only (peak RSS from `/proc/self/status`).

use std::path::Path;
use std::process::Command;

use ringmesh::design::DesignSettings;
use ringmesh::geometry::build_mesh;
use ringmesh::scene::Scene;

const SCENES: [&str; 3] = ["realistic-26m", "super-60m", "super-100m"];

/// Peak resident set size of this process, bytes (`VmHWM`).
fn peak_rss_bytes() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| 1024.0 * kb)
}

/// One design of `name` in this process: prints a tab-separated line
/// `nodes total_s mesh uniformity truss loop_rest margin verification
/// conventional writing peak_rss_bytes`.
fn one(name: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{name}.toml"));
    let scene = Scene::read(&path).expect("shipped scene");
    let nodes = build_mesh(&scene).expect("mesh").network.n_nodes();
    let out = tempfile::tempdir().expect("a temporary folder");
    let outcome = ringmesh::run::design(
        &path,
        &DesignSettings::default(),
        Some(out.path()),
        &mut |_, _| {},
    )
    .expect("the shipped scenes design");
    let t = &outcome.report.timings;
    let uniformity: f64 = t.uniformity_s.iter().sum();
    let truss: f64 = t.truss_s.iter().sum();
    println!(
        "{nodes}\t{}\t{}\t{uniformity}\t{truss}\t{}\t{}\t{}\t{}\t{}\t{}\t{}",
        t.total_s,
        t.read_s + t.mesh_s,
        t.truss_setup_s + t.loop_other_s,
        t.margin_s,
        t.verification_s,
        t.conventional_s,
        t.writing_s,
        outcome.report.outer_iterations,
        peak_rss_bytes()
    );
}

fn main() {
    // As the command line does (`resources::retain_freed_memory`).
    ringmesh::resources::retain_freed_memory();
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(i) = args.iter().position(|a| a == "--one") {
        one(&args[i + 1]);
        return;
    }
    let chosen: Vec<&str> = SCENES
        .iter()
        .copied()
        .filter(|s| !args.iter().any(|a| !a.starts_with('-')) || args.iter().any(|a| a == s))
        .collect();
    println!(
        "| scene | nodes | outer iterations | mesh | uniformity | truss | loop rest | margin | \
         verification | conventional | writing | total | peak RSS |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let mut sizes: Vec<(f64, f64, f64)> = Vec::new();
    for name in chosen {
        let exe = std::env::current_exe().expect("this bench");
        let output = Command::new(exe)
            .args(["--one", name])
            .output()
            .expect("run one size");
        let text = String::from_utf8_lossy(&output.stdout);
        let Some(line) = text.lines().last() else {
            eprintln!("{name}: {}", String::from_utf8_lossy(&output.stderr));
            continue;
        };
        let v: Vec<f64> = line
            .split('\t')
            .map(|x| x.parse().unwrap_or(f64::NAN))
            .collect();
        if v.len() != 12 {
            eprintln!("{name}: {line}");
            continue;
        }
        println!(
            "| {name} | {} | {} | {:.2} s | {:.2} s | {:.2} s | {:.2} s | {:.2} s | {:.2} s | \
             {:.2} s | {:.2} s | {:.1} s | {:.2} GB |",
            v[0],
            v[10],
            v[2],
            v[3],
            v[4],
            v[5],
            v[6],
            v[7],
            v[8],
            v[9],
            v[1],
            v[11] / 1e9
        );
        sizes.push((v[0], v[1], v[11]));
    }
    for w in sizes.windows(2) {
        let ((n1, t1, m1), (n2, t2, m2)) = (w[0], w[1]);
        let exponent = |a: f64, b: f64| (b / a).ln() / (n2 / n1).ln();
        println!(
            "{n1} → {n2} nodes: time ∝ n^{:.2}, memory ∝ n^{:.2}",
            exponent(t1, t2),
            exponent(m1, m2)
        );
    }
}
