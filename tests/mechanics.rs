//! The multibody statics engine against closed forms: SO(3) maps, the
//! cantilever rolled up by a tip moment (paper §3.4, Tables 1–2) and the
//! Crisfield–Jelenić element's own discrete solution, joints that transmit
//! what they should, Newton's quadratic convergence, arc length through the
//! limit point of a von Mises truss and load control stopping at it (never
//! converging on the snapped-through branch), and named errors for bad frames.

use std::f64::consts::{PI, TAU};

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use ringmesh::frame::cantilever;
use ringmesh::mechanics::rotation::{exp, log, skew, tangent};
use ringmesh::mechanics::{
    ElementKind, Frame, JointKind, MechanicsError, ModelBuilder, NodeId, PathControl, Rod, RodSpec,
    StaticSettings, StaticSolution, StaticSolver, StaticTermination,
};

mod common;

use common::frames::{von_mises, von_mises_limit, von_mises_load, VM_RISE_M};
use common::{angle_between, assert_quadratic, Random};

const EPS: f64 = f64::EPSILON;

// ---------------------------------------------------------------------------
// Rotations

#[test]
fn exp_log_round_trip_recovers_every_rotation_up_to_pi() {
    let mut rng = Random(1);
    let mut angles: Vec<f64> = (0..200).map(|_| PI * rng.next_f64()).collect();
    angles.extend([1e-12, 1e-8, 1e-4, 0.5, 3.0]);
    // Within 1e-6 of π, and π itself, where the logarithm may return −θ.
    angles.extend((6..=15).map(|k| PI - 10f64.powi(-k)));
    angles.push(PI);
    let mut worst_vector = 0.0f64;
    let mut worst_rotation = 0.0f64;
    for &angle in angles.iter().filter(|a| **a > 0.0) {
        let theta = rng.axis() * angle;
        let q = exp(&theta);
        let back = log(&q);
        // The principal logarithm: angle in [0, π], the same rotation.
        assert!(
            back.norm() <= PI * (1.0 + EPS),
            "|log| = {} > π",
            back.norm()
        );
        let rotation_error = angle_between(&exp(&back), &q);
        // exp and log each round a handful of times: a few ε of angle.
        assert!(
            rotation_error <= 8.0 * EPS,
            "angle {angle}: rotation error {rotation_error:e}"
        );
        worst_rotation = worst_rotation.max(rotation_error);
        // The vector itself, except at |θ| = π where θ and −θ are one rotation.
        let vector_error = if PI - angle < 1e-15 {
            (back - theta).norm().min((back + theta).norm())
        } else {
            (back - theta).norm()
        };
        assert!(
            vector_error <= 8.0 * EPS * angle.max(1.0),
            "angle {angle}: |log(exp θ) − θ| = {vector_error:e}"
        );
        worst_vector = worst_vector.max(vector_error / angle.max(1.0));
    }
    eprintln!("exp/log: worst rotation {worst_rotation:e}, worst vector {worst_vector:e}");
}

#[test]
fn log_exp_round_trip_recovers_any_quaternion_from_either_hemisphere() {
    let mut rng = Random(2);
    for _ in 0..200 {
        // A uniform random quaternion, w of either sign.
        let q = nalgebra::Quaternion::new(
            rng.next_f64() - 0.5,
            rng.next_f64() - 0.5,
            rng.next_f64() - 0.5,
            rng.next_f64() - 0.5,
        );
        let q = UnitQuaternion::from_quaternion(q);
        let theta = log(&q);
        assert!(theta.norm() <= PI * (1.0 + EPS));
        let error = angle_between(&exp(&theta), &q);
        assert!(error <= 8.0 * EPS, "{q:?}: {error:e}");
    }
}

