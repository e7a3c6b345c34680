//! Critical points are changes of the tangent's inertia (issue 40 items 10
//! and 11), on the Argyris right-angle frame: two legs of 240 m at a right
//! angle, clamped at one end, a deep narrow section (in-plane bending
//! stiffness 2 500 × the out-of-plane), an in-plane tip force across the
//! second leg; it buckles laterally (out of plane) from a planar
//! fundamental path that load control never leaves.
//!
//! * Load control, the default solver, loaded to 1.2 × the bifurcation load
//!   arc length locates: it reports the bifurcation it passed within 1e-4
//!   of arc length's, and that the full load lies on an unstable branch
//!   (exit 3, the target named).
//! * Arc length followed far past the buckling reports exactly one
//!   bifurcation, and the count of negative eigenvalues stays 1 from it to
//!   the end (the count is checked against an independent eigenvalue count
//!   in the unit tests of `mechanics::stability`).
//!
//! Item 11's own case is a planar portal frame of tubes (equal bending
//! stiffness in and out of its plane) whose columns buckle out of plane,
//! followed by arc length past that buckling: past it, the least-magnitude
//! eigenvalue switches from the negative out-of-plane mode to the positive
//! in-plane sway mode (their magnitudes cross), a sign change the
//! least-eigenvalue test read as a crossing. Meshed finely, its tangent has
//! more rows than the dense count takes: the sparse count sees it through.

mod common;

use ringmesh::frame::FrameFile;
use ringmesh::mechanics::{CriticalKind, PathSolution, StaticSolver, StaticTermination};

/// The Argyris frame's file: tip force `force_n` along −x, followed by
/// `path` to the load factor `target`.
fn argyris(force_n: f64, path: &str, target: f64) -> String {
    format!(
        r#"
[[nodes]]
name = "root"
position_m = [0.0, 0.0, 0.0]
[[nodes]]
name = "corner"
position_m = [240.0, 0.0, 0.0]
[[nodes]]
name = "tip"
position_m = [240.0, 240.0, 0.0]

# E = 71 240, G = 27 190, a 30 × 0.6 section (Argyris et al. 1979).
[sections.deep]
axial_n = 1.28232e6
shear_n = [4.8942e5, 4.8942e5]
torsion_nm2 = 58730.4
bending_nm2 = [9.6174e7, 38470.0]

[[rods]]
name = "leg1"
start = "root"
end = "corner"
section = "deep"
elements = 10
up = [0.0, 0.0, 1.0]
[[rods]]
name = "leg2"
start = "corner"
end = "tip"
section = "deep"
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
force_n = [{force_n:?}, 0.0, 0.0]

[solver]
path = "{path}"
max_step = 0.05

[path]
target = {{ load_factor = {target:?} }}

[output]
nodes = ["tip"]
"#
    )
}

fn follow(text: &str) -> PathSolution {
    let file = FrameFile::from_toml(text).unwrap();
    StaticSolver::new(file.model.clone())
        .unwrap()
        .follow_path(&file.path, &file.settings)
        .unwrap()
}

fn bifurcations(path: &PathSolution) -> Vec<f64> {
    path.critical_points
        .iter()
        .filter(|c| c.kind == CriticalKind::Bifurcation)
        .map(|c| c.load_factor)
        .collect()
}

/// The lateral buckling load arc length locates, N (tip force 1 N × its
/// load factor).
fn arc_length_critical_force() -> f64 {
    let path = follow(&argyris(-1.0, "arc_length", 1.0));
    assert_eq!(path.solution.termination, StaticTermination::Converged);
    let found = bifurcations(&path);
    assert_eq!(found.len(), 1, "{:?}", path.critical_points);
    found[0]
}

