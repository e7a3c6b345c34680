//! Helpers shared by the integration tests: the shipped problems and scenes,
//! the reference data of `tests/data/`, the command line, a deterministic
//! random source and proptest settings, the net's pull on the truss, and
//! Newton's convergence rate measured from the residual history. Every test
//! file declares `mod common;` and takes what it needs.
#![allow(dead_code)] // each test file uses its own part

pub mod frames;
pub mod hexnet;
pub mod nets;
pub mod plan_lp;

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use std::process::{Command, Output};

use nalgebra::{UnitQuaternion, Vector3};
use proptest::test_runner::{Config as ProptestConfig, RngSeed};
use ringmesh::design::{scene_problem, TiedNets};
use ringmesh::effects::SceneEffects;
use ringmesh::fdm::solve_network;
use ringmesh::geometry::{build_mesh, ReflectorMesh};
use ringmesh::mechanics::rotation::exp;
use ringmesh::mechanics::{State, StaticSettings, StaticSolution, StaticSolver};
use ringmesh::network::{CableGroup, Network};
use ringmesh::scene::TrussModel;
use ringmesh::truss::{self, TrussOracle};
use ringmesh::uniformity::UniformityProblem;
use ringmesh::Scene;

/// A deterministic generator (splitmix64): the tests need variety, not entropy.
pub struct Random(pub u64);

impl Random {
    /// Uniform in [0, 1).
    pub fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A unit vector, uniform on the sphere.
    pub fn axis(&mut self) -> Vector3<f64> {
        let z = 2.0 * self.next_f64() - 1.0;
        let phi = TAU * self.next_f64();
        let r = (1.0 - z * z).sqrt();
        Vector3::new(r * phi.cos(), r * phi.sin(), z)
    }
}

/// The angle of the rotation taking `a` to `b`, accurate down to roundoff
/// (`2 atan2(|v|, |w|)`; nalgebra's `angle` goes through `acos` and cannot see
/// angles below ~1e-8).
pub fn angle_between(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    let d = a.inverse() * b;
    2.0 * d.imag().norm().atan2(d.w.abs())
}

/// The path of a shipped problem file (`small-hex.toml`, `frames/…`).
pub fn problem(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("problems")
        .join(name)
}

/// The crate's source folder, `src/`.
pub fn source_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// [`problem`] as a command-line argument.
pub fn problem_arg(name: &str) -> String {
    problem(name).display().to_string()
}

/// A shipped scene, by name (`small-hex`).
pub fn scene(name: &str) -> Scene {
    Scene::read(&problem(&format!("{name}.toml"))).expect("shipped scene")
}

/// small-hex: its scene, mesh and two-stage design problem (weightless).
pub fn small_hex_nets() -> (Scene, ReflectorMesh, TiedNets) {
    scene_nets("small-hex")
}

/// A shipped scene, its mesh and its tied nets.
pub fn scene_nets(name: &str) -> (Scene, ReflectorMesh, TiedNets) {
    let scene = scene(name);
    let (mesh, problem) = scene_problem(&scene).unwrap_or_else(|e| panic!("{name} builds: {e}"));
    let nets = TiedNets::new(&mesh, problem).unwrap_or_else(|e| panic!("{name}'s nets: {e}"));
    (scene, mesh, nets)
}

/// The front net of `scene` on its mesh, its mean tension the target.
pub fn front_problem(scene: &Scene) -> UniformityProblem {
    let mesh = build_mesh(scene).unwrap();
    UniformityProblem::from_mesh(
        &mesh,
        &[(CableGroup::Front, scene.front_net.mean_tension_n)],
        scene.cables.max_force_density_n_per_m,
    )
    .unwrap()
}

/// The reference network of an independent implementation
/// (`tests/data/hex5-lp.json`; its origin: `tests/data/README.md`).
pub fn reference_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/hex5-lp.json")
}

/// [`reference_path`], read.
pub fn reference_network() -> Network {
    Network::read_json(&reference_path()).expect("tests/data/hex5-lp.json")
}

/// Runs the `ringmesh` binary with `args` in the current directory.
pub fn ringmesh(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ringmesh"))
        .args(args)
        .output()
        .expect("run ringmesh")
}

/// Runs the `ringmesh` binary with `args` in `dir`.
pub fn ringmesh_in(args: &[&str], dir: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ringmesh"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run ringmesh")
}