#[test]
fn multiplicative_updates_roll_past_two_pi_without_drift() {
    // 1000 spatial increments R ← exp(δθ) R about one axis summing to 2.5 turns:
    // the result is exp of the total angle mod 2π (= π), and every intermediate
    // rotation is exp of its partial sum. Each product rounds at a few ε, so
    // after k updates the error is O(k ε): 1000 updates stay near 1e-13.
    let mut rng = Random(3);
    let axis = rng.axis();
    let updates = 1000;
    let total = 2.5 * TAU;
    let step = total / updates as f64;
    let increment = exp(&(axis * step));
    let mut q = UnitQuaternion::identity();
    let mut worst = 0.0f64;
    for k in 1..=updates {
        q = increment * q;
        let partial = (k as f64 * step) % TAU;
        let expected = exp(&(axis * partial));
        let error = angle_between(&q, &expected);
        // k products of ~4ε each, plus the reference's own rounding of k·δ.
        let bound = 8.0 * EPS * k as f64 + 4.0 * EPS * total;
        assert!(error <= bound, "after {k} updates: {error:e} > {bound:e}");
        worst = worst.max(error);
    }
    let expected = exp(&(axis * (total % TAU)));
    let error = angle_between(&q, &expected);
    assert!(error <= 1e-12, "after 2.5 turns: {error:e}");
    // Not renormalised: the unit norm drifts by roundoff only.
    assert!((q.quaternion().norm() - 1.0).abs() <= 1e-13);
    // Components, up to the quaternion's double cover.
    let components = (q.coords - expected.coords)
        .norm()
        .min((q.coords + expected.coords).norm());
    assert!(components <= 1e-12, "quaternion components: {components:e}");
    // The logarithm recovers the principal angle π about ±axis.
    let back = log(&q);
    assert!((back.norm() - PI).abs() <= 1e-12);
    assert!(back.normalize().cross(&axis).norm() <= 1e-12);
    eprintln!(
        "2.5 turns: final {error:e}, worst intermediate {worst:e}, components {components:e}"
    );
}

#[test]
fn quaternion_and_matrix_forms_agree() {
    let mut rng = Random(4);
    let mut product_q = UnitQuaternion::identity();
    let mut product_m = Matrix3::identity();
    for _ in 0..100 {
        let angle = 2.0 * TAU * rng.next_f64();
        let theta = rng.axis() * angle;
        // Rodrigues (paper eq. 7): R = I + (sin θ/θ) θ̃ + ((1 − cos θ)/θ²) θ̃².
        let s = skew(&theta);
        let rodrigues = Matrix3::identity()
            + s * (angle.sin() / angle)
            + s * s * ((1.0 - angle.cos()) / (angle * angle));
        let q = exp(&theta);
        let m = q.to_rotation_matrix().into_inner();
        assert!((m - rodrigues).amax() <= 16.0 * EPS * angle.max(1.0));
        assert!((m.transpose() * m - Matrix3::identity()).amax() <= 8.0 * EPS);
        assert!((m.determinant() - 1.0).abs() <= 8.0 * EPS);
        // Rotating a vector either way.
        let v = Vector3::new(0.3, -1.2, 2.0);
        assert!((q * v - m * v).amax() <= 8.0 * EPS * v.norm());
        // Matrix → quaternion → the same rotation.
        let back = UnitQuaternion::from_matrix(&m);
        assert!(angle_between(&back, &q) <= 8.0 * EPS);
        // Products compose alike.
        product_q = q * product_q;
        product_m = m * product_m;
    }
    let m = product_q.to_rotation_matrix().into_inner();
    assert!(
        (m - product_m).amax() <= 1e-13,
        "{:e}",
        (m - product_m).amax()
    );
}

#[test]
fn tangent_operator_matches_differences_of_exp() {
    // T(θ) δθ is the spatial increment of exp(θ) along δθ (paper eq. 11–12):
    // column j = d/dh log(exp(θ + h e_j) exp(θ)ᵀ) at h = 0. Central differences
    // with h = 1e-5 carry O(h²) ≈ 1e-10 truncation and O(ε/h) ≈ 1e-11 roundoff.
    let mut rng = Random(5);
    let h = 1e-5;
    let mut worst = 0.0f64;
    for &angle in &[1e-4, 1e-2, 0.5, 1.5, 3.0, PI, 4.0, 6.0, 6.2] {
        let theta = rng.axis() * angle;
        let t = tangent(&theta);
        let base_inverse = exp(&theta).inverse();
        for j in 0..3 {
            let mut d = Vector3::zeros();
            d[j] = h;
            let plus = log(&(exp(&(theta + d)) * base_inverse));
            let minus = log(&(exp(&(theta - d)) * base_inverse));
            let fd = (plus - minus) / (2.0 * h);
            let error = (fd - t.column(j)).norm();
            assert!(
                error <= 1e-8 * t.norm(),
                "angle {angle}, column {j}: {error:e}"
            );
            worst = worst.max(error / t.norm());
        }
    }
    eprintln!("tangent: worst relative error {worst:e}");
}

// ---------------------------------------------------------------------------
// Cantilever rolled up by a tip moment (paper §3.4)

/// The tip moment at `ML/(πEI) = m_ratio`.
fn tip_moment(m_ratio: f64) -> f64 {
    m_ratio * PI * cantilever::BENDING_NM2 / cantilever::LENGTH_M
}

