//! Curved rods (`arc = { … }` in a frame file, [`ModelBuilder::add_arc_rod`])
//! against closed forms: a reference arc is stress-free, on its circle, with
//! tangent first axes and one relative rotation between all neighbours; a
//! quarter circle under an end moment stays a circle of curvature
//! `1/R + M/EI`, which SE(3) elements reproduce exactly with 1, 4 and 16
//! elements and a polygon of chords through the same nodes does not; the
//! `through_m` form builds the model of the equivalent `centre_m` form; bad
//! arcs are rejected with the key at fault named.

use std::f64::consts::FRAC_PI_2;

use nalgebra::{UnitQuaternion, Vector3};
use ringmesh::frame::{cantilever, FrameFile};
use ringmesh::mechanics::rotation::{log, rod_frame};
use ringmesh::mechanics::{
    CircularArc, ElementKind, Frame, JointKind, ModelBuilder, RodSpec, StaticSettings,
    StaticSolution, StaticSolver, StaticTermination,
};

mod common;

use common::angle_between;

fn spec(elements: usize, kind: ElementKind) -> RodSpec {
    RodSpec {
        section: cantilever::section(),
        elements,
        kind,
    }
}

fn solve(builder: ModelBuilder) -> StaticSolution {
    let solver = StaticSolver::new(builder.build().unwrap()).unwrap();
    let solution = solver.solve(&StaticSettings::default()).unwrap();
    assert_eq!(solution.termination, StaticTermination::Converged);
    solution
}

#[test]
fn a_reference_arc_is_stress_free_on_its_circle_with_tangent_first_axes() {
    // Arcs of a circle of radius 2.5 m about (1, −2, 3) in a tilted plane,
    // `up` nowhere near the plane's normal — 200° in 5 elements, and a half
    // circle in 2 quarter turns: every node on the circle, its first axis the
    // tangent `n̂ × (x − c)/R`, its second axis at the start the one closest
    // to `up`, one relative rotation `Δφ R₀ᵀ n̂` between all neighbours
    // (uniform curvature); unloaded, it does not move and its support takes
    // nothing.
    let centre = Vector3::new(1.0, -2.0, 3.0);
    let normal = Vector3::new(0.3, -0.4, 0.8).normalize();
    let radius = 2.5;
    let u = normal.cross(&Vector3::x()).normalize();
    let v = normal.cross(&u);
    let at = |deg: f64| {
        let a = deg.to_radians();
        centre + (u * a.cos() + v * a.sin()) * radius
    };
    let up = Vector3::new(1.0, 1.0, 0.0);
    for (span_deg, elements) in [(200.0, 5), (180.0, 2)] {
        let (start, end) = (at(10.0), at(10.0 + span_deg));
        for kind in [ElementKind::Se3, ElementKind::CrisfieldJelenic] {
            let what = format!("{span_deg}° in {elements}, {kind:?}");
            let mut b = ModelBuilder::new();
            let arc = CircularArc::Centre {
                centre_m: centre,
                normal: Some(normal * 7.0),
            };
            let rod = b.add_arc_rod(start, end, &arc, up, &spec(elements, kind));
            b.fix(rod.start(), [true; 6]);
            let frames: Vec<Frame> = rod.nodes.iter().map(|&n| *b.frame(n).unwrap()).collect();
            assert_eq!(frames.len(), elements + 1);
            assert_eq!(frames[0].position_m, start);
            assert_eq!(frames[elements].position_m, end);
            let start_frame = rod_frame(&normal.cross(&(start - centre)), &up);
            let step = span_deg.to_radians() / elements as f64;
            let omega = start_frame.inverse() * (normal * step);
            for (i, f) in frames.iter().enumerate() {
                let r = f.position_m - centre;
                assert!(
                    (r.norm() - radius).abs() < 1e-12 * radius,
                    "{what}: node {i}"
                );
                assert!(r.dot(&normal).abs() < 1e-12 * radius, "{what}: node {i}");
                let tangent = normal.cross(&r) / radius;
                assert!(
                    (f.rotation * Vector3::x() - tangent).norm() < 1e-12,
                    "{what}: node {i}"
                );
                let expected =
                    UnitQuaternion::from_scaled_axis(normal * (step * i as f64)) * start_frame;
                assert!(
                    angle_between(&f.rotation, &expected) < 1e-12,
                    "{what}: node {i}"
                );
                if i > 0 {
                    let relative = log(&(frames[i - 1].rotation.inverse() * f.rotation));
                    assert!((relative - omega).norm() < 1e-12, "{what}: element {i}");
                }
            }
            // `up` at the start: the second axis is up's part across the tangent.
            let e1 = start_frame * Vector3::x();
            let closest = (up - e1 * e1.dot(&up)).normalize();
            assert!((frames[0].rotation * Vector3::y() - closest).norm() < 1e-12);

            let solution = solve(b);
            for (i, (s, r)) in solution.state.frames.iter().zip(&frames).enumerate() {
                let moved = (s.position_m - r.position_m).norm() / radius
                    + angle_between(&s.rotation, &r.rotation);
                // Written to fail on NaN, which a max over a fold would drop.
                assert!(moved < 1e-12, "{what}: node {i} moved by {moved:e}");
            }
            for r in solution.reactions[rod.start()] {
                assert!(r.abs() < 1e-9, "{what}: reaction {r:e}");
            }
        }
    }
}

