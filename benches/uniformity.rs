//! Criterion benchmarks of the uniformity solvers.
//!
//! * `solver/<name>` — each solver on the realistic 26 m scene with 3, 6 and 10
//!   front-net rings (the id is the number of cables; `bisection` on 3 and 6
//!   rings only: at 10 it takes ≈ 30 s a solve);
//! * `bisection_tolerance` — ratio bisection on the small hexagonal scene, the id
//!   the relative bracket tolerance: what each digit of the ratio costs;
//! * `lp_nodes` — the `lp` optimum of the paper scene (30 bays) with its front net
//!   refined to ~10³, 10⁴ and 3·10⁴ net nodes (the id is the node count, front +
//!   rear); `RINGMESH_BENCH_RINGS=57` adds a ~10⁵-node net;
//! * `lp_independent` — the `lp` optimum of independently generated tied nets
//!   (`tests/common/hexnet.rs`: hexagonal grid, shuffled nodes and cables,
//!   every free node on its own anchor) of ~10³ and ~10⁴ free nodes, of two
//!   kinds: `hex5/<free>`, the kind of `tests/data/hex5-lp.json` (D = 26 m,
//!   F = 4 m, sag 5 %: issue 15's target net), and `100m/<free>` (D = 100 m,
//!   F/D = 0.4); `RINGMESH_BENCH_FREE=100000` adds ~10⁵-node nets of both
//!   (20–40 s a solve);
//! * `lp_families` — the `lp` optimum of the three net families of issue 38
//!   (`tests/common/nets.rs`: `hex`, the hexagonal generator's 100 m kind;
//!   `sector`, a six-sector grid with every row sagged, `hex5-lp.json`'s kind;
//!   `jitter`, that grid graded and jittered ±10 %) at ~10³ and ~10⁴ free
//!   nodes (`RINGMESH_BENCH_FAMILY_FREE=100000` adds ~10⁵); the id is
//!   `<family>/<free nodes>`; the plan interior point's iterations are printed;
//! * `clarabel_plan_lp` — clarabel on the same plan LPs (written from the
//!   network in `tests/common/plan_lp.rs`), QDLDL and faer backends, ids
//!   `<backend>/<family>/<free nodes>`, so the ratio to `lp_families` is
//!   measured in one run (`cargo bench --bench uniformity -- 'lp_families|clarabel_plan_lp'`;
//!   `benches/side_by_side.rs`, run by `scripts/bench/side-by-side.sh`,
//!   times both and `gradient` side by side and writes the ratios to
//!   `results/bench/side-by-side.csv`);
//! * `gradient_nodes` — the `gradient` solver on the paper scene with 3 rings
//!   (362 net nodes);
//! * `gradient_independent` — the `gradient` solver (L-BFGS from afar, then
//!   the exact finish: sequential QPs on the unsmoothed ratio; here from
//!   `lp`'s optimum, without L-BFGS) on the independently generated tied
//!   nets of `lp_independent`'s `hex5` kind, 428 and 2 516 nodes
//!   (`RINGMESH_BENCH_GRADIENT_RINGS=26,41,130` adds 4 208, 10 328 and
//!   102 176: ≈ 2.5 s, 9 s and minutes a solve); the ratio against `lp`'s,
//!   the surface RMS, the iterations and the exact objective of one solve
//!   are printed beside the time;
//! * `smooth_independent` — `gradient-smooth` (L-BFGS on the soft max/min
//!   alone) on the same nets, 428 and 4 208 nodes
//!   (`RINGMESH_BENCH_SMOOTH_RINGS=41,130` adds ≈ 10⁴ and 10⁵), printed as
//!   above;
//! * `smooth_sharpness` — `gradient-smooth` on the 2 516-node tied net
//!   (20 rings) at the soft max's sharpness 100, 300 and 1 000: what a
//!   sharper ratio surrogate costs (printed as above).
//!
//! A net of more than [`SAMPLED_MAX_NODES`] nodes is solved once, its time
//! printed, not sampled: criterion's ten samples would take an hour.
//!
//! Run with `cargo bench --bench uniformity`.

#[path = "../tests/common/hexnet.rs"]
mod hexnet;
#[path = "../tests/common/nets.rs"]
mod nets;
#[path = "../tests/common/plan_lp.rs"]
mod plan_lp;

use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use ringmesh::design::scene_problem;
use ringmesh::uniformity::{
    Bisection, Gradient, Lp, SolverKind, UniformityProblem, UniformitySolver,
};
use ringmesh::Scene;

fn problem(name: &str, rings: Option<usize>) -> UniformityProblem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("problems/{name}.toml"));
    let mut scene = Scene::read(&path).expect("shipped scene");
    if let Some(rings) = rings {
        scene.front_net.rings = rings;
        // Dense meshes load the scalloped boundary harder than the shipped bound.
        scene.cables.max_force_density_n_per_m = 1e9;
    }
    scene_problem(&scene).expect("valid scene").1
}