/// Every node of rod `rod` in `solution`, start to end.
fn rod_frames(solver: &StaticSolver, solution: &StaticSolution, rod: usize) -> Vec<Frame> {
    solver.model().rods()[rod]
        .nodes
        .iter()
        .map(|&n| solution.state.frames[n])
        .collect()
}

#[test]
fn crisfield_jelenic_nodes_lie_on_their_discrete_circle() {
    // Under a tip moment the internal force vanishes and the moment is M all
    // along, so every element has Γ = Γ₀ (its chord keeps length le, along
    // the mid rotation) and relative rotation κ le, κ = M/EI: the nodes are the
    // vertices of a regular polygon inscribed in the circle of radius
    // ρ = le/(2 sin(κ le/2)), node i at angle iκle, rotated by iκle about z.
    // This is the element's exact discrete answer, so only roundoff and the
    // solver tolerance separate it from the computed nodes; a tolerance of
    // 1e-12 puts the latter at ~1e-12·θ·L.
    let settings = StaticSettings {
        tolerance: 1e-12,
        ..StaticSettings::default()
    };
    let mut worst = (0.0f64, 0.0f64);
    for elements in [3, 7, 10, 25] {
        for m_ratio in [0.3, 1.0, 2.0] {
            let moment = tip_moment(m_ratio);
            let solver =
                cantilever::model(elements, ElementKind::CrisfieldJelenic, moment).unwrap();
            let solution = solver.solve(&settings).unwrap();
            assert!(solution.converged(), "{:?}", solution.termination);
            let le = cantilever::LENGTH_M / elements as f64;
            let alpha = moment / cantilever::BENDING_NM2 * le;
            let radius = le / (2.0 * (alpha / 2.0).sin());
            for (i, f) in rod_frames(&solver, &solution, 0).iter().enumerate() {
                let a = i as f64 * alpha;
                let vertex = Vector3::new(radius * a.sin(), radius * (1.0 - a.cos()), 0.0);
                let position = (f.position_m - vertex).norm() / cantilever::LENGTH_M;
                let rotation = angle_between(&f.rotation, &exp(&(Vector3::z() * a)));
                assert!(
                    position <= 1e-10,
                    "{elements} elements, ML/πEI = {m_ratio}, node {i}: {position:e} of L"
                );
                assert!(
                    rotation <= 1e-9,
                    "{elements} elements, ML/πEI = {m_ratio}, node {i}: rotation off by {rotation:e}"
                );
                worst = (worst.0.max(position), worst.1.max(rotation));
            }
        }
    }
    eprintln!(
        "CJ polygon: worst position {:e} L, rotation {:e} rad",
        worst.0, worst.1
    );
}

#[test]
fn se3_nodes_lie_on_the_exact_circle() {
    // The SE(3) element is exact for constant curvature: node i at arc length
    // s_i lies at (R sin(s/R), R(1 − cos(s/R))), R = EI/M, rotated by s/R.
    let mut worst = 0.0f64;
    for m_ratio in [0.3, 1.0, 2.0] {
        let moment = tip_moment(m_ratio);
        let solver = cantilever::model(10, ElementKind::Se3, moment).unwrap();
        let solution = solver.solve(&StaticSettings::default()).unwrap();
        assert!(solution.converged(), "{:?}", solution.termination);
        let radius = cantilever::BENDING_NM2 / moment;
        for (i, f) in rod_frames(&solver, &solution, 0).iter().enumerate() {
            let a = i as f64 * cantilever::LENGTH_M / 10.0 / radius;
            let arc = Vector3::new(radius * a.sin(), radius * (1.0 - a.cos()), 0.0);
            let error = (f.position_m - arc).norm() / cantilever::LENGTH_M;
            assert!(
                error <= 1e-9,
                "ML/πEI = {m_ratio}, node {i}: {error:e} of L"
            );
            worst = worst.max(error);
        }
    }
    eprintln!("SE(3) arc: worst {worst:e} L");
}

#[test]
fn cantilever_ten_crisfield_jelenic_elements_beat_the_paper() {
    // Paper Tables 1–2: 2.8 % at ML/πEI = 1 with 10 elements; a correct
    // one-point Simo–Reissner element is within 0.5 % up to 1 and 1 % at the
    // full circle.
    let rows = cantilever::table(10, ElementKind::CrisfieldJelenic).unwrap();
    assert_eq!(rows.len(), cantilever::M_RATIOS.len());
    for r in &rows {
        assert!(r.converged, "ML/πEI = {}", r.m_ratio);
        let bound = if r.m_ratio <= 1.0 { 5e-3 } else { 1e-2 };
        assert!(
            r.relative_error <= bound,
            "ML/πEI = {}: {:.3} % > {:.1} %",
            r.m_ratio,
            100.0 * r.relative_error,
            100.0 * bound
        );
        eprintln!(
            "CJ 10 ML/πEI = {}: {:.4} %",
            r.m_ratio,
            100.0 * r.relative_error
        );
    }
}