/// The quarter circle of radius `R` about the origin in the x–y plane, from
/// `(R, 0, 0)` to `(0, R, 0)` (turning about +z), clamped at the start, under
/// a moment `M` about +z at the end. The internal moment is `M` everywhere,
/// the axial and shear forces zero, so the rod stays a circular arc of the same
/// length `s = πR/2` and curvature `κ = 1/R + M/EI`: from the start, along +y,
/// it turns by `ψ = κ s` about the centre `(R − 1/κ, 0, 0)`, so the tip is at
/// `(R − 1/κ + cos ψ/κ, sin ψ/κ, 0)` with rotation `exp(ψ ẑ) R₀`.
const RADIUS_M: f64 = 2.0;

fn quarter_tip(moment_nm: f64) -> (Vector3<f64>, UnitQuaternion<f64>) {
    let kappa = 1.0 / RADIUS_M + moment_nm / cantilever::section().bending_nm2[0];
    let psi = kappa * FRAC_PI_2 * RADIUS_M;
    let tip = Vector3::new(
        RADIUS_M - 1.0 / kappa + psi.cos() / kappa,
        psi.sin() / kappa,
        0.0,
    );
    let start = rod_frame(&Vector3::y(), &Vector3::z());
    (
        tip,
        UnitQuaternion::from_scaled_axis(Vector3::z() * psi) * start,
    )
}

/// The tip's position error over `R` and rotation error (rad) of the quarter
/// circle under `moment_nm`: as one arc rod of `elements`, or (`chords`) as
/// that many straight one-element rods between the same nodes, fixed to each
/// other at the nodes.
fn quarter_errors(elements: usize, kind: ElementKind, moment_nm: f64, chords: bool) -> (f64, f64) {
    let (start, end) = (RADIUS_M * Vector3::x(), RADIUS_M * Vector3::y());
    let arc = CircularArc::Centre {
        centre_m: Vector3::zeros(),
        normal: None,
    };
    let mut b = ModelBuilder::new();
    let (root, tip) = if chords {
        let points: Vec<Vector3<f64>> = arc
            .geometry(start, end)
            .unwrap()
            .frames(&Vector3::z(), elements)
            .iter()
            .map(|f| f.position_m)
            .collect();
        let rods: Vec<_> = points
            .windows(2)
            .map(|w| b.add_rod(w[0], w[1], Vector3::z(), &spec(1, kind)))
            .collect();
        for (k, pair) in rods.windows(2).enumerate() {
            b.add_joint(
                JointKind::Fixed,
                pair[0].end(),
                pair[1].start(),
                points[k + 1],
            );
        }
        (rods[0].start(), rods[elements - 1].end())
    } else {
        let rod = b.add_arc_rod(start, end, &arc, Vector3::z(), &spec(elements, kind));
        (rod.start(), rod.end())
    };
    b.fix(root, [true; 6]);
    b.add_load(tip, Vector3::zeros(), Vector3::z() * moment_nm);
    let solution = solve(b);
    let (expected, rotation) = quarter_tip(moment_nm);
    let got = &solution.state.frames[tip];
    (
        (got.position_m - expected).norm() / RADIUS_M,
        angle_between(&got.rotation, &rotation),
    )
}