/// `sizes` and the comma-separated sizes of the environment variable `var`.
fn with_extra(mut sizes: Vec<usize>, var: &str) -> Vec<usize> {
    if let Ok(extra) = std::env::var(var) {
        sizes.extend(
            extra
                .split(',')
                .filter_map(|r| r.trim().parse::<usize>().ok()),
        );
    }
    sizes
}

/// Largest problem `solver/bisection` is run on (the 6-ring scene).
const BISECTION_MAX_CABLES: usize = 5_000;

fn solvers(c: &mut Criterion) {
    let problems: Vec<UniformityProblem> = [3, 6, 10]
        .iter()
        .map(|&r| problem("realistic-26m", Some(r)))
        .collect();
    for kind in [
        SolverKind::Lp,
        SolverKind::Bisection,
        SolverKind::Gradient,
        SolverKind::GradientSmooth,
        SolverKind::LeastSquares,
    ] {
        let solver = kind.build(None);
        let mut group = c.benchmark_group(format!("solver/{}", solver.name()));
        group
            .sample_size(10)
            .measurement_time(Duration::from_secs(5));
        for p in &problems {
            // Ratio bisection solves one clarabel program per step: ≈ 30 s a
            // solve at 10 rings, minutes for 10 samples.
            if kind == SolverKind::Bisection && p.network().n_edges() > BISECTION_MAX_CABLES {
                continue;
            }
            group.bench_with_input(
                BenchmarkId::from_parameter(p.network().n_edges()),
                p,
                |b, p| b.iter(|| solver.solve(p)),
            );
        }
        group.finish();
    }
}

fn bisection_tolerance(c: &mut Criterion) {
    let p = problem("small-hex", None);
    let mut group = c.benchmark_group("bisection_tolerance");
    group.sample_size(10);
    for tolerance in [1e-2, 1e-4, 1e-6, 1e-8] {
        let solver = Bisection {
            relative_tolerance: tolerance,
            ..Bisection::default()
        };
        group.bench_with_input(BenchmarkId::from_parameter(tolerance), &p, |b, p| {
            b.iter(|| solver.solve(p))
        });
    }
    group.finish();
}

fn lp_nodes(c: &mut Criterion) {
    let rings = with_extra(vec![4, 18, 32], "RINGMESH_BENCH_RINGS");
    let mut group = c.benchmark_group("lp_nodes");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for r in rings {
        let p = problem("paper-26m", Some(r));
        group.bench_with_input(
            BenchmarkId::from_parameter(p.network().n_nodes()),
            &p,
            |b, p| b.iter(|| Lp.solve(p)),
        );
    }
    group.finish();
}

fn lp_independent(c: &mut Criterion) {
    let sizes = with_extra(vec![1_000, 10_000], "RINGMESH_BENCH_FREE");
    let mut group = c.benchmark_group("lp_independent");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for free in sizes {
        let rings = hexnet::HexNet::with_free_nodes(free, 100.0).rings;
        let kinds = [
            ("hex5", hexnet::HexNet::like_hex5(rings)),
            ("100m", hexnet::HexNet::with_free_nodes(free, 100.0)),
        ];
        for (kind, net) in kinds {
            let p = hexnet::tied_net_problem(net.build(), "hangers", 50.0, 1e9);
            let free = p.structure().free_nodes().len();
            group.bench_with_input(BenchmarkId::new(kind, free), &p, |b, p| {
                b.iter(|| Lp.solve(p))
            });
        }
    }
    group.finish();
}

/// The problems of `lp_families` and `clarabel_plan_lp`: each family at
/// ~10³, ~10⁴ and the sizes of `RINGMESH_BENCH_FAMILY_FREE`.
fn family_problems() -> Vec<(nets::Family, usize, UniformityProblem)> {
    let mut problems = Vec::new();
    for free in with_extra(vec![1_000, 10_000], "RINGMESH_BENCH_FAMILY_FREE") {
        for family in nets::Family::ALL {
            let p = family.problem(nets::rings_for(free));
            let n_free = p.structure().free_nodes().len();
            problems.push((family, n_free, p));
        }
    }
    problems
}

fn lp_families(c: &mut Criterion) {
    let mut group = c.benchmark_group("lp_families");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for (family, free, p) in family_problems() {
        let id = format!("lp_families/{}/{free}", family.name());
        if let Ok(d) = Lp.solve(&p) {
            eprintln!(
                "{id}: {} interior-point iterations, route {:?}, {:.2} s",
                d.iterations, d.route, d.time_s
            );
        }
        if p.network().n_nodes() > SAMPLED_MAX_NODES {
            continue;
        }
        group.bench_with_input(BenchmarkId::new(family.name(), free), &p, |b, p| {
            b.iter(|| Lp.solve(p))
        });
    }
    group.finish();
}

