//! Criterion benchmarks of the multibody statics engine on the paper's
//! cantilever (§3.4) rolled into a full circle, `ML/(πEI) = 2`: solve time
//! against elements per rod, for both element types.
//!
//! Group `cantilever`, ids `BenchmarkId::new(kind, elements)` with kind
//! `se3` or `crisfield-jelenic` and 2…64 elements. Each size's model is built
//! (structure analysed, symbolic LU computed) outside the timed loop; the loop
//! times [`StaticSolver::solve`] from the straight rod: adaptive load steps,
//! assembly, factorisations. The tip error against the closed form, the load
//! steps and the Newton iterations of each size are printed once, beside it.
//!
//! Run with `cargo bench --bench truss`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ringmesh::mechanics::{cantilever, ElementKind, StaticSettings, StaticSolver};

/// Elements per rod.
const ELEMENTS: [usize; 6] = [2, 4, 8, 16, 32, 64];

/// The full circle: `ML/(πEI) = 2`.
const M_RATIO: f64 = 2.0;

/// A built cantilever and what its solve gives.
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

criterion_group!(benches, bench_cantilever);
criterion_main!(benches);
