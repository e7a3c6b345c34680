//! Frames with closed-form equilibrium paths, shared by the statics tests:
//! the von Mises truss.

use nalgebra::Vector3;
use ringmesh::frame::{cantilever, FrameFile};
use ringmesh::mechanics::{
    ElementKind, JointKind, ModelBuilder, NodeId, RodSpec, Section, StaticSolver,
};

/// Half span, rise (m) and bar stiffness EA (N) of the truss: a shallow truss
/// (rise/span 0.05) of bars that neither buckle (Euler load π²EI/L₀² ≈ 980 N
/// against a bar force below 50 N) nor bend (loads at the pins only).
pub const VM_HALF_SPAN_M: f64 = 1.0;
pub const VM_RISE_M: f64 = 0.1;
pub const VM_EA_N: f64 = 1e4;

/// The von Mises truss: two bars from (∓b, 0, 0) to the apex (0, h, 0), one
/// element each, pinned about z at the supports (out of plane they are
/// clamped), joined at the apex by a spherical joint, the apex loaded
/// downward by `load_n`.
pub fn von_mises(load_n: f64) -> (StaticSolver, NodeId) {
    let (solver, apex, _) = von_mises_loaded(load_n, None);
    (solver, apex)
}

/// [`von_mises`] loaded through a vertical spring of stiffness
/// `spring_n_per_m` (a bar 1 m long above the apex, joined to it by a
/// spherical joint, its top sliding along y without turning), or at the
/// apex without one: the solver, the apex and the loaded node.
pub fn von_mises_loaded(
    load_n: f64,
    spring_n_per_m: Option<f64>,
) -> (StaticSolver, NodeId, NodeId) {
    let bar = |axial_n: f64| RodSpec {
        section: Section {
            axial_n,
            ..cantilever::section()
        },
        elements: 1,
        kind: ElementKind::Se3,
    };
    let apex = Vector3::new(0.0, VM_RISE_M, 0.0);
    let mut b = ModelBuilder::new();
    let left = b.add_rod(
        Vector3::new(-VM_HALF_SPAN_M, 0.0, 0.0),
        apex,
        Vector3::z(),
        &bar(VM_EA_N),
    );
    let right = b.add_rod(
        Vector3::new(VM_HALF_SPAN_M, 0.0, 0.0),
        apex,
        Vector3::z(),
        &bar(VM_EA_N),
    );
    let pin = [true, true, true, true, true, false];
    b.fix(left.start(), pin);
    b.fix(right.start(), pin);
    b.add_joint(JointKind::Spherical, left.end(), right.end(), apex);
    let loaded = match spring_n_per_m {
        None => left.end(),
        Some(k) => {
            let spring = b.add_rod(apex, apex + Vector3::y(), Vector3::z(), &bar(k));
            b.fix(spring.end(), [true, false, true, true, true, true]);
            b.add_joint(JointKind::Spherical, left.end(), spring.start(), apex);
            spring.end()
        }
    };
    b.add_load(loaded, Vector3::new(0.0, -load_n, 0.0), Vector3::zeros());
    (
        StaticSolver::new(b.build().unwrap()).unwrap(),
        left.end(),
        loaded,
    )
}

/// The apex load that holds the apex at height `y`. Straight bars of length
/// `L = √(b² + y²)` carry `N = EA (L − L₀)/L₀` (the elements' axial strain),
/// so vertical equilibrium gives `P(y) = −2 N y/L = 2 EA y (1/L − 1/L₀)`.
pub fn von_mises_load(y: f64) -> f64 {
    let (b, h) = (VM_HALF_SPAN_M, VM_RISE_M);
    let l0 = (b * b + h * h).sqrt();
    let l = (b * b + y * y).sqrt();
    2.0 * VM_EA_N * y * (1.0 / l - 1.0 / l0)
}

/// The limit load: `dP/dy = 2EA (b²/L³ − 1/L₀) = 0` at `L³ = b² L₀`
/// (≈ 3.81 N here; the shallow-truss formula `EA h³/(3√3 b³)·2` gives 3.85 N).
pub fn von_mises_limit() -> (f64, f64) {
    let (b, h) = (VM_HALF_SPAN_M, VM_RISE_M);
    let l0 = (b * b + h * h).sqrt();
    let l = (b * b * l0).cbrt();
    let y = (l * l - b * b).sqrt();
    (von_mises_load(y), y)
}

/// Length (m) and weak bending stiffness (N·m²) of the Euler columns; the
/// other plane 10 × stiffer, so that one mode buckles first, and EA, GA
/// 1e6 × EI/L², so that shortening and shear move the critical load by
/// ~1e-6 of it, far below the discretisation's h² error.
pub const COLUMN_LENGTH_M: f64 = 1.0;
pub const COLUMN_EI_NM2: f64 = 1.0;

/// How an Euler column is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ColumnEnds {
    /// Clamped at x = 0, free at x = L: `P_cr = π²EI/(4L²)`, mode `1 − cos(πx/2L)`.
    ClampedFree,
    /// Pinned at both ends (the far end free to slide along x, every end
    /// free to turn but not about the axis): `P_cr = π²EI/L²`, mode `sin(πx/L)`.
    PinnedPinned,
}