#[test]
fn load_control_past_the_bifurcation_reports_it_and_the_unstable_end() {
    let p_cr = arc_length_critical_force();
    let path = follow(&argyris(-1.2 * p_cr, "load", 1.0));
    // Load control reaches the full load on the fundamental path …
    assert_eq!(path.solution.termination, StaticTermination::Converged);
    // … having passed the bifurcation, located as arc length locates it.
    let found = bifurcations(&path);
    assert_eq!(found.len(), 1, "{:?}", path.critical_points);
    let located = 1.2 * p_cr * found[0];
    assert!(
        (located - p_cr).abs() <= 1e-4 * p_cr,
        "load control: {located} N, arc length: {p_cr} N"
    );
    // Its end is on the unstable branch: one negative eigenvalue.
    assert_eq!(path.final_negative_eigenvalues, Some(1));
    let last = path.points.last().unwrap();
    assert_eq!(last.negative_eigenvalues, Some(1));
    assert_eq!(path.points[0].negative_eigenvalues, Some(0));

    // The command says so and exits 3, naming the target it reached.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("argyris.toml");
    std::fs::write(&file, argyris(-1.2 * p_cr, "load", 1.0)).unwrap();
    let out = dir.path().join("frame.json");
    let run = common::ringmesh(&["frame", file.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("reached the full load (load factor 1) on an UNSTABLE branch"),
        "{stderr}"
    );
    assert!(out.exists());
}

#[test]
fn below_the_bifurcation_load_control_is_a_plain_success() {
    let p_cr = arc_length_critical_force();
    let path = follow(&argyris(-0.9 * p_cr, "load", 1.0));
    assert_eq!(path.solution.termination, StaticTermination::Converged);
    assert!(
        path.critical_points.is_empty(),
        "{:?}",
        path.critical_points
    );
    assert_eq!(path.final_negative_eigenvalues, Some(0));
}

#[test]
fn arc_length_far_past_the_buckling_reports_exactly_one_bifurcation() {
    let p_cr = arc_length_critical_force();
    let path = follow(&argyris(-1.0, "arc_length", 3.0 * p_cr));
    assert_eq!(path.solution.termination, StaticTermination::Converged);
    let found = bifurcations(&path);
    assert_eq!(found.len(), 1, "{:?}", path.critical_points);
    assert!((found[0] - p_cr).abs() <= 1e-6 * p_cr);
    // One negative eigenvalue from the bifurcation to the end, none before.
    for p in &path.points {
        let expected = usize::from(p.load_factor > found[0]);
        assert_eq!(
            p.negative_eigenvalues,
            Some(expected),
            "λ = {}",
            p.load_factor
        );
    }
}

/// A displacement target not reached is named as such, not "the full
/// load".
#[test]
fn an_exit_3_names_the_target_not_reached() {
    let dir = tempfile::tempdir().unwrap();
    let text = argyris(-1.0, "arc_length", 1.0).replace(
        "target = { load_factor = 1.0 }",
        "target = { on = { node = \"tip\" }, component = \"x\", displacement_m = -50.0 }",
    );
    let file = dir.path().join("argyris.toml");
    std::fs::write(
        &file,
        text.replace("max_step = 0.05", "max_step = 0.05\nmax_steps = 3"),
    )
    .unwrap();
    let out = dir.path().join("frame.json");
    let run = common::ringmesh(&["frame", file.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("ended before the target x displacement -50 m of")
            && !stderr.contains("full load"),
        "{stderr}"
    );
}

/// A portal frame in the x–y plane: two columns of 4 m clamped at their
/// feet, a beam of 4 m fixed to their tops, every rod a 24/22 mm tube
/// (E = 160 GPa, G = 60 GPa: bending stiffness 766 N·m² about both axes,
/// torsion 574.6 N·m²) of `elements` elements, 100 N down on each top
/// corner, followed by arc length to the load factor `target`.
///
/// The columns buckle out of plane first, together (the beam translating
/// and turning about its own axis, so restraining nothing): each a
/// cantilever, `P = π²EI/(4H²)` = 118.13 N, by shear `1/(1/P + 1/GA)`
/// = 118.12 N. In plane they sway with the beam restraining their tops,
/// above 3 × 100 N.
fn portal(elements: usize, target: f64) -> String {
    format!(
        r#"
nodes = [
  {{ name = "a", position_m = [0.0, 0.0, 0.0] }},
  {{ name = "b", position_m = [0.0, 4.0, 0.0] }},
  {{ name = "c", position_m = [4.0, 4.0, 0.0] }},
  {{ name = "d", position_m = [4.0, 0.0, 0.0] }},
]

[sections.tube]
axial_n = 1.156e7
shear_n = [2.2e6, 2.2e6]
torsion_nm2 = 574.6
bending_nm2 = [766.0, 766.0]

[[rods]]
name = "left"
start = "a"
end = "b"
section = "tube"
elements = {elements}
up = [0.0, 0.0, 1.0]
[[rods]]
name = "beam"
start = "b"
end = "c"
section = "tube"
elements = {elements}
up = [0.0, 0.0, 1.0]
[[rods]]
name = "right"
start = "d"
end = "c"
section = "tube"
elements = {elements}
up = [0.0, 0.0, 1.0]

[[joints]]
kind = "fixed"
a = {{ rod = "left", end = "end" }}
b = {{ rod = "beam", end = "start" }}
[[joints]]
kind = "fixed"
a = {{ rod = "beam", end = "end" }}
b = {{ rod = "right", end = "end" }}

[[supports]]
on = {{ rod = "left", end = "start" }}
fixed = ["all"]
[[supports]]
on = {{ rod = "right", end = "start" }}
fixed = ["all"]

[[loads]]
on = {{ rod = "beam", end = "start" }}
force_n = [0.0, -100.0, 0.0]
[[loads]]
on = {{ rod = "beam", end = "end" }}
force_n = [0.0, -100.0, 0.0]

[solver]
path = "arc_length"
max_step = 0.05

[path]
target = {{ load_factor = {target:?} }}

[output]
nodes = [{{ rod = "beam", end = "start" }}]
"#
    )
}

/// Issue 40 item 11: past the out-of-plane buckling the least eigenvalue
/// switches modes, and exactly one bifurcation is reported, the inertia 1
/// from it to the end.
#[test]
fn a_portal_with_equal_bending_stiffnesses_reports_only_its_real_bifurcation() {
    // 60 elements per rod: 183 nodes, 1 098 unknowns and 12 multipliers
    // less 12 fixed components = 1 098 rows, above the dense count's 1 000.
    let path = follow(&portal(60, 3.0));
    assert_eq!(path.solution.termination, StaticTermination::Converged);
    let found = bifurcations(&path);
    assert_eq!(found.len(), 1, "{:?}", path.critical_points);
    assert_eq!(path.critical_points.len(), 1, "{:?}", path.critical_points);
    // The continuum load, the element converging at second order: 9.2e-4,
    // 2.4e-4, 6.7e-5 above it at 15, 30 and 60 elements per rod.
    let euler = std::f64::consts::PI.powi(2) * 766.0 / (4.0 * 4.0 * 4.0);
    let continuum = 1.0 / (1.0 / euler + 1.0 / 2.2e6);
    let located = 100.0 * found[0];
    assert!(
        (located - continuum).abs() <= 1e-4 * continuum,
        "located {located} N, continuum {continuum} N"
    );
    // The inertia: 0 before, exactly 1 from the buckling to the end.
    for p in &path.points {
        let expected = usize::from(p.load_factor > found[0]);
        assert_eq!(
            p.negative_eigenvalues,
            Some(expected),
            "λ = {}",
            p.load_factor
        );
    }
    assert_eq!(path.final_negative_eigenvalues, Some(1));
    // The case is item 11's: after the buckling, the least-magnitude
    // eigenvalue changes sign again between two steps (from the negative
    // out-of-plane mode to the positive in-plane one) with no crossing.
    let after: Vec<f64> = path
        .points
        .iter()
        .filter(|p| p.load_factor > found[0])
        .map(|p| p.lowest_stiffness_n_per_m.unwrap())
        .collect();
    let switches = after
        .windows(2)
        .filter(|w| w[0] < 0.0 && w[1] > 0.0)
        .count();
    assert_eq!(switches, 1, "{after:?}");
}
