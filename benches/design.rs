//! Criterion benchmarks of the outer design loop (paper §4) and of the
//! verification by assembly (paper §5).
//!
//! * Group `design_loop` — the outer loop (`lp`, Anderson, tolerance 1e-6 m)
//!   from the theoretical boundary to the converged design, a fresh truss
//!   oracle each time (the exact oracle warm-starts across the iterations of
//!   one loop, never across loops); ids `BenchmarkId::new(scene, model)`:
//!   `small-hex` with the rigid, linear and exact truss, `realistic-26m` with
//!   the exact truss. The mesh and the design problem are built outside the
//!   timed loop; the outer iterations of each case are printed once.
//! * Group `verify` — the converged design cut to length and assembled on the
//!   flexible truss ([`ringmesh::verify::verify`]); ids the scene.
//!
//! Run with `cargo bench --bench design` (about a minute on two cores).

use std::path::Path;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, SamplingMode,
};
use ringmesh::design::SceneNets;
use ringmesh::design::{LoopOutcome, LoopSettings};
use ringmesh::scene::{Scene, TrussModel};
use ringmesh::uniformity::{SolverKind, UniformitySolver};
use ringmesh::verify::{verify, AssemblyTruss};

/// A scene with its nets built.
struct Fixture {
    name: &'static str,
    scene: Scene,
    nets: SceneNets,
    solver: Box<dyn UniformitySolver>,
}

impl Fixture {
    fn new(name: &'static str) -> Fixture {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{name}.toml"));
        let scene = Scene::read(&path).expect("shipped scene");
        let nets = SceneNets::new(&scene).expect("valid scene");
        Fixture {
            name,
            scene,
            nets,
            solver: SolverKind::Lp.build(None),
        }
    }

    /// The outer loop with a fresh oracle of `model`.
    fn design(&self, model: TrussModel) -> LoopOutcome {
        self.nets
            .design_loop(
                &self.scene,
                self.solver.as_ref(),
                model,
                &LoopSettings::default(),
                &mut |_| {},
            )
            .expect("the shipped scenes carry their nets")
    }
}

fn model_name(model: TrussModel) -> &'static str {
    match model {
        TrussModel::Rigid => "rigid",
        TrussModel::Linear => "linear",
        TrussModel::Exact => "exact",
    }
}

/// 4 s of samples for the small scene; 10 flat samples of the large one
/// (half a second each).
fn measure_time(group: &mut BenchmarkGroup<'_, WallTime>, f: &Fixture) {
    if f.name == "small-hex" {
        group
            .sampling_mode(SamplingMode::Auto)
            .measurement_time(Duration::from_secs(4));
    } else {
        group
            .sampling_mode(SamplingMode::Flat)
            .measurement_time(Duration::from_secs(8));
    }
}

fn bench_design(c: &mut Criterion) {
    let fixtures = [Fixture::new("small-hex"), Fixture::new("realistic-26m")];
    let cases = [
        (&fixtures[0], TrussModel::Rigid),
        (&fixtures[0], TrussModel::Linear),
        (&fixtures[0], TrussModel::Exact),
        (&fixtures[1], TrussModel::Exact),
    ];
    for (f, model) in cases {
        let outcome = f.design(model);
        eprintln!(
            "design bench: {} with the {} truss: {:?} after {} outer iterations, residual {:.2e} m, \
             ratio {:.6}",
            f.name,
            model_name(model),
            outcome.termination,
            outcome.history.len(),
            outcome.boundary_residual_m(),
            outcome.design.ratio
        );
    }

    let mut group = c.benchmark_group("design_loop");
    group.sample_size(10).warm_up_time(Duration::from_secs(1));
    for (f, model) in cases {
        measure_time(&mut group, f);
        group.bench_with_input(
            BenchmarkId::new(f.name, model_name(model)),
            &(f, model),
            |b, &(f, model)| b.iter(|| f.design(model)),
        );
    }
    group.finish();

    let mut group = c.benchmark_group("verify");
    group.sample_size(10).warm_up_time(Duration::from_secs(1));
    for f in &fixtures {
        measure_time(&mut group, f);
        let outcome = f.design(TrussModel::Exact);
        let network = outcome.problem.network();
        group.bench_function(f.name, |b| {
            b.iter(|| {
                verify(
                    &f.scene,
                    &f.nets.mesh,
                    &f.nets.effects,
                    network,
                    &outcome.design,
                    AssemblyTruss::Flexible,
                    None,
                )
                .expect("the converged design assembles")
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_design);
criterion_main!(benches);