impl ColumnEnds {
    /// The continuum critical load, N.
    pub fn critical_load_n(self) -> f64 {
        let euler = std::f64::consts::PI.powi(2) * COLUMN_EI_NM2 / COLUMN_LENGTH_M.powi(2);
        match self {
            ColumnEnds::ClampedFree => euler / 4.0,
            ColumnEnds::PinnedPinned => euler,
        }
    }

    /// The continuum mode's lateral deflection at `x`, largest 1.
    pub fn mode(self, x: f64) -> f64 {
        let s = x / COLUMN_LENGTH_M;
        match self {
            ColumnEnds::ClampedFree => 1.0 - (std::f64::consts::FRAC_PI_2 * s).cos(),
            ColumnEnds::PinnedPinned => (std::f64::consts::PI * s).sin(),
        }
    }
}

/// A straight column along x of `elements` SE(3) elements, compressed by
/// `load_n` at x = L; returns the solver and the rod's nodes. The section's
/// weak bending is about z (deflection along y).
pub fn euler_column(
    ends: ColumnEnds,
    elements: usize,
    load_n: f64,
    stiff_sections: (f64, f64),
) -> (StaticSolver, Vec<NodeId>) {
    let (axial, shear) = stiff_sections;
    let spec = RodSpec {
        section: Section {
            axial_n: axial,
            shear_n: [shear, shear],
            torsion_nm2: COLUMN_EI_NM2,
            bending_nm2: [COLUMN_EI_NM2, 10.0 * COLUMN_EI_NM2],
        },
        elements,
        kind: ElementKind::Se3,
    };
    let mut b = ModelBuilder::new();
    let rod = b.add_rod(
        Vector3::zeros(),
        Vector3::new(COLUMN_LENGTH_M, 0.0, 0.0),
        Vector3::z(),
        &spec,
    );
    match ends {
        ColumnEnds::ClampedFree => b.fix(rod.start(), [true; 6]),
        ColumnEnds::PinnedPinned => {
            b.fix(rod.start(), [true, true, true, true, false, false]);
            b.fix(rod.end(), [false, true, true, false, false, false]);
        }
    }
    b.add_load(rod.end(), Vector3::new(-load_n, 0.0, 0.0), Vector3::zeros());
    (StaticSolver::new(b.build().unwrap()).unwrap(), rod.nodes)
}

/// Radius (m) and in-plane bending stiffness (N·m²) of the ring; out of
/// plane and in torsion 10 × stiffer (its out-of-plane critical load is
/// then far above the in-plane one), EA and GA 1e6 × EI/R².
pub const RING_RADIUS_M: f64 = 1.0;
pub const RING_EI_NM2: f64 = 1.0;

/// A quarter of a circular ring (one arc rod of `elements` elements from
/// θ = 0 to θ = π/2 in the x–y plane) with the supports of its symmetry
/// about both axes — each end held tangentially, out of plane and in
/// rotation, free radially — under uniform radial dead loads `q` (N/m,
/// inward) lumped at the nodes (half at each end). The symmetric modes of
/// the whole ring (cos 2θ, cos 4θ, …) are its modes, and no rigid rotation
/// enters them. Returns the solver and the rod's nodes.
pub fn quarter_ring(elements: usize, q: f64) -> (StaticSolver, Vec<NodeId>) {
    use ringmesh::mechanics::CircularArc;
    let (r, ei) = (RING_RADIUS_M, RING_EI_NM2);
    let spec = RodSpec {
        section: Section {
            axial_n: 1e6 * ei / (r * r),
            shear_n: [1e6 * ei / (r * r); 2],
            torsion_nm2: 10.0 * ei,
            bending_nm2: [ei, 10.0 * ei],
        },
        elements,
        kind: ElementKind::Se3,
    };
    let mut b = ModelBuilder::new();
    let rod = b.add_arc_rod(
        Vector3::new(r, 0.0, 0.0),
        Vector3::new(0.0, r, 0.0),
        &CircularArc::Centre {
            centre_m: Vector3::zeros(),
            normal: Some(Vector3::z()),
        },
        Vector3::z(),
        &spec,
    );
    b.fix(rod.start(), [false, true, true, true, true, true]);
    b.fix(rod.end(), [true, false, true, true, true, true]);
    let step = std::f64::consts::FRAC_PI_2 / elements as f64;
    for (i, &n) in rod.nodes.iter().enumerate() {
        let theta = i as f64 * step;
        let share = if i == 0 || i == elements { 0.5 } else { 1.0 };
        let force = -q * r * step * share * Vector3::new(theta.cos(), theta.sin(), 0.0);
        b.add_load(n, force, Vector3::zeros());
    }
    (StaticSolver::new(b.build().unwrap()).unwrap(), rod.nodes)
}

/// The frame file `text` is refused as bad input with a message containing
/// `expected` (`what` names the case).
pub fn assert_refused(what: &str, text: &str, expected: &str) {
    let error = match FrameFile::from_toml(text) {
        Ok(_) => panic!("{what}: accepted"),
        Err(e) => e,
    };
    assert!(error.is_bad_input(), "{what}");
    let message = error.to_string();
    assert!(
        message.contains(expected),
        "{what}: {message:?} does not contain {expected:?}"
    );
}