#[test]
fn a_quarter_circle_under_an_end_moment_stays_a_circle_of_curvature_one_over_r_plus_m_over_ei() {
    // M R/EI = ±1/2: curled to 135°, opened to 45°. SE(3) elements
    // interpolate a uniformly curved rod exactly, so 1 element is as exact as
    // 16 (to the solver's tolerance); chords through the same nodes are a
    // polygon, short of the arc by 1 − sin(Δφ/2)/(Δφ/2) and kinked, and miss
    // the tip by orders of magnitude more, even at 16 elements.
    let ei = cantilever::section().bending_nm2[0];
    for ratio in [0.5, -0.5] {
        let moment = ratio * ei / RADIUS_M;
        for elements in [1, 4, 16] {
            let (arc, arc_rotation) = quarter_errors(elements, ElementKind::Se3, moment, false);
            let (chord, _) = quarter_errors(elements, ElementKind::Se3, moment, true);
            eprintln!(
                "M R/EI = {ratio}, {elements:2} SE(3) elements: tip error / R: arc {arc:.1e} \
                 (rotation {arc_rotation:.1e} rad), chords {chord:.1e}"
            );
            assert!(arc < 1e-9, "{elements} elements: arc tip error {arc:e}");
            assert!(
                arc_rotation < 1e-9,
                "{elements}: arc tip rotation {arc_rotation:e}"
            );
            assert!(chord > 1e-4, "{elements} elements: chords {chord:e}");
            assert!(
                chord > 1e4 * arc.max(1e-12),
                "{elements}: {chord:e} vs {arc:e}"
            );
        }
    }
}

#[test]
fn crisfield_jelenic_arcs_bend_by_m_over_ei_times_the_arc_length() {
    // The Crisfield–Jelenić element's centreline is the chord, so its tip
    // position converges at second order; but its curvature `Ω/L` takes the
    // element's arc length, so the rotation a uniform moment adds, M s/EI
    // over the whole arc, is exact at any mesh (with chord lengths it would
    // be short by M (s − Σ chords)/EI: 8e-2 rad at 1 element).
    let moment = 0.5 * cantilever::section().bending_nm2[0] / RADIUS_M;
    let mut previous = f64::INFINITY;
    for elements in [1, 4, 16] {
        let (position, rotation) =
            quarter_errors(elements, ElementKind::CrisfieldJelenic, moment, false);
        eprintln!(
            "{elements:2} Crisfield–Jelenić elements: tip error / R {position:.1e}, \
             rotation {rotation:.1e} rad"
        );
        assert!(
            rotation < 1e-9,
            "{elements} elements: rotation {rotation:e}"
        );
        if elements > 1 {
            // Second order: 4× the elements, ~16× less error.
            assert!(
                position < previous / 10.0,
                "{elements}: {position:e} vs {previous:e}"
            );
        }
        previous = position;
    }
}