#[test]
fn cantilever_fifty_crisfield_jelenic_elements_within_five_hundredths_percent() {
    for r in cantilever::table(50, ElementKind::CrisfieldJelenic).unwrap() {
        assert!(r.converged, "ML/πEI = {}", r.m_ratio);
        assert!(
            r.relative_error <= 5e-4,
            "ML/πEI = {}: {:.4} %",
            r.m_ratio,
            100.0 * r.relative_error
        );
        eprintln!(
            "CJ 50 ML/πEI = {}: {:.5} %",
            r.m_ratio,
            100.0 * r.relative_error
        );
    }
}

#[test]
fn se3_cantilever_is_exact_at_every_load_up_to_the_full_circle() {
    for r in cantilever::table(10, ElementKind::Se3).unwrap() {
        assert!(r.converged, "ML/πEI = {}", r.m_ratio);
        assert!(
            r.relative_error <= 1e-8,
            "ML/πEI = {}: {:e}",
            r.m_ratio,
            r.relative_error
        );
        eprintln!(
            "SE(3) 10 ML/πEI = {}: {:e} ({} steps, {} iterations)",
            r.m_ratio, r.relative_error, r.load_steps, r.newton_iterations
        );
    }
}

// ---------------------------------------------------------------------------
// Newton's convergence

#[test]
fn newton_converges_quadratically_on_the_cantilever() {
    let (ea, le) = (cantilever::section().axial_n, cantilever::LENGTH_M / 10.0);
    let roundoff = EPS * ea / le * cantilever::LENGTH_M;
    for kind in [ElementKind::Se3, ElementKind::CrisfieldJelenic] {
        for m_ratio in [1.0, 2.0] {
            let solver = cantilever::model(10, kind, tip_moment(m_ratio)).unwrap();
            let solution = solver.solve(&StaticSettings::default()).unwrap();
            assert!(solution.converged());
            let clamp = solver.model().rods()[0].start();
            let what = format!("{kind:?} at ML/πEI = {m_ratio}");
            let (slope, _) = assert_quadratic(&solver, &solution, &[clamp], 1.0, roundoff, &what);
            eprintln!("{what}: slope ≥ {slope:.4}");
        }
    }
}

#[test]
fn newton_converges_quadratically_on_a_jointed_frame() {
    // Two rods, a rigid body, a revolute and a fixed joint, two clamps, under a
    // load that turns the hinge by ~0.06 rad: the multiplier terms of the
    // tangent (s Σ μ ∂²g) must be consistent too.
    for joint in [JointKind::Revolute { axis: Vector3::x() }, JointKind::Fixed] {
        let s = shaft(joint, shaft_force(), shaft_moment());
        let solution = s.solver.solve(&StaticSettings::default()).unwrap();
        assert!(solution.converged());
        let clamped = [s.rod1.start(), s.solver.model().rods()[1].end()];
        let roundoff = EPS * cantilever::section().axial_n / 0.25 * 1.5;
        let what = format!("{joint:?} shaft");
        let (slope, _) = assert_quadratic(&s.solver, &solution, &clamped, 1.0, roundoff, &what);
        eprintln!("{what}: slope ≥ {slope:.4}");
    }
}

// ---------------------------------------------------------------------------
// Joints

/// A rod spec of the cantilever's section (EA = GA = 1e4 N, GJ = EI = 100 N·m²).
fn spec(elements: usize) -> RodSpec {
    RodSpec {
        section: cantilever::section(),
        elements,
        kind: ElementKind::Se3,
    }
}

/// Force and moment of a node's support reaction.
fn reaction(solution: &StaticSolution, node: usize) -> (Vector3<f64>, Vector3<f64>) {
    let r = solution.reactions[node];
    (
        Vector3::new(r[0], r[1], r[2]),
        Vector3::new(r[3], r[4], r[5]),
    )
}

fn shaft_force() -> Vector3<f64> {
    Vector3::new(10.0, -15.0, 8.0)
}

fn shaft_moment() -> Vector3<f64> {
    Vector3::new(20.0, 5.0, -10.0)
}

/// A shaft with a coupling: rod 1 clamped at O = 0 along x to P = (1, 0, 0),
/// a body at P joined to rod 1's tip by `joint`, and rod 2 welded to the body
/// at P and running up to Q = (1, 0, 1), where it is clamped. The body carries
/// `force` and `moment`.
struct Shaft {
    solver: StaticSolver,
    rod1: Rod,
    body: NodeId,
}

