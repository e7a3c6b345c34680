//! The error budget's cost (issue 35's targets), one scene at a time:
//!
//! * `linearised` — the design's wall time against its **linearised
//!   budget**: the assembly's tangent factored once, then every thermal case
//!   and tolerance sample of the scene through it (one residual, one solve,
//!   the surface measured), in parallel as `ringmesh budget` runs its
//!   samples. Printed: design, tangent, points, their total and its share of
//!   the design (target ≤ 10 % on super-60m).
//! * `samples` — `N` **nonlinear** Monte Carlo samples (chord iterations on
//!   the design's tangent, Newton from the design's assembly where they are
//!   slow), in parallel: the wall time of all, and per sample (targets:
//!   1 000 of realistic-26m ≤ 60 s; ≤ 5 s a sample of super-100m).
//!
//! The design itself is not part of either figure: `budget` reuses the
//! design run's own assembly. A whole design at 10⁵ nodes takes a minute,
//! so this is not a criterion bench: one run per figure, on a quiet machine.
//!
//!     cargo bench --bench budget                        # super-60m linearised; realistic-26m, 1 000 samples
//!     cargo bench --bench budget -- super-100m:4        # super-100m, 4 samples (and its linearised budget)
//!
//! An argument `scene:N` runs `scene` with `N` nonlinear samples (`N` = 0:
//! the linearised budget only).

use std::path::Path;
use std::time::Instant;

use rayon::prelude::*;
use ringmesh::budget::{thermal_perturbation, PerturbedAssembly, ToleranceModel};
use ringmesh::design::{self, DesignSettings};
use ringmesh::effects::ThermalExpansion;
use ringmesh::scene::Scene;
use ringmesh::surface::resolve_front_rings;
use ringmesh::verify::Perturbation;

const DEFAULT: [(&str, usize); 2] = [("super-60m", 0), ("realistic-26m", 1000)];

/// The scene's thermal cases, then `samples` tolerance samples of seed 1
/// (the scene's own count when `samples` is `None`).
fn perturbations(
    scene: &Scene,
    run: &design::DesignRun,
    samples: Option<usize>,
) -> (Vec<Perturbation>, Vec<Perturbation>) {
    let cases = match ThermalExpansion::of(scene) {
        Some(effect) => effect
            .cases()
            .iter()
            .map(|case| {
                thermal_perturbation(
                    &effect,
                    case,
                    &run.mesh,
                    &run.network,
                    &run.report.net.nodes_xyz_m,
                )
            })
            .collect(),
        None => Vec::new(),
    };
    let drawn = match &scene.tolerances {
        Some(t) => {
            let model =
                ToleranceModel::new(t, &run.mesh, &run.network, &run.report.net, &scene.cables);
            let n = samples.unwrap_or(t.samples.unwrap_or(100));
            (0..n).map(|k| model.sample(1, k)).collect()
        }
        None => Vec::new(),
    };
    (cases, drawn)
}

fn one(name: &str, samples: usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{name}.toml"));
    let scene = Scene::read(&path).expect("shipped scene");
    let clock = Instant::now();
    let mut run = design::run(&scene, &DesignSettings::default(), &mut |_, _| {}).expect("designs");
    let design_s = clock.elapsed().as_secs_f64();
    let scene = resolve_front_rings(&scene).expect("rings chosen");
    let nominal = run.assembled.take();
    let core = PerturbedAssembly::new(&scene, &run.mesh, &run.network, &run.report.net, nominal)
        .expect("assembles");

    let clock = Instant::now();
    let tangent = core.linearise().expect("factors");
    let tangent_s = clock.elapsed().as_secs_f64();
    let (cases, drawn) = perturbations(&scene, &run, None);
    let points: Vec<&Perturbation> = cases.iter().chain(&drawn).collect();
    let clock = Instant::now();
    let linear: Vec<f64> = points
        .par_iter()
        .map(|p| {
            let v = core.linear(&tangent, p).expect("responds");
            core.change(&v).expect("measures").best_fit_mm
        })
        .collect();
    let points_s = clock.elapsed().as_secs_f64();
    let budget_s = tangent_s + points_s;
    assert!(linear.iter().all(|r| r.is_finite()));
    println!(
        "{name} linearised: design {design_s:.2} s, tangent {tangent_s:.3} s, {} points \
         {points_s:.3} s ({:.4} s each), budget {budget_s:.3} s = {:.1} % of the design",
        points.len(),
        points_s / points.len().max(1) as f64,
        100.0 * budget_s / design_s
    );
    if samples == 0 {
        return;
    }
    let (_, drawn) = perturbations(&scene, &run, Some(samples));
    let clock = Instant::now();
    let outcomes: Vec<Result<f64, String>> = drawn
        .par_iter()
        .map(|p| {
            core.nonlinear(&tangent, p)
                .and_then(|v| core.change(&v))
                .map(|m| m.best_fit_mm)
                .map_err(|e| e.to_string())
        })
        .collect();
    let wall = clock.elapsed().as_secs_f64();
    let failed = outcomes.iter().filter(|o| o.is_err()).count();
    println!(
        "{name} nonlinear: {samples} samples {wall:.2} s ({:.4} s each, {failed} failed) on {} threads",
        wall / samples as f64,
        rayon::current_num_threads()
    );
}

fn main() {
    // As the command line does (`resources::retain_freed_memory`).
    ringmesh::resources::retain_freed_memory();
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let chosen: Vec<(String, usize)> = if args.is_empty() {
        DEFAULT.iter().map(|&(s, n)| (s.to_string(), n)).collect()
    } else {
        args.iter()
            .map(|a| match a.split_once(':') {
                Some((s, n)) => (s.to_string(), n.parse().expect("scene:N, N a count")),
                None => (a.clone(), 0),
            })
            .collect()
    };
    for (scene, samples) in chosen {
        one(&scene, samples);
    }
}
