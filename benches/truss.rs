//! Criterion benchmarks of the multibody statics engine: solve time against
//! elements per rod, with the accuracy each mesh buys printed beside it.
//!
//! * Group `cantilever` — the paper's cantilever (§3.4) rolled into a full
//!   circle, `ML/(πEI) = 2`; ids `BenchmarkId::new(kind, elements)` with kind
//!   `se3` or `crisfield-jelenic` and 2…64 elements (and the 10). The
//!   tip error against the closed form, the load steps and the Newton
//!   iterations of each size are printed once.
//! * Group `ring_truss` — the ring truss of `problems/paper-26m.toml` (30
//!   bays, 120/112 mm tubes) under the pull of its net, the boundary reactions
//!   of forward FDM with the net's initial q, as `ringmesh truss` applies
//!   them; ids `BenchmarkId::new("paper-26m", elements_per_rod)` with 1, 2, 4
//!   and 8 SE(3) elements per rod. Printed once per mesh: size, Newton
//!   iterations, load steps, the largest attachment-point displacement and
//!   its change against the finest mesh (the discretisation error).
//!
//! Each model is built (structure analysed, symbolic LU computed) outside the
//! timed loop; the loop times a cold [`StaticSolver::solve`] from the
//! unstressed frame: adaptive load steps, assembly, factorisations.
//!
//! Run with `cargo bench --bench truss` (a few minutes on two cores), or one
//! group with `cargo bench --bench truss -- ring_truss`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use nalgebra::Vector3;
use ringmesh::effects::SceneEffects;
use ringmesh::fdm::solve_network;
use ringmesh::frame::cantilever;
use ringmesh::geometry::build_mesh;
use ringmesh::mechanics::{ElementKind, NodalLoad, StaticSettings, StaticSolution, StaticSolver};
use ringmesh::scene::Scene;
use ringmesh::truss::RingTruss;

/// Elements per rod of the cantilever.
const ELEMENTS: [usize; 7] = [2, 4, 8, 10, 16, 32, 64];

/// The full circle: `ML/(πEI) = 2`.
const M_RATIO: f64 = 2.0;

/// Elements per rod of the ring truss; the last is the reference mesh.
const RING_ELEMENTS: [usize; 4] = [1, 2, 4, 8];

/// The ring-truss scene.
const RING_SCENE: &str = "paper-26m";

/// A built cantilever.
struct Fixture {
    kind: ElementKind,
    elements: usize,
    solver: StaticSolver,
}

fn fixture(kind: ElementKind, elements: usize, settings: &StaticSettings) -> Fixture {
    let moment = M_RATIO * std::f64::consts::PI * cantilever::BENDING_NM2 / cantilever::LENGTH_M;
    let solver = cantilever::model(elements, kind, moment).expect("the cantilever is valid");
    let row = cantilever::row(elements, kind, M_RATIO, settings).expect("valid settings");
    // At the full circle the Crisfield–Jelenić polygon closes exactly, so its
    // tip error there is roundoff; at ML/(πEI) = 1.5 its discretisation shows.
    let open = cantilever::row(elements, kind, 1.5, settings).expect("valid settings");
    eprintln!(
        "truss bench: cantilever {:>17} {elements:>2} elements: tip error {:.3e} ({}), {} load steps, {} Newton iterations; at ML/πEI = 1.5: {:.3e}",
        kind.name(),
        row.relative_error,
        if row.converged { "converged" } else { "NOT converged" },
        row.load_steps,
        row.newton_iterations,
        open.relative_error,
    );
    Fixture {
        kind,
        elements,
        solver,
    }
}

