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
//! * Group `net_choice` — what a surface target costs (issue 34): choosing
//!   the coarsest net for `problems/target-40m.toml`'s 1.5 mm
//!   ([`ringmesh::surface::resolve_front_rings`], geometry only) beside the
//!   whole `design::run` of the scene it completes, in one run; the ratio is
//!   printed.
//!
//! Run with `cargo bench --bench design` (about three minutes on two cores).

use std::path::Path;
use std::time::Duration;

use criterion::measurement::WallTime;
use criterion::{
    criterion_group, criterion_main, BenchmarkGroup, BenchmarkId, Criterion, SamplingMode,
};
use ringmesh::design::SceneNets;
use ringmesh::design::{DesignSettings, LoopOutcome, LoopSettings};
use ringmesh::scene::{Scene, TrussModel};
use ringmesh::surface::resolve_front_rings;
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

fn bench_net_choice(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/target-40m.toml");
    let scene = Scene::read(&path).expect("shipped scene");
    let resolved = resolve_front_rings(&scene).expect("a net meets the target");
    let mut group = c.benchmark_group("net_choice");
    group
        .sample_size(10)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_secs(1));
    group.bench_function("choose/target-40m", |b| {
        b.iter(|| resolve_front_rings(&scene).expect("a net meets the target"))
    });
    group.bench_function("design/target-40m", |b| {
        b.iter(|| {
            ringmesh::design::run(&resolved, &DesignSettings::default(), &mut |_, _| {})
                .expect("the scene designs")
        })
    });
    group.finish();
    // The ratio, from one more timing of each in this run.
    let time = |f: &dyn Fn()| {
        let clock = std::time::Instant::now();
        f();
        clock.elapsed().as_secs_f64()
    };
    let choose_s = time(&|| drop(resolve_front_rings(&scene)));
    let design_s = time(&|| {
        drop(ringmesh::design::run(
            &resolved,
            &DesignSettings::default(),
            &mut |_, _| {},
        ))
    });
    eprintln!(
        "net_choice: {} rings chosen in {choose_s:.3} s, the design {design_s:.2} s: {:.1} % \
         of it",
        resolved.front_net.rings,
        100.0 * choose_s / design_s
    );
}

criterion_group!(benches, bench_design, bench_net_choice);
criterion_main!(benches);
