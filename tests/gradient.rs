use std::path::Path;
use std::time::Instant;

use ringmesh::geometry::build_mesh;
use ringmesh::uniformity::{Gradient, Lp, UniformityProblem, UniformitySolver};
use ringmesh::{CableGroup, Scene};

fn scene(name: &str) -> Scene {
    Scene::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{name}.toml")))
        .unwrap()
}

fn front_problem(scene: &Scene) -> UniformityProblem {
    let mesh = build_mesh(scene).unwrap();
    UniformityProblem::from_mesh(
        &mesh,
        &[(CableGroup::Front, scene.front_net.mean_tension_n)],
        scene.cables.max_force_density_n_per_m,
    )
    .unwrap()
}

#[test]
#[ignore]
fn explore() {
    let w: f64 = std::env::var("W")
        .map(|v| v.parse().unwrap())
        .unwrap_or(1e-3);
    let b: f64 = std::env::var("B")
        .map(|v| v.parse().unwrap())
        .unwrap_or(100.0);
    for name in ["small-hex", "small-offset"] {
        let s = scene(name);
        let p = front_problem(&s);
        let lp = Lp.solve(&p).unwrap();
        let g = Gradient {
            weight: w,
            sharpness: b,
            ..Gradient::default()
        };
        let t = Instant::now();
        let (d, h) = g.solve_with_history(&p).unwrap();
        let el = t.elapsed().as_secs_f64();
        println!(
            "{name}: nodes {} edges {} lp {:.5} grad {:.5} ({:+.2}%) rms {:.3e} it {} {:?} {:.3}s J {:.3e}->{:.3e} |g| {:.2e}->{:.2e} warn {:?}",
            p.network().n_nodes(), p.network().n_edges(),
            lp.ratio, d.ratio, 100.0 * (d.ratio / lp.ratio - 1.0), d.surface_rms_m, d.iterations, d.termination, el,
            h.objective[0], h.objective.last().unwrap(), h.gradient_norm[0], h.gradient_norm.last().unwrap(), d.warnings
        );
    }
}