fn shaft(joint: JointKind, force: Vector3<f64>, moment: Vector3<f64>) -> Shaft {
    let p = Vector3::new(1.0, 0.0, 0.0);
    let mut b = ModelBuilder::new();
    let rod1 = b.add_rod(Vector3::zeros(), p, Vector3::y(), &spec(4));
    let body = b.add_body(p);
    let rod2 = b.add_rod(p, Vector3::new(1.0, 0.0, 1.0), Vector3::x(), &spec(4));
    b.fix(rod1.start(), [true; 6]);
    b.fix(rod2.end(), [true; 6]);
    b.add_joint(joint, rod1.end(), body, p);
    b.add_joint(JointKind::Fixed, rod2.start(), body, p);
    b.add_load(body, force, moment);
    Shaft {
        solver: StaticSolver::new(b.build().unwrap()).unwrap(),
        rod1,
        body,
    }
}

/// The moment rod 1 receives at its tip, from its clamp reaction and deformed
/// tip: rod 1 in equilibrium about O gives `m = −R_m + x_tip × R_f`.
fn moment_into_rod1(s: &Shaft, solution: &StaticSolution) -> Vector3<f64> {
    let (rf, rm) = reaction(solution, s.rod1.start());
    let tip = solution.state.frames[s.rod1.end()].position_m;
    -rm + tip.cross(&rf)
}

#[test]
fn revolute_joint_transmits_no_moment_about_its_axis() {
    // The body takes a general force and moment; rod 2 is the only path for
    // the moment about the hinge axis, so the moment rod 1 receives through
    // the hinge — read from rod 1's clamp reaction — has no component along
    // the hinge's current axis (rod 1's deformed tip tangent), while the
    // components across it reach the rod and bend it. The same frame with a
    // fixed coupling twists rod 1: the claim is not vacuous.
    let (force, moment) = (shaft_force(), shaft_moment());
    let scale = moment.norm() + force.norm() * 1.0;
    let hinge = shaft(JointKind::Revolute { axis: Vector3::x() }, force, moment);
    let solution = hinge.solver.solve(&StaticSettings::default()).unwrap();
    assert!(solution.converged(), "{:?}", solution.termination);
    let tip = solution.state.frames[hinge.rod1.end()];
    let axis = tip.rotation * Vector3::x();
    let m = moment_into_rod1(&hinge, &solution);
    // Equilibrium holds to the solver tolerance (1e-10 of the loads) summed
    // over a few nodes.
    assert!(
        m.dot(&axis).abs() <= 1e-9 * scale,
        "moment along the hinge axis: {:e}",
        m.dot(&axis)
    );
    assert!(m.cross(&axis).norm() >= 0.1 * moment.norm());
    // The hinge turned: the body is rotated about the axis relative to rod 1.
    let body = solution.state.frames[hinge.body];
    let relative = tip.rotation.inverse() * body.rotation;
    let turn = log(&relative);
    assert!(turn.norm() >= 1e-2, "hinge angle {}", turn.norm());
    assert!(
        turn.cross(&Vector3::x()).norm() <= 1e-9,
        "relative rotation off the axis: {turn:?}"
    );

    let welded = shaft(JointKind::Fixed, force, moment);
    let solution = welded.solver.solve(&StaticSettings::default()).unwrap();
    assert!(solution.converged());
    let welded_axis = solution.state.frames[welded.rod1.end()].rotation * Vector3::x();
    let m_welded = moment_into_rod1(&welded, &solution);
    assert!(m_welded.dot(&welded_axis).abs() >= 0.1 * moment.norm());
    eprintln!(
        "revolute: m·a = {:e} (bound {:e}), |m×a| = {:.3}, hinge {:.4} rad; fixed: m·a = {:.3}",
        m.dot(&axis),
        1e-9 * scale,
        m.cross(&axis).norm(),
        turn.norm(),
        m_welded.dot(&welded_axis)
    );
}