/// Proptest settings: `cases` cases from the fixed `seed`, nothing persisted.
pub fn proptest_config(cases: u32, seed: u64) -> ProptestConfig {
    ProptestConfig {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        ..ProptestConfig::default()
    }
}

/// Largest `‖p − q‖∞` over two point lists.
pub fn max_abs_diff(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |c| (p[c] - q[c]).abs()))
        .fold(0.0, f64::max)
}

/// A fresh truss oracle of `model` for `scene`'s truss on `mesh`, with the
/// effects the scene asks for.
pub fn scene_oracle(
    model: TrussModel,
    scene: &Scene,
    mesh: &ReflectorMesh,
) -> Box<dyn TrussOracle> {
    truss::oracle(model, scene, &mesh.truss, &SceneEffects::of(scene)).expect("the truss builds")
}

/// The pull of the scene's net (forward FDM with its initial q) on the hinges.
pub fn net_pull(mesh: &ReflectorMesh) -> Vec<[f64; 3]> {
    let (_, eq) = solve_network(&mesh.network).expect("net solves");
    eq.reactions_n
        .iter()
        .map(|r| [-r[0], -r[1], -r[2]])
        .collect()
}

/// `loads` times `s`.
pub fn scaled(loads: &[[f64; 3]], s: f64) -> Vec<[f64; 3]> {
    loads.iter().map(|l| l.map(|v| v * s)).collect()
}

/// `solution`'s state with every node but `clamped` moved by `size` (positions
/// by `size·length_m`, rotations by `size` rad) in fixed random directions.
pub fn perturbed(
    solution: &StaticSolution,
    clamped: &[usize],
    size: f64,
    length_m: f64,
    seed: u64,
) -> State {
    let mut rng = Random(seed);
    let mut state = solution.state.clone();
    for (n, frame) in state.frames.iter_mut().enumerate() {
        let (dx, dt) = (rng.axis(), rng.axis());
        if clamped.contains(&n) {
            continue;
        }
        frame.position_m += dx * (size * length_m);
        frame.rotation = exp(&(dt * size)) * frame.rotation;
    }
    state
}

/// Newton's residual history at the full load, starting from `start`.
pub fn newton_from(solver: &StaticSolver, start: State) -> Vec<f64> {
    let solution = solver
        .solve_from(start, 0.0, &StaticSettings::default())
        .unwrap();
    assert!(solution.converged(), "{:?}", solution.termination);
    assert_eq!(solution.rejected_steps, 0);
    assert_eq!(solution.steps.len(), 1);
    solution.steps[0].residuals.clone()
}

/// Newton from the equilibrium `solution` moved by δ = 1e-4, 1e-5, 1e-6: the
/// first residual r₀ ∝ δ; with the consistent tangent the next is
/// r₁ = C r₀² + o(r₀²), so log r₁ against log r₀ has slope 2 (an inconsistent
/// tangent leaves slope 1). Checked on every decade, with r₁ at least 100
/// times above the roundoff of the assembled forces, `ε · (EA/le) · |x|max`.
/// Returns the smallest slope and the residual histories.
pub fn assert_quadratic(
    solver: &StaticSolver,
    solution: &StaticSolution,
    clamped: &[usize],
    length_m: f64,
    roundoff: f64,
    what: &str,
) -> (f64, Vec<Vec<f64>>) {
    let histories: Vec<Vec<f64>> = [1e-4, 1e-5, 1e-6]
        .iter()
        .map(|&size| {
            let r = newton_from(solver, perturbed(solution, clamped, size, length_m, 7));
            assert!(r.len() >= 2, "{what}: δ = {size} converged at once");
            assert!(
                r[1] >= 100.0 * roundoff,
                "{what}: δ = {size}: r₁ = {:e} is near roundoff {roundoff:e}",
                r[1]
            );
            r
        })
        .collect();
    let pairs: Vec<(f64, f64)> = histories.iter().map(|r| (r[0], r[1])).collect();
    let mut smallest = f64::INFINITY;
    for w in pairs.windows(2) {
        let slope = (w[0].1 / w[1].1).ln() / (w[0].0 / w[1].0).ln();
        assert!(
            slope >= 1.8,
            "{what}: r₁ against r₀ has slope {slope:.3} ({:?})",
            pairs
        );
        smallest = smallest.min(slope);
    }
    (smallest, histories)
}

/// Every entry of a folder with its bytes, by name (a sub-folder: no bytes).
pub fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let path = e.unwrap().path();
            let name = path.file_name().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&path).unwrap_or_default())
        })
        .collect();
    files.sort();
    files
}