fn bench_cantilever(c: &mut Criterion) {
    let settings = StaticSettings::default();
    let fixtures: Vec<Fixture> = [ElementKind::Se3, ElementKind::CrisfieldJelenic]
        .into_iter()
        .flat_map(|kind| ELEMENTS.map(|n| (kind, n)))
        .map(|(kind, n)| fixture(kind, n, &settings))
        .collect();

    let mut group = c.benchmark_group("cantilever");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for f in &fixtures {
        group.bench_with_input(BenchmarkId::new(f.kind.name(), f.elements), f, |b, f| {
            b.iter(|| {
                f.solver
                    .solve(black_box(&settings))
                    .expect("valid settings")
            })
        });
    }
    group.finish();
}

/// A built ring truss under its net's pull, and its solution.
struct RingFixture {
    elements_per_rod: usize,
    solver: StaticSolver,
    attachments: Vec<usize>,
    solution: StaticSolution,
}

impl RingFixture {
    /// Displacement of every attachment point (top hinges, then bottom), m.
    fn displacements(&self) -> Vec<Vector3<f64>> {
        let reference = self.solver.model().reference();
        self.attachments
            .iter()
            .map(|&n| self.solution.state.frames[n].position_m - reference[n].position_m)
            .collect()
    }
}

fn ring_fixture(scene: &Scene, elements_per_rod: usize, settings: &StaticSettings) -> RingFixture {
    let mut scene = scene.clone();
    scene.truss.elements_per_rod = elements_per_rod;
    let mesh = build_mesh(&scene).expect("the shipped scene builds");
    // The net pulls on its supports with −(reactions), as `ringmesh truss`.
    let (_, eq) = solve_network(&mesh.network).expect("the net solves");
    let ring = RingTruss::new(&scene, &mesh.truss, &SceneEffects::of(&scene))
        .expect("the ring truss builds");
    let loads = ring
        .attachments
        .iter()
        .zip(&eq.reactions_n)
        .map(|(&node, r)| NodalLoad {
            node,
            force_n: -Vector3::new(r[0], r[1], r[2]),
            moment_nm: Vector3::zeros(),
        })
        .collect();
    let mut solver = StaticSolver::new(ring.model).expect("the frame is analysable");
    solver.model_mut().set_loads(loads).expect("valid loads");
    let solution = solver.solve(settings).expect("valid settings");
    RingFixture {
        elements_per_rod,
        solver,
        attachments: ring.attachments,
        solution,
    }
}

fn bench_ring_truss(c: &mut Criterion) {
    let settings = StaticSettings::default();
    let path = format!("{}/problems/{RING_SCENE}.toml", env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::read(std::path::Path::new(&path)).expect("the shipped scene reads");
    let fixtures: Vec<RingFixture> = RING_ELEMENTS
        .iter()
        .map(|&n| ring_fixture(&scene, n, &settings))
        .collect();
    let finest = fixtures.last().expect("meshes").displacements();
    for f in &fixtures {
        let d = f.displacements();
        let largest = d.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let change = d
            .iter()
            .zip(&finest)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        let model = f.solver.model();
        eprintln!(
            "truss bench: ring truss {RING_SCENE} {} elements/rod ({} nodes, {} elements, {} joints): {:?}, {} load steps, {} Newton iterations ({} cut); max attachment displacement {:.4} mm, max change vs {} elements/rod {:.2e} mm",
            f.elements_per_rod,
            model.node_count(),
            model.element_count(),
            model.joint_count(),
            f.solution.termination,
            f.solution.steps.len(),
            f.solution.newton_iterations,
            f.solution.rejected_steps,
            1e3 * largest,
            RING_ELEMENTS.last().expect("meshes"),
            1e3 * change,
        );
    }

    let mut group = c.benchmark_group("ring_truss");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    for f in &fixtures {
        group.bench_with_input(
            BenchmarkId::new(RING_SCENE, f.elements_per_rod),
            f,
            |b, f| {
                b.iter(|| {
                    f.solver
                        .solve(black_box(&settings))
                        .expect("valid settings")
                })
            },
        );
    }
    group.finish();
}

criterion_group!(benches, bench_cantilever, bench_ring_truss);
criterion_main!(benches);