#[test]
fn fixed_joint_transmits_all_six_components() {
    // A body welded by a fixed joint to the tip of a clamped rod, away from the
    // joint, is loaded with a general force and moment; nothing else holds it,
    // so each of the six components must pass the joint. The clamp reactions
    // balance the load about the deformed body, R_f = −F,
    // R_m = −(M + x_body × F), the body stays welded (no relative rotation,
    // marker points together), and a body at the tip itself gives exactly the
    // rod loaded at its tip.
    let (force, moment) = (shaft_force(), shaft_moment());
    let p = Vector3::new(1.0, 0.0, 0.0);
    let body_at = Vector3::new(1.3, 0.2, -0.1);
    let mut b = ModelBuilder::new();
    let rod = b.add_rod(Vector3::zeros(), p, Vector3::y(), &spec(4));
    let body = b.add_body(body_at);
    b.fix(rod.start(), [true; 6]);
    b.add_joint(JointKind::Fixed, rod.end(), body, p);
    b.add_load(body, force, moment);
    let solver = StaticSolver::new(b.build().unwrap()).unwrap();
    let solution = solver.solve(&StaticSettings::default()).unwrap();
    assert!(solution.converged(), "{:?}", solution.termination);

    let (rf, rm) = reaction(&solution, rod.start());
    let x_body = solution.state.frames[body].position_m;
    let expected_m = -(moment + x_body.cross(&force));
    let force_error = (rf + force).amax() / force.amax();
    let moment_error = (rm - expected_m).amax() / expected_m.amax();
    assert!(force_error <= 1e-9, "force reaction {rf:?} vs {:?}", -force);
    assert!(
        moment_error <= 1e-9,
        "moment reaction {rm:?} vs {expected_m:?}"
    );
    let tip = solution.state.frames[rod.end()];
    let body_frame = solution.state.frames[body];
    let turned = angle_between(&tip.rotation, &UnitQuaternion::identity());
    assert!(turned >= 0.1, "the tip barely turned: {turned}");
    assert!(angle_between(&tip.rotation, &body_frame.rotation) <= 1e-9);
    let marker = body_frame.position_m + body_frame.rotation * (p - body_at);
    assert!((marker - tip.position_m).norm() <= 1e-9);

    // The body at the tip: the same as loading the rod's tip directly.
    let tip_loaded = |through_body: bool| {
        let mut b = ModelBuilder::new();
        let rod = b.add_rod(Vector3::zeros(), p, Vector3::y(), &spec(4));
        b.fix(rod.start(), [true; 6]);
        if through_body {
            let body = b.add_body(p);
            b.add_joint(JointKind::Fixed, rod.end(), body, p);
            b.add_load(body, force, moment);
        } else {
            b.add_load(rod.end(), force, moment);
        }
        let solver = StaticSolver::new(b.build().unwrap()).unwrap();
        let solution = solver.solve(&StaticSettings::default()).unwrap();
        assert!(solution.converged());
        rod_frames(&solver, &solution, 0)
    };
    let (joined, direct) = (tip_loaded(true), tip_loaded(false));
    let mut worst = 0.0f64;
    for (a, b) in joined.iter().zip(&direct) {
        let error = (a.position_m - b.position_m)
            .norm()
            .max(angle_between(&a.rotation, &b.rotation));
        assert!(error <= 1e-9, "{a:?} vs {b:?}");
        worst = worst.max(error);
    }
    eprintln!(
        "fixed: force {force_error:e}, moment {moment_error:e}, tip turned {turned:.3} rad, through a body vs direct {worst:e}"
    );
}

// ---------------------------------------------------------------------------
// Limit points: the von Mises truss

#[test]
fn arc_length_passes_the_von_mises_limit_point() {
    // Loaded at 1.5 times its limit load, the truss has no equilibrium on its
    // loading branch at λ = 1: arc length must climb to the limit (λ = 2/3),
    // pass it, and come down the unstable branch, where every converged point
    // still satisfies P(y) = λ·1.5 P_lim.
    let (p_lim, _) = von_mises_limit();
    let applied = 1.5 * p_lim;
    let (solver, apex) = von_mises(applied);
    let settings = StaticSettings {
        path: PathControl::ArcLength,
        initial_step: 0.02,
        ..StaticSettings::default()
    };
    let solution = solver.solve(&settings).unwrap();
    let StaticTermination::LimitPoint { limit_load_factor } = solution.termination else {
        panic!("expected a limit point, got {:?}", solution.termination);
    };
    let exact = p_lim / applied;
    // Every converged point lies on the path, which never exceeds the limit.
    assert!(limit_load_factor <= exact * (1.0 + 1e-9));
    // Near the top λ(y) is flat to second order: a sample Δy from the top is
    // low by ½|P''|Δy²/P_app ≈ 900 Δy² — within 2 % for samples ≲ 1 cm of
    // apex travel from it (steps of a few cm for this 10 cm rise).
    assert!(
        limit_load_factor >= 0.98 * exact,
        "limit λ {limit_load_factor} vs {exact}"
    );
    // Up, then down.
    let lambdas: Vec<f64> = solution.steps.iter().map(|s| s.load_factor).collect();
    let top = lambdas
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .unwrap()
        .0;
    assert!(top > 0 && top + 1 < lambdas.len(), "{lambdas:?}");
    assert!(
        lambdas[..=top].windows(2).all(|w| w[1] > w[0]),
        "{lambdas:?}"
    );
    assert!(
        lambdas[top..].windows(2).all(|w| w[1] < w[0]),
        "{lambdas:?}"
    );
    // The last point, past the limit, is on the analytic path and symmetric.
    let x = solution.state.frames[apex].position_m;
    let on_path = (von_mises_load(x.y) - solution.load_factor * applied).abs() / p_lim;
    assert!(on_path <= 1e-8, "off the path by {on_path:e} P_lim");
    assert!(
        x.x.abs() <= 1e-9 && x.z.abs() <= 1e-9,
        "apex left the plane of symmetry: {x:?}"
    );
    eprintln!(
        "arc length: limit λ {limit_load_factor:.6} vs {exact:.6} ({:.3} %), {} steps {lambdas:.4?}, end off the path {on_path:e}",
        100.0 * (limit_load_factor / exact - 1.0),
        lambdas.len()
    );
}

