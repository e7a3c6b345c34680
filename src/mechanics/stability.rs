//! Stability of an equilibrium (DESIGN §5, §9): whether the tangent
//! stiffness is positive definite on the joints' constraints.
//!
//! Load control alone cannot see a bifurcation: a symmetric ring under a
//! symmetric pull stays on its fundamental branch past the buckling load,
//! Newton converging there as well as anywhere. The test here is on the state
//! itself. At equilibrium the tangent is the saddle-point matrix
//! `J = [[H, Aᵀ], [A, 0]]` (`H` the stiffness, `A` the constraint Jacobian),
//! and the frame is stable when `H` is positive definite on `ker A`.
//! Inverse iteration with `J`'s factor finds the reduced eigenvalue of least
//! magnitude: solving `J [z; y] = [W² x; 0]` gives `z ∈ ker A` with
//! `zᵀ H z = zᵀ W² x` — the curvature along `z` comes from the solve itself,
//! without a product with `H`. `W` weights rotations by the mean element
//! length, so eigenvalues are stiffnesses in N/m. The eigenvalue crossing zero
//! first along a path is the least in magnitude just before it does, whatever
//! its multiplicity (a ring's buckling modes come in pairs), and a negative
//! curvature `zᵀ H z < 0` is a certificate of instability.
//!
//! How many eigenvalues are negative is the tangent's inertia
//! ([`negative_eigenvalues`]): by Sylvester's law and the saddle point's
//! structure, `J` has exactly `m` more negative eigenvalues than `H` has on
//! `ker A` (`m` the multipliers, `A` of full rank), and the count is the
//! number of negative pivots of a symmetric indefinite (Bunch–Kaufman)
//! factorisation `P J Pᵀ = L B Lᵀ` — dense up to [`INERTIA_ROWS`] rows, of
//! the congruent augmented tangent by a sparse supernodal one above
//! ([`InertiaStructure`]), so that every symmetric tangent has its count.
//! It changes where, and only where, an eigenvalue crosses zero: a critical
//! point, whichever mode is the least in magnitude on either side.

use faer::Mat;
use serde::Serialize;

use super::assembly::{State, System};
use super::inertia::{negative_pivots, InertiaStructure, SYMMETRY};
use super::model::MechanicsError;
use super::solver::{wdot, StaticSolver};

/// Inverse iterations at most.
const MAX_ITERATIONS: usize = 60;

/// Relative change of the eigenvalue estimate at which inverse iteration stops.
const EIGENVALUE_TOLERANCE: f64 = 1e-4;

/// A curvature counts as negative below this fraction of its roundoff scale
/// `‖z‖_W ‖x‖_W` (as the Newton solver's curvature test).
const CURVATURE_NOISE: f64 = 1e-8;

/// The stability of one equilibrium state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Stability {
    /// The least-magnitude eigenvalue of the stiffness on the constraints
    /// (rotations weighted by the mean element length), N/m: the estimate
    /// inverse iteration reached, or the curvature of the first direction
    /// found negative.
    pub lowest_stiffness_n_per_m: f64,
    /// True when no direction of negative curvature was found.
    pub stable: bool,
    /// Inverse iterations.
    pub iterations: usize,
    /// The direction the estimate belongs to: the lowest mode when stable,
    /// the direction of negative curvature otherwise.
    #[serde(skip)]
    pub mode: Mode,
}

/// A mode shape: every node's translation, scaled so that the largest is 1 m
/// (its sign is arbitrary).
#[derive(Clone, PartialEq, Default)]
pub struct Mode(Vec<[f64; 3]>);

impl Mode {
    /// Every node's translation, m.
    pub fn translations_m(&self) -> &[[f64; 3]] {
        &self.0
    }
}

impl std::fmt::Debug for Mode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Mode({} nodes)", self.0.len())
    }
}