/// A quarter-circle-and-more rod from `(2, 0, 0)`, its arc written `arc`,
/// clamped at the start, a force and a moment on its end.
fn arc_file(end: [f64; 3], arc: &str, elements: usize) -> String {
    format!(
        r#"
[[nodes]]
name = "a"
position_m = [2.0, 0.0, 0.0]
[[nodes]]
name = "b"
position_m = {end:?}

[[rods]]
name = "arc"
start = "a"
end = "b"
axial_n = 1e4
shear_n = [1e4, 1e4]
torsion_nm2 = 100.0
bending_nm2 = [100.0, 100.0]
elements = {elements}
up = [0.0, 0.3, 1.0]
arc = {arc}

[[supports]]
on = {{ rod = "arc", end = "start" }}
fixed = ["all"]

[[loads]]
on = {{ rod = "arc", end = "end" }}
force_n = [1.0, -2.0, 3.0]
moment_nm = [0.0, 0.0, 10.0]
"#
    )
}

#[test]
fn through_m_builds_the_model_of_the_equivalent_centre_m() {
    // The circle of radius 2 about the origin in the x–y plane. Each case:
    // the end, the `through_m` form, its `centre_m` form(s), elements.
    let at = |deg: f64| {
        let a: f64 = deg.to_radians();
        [2.0 * a.cos(), 2.0 * a.sin(), 0.0]
    };
    let cases = [
        (
            "a quarter, the shorter arc",
            at(90.0),
            format!("{{ through_m = {:?} }}", at(30.0)),
            vec![
                "{ centre_m = [0.0, 0.0, 0.0] }".to_string(),
                "{ centre_m = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 2.0] }".to_string(),
            ],
            4,
        ),
        (
            "three quarters, the longer arc (clockwise)",
            at(90.0),
            format!("{{ through_m = {:?} }}", at(200.0)),
            vec!["{ centre_m = [0.0, 0.0, 0.0], normal = [0.0, 0.0, -1.0] }".to_string()],
            6,
        ),
        (
            "a half circle",
            at(180.0),
            format!("{{ through_m = {:?} }}", at(100.0)),
            vec!["{ centre_m = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }".to_string()],
            3,
        ),
    ];
    for (what, end, through, centres, elements) in cases {
        let read = |arc: &str| FrameFile::from_toml(&arc_file(end, arc, elements)).unwrap();
        let reference = read(&through);
        let solution = |file: &FrameFile| {
            StaticSolver::new(file.model.clone())
                .unwrap()
                .solve(&file.settings)
                .unwrap()
        };
        let through_solution = solution(&reference);
        assert_eq!(through_solution.termination, StaticTermination::Converged);
        for centre in centres {
            let file = read(&centre);
            let (a, b) = (reference.model.reference(), file.model.reference());
            assert_eq!(a.len(), elements + 1, "{what}");
            assert_eq!(a.len(), b.len(), "{what}");
            for (i, (a, b)) in a.iter().zip(b).enumerate() {
                let d = (a.position_m - b.position_m).norm();
                let r = angle_between(&a.rotation, &b.rotation);
                assert!(
                    d < 1e-12 && r < 1e-12,
                    "{what}, {centre}: node {i} {d:e} m {r:e} rad"
                );
            }
            let centre_solution = solution(&file);
            for (i, (a, b)) in through_solution
                .state
                .frames
                .iter()
                .zip(&centre_solution.state.frames)
                .enumerate()
            {
                let d = (a.position_m - b.position_m).norm();
                assert!(
                    d < 1e-9,
                    "{what}, {centre}: solved node {i} apart by {d:e} m"
                );
            }
        }
    }
}