#[test]
fn load_control_does_not_report_a_snapped_through_truss_as_converged() {
    let (p_lim, y_lim) = von_mises_limit();
    for factor in [1.2, 1.5, 3.0] {
        let (solver, apex) = von_mises(factor * p_lim);
        let solution = solver.solve(&StaticSettings::default()).unwrap();
        let y = solution.state.frames[apex].position_m.y;
        assert!(!solution.converged(), "{factor} P_lim: {:?} with the apex at y = {y:.4} (limit at y = {y_lim:.4}, supports at 0)", solution.termination);
    }
}

#[test]
fn load_control_stops_at_the_von_mises_limit_point() {
    // Beyond the limit load the loading branch ends: every step past
    // λ* = P_lim/P is cut (Newton bounces through the unstable states towards
    // the inverted branch instead of contracting onto the predicted point)
    // until it is shorter than min_step, so the solve ends as a limit point
    // whose load factor is within the stall resolution of λ*: the first
    // failing step was shorter than 4·min_step. The apex stays on the loading
    // branch, above the limit height.
    let (p_lim, y_lim) = von_mises_limit();
    let settings = StaticSettings::default();
    for factor in [1.2, 1.5, 3.0] {
        let applied = factor * p_lim;
        let (solver, apex) = von_mises(applied);
        let solution = solver.solve(&settings).unwrap();
        let StaticTermination::LimitPoint { limit_load_factor } = solution.termination else {
            panic!(
                "{factor} P_lim: expected a limit point, got {:?}",
                solution.termination
            );
        };
        assert_eq!(limit_load_factor, solution.load_factor);
        let exact = p_lim / applied;
        assert!(limit_load_factor <= exact * (1.0 + 1e-9));
        assert!(
            exact - limit_load_factor <= 4.0 * settings.min_step,
            "{factor} P_lim: stopped at {limit_load_factor}, limit {exact}"
        );
        let x = solution.state.frames[apex].position_m;
        assert!(
            x.y > y_lim,
            "{factor} P_lim: the apex passed the limit height: {} < {y_lim}",
            x.y
        );
        // The last converged state is an equilibrium of the loading branch.
        let on_path = (von_mises_load(x.y) - solution.load_factor * applied).abs() / p_lim;
        assert!(
            on_path <= 1e-8,
            "{factor} P_lim: off the path by {on_path:e} P_lim"
        );
        eprintln!(
            "load control at {factor} P_lim: limit point at λ {limit_load_factor:.8} vs {exact:.8} (gap {:.1e}), apex y {:.5} (limit {y_lim:.5}), {} steps, {} cut, {} Newton iterations",
            exact - limit_load_factor,
            x.y,
            solution.steps.len(),
            solution.rejected_steps,
            solution.newton_iterations
        );
    }
}

#[test]
fn load_control_converges_on_the_stable_branch_below_the_limit_load() {
    // At 0.8 P_lim the loading branch carries the full load: converged, the
    // apex above the limit height, on the analytic path P(y) = 0.8 P_lim.
    let (p_lim, y_lim) = von_mises_limit();
    let applied = 0.8 * p_lim;
    let (solver, apex) = von_mises(applied);
    let solution = solver.solve(&StaticSettings::default()).unwrap();
    assert_eq!(solution.termination, StaticTermination::Converged);
    let x = solution.state.frames[apex].position_m;
    assert!(
        x.y > y_lim && x.y < VM_RISE_M,
        "apex at y = {} (limit {y_lim})",
        x.y
    );
    let on_path = (von_mises_load(x.y) - applied).abs() / p_lim;
    assert!(on_path <= 1e-8, "off the path by {on_path:e} P_lim");
    assert!(
        x.x.abs() <= 1e-9 && x.z.abs() <= 1e-9,
        "apex off the plane of symmetry: {x:?}"
    );
    eprintln!(
        "0.8 P_lim: apex y {:.5} (limit {y_lim:.5}), {} steps, {} cut",
        x.y,
        solution.steps.len(),
        solution.rejected_steps
    );
}

