use ringmesh::uniformity::{LeastSquares, UniformityProblem, UniformitySolver};
use std::path::Path;

fn problem_text(text: &str) -> UniformityProblem {
    let scene = ringmesh::Scene::from_toml(text, "x").unwrap();
    let mesh = ringmesh::geometry::build_mesh(&scene).unwrap();
    UniformityProblem::from_mesh(
        &mesh,
        &[(ringmesh::CableGroup::Front, scene.front_net.mean_tension_n)],
        1e7,
    )
    .unwrap()
}

#[test]
fn scratch() {
    for file in ["small-hex", "small-offset", "paper-26m", "realistic-26m"] {
        let base = std::fs::read_to_string(
            Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{file}.toml")),
        )
        .unwrap();
        let p = problem_text(&base);
        println!(
            "{file}: nodes {} edges {}",
            p.network().n_nodes(),
            p.network().n_edges()
        );
        for lambda in [None, Some(1e-3), Some(1.0)] {
            for delta in [1e-6, 1e-9] {
                let s = LeastSquares {
                    lambda,
                    other_weight: delta,
                    max_proximal: 100,
                    ..Default::default()
                };
                let t0 = std::time::Instant::now();
                match s.solve(&p) {
                Ok(d) => println!("  λ={lambda:?} δ={delta:e}: {:?} it {} ratio {:.6} resid {:.3e} t {:.3}s (wall {:.3}) {:?}", d.termination, d.iterations, d.ratio, d.max_residual_n, d.time_s, t0.elapsed().as_secs_f64(), d.warnings),
                Err(e) => println!("  λ={lambda:?} δ={delta:e}: ERR {}", &e.to_string()[..200]),
            }
            }
        }
    }
}