fn clarabel_plan_lp(c: &mut Criterion) {
    let mut group = c.benchmark_group("clarabel_plan_lp");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    for (family, free, p) in family_problems() {
        for backend in ["qdldl", "faer"] {
            let id = format!("{backend}/{}", family.name());
            let start = std::time::Instant::now();
            let once = plan_lp::solve_plan(&p, backend);
            eprintln!(
                "clarabel_plan_lp/{id}/{free}: {} iterations, {}, ratio {:.8}, {:.2} s",
                once.iterations,
                once.status,
                once.ratio,
                start.elapsed().as_secs_f64()
            );
            if p.network().n_nodes() > SAMPLED_MAX_NODES {
                continue;
            }
            group.bench_with_input(BenchmarkId::new(id, free), &p, |b, p| {
                b.iter(|| plan_lp::solve_plan(p, backend))
            });
        }
    }
    group.finish();
}

fn gradient_nodes(c: &mut Criterion) {
    let p = problem("paper-26m", Some(3));
    let mut group = c.benchmark_group("gradient_nodes");
    group.sample_size(10);
    group.bench_with_input(
        BenchmarkId::from_parameter(p.network().n_nodes()),
        &p,
        |b, p| b.iter(|| Gradient::default().solve(p)),
    );
    group.finish();
}

/// Nets above this many nodes are solved once, not sampled.
const SAMPLED_MAX_NODES: usize = 50_000;

/// The gradient solvers on the independently generated tied nets:
/// `gradient` on 428 (issue 17's ~430-node net) and 2 516 nodes,
/// `gradient-smooth` on 428 and 4 208, each with the rings of its
/// environment variable.
fn independent(c: &mut Criterion) {
    for (name, solver, rings, var) in [
        (
            "gradient_independent",
            Gradient::default(),
            vec![8, 20],
            "RINGMESH_BENCH_GRADIENT_RINGS",
        ),
        (
            "smooth_independent",
            Gradient::smooth(),
            vec![8, 26],
            "RINGMESH_BENCH_SMOOTH_RINGS",
        ),
    ] {
        let mut group = c.benchmark_group(name);
        group.sample_size(10);
        for r in with_extra(rings, var) {
            let net = hexnet::HexNet::like_hex5(r);
            let p = hexnet::tied_net_problem(net.build(), "hangers", 50.0, 1e9);
            let nodes = p.network().n_nodes();
            print_gradient_solve(&format!("{name}/{nodes}"), &solver, &p);
            if nodes <= SAMPLED_MAX_NODES {
                group.bench_with_input(BenchmarkId::from_parameter(nodes), &p, |b, p| {
                    b.iter(|| solver.solve(p))
                });
            }
        }
        group.finish();
    }
}

/// What one `solver` solve of `p` reaches, printed beside the benchmark's time:
/// the ratio against `lp`'s optimum, the surface RMS, the iterations (L-BFGS
/// iterations plus the exact finish's programs), the objective with the exact
/// ratio and the solve's time.
fn print_gradient_solve(id: &str, solver: &Gradient, p: &UniformityProblem) {
    let optimum = Lp.solve(p).map(|d| d.ratio).unwrap_or(f64::NAN);
    if let Ok(d) = solver.solve(p) {
        let exact = solver.exact_objective(p, &d.q).unwrap_or(f64::NAN);
        eprintln!(
            "{id}: ratio {:.4} ({:+.2} % of lp's {optimum:.4}), surface RMS {:.3e} mm, \
             {} iterations, {}, exact J {exact:.8}, {:.2} s",
            d.ratio,
            100.0 * (d.ratio / optimum - 1.0),
            1e3 * d.surface_rms_m,
            d.iterations,
            ringmesh::report::json_name(&d.termination),
            d.time_s
        );
    }
}

/// The sharpness of the soft max/min against time and iterations on a net
/// where the default (1 000) needs thousands of L-BFGS iterations.
fn smooth_sharpness(c: &mut Criterion) {
    let net = hexnet::HexNet::like_hex5(20);
    let p = hexnet::tied_net_problem(net.build(), "hangers", 50.0, 1e9);
    let mut group = c.benchmark_group("smooth_sharpness");
    group.sample_size(10);
    for sharpness in [100.0, 300.0, 1000.0] {
        let solver = Gradient {
            sharpness,
            ..Gradient::smooth()
        };
        print_gradient_solve(&format!("smooth_sharpness/{sharpness}"), &solver, &p);
        group.bench_with_input(BenchmarkId::from_parameter(sharpness), &p, |b, p| {
            b.iter(|| solver.solve(p))
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    solvers,
    bisection_tolerance,
    lp_nodes,
    lp_independent,
    lp_families,
    clarabel_plan_lp,
    gradient_nodes,
    independent,
    smooth_sharpness
);
criterion_main!(benches);