// ---------------------------------------------------------------------------
// Bad input

fn invalid_item(result: Result<ringmesh::mechanics::Model, MechanicsError>) -> (String, String) {
    match result {
        Err(MechanicsError::Invalid { item, reason }) => (item, reason),
        other => panic!("expected MechanicsError::Invalid, got {other:?}"),
    }
}

#[test]
fn bad_frames_are_refused_naming_the_item() {
    let a = Vector3::zeros();
    let p = Vector3::new(1.0, 0.0, 0.0);

    let mut b = ModelBuilder::new();
    b.add_rod(a, p, Vector3::y(), &spec(2));
    b.add_rod(p, p, Vector3::y(), &spec(2));
    let (item, reason) = invalid_item(b.build());
    assert_eq!(item, "rod 1");
    assert!(reason.contains("zero length"), "{reason}");

    let mut b = ModelBuilder::new();
    let rod = b.add_rod(a, p, Vector3::y(), &spec(2));
    let body = b.add_body(p);
    b.add_joint(JointKind::Fixed, rod.end(), body, p);
    b.add_joint(JointKind::Revolute { axis: Vector3::z() }, rod.end(), 99, p);
    let (item, reason) = invalid_item(b.build());
    assert_eq!(item, "joint 1");
    assert!(reason.contains("node 99"), "{reason}");

    let mut b = ModelBuilder::new();
    let rod = b.add_rod(a, p, Vector3::y(), &spec(2));
    let body = b.add_body(p);
    b.add_joint(JointKind::Fixed, rod.end(), body, p);
    b.add_joint(JointKind::Fixed, body, body, p);
    let (item, reason) = invalid_item(b.build());
    assert_eq!(item, "joint 1");
    assert!(reason.contains("itself"), "{reason}");
}

#[test]
fn an_unsupported_rod_is_refused_as_a_mechanism() {
    // Six rigid-body modes and no support: the tangent is singular, and the
    // small-displacement solve says so instead of returning roundoff-sized
    // pivots' garbage (small systems are factored dense).
    let mut b = ModelBuilder::new();
    let rod = b.add_rod(Vector3::zeros(), Vector3::x(), Vector3::y(), &spec(3));
    b.add_load(rod.end(), Vector3::y(), Vector3::zeros());
    let solver = StaticSolver::new(b.build().unwrap()).unwrap();
    match solver.linear_response() {
        Err(MechanicsError::Mechanism { detail }) => eprintln!("mechanism: {detail}"),
        other => panic!("expected a mechanism, got {:?}", other.map(|s| s.frames[3])),
    }
}

/// A solver of a model of the same structure shares the analysis
/// (`StaticSolver::with_model`) and finds what a fresh solver finds; a model
/// of another structure is refused, naming it.
#[test]
fn a_model_of_the_same_structure_shares_the_analysis_and_another_is_refused() {
    let revolute = JointKind::Revolute { axis: Vector3::x() };
    let first = shaft(revolute, shaft_force(), shaft_moment());
    let second = shaft(revolute, -2.0 * shaft_force(), shaft_moment());
    let shared = first
        .solver
        .with_model(second.solver.model().clone())
        .expect("the same structure");
    let settings = StaticSettings::default();
    let a = shared.solve(&settings).unwrap();
    let b = second.solver.solve(&settings).unwrap();
    assert!(a.converged() && b.converged());
    for (fa, fb) in a.state.frames.iter().zip(&b.state.frames) {
        assert!((fa.position_m - fb.position_m).norm() <= 1e-12);
    }
    // The loaded body is where the two loads differ: it moved.
    let moved = (a.state.frames[second.body].position_m
        - first.solver.solve(&settings).unwrap().state.frames[first.body].position_m)
        .norm();
    assert!(moved > 1e-3, "{moved}");
    let other = shaft(JointKind::Fixed, shaft_force(), shaft_moment());
    let refused = first.solver.with_model(other.solver.model().clone());
    assert!(
        matches!(&refused, Err(e) if e.to_string().contains("another structure")),
        "{:?}",
        refused.err()
    );
}