#[test]
fn malformed_arcs_name_the_key_at_fault() {
    let quarter = [0.0, 2.0, 0.0];
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "ends not on one circle",
            arc_file([0.0, 2.1, 0.0], "{ centre_m = [0.0, 0.0, 0.0] }", 4),
            "rods[0].arc.centre_m: start is 2.000 m from the centre, end 2.100 m: not on one circle",
        ),
        (
            "a half circle without its normal",
            arc_file([-2.0, 0.0, 0.0], "{ centre_m = [0.0, 0.0, 0.0] }", 4),
            "rods[0].arc.normal: missing: start, centre and end are on one line",
        ),
        (
            "both forms",
            arc_file(quarter, "{ centre_m = [0.0, 0.0, 0.0], through_m = [1.0, 1.0, 0.0] }", 4),
            "rods[0].arc: give either `centre_m` (with an optional `normal`) or `through_m`, not both",
        ),
        (
            "neither form",
            arc_file(quarter, "{ normal = [0.0, 0.0, 1.0] }", 4),
            "rods[0].arc: missing: `centre_m` (with an optional `normal`) or `through_m`",
        ),
        (
            "through a point on the chord",
            arc_file(quarter, "{ through_m = [1.0, 1.0, 0.0] }", 4),
            "rods[0].arc.through_m: start, this point and end are on one line",
        ),
        (
            "through the start",
            arc_file(quarter, "{ through_m = [2.0, 0.0, 0.0] }", 4),
            "rods[0].arc.through_m: is the rod's start",
        ),
        (
            "a normal with through_m",
            arc_file(quarter, "{ through_m = [1.0, 1.5, 0.0], normal = [0.0, 0.0, 1.0] }", 4),
            "rods[0].arc.normal: the circle through the start",
        ),
        (
            "a normal along a radius",
            arc_file(quarter, "{ centre_m = [0.0, 0.0, 0.0], normal = [1.0, 0.0, 1.0] }", 4),
            "rods[0].arc.normal: is not across the plane of the arc",
        ),
        (
            "a zero normal",
            arc_file(quarter, "{ centre_m = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 0.0] }", 4),
            "rods[0].arc.normal: must be a non-zero vector",
        ),
        (
            "the centre at the start",
            arc_file(quarter, "{ centre_m = [2.0, 0.0, 0.0] }", 4),
            "rods[0].arc.centre_m: is the rod's start: the arc has no radius",
        ),
        (
            "a non-finite centre",
            arc_file(quarter, "{ centre_m = [0.0, nan, 0.0] }", 4),
            "rods[0].arc.centre_m: a component is not finite",
        ),
        (
            "three quarters in two elements",
            arc_file(quarter, "{ centre_m = [0.0, 0.0, 0.0], normal = [0.0, 0.0, -1.0] }", 2),
            "rods[0].elements: 2 is too few for an arc of 270.0°: at least 3",
        ),
        (
            "a closed circle",
            arc_file([2.0, 0.0, 0.0], "{ centre_m = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }", 4),
            "rods[0].end: node \"b\" is where the rod starts (node \"a\"): zero length (a closed \
             circle is two arcs, joined)",
        ),
        (
            "an unknown key",
            arc_file(quarter, "{ center_m = [0.0, 0.0, 0.0] }", 4),
            "unknown field `center_m`",
        ),
    ];
    for (what, text, expected) in cases {
        common::frames::assert_refused(what, &text, expected);
    }
    // The engine names the rod and the arc's input on its own.
    let mut b = ModelBuilder::new();
    let arc = CircularArc::Centre {
        centre_m: Vector3::new(0.0, 0.1, 0.0),
        normal: None,
    };
    b.add_arc_rod(
        2.0 * Vector3::x(),
        2.0 * Vector3::y(),
        &arc,
        Vector3::z(),
        &spec(4, ElementKind::Se3),
    );
    let message = b.build().unwrap_err().to_string();
    assert!(
        message.starts_with("rod 0: arc centre_m: start is 2.002 m from the centre, end 1.900 m"),
        "{message}"
    );
    let mut b = ModelBuilder::new();
    let arc = CircularArc::Through {
        through_m: Vector3::new(0.0, -2.0, 0.0),
    };
    b.add_arc_rod(
        2.0 * Vector3::x(),
        2.0 * Vector3::y(),
        &arc,
        Vector3::z(),
        &spec(1, ElementKind::Se3),
    );
    let message = b.build().unwrap_err().to_string();
    assert!(
        message.contains("rod 0: its arc of 270.0° needs at least 3 elements"),
        "{message}"
    );
}
