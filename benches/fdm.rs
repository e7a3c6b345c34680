//! Criterion benchmarks of the force density method on reflector nets of about
//! 10³, 10⁴ and 10⁵ nodes (front + rear net of a 6-bay ring truss).
//!
//! Groups, each with the total node count as the benchmark id:
//!
//! * `structure` — [`FdmStructure::new`]: validation, sparsity of `D` and its
//!   symbolic Cholesky factorisation (ordering included);
//! * `solve` — [`FdmStructure::solve`] with the structure reused: value fill,
//!   numeric factorisation, three solves, lengths, forces and reactions (the
//!   cost of a new `q` on a fixed topology);
//! * `forward` — [`ringmesh::fdm::solve_network`]: the whole forward solve from
//!   scratch;
//! * `sensitivities` — one adjoint solve, [`Equilibrium::sensitivities`].
//!
//! Run with `cargo bench --bench fdm`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, SamplingMode};
use ringmesh::fdm::solve_network;
use ringmesh::geometry::build_mesh;
use ringmesh::{Equilibrium, FdmStructure, Network, Scene};

/// Front-net rings giving ≈ 10³, 10⁴ and 10⁵ net nodes in all: a 6-bay net of
/// `r` rings has `1 + 3 r (r + 1)` nodes per net, so 938, 9 842 and 100 622.
const RINGS: [usize; 3] = [12, 40, 129];

/// Above this many nodes a benchmark runs in flat sampling mode with 10 samples,
/// so that the largest cases finish in seconds.
const LARGE: usize = 50_000;

/// problems/small-hex.toml (6 bays, 6 m aperture) with `{rings}` to be replaced.
/// At 129 rings its shortest cables are ≈ 2 cm, well above the degenerate-cable
/// limit (`MIN_CABLE_LENGTH_RATIO` × aperture).
const SCENE: &str = r#"
name = "bench"

[reflector]
aperture_diameter_m = 6.0
focal_length_m = 4.0
offset_m = 0.0

[truss]
bays = 6
height_m = 1.5
tube_outer_diameter_m = 0.024
tube_inner_diameter_m = 0.022
youngs_modulus_pa = 160e9
shear_modulus_pa = 61.5e9
density_kg_per_m3 = 1600.0

[front_net]
rings = {rings}
boundary_sag_ratio = 0.05
mean_tension_n = 70.0

[rear_net]
focal_length_m = 8.0
mean_tension_n = 140.0

[cables]
diameter_m = 0.005
youngs_modulus_pa = 50e9
density_kg_per_m3 = 1440.0
max_force_density_n_per_m = 5000.0
"#;

/// Everything a benchmark needs, built once per size outside the timed loop.
struct Fixture {
    network: Network,
    structure: FdmStructure,
    equilibrium: Equilibrium,
    /// Gradient of `J = ½ Σ z²` over the nodes: n_nodes × 3.
    dj_dx: Vec<[f64; 3]>,
}

impl Fixture {
    fn new(rings: usize) -> Self {
        let text = SCENE.replace("{rings}", &rings.to_string());
        let scene = Scene::from_toml(&text, "bench").expect("the bench scene is valid");
        let network = build_mesh(&scene)
            .expect("the bench scene builds a mesh")
            .network;
        let (structure, equilibrium) = solve_network(&network).expect("forward solve");
        let dj_dx = equilibrium
            .nodes_xyz_m
            .iter()
            .map(|&[_, _, z]| [0.0, 0.0, z])
            .collect();
        Fixture {
            network,
            structure,
            equilibrium,
            dj_dx,
        }
    }

    fn n_nodes(&self) -> usize {
        self.network.n_nodes()
    }
}

fn fixtures() -> Vec<Fixture> {
    RINGS
        .iter()
        .map(|&rings| {
            let fixture = Fixture::new(rings);
            eprintln!(
                "fdm bench: {rings} rings → {} nodes ({} free), {} cables, {} nonzeros in tril(D)",
                fixture.n_nodes(),
                fixture.structure.free_nodes().len(),
                fixture.network.n_edges(),
                fixture.structure.d_nonzeros(),
            );
            fixture
        })
        .collect()
}

/// Sampling settings by size: many quick samples for the small nets, 10 flat
/// samples for the largest.
fn configure(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    n: usize,
) {
    if n >= LARGE {
        group
            .sample_size(10)
            .sampling_mode(SamplingMode::Flat)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(4));
    } else {
        group
            .sample_size(30)
            .sampling_mode(SamplingMode::Auto)
            .warm_up_time(Duration::from_secs(1))
            .measurement_time(Duration::from_secs(3));
    }
}

fn bench_fdm(c: &mut Criterion) {
    let fixtures = fixtures();

    let mut group = c.benchmark_group("structure");
    for f in &fixtures {
        configure(&mut group, f.n_nodes());
        group.bench_with_input(BenchmarkId::new("structure", f.n_nodes()), f, |b, f| {
            b.iter(|| FdmStructure::new(black_box(&f.network)).expect("structure"))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("solve");
    for f in &fixtures {
        configure(&mut group, f.n_nodes());
        group.bench_with_input(BenchmarkId::new("solve", f.n_nodes()), f, |b, f| {
            b.iter(|| {
                f.structure
                    .solve(black_box(&f.network.q), black_box(&f.network.nodes), None)
                    .expect("solve")
            })
        });
    }
    group.finish();

    let mut group = c.benchmark_group("forward");
    for f in &fixtures {
        configure(&mut group, f.n_nodes());
        group.bench_with_input(BenchmarkId::new("forward", f.n_nodes()), f, |b, f| {
            b.iter(|| solve_network(black_box(&f.network)).expect("forward solve"))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("sensitivities");
    for f in &fixtures {
        configure(&mut group, f.n_nodes());
        group.bench_with_input(BenchmarkId::new("sensitivities", f.n_nodes()), f, |b, f| {
            b.iter(|| {
                f.equilibrium
                    .sensitivities(&f.structure, black_box(&f.dj_dx), None)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_fdm);
criterion_main!(benches);