/// The stability of `state`, an equilibrium at load factor `lambda`.
pub(super) fn stability(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Result<Stability, MechanicsError> {
    let run = inverse_iteration(solver, state, lambda, true)?;
    Ok(Stability {
        lowest_stiffness_n_per_m: run.eigenvalue,
        stable: !run.negative,
        iterations: run.iterations,
        mode: translations(solver, &run.vector),
    })
}

/// The least-magnitude eigenvalue of the stiffness on the joints'
/// constraints at `state`, signed, and its eigenvector in unknown order
/// (multipliers zero, weighted norm 1): inverse iteration run to
/// convergence (not stopped at the first negative curvature, as
/// [`stability`] is), so that the value is a continuous function along a
/// path and crosses zero where the path meets a critical point.
pub(super) fn lowest_eigenpair(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Result<EigenPair, MechanicsError> {
    inverse_iteration(solver, state, lambda, false)
}

/// The outcome of inverse iteration.
pub(super) struct EigenPair {
    /// The Rayleigh quotient `zᵀHz / zᵀW²z` of the last iterate, N/m.
    pub eigenvalue: f64,
    /// Some iterate had a curvature below the noise: negative.
    pub negative: bool,
    /// Inverse iterations.
    pub iterations: usize,
    /// The last iterate (unknown order, multipliers zero), weighted norm 1.
    pub vector: Vec<f64>,
}

/// Inverse iteration with the tangent's factor (module doc), stopped at the
/// first direction of negative curvature when `stop_on_negative`.
fn inverse_iteration(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
    stop_on_negative: bool,
) -> Result<EigenPair, MechanicsError> {
    let system = solver.system();
    let ev = system.evaluate(solver.model(), state, lambda);
    let lu = system.factor(&ev.values)?;
    let w = solver.weights();
    let n_free = system.n_free;
    // A start with every component: a fixed pseudo-random sequence.
    let mut x: Vec<f64> = (0..system.n_rows)
        .map(|i| {
            if i < n_free {
                (0.754_877_666 * (i + 1) as f64).fract() - 0.5
            } else {
                0.0
            }
        })
        .collect();
    let mut estimate = f64::NAN;
    let mut negative = false;
    for iteration in 1..=MAX_ITERATIONS {
        let mut rhs = Mat::from_fn(system.n_rows, 1, |i, _| {
            if i < n_free {
                w[i] * w[i] * x[i]
            } else {
                0.0
            }
        });
        System::solve_in_place(&lu, rhs.as_mut());
        let z: Vec<f64> = (0..system.n_rows)
            .map(|i| if i < n_free { rhs[(i, 0)] } else { 0.0 })
            .collect();
        let curvature = wdot(&w, &z, &x);
        let (z_norm, x_norm) = (wdot(&w, &z, &z).sqrt(), wdot(&w, &x, &x).sqrt());
        if !(z_norm.is_finite() && z_norm > 0.0) {
            return Err(MechanicsError::Mechanism {
                detail: "inverse iteration on the tangent gave no finite direction".into(),
            });
        }
        let previous = estimate;
        estimate = curvature / (z_norm * z_norm);
        negative |= curvature < -CURVATURE_NOISE * z_norm * x_norm;
        let settled = (estimate - previous).abs() <= EIGENVALUE_TOLERANCE * estimate.abs();
        x = z.iter().map(|v| v / z_norm).collect();
        if (negative && stop_on_negative) || settled || iteration == MAX_ITERATIONS {
            return Ok(EigenPair {
                eigenvalue: estimate,
                negative,
                iterations: iteration,
                vector: x,
            });
        }
    }
    unreachable!("the last iteration returns")
}

/// Rows up to which the tangent's inertia is counted dense
/// ([`dense_negative_eigenvalues`]): a Bunch–Kaufman factorisation with
/// pivoting over the whole matrix, `n³/3` operations (≈ 0.3 G at 1 000 rows,
/// tens of ms). Above, the sparse count ([`InertiaStructure`]).
pub(super) const INERTIA_ROWS: usize = 1_000;

/// The number of negative eigenvalues of the stiffness on the joints'
/// constraints at `state` (module doc): the negative pivots of a symmetric
/// indefinite factorisation of the tangent, less one per multiplier —
/// dense up to [`INERTIA_ROWS`] rows ([`dense_negative_eigenvalues`]),
/// sparse above ([`InertiaStructure`]). `None` for a tangent with entries
/// that are not finite, or unsymmetric ([`SYMMETRY`]: loads that are not
/// conservative have no energy whose second variation the inertia would
/// count), or whose sparse factorisation could not be analysed or met a
/// pivot that is not finite.
pub(super) fn negative_eigenvalues(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Option<usize> {
    if solver.system().n_rows <= INERTIA_ROWS {
        dense_negative_eigenvalues(solver, state, lambda)
    } else {
        sparse_negative_eigenvalues(solver, state, lambda)
    }
}

/// The tangent's values at `state` (pattern order), `None` when one is not
/// finite: what both counts factor.
fn finite_tangent(solver: &StaticSolver, state: &State, lambda: f64) -> Option<Vec<f64>> {
    let ev = solver.system().evaluate(solver.model(), state, lambda);
    ev.values.iter().all(|v| v.is_finite()).then_some(ev.values)
}

/// [`negative_eigenvalues`] by faer's dense Bunch–Kaufman `LBLᵀ` of the
/// whole tangent, whatever its size.
pub(super) fn dense_negative_eigenvalues(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Option<usize> {
    let system = solver.system();
    let j = system.dense_tangent(&finite_tangent(solver, state, lambda)?);
    let n = system.n_rows;
    let mut largest: f64 = 0.0;
    let mut asymmetry: f64 = 0.0;
    for c in 0..n {
        for r in 0..n {
            largest = largest.max(j[(r, c)].abs());
            asymmetry = asymmetry.max((j[(r, c)] - j[(c, r)]).abs());
        }
    }
    if asymmetry > SYMMETRY * largest {
        return None;
    }
    let symmetric = Mat::from_fn(n, n, |r, c| 0.5 * (j[(r, c)] + j[(c, r)]));
    let lblt = symmetric.lblt(faer::Side::Lower);
    let (diag, sub) = (lblt.B_diag(), lblt.B_subdiag());
    let (diag, sub) = (diag.column_vector(), sub.column_vector());
    let negative = negative_pivots((0..n).map(|i| (diag[i], sub[i])))?;
    Some(negative.saturating_sub(n - system.n_free))
}

/// [`negative_eigenvalues`] by the sparse count ([`InertiaStructure`]),
/// whatever the tangent's size.
pub(super) fn sparse_negative_eigenvalues(
    solver: &StaticSolver,
    state: &State,
    lambda: f64,
) -> Option<usize> {
    let system = solver.system();
    let j = system
        .sparse_tangent(&finite_tangent(solver, state, lambda)?)
        .ok()?;
    let structure = system
        .inertia
        .get_or_init(|| InertiaStructure::new(&j, system.n_free, system.scale).ok())
        .as_ref()?;
    structure.negative_eigenvalues(&j)
}

/// Every node's translation in the unknowns `z` (0 where fixed), scaled so
/// that the largest is 1 m.
pub(super) fn translations(solver: &StaticSolver, z: &[f64]) -> Mode {
    let system = solver.system();
    let mut t: Vec<[f64; 3]> = (0..solver.model().node_count())
        .map(|n| std::array::from_fn(|c| system.unknown(n, c).map_or(0.0, |i| z[i])))
        .collect();
    let largest = t
        .iter()
        .map(|v| crate::algebra::norm3(*v))
        .fold(0.0, f64::max);
    if largest > 0.0 {
        t.iter_mut().flatten().for_each(|v| *v /= largest);
    }
    Mode(t)
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, Vector3};

    use super::*;
    use crate::mechanics::{ElementKind, JointKind, ModelBuilder, RodSpec, Section};
    use crate::mechanics::{StaticSettings, StaticTermination};

    /// A clamped-free column of length 1 m along x in two rods joined by a
    /// fixed joint (so that the tangent has multipliers), bending
    /// stiffnesses 1 and 2 N·m², under an axial tip force `p` (N).
    fn column(p: f64) -> StaticSolver {
        let spec = RodSpec {
            section: Section {
                axial_n: 1e4,
                shear_n: [1e4, 1e4],
                torsion_nm2: 1.0,
                bending_nm2: [1.0, 2.0],
            },
            elements: 4,
            kind: ElementKind::Se3,
        };
        let mut b = ModelBuilder::new();
        let mid = Vector3::new(0.5, 0.0, 0.0);
        let first = b.add_rod(Vector3::zeros(), mid, Vector3::z(), &spec);
        let second = b.add_rod(mid, Vector3::x(), Vector3::z(), &spec);
        b.add_joint(JointKind::Fixed, first.end(), second.start(), mid);
        b.fix(first.start(), [true; 6]);
        b.add_load(second.end(), Vector3::new(-p, 0.0, 0.0), Vector3::zeros());
        StaticSolver::new(b.build().unwrap()).unwrap()
    }

    /// The negative eigenvalues of the stiffness on `ker A`, counted
    /// independently of the factorisation: `ker A` from the eigenvectors
    /// of `AᵀA` with zero eigenvalue, then the eigenvalues of `ZᵀHZ`.
    fn negative_by_eigenvalues(solver: &StaticSolver, state: &State, lambda: f64) -> usize {
        let system = solver.system();
        let ev = system.evaluate(solver.model(), state, lambda);
        let j = system.dense_tangent(&ev.values);
        let (n, m) = (system.n_free, system.n_rows - system.n_free);
        let h = DMatrix::from_fn(n, n, |r, c| 0.5 * (j[(r, c)] + j[(c, r)]));
        let a = DMatrix::from_fn(m, n, |r, c| j[(n + r, c)]);
        let ata = (a.transpose() * &a).symmetric_eigen();
        let top = ata.eigenvalues.amax();
        let kernel: Vec<usize> = (0..n)
            .filter(|&i| ata.eigenvalues[i] <= 1e-10 * top)
            .collect();
        assert_eq!(kernel.len(), n - m, "A has full rank");
        let z = DMatrix::from_fn(n, kernel.len(), |r, c| ata.eigenvectors[(r, kernel[c])]);
        let reduced = (z.transpose() * h * &z).symmetric_eigen();
        let scale = reduced.eigenvalues.amax();
        reduced
            .eigenvalues
            .iter()
            .filter(|&&e| e < -1e-10 * scale)
            .count()
    }

    #[test]
    fn the_inertia_counts_the_negative_eigenvalues_on_the_constraints() {
        // Euler's clamped-free loads π²EI/(4L²): 2.467 N and 4.935 N.
        let first = std::f64::consts::PI.powi(2) / 4.0;
        for (p, expected) in [(0.5 * first, 0), (1.5 * first, 1), (3.0 * first, 2)] {
            let solver = column(p);
            let solution = solver.solve(&StaticSettings::default()).unwrap();
            assert_eq!(solution.termination, StaticTermination::Converged, "{p}");
            let counted = negative_eigenvalues(&solver, &solution.state, 1.0);
            let independent = negative_by_eigenvalues(&solver, &solution.state, 1.0);
            assert_eq!(independent, expected, "P = {p} N");
            assert_eq!(counted, Some(expected), "P = {p} N");
            let sparse = sparse_negative_eigenvalues(&solver, &solution.state, 1.0);
            assert_eq!(sparse, Some(expected), "P = {p} N");
        }
    }

    /// The dense and sparse counts at equilibria of `file` under its loads
    /// times each of `factors` (increasing), each solved by load control
    /// from the last: the fundamental path, through and past its
    /// bifurcations. Returns the counts.
    fn counts_along(file: &crate::frame::FrameFile, factors: &[f64]) -> Vec<usize> {
        let mut solver = StaticSolver::new(file.model.clone()).unwrap();
        let base = file.model.loads().to_vec();
        let settings = StaticSettings {
            max_step: 0.25,
            ..StaticSettings::default()
        };
        let (mut state, mut last) = (solver.reference_state(), 0.0);
        let mut counts = Vec::new();
        for &t in factors {
            let scaled = base
                .iter()
                .map(|l| crate::mechanics::NodalLoad {
                    force_n: l.force_n * t,
                    moment_nm: l.moment_nm * t,
                    ..*l
                })
                .collect();
            solver.model_mut().set_loads(scaled).unwrap();
            let solution = solver.solve_from(state, last / t, &settings).unwrap();
            assert_eq!(solution.termination, StaticTermination::Converged, "× {t}");
            let dense = dense_negative_eigenvalues(&solver, &solution.state, 1.0);
            let sparse = sparse_negative_eigenvalues(&solver, &solution.state, 1.0);
            assert!(dense.is_some(), "× {t}");
            assert_eq!(sparse, dense, "× {t}");
            counts.push(dense.unwrap());
            (state, last) = (solution.state, t);
        }
        counts
    }

    /// The Argyris frame (`tests/critical_points.rs`): 2 × 10 elements, a
    /// fixed joint at the corner, so the second leg is held by the joint
    /// alone; bending stiffnesses `[in-plane, out-of-plane]`, tip force
    /// 1 N across the second leg.
    fn argyris(bending: [f64; 2]) -> crate::frame::FrameFile {
        let text = format!(
            r#"
nodes = [
  {{ name = "root", position_m = [0.0, 0.0, 0.0] }},
  {{ name = "corner", position_m = [240.0, 0.0, 0.0] }},
  {{ name = "tip", position_m = [240.0, 240.0, 0.0] }},
]
[sections.s]
axial_n = 1.28232e6
shear_n = [4.8942e5, 4.8942e5]
torsion_nm2 = 58730.4
bending_nm2 = {bending:?}
[[rods]]
name = "leg1"
start = "root"
end = "corner"
section = "s"
elements = 10
up = [0.0, 0.0, 1.0]
[[rods]]
name = "leg2"
start = "corner"
end = "tip"
section = "s"
elements = 10
up = [0.0, 0.0, 1.0]
[[joints]]
kind = "fixed"
a = {{ rod = "leg1", end = "end" }}
b = {{ rod = "leg2", end = "start" }}
[[supports]]
on = {{ rod = "leg1", end = "start" }}
fixed = ["all"]
[[loads]]
on = {{ rod = "leg2", end = "end" }}
force_n = [-1.0, 0.0, 0.0]
"#
        );
        crate::frame::FrameFile::from_toml(&text).unwrap()
    }

    #[test]
    fn the_sparse_count_is_the_dense_one_through_the_argyris_frames_buckling() {
        // Deep section: lateral buckling between 0.6 and 0.7 N, a second
        // mode between 2.4 and 2.5 N on the (unstable) fundamental path.
        let file = argyris([9.6174e7, 38470.0]);
        let factors: Vec<f64> = (1..=30).map(|k| 0.1 * k as f64).collect();
        let counts = counts_along(&file, &factors);
        assert_eq!((counts[0], counts[9], counts[29]), (0, 1, 2), "{counts:?}");
    }

    #[test]
    fn the_sparse_count_is_the_dense_one_through_the_ring_trusss_buckling() {
        // 1 038 rows (above INERTIA_ROWS: the sparse count is the one
        // paths use here). Hinge bodies held by revolute and fixed joints only; the file's
        // radial loads turned down (−z), so that battens and diagonals
        // carry the compression.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("problems/frames/ring-truss-frame.toml");
        let mut file = crate::frame::FrameFile::read(&path).unwrap();
        let down = file
            .model
            .loads()
            .iter()
            .map(|l| crate::mechanics::NodalLoad {
                force_n: nalgebra::Vector3::new(0.0, 0.0, -l.force_n.norm()),
                ..*l
            })
            .collect();
        file.model.set_loads(down).unwrap();
        // A pair of modes crosses between 5.39 and 5.41 × the loads: the
        // count jumps from 0 to 2 there (load control stops near 5.68).
        let factors: Vec<f64> = (1..=10)
            .map(|k| 0.5 * k as f64)
            .chain((1..=20).map(|k| 5.0 + 0.034 * k as f64))
            .collect();
        let counts = counts_along(&file, &factors);
        assert_eq!(counts[0], 0, "{counts:?}");
        assert_eq!(*counts.last().unwrap(), 2, "{counts:?}");
        assert!(counts.windows(2).all(|w| w[0] <= w[1]), "{counts:?}");
    }

    #[test]
    fn a_moment_fixed_in_space_leaves_the_inertia_uncounted_dense_or_sparse() {
        // Not conservative under finite rotations: the tangent is
        // unsymmetric by the moment's size, and no energy's second
        // variation is there to count.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("problems/frames/cantilever-moment.toml");
        let file = crate::frame::FrameFile::read(&path).unwrap();
        let solver = StaticSolver::new(file.model.clone()).unwrap();
        let solution = solver.solve(&file.settings).unwrap();
        assert_eq!(solution.termination, StaticTermination::Converged);
        let state = &solution.state;
        assert_eq!(dense_negative_eigenvalues(&solver, state, 1.0), None);
        assert_eq!(sparse_negative_eigenvalues(&solver, state, 1.0), None);
        // The unloaded reference is symmetric: counted, both ways.
        let reference = solver.reference_state();
        assert_eq!(
            dense_negative_eigenvalues(&solver, &reference, 0.0),
            Some(0)
        );
        assert_eq!(
            sparse_negative_eigenvalues(&solver, &reference, 0.0),
            Some(0)
        );
    }
}
