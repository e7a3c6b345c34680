//! The limit margin against closed-form critical loads (issue 16): at the
//! truss margin's precision, the bracket holds the critical load, its upper
//! end is a certified instability, and the mode it reports is the buckling
//! mode.

use std::f64::consts::PI;

use nalgebra::Vector3;
use ringmesh::mechanics::{
    limit_load_factor, ElementKind, JointKind, LimitBound, LimitSearch, ModelBuilder, RodSpec,
    Section, StaticSettings, StaticSolver,
};
use ringmesh::truss::MARGIN_PRECISION;

/// The limit search of the frame `b` builds, at the truss margin's
/// precision, up to `search_to` × its loads.
fn search_limit(b: ModelBuilder, search_to: f64) -> (StaticSolver, LimitSearch) {
    let mut solver = StaticSolver::new(b.build().unwrap()).unwrap();
    let search = limit_load_factor(
        &mut solver,
        search_to,
        MARGIN_PRECISION,
        &StaticSettings::default(),
    )
    .unwrap();
    (solver, search)
}

/// The bracket `[stable_to, unstable_from]` of `search` (loads × `scale`)
/// is certified, at most [`MARGIN_PRECISION`] wide, and holds `expected`
/// within `MARGIN_PRECISION`.
fn assert_brackets(search: &LimitSearch, scale: f64, expected: f64) {
    let LimitBound::Unstable { load_factor } = search.bound else {
        panic!("not a certified instability: {search:?}");
    };
    let (lo, hi) = (scale * search.stable_to, scale * load_factor);
    assert!(hi - lo <= MARGIN_PRECISION * hi, "[{lo}, {hi}]");
    assert!(
        lo <= expected * (1.0 + MARGIN_PRECISION) && hi >= expected * (1.0 - MARGIN_PRECISION),
        "[{lo}, {hi}] against {expected}"
    );
}

/// A clamped–free column of length 10 m (EI = 100 N·m², EA = GA = 10⁴ N),
/// 32 elements, under half its Euler load `π²EI/(4L²)` at the head: the
/// margin is 2 (the shear and axial flexibility shift it by 2.5e-4 and the
/// mesh by 2e-4, inside the precision). Its mode is the quarter sine wave
/// `1 − cos(πz/2L)`.
#[test]
fn a_clamped_free_column_buckles_at_eulers_load() {
    let (length, ei) = (10.0, 100.0);
    let euler = PI * PI * ei / (4.0 * length * length);
    let mut b = ModelBuilder::new();
    let rod = b.add_rod(
        Vector3::zeros(),
        Vector3::new(0.0, 0.0, length),
        Vector3::x(),
        &RodSpec {
            section: Section {
                axial_n: 1e4,
                shear_n: [1e4, 1e4],
                torsion_nm2: ei,
                bending_nm2: [ei, ei],
            },
            elements: 32,
            kind: ElementKind::Se3,
        },
    );
    b.fix(rod.start(), [true; 6]);
    b.add_load(
        rod.end(),
        Vector3::new(0.0, 0.0, -0.5 * euler),
        Vector3::zeros(),
    );
    let (solver, search) = search_limit(b, 4.0);
    assert_brackets(&search, 0.5, 1.0);
    // The mode: lateral, the quarter sine wave along the column.
    for &n in &rod.nodes {
        let z = solver.model().reference()[n].position_m.z;
        let [x, y, axial] = search.mode.translations_m()[n];
        let shape = 1.0 - (PI * z / (2.0 * length)).cos();
        assert!(
            ((x * x + y * y).sqrt() - shape).abs() <= 0.02,
            "z = {z}: {x}, {y} against {shape}"
        );
        assert!(axial.abs() <= 0.02, "z = {z}: axial {axial}");
    }
}

/// A ring of radius R = 1 m (in-plane EI = 1 N·m², 64 bays of two elements
/// each between hinge bodies), loaded at the bodies by dead forces towards
/// its centre, `q` per unit length. Held tangentially at the four quarter
/// points and out of its plane everywhere: the oval (n = 2) mode needs no
/// rigid rotation, which dead loads would destabilise, so the classical
/// critical load of loads of constant direction holds, `q = 4EI/R³`
/// (Timoshenko & Gere §7.5's fixed-direction case; the pressure that stays
/// normal gives 3, the centrally directed load 4.5). Loaded at 1 EI/R³:
/// the margin is 4.
#[test]
fn a_ring_under_radial_dead_loads_buckles_oval_at_four_ei_over_r_cubed() {
    let (bays, radius, ei) = (64, 1.0, 1.0);
    let section = Section {
        axial_n: 1e6,
        shear_n: [1e6, 1e6],
        torsion_nm2: 1e3,
        bending_nm2: [ei, 1e3],
    };
    let point = |k: usize| {
        let t = 2.0 * PI * k as f64 / bays as f64;
        Vector3::new(radius * t.cos(), radius * t.sin(), 0.0)
    };
    let mut b = ModelBuilder::new();
    let bodies: Vec<_> = (0..bays).map(|k| b.add_body(point(k))).collect();
    for k in 0..bays {
        let next = (k + 1) % bays;
        let spec = RodSpec {
            section,
            elements: 2,
            kind: ElementKind::Se3,
        };
        let rod = b.add_rod(point(k), point(next), Vector3::z(), &spec);
        b.add_joint(JointKind::Fixed, bodies[k], rod.start(), point(k));
        b.add_joint(JointKind::Fixed, bodies[next], rod.end(), point(next));
    }
    // q = 1·EI/R³ per unit length, lumped at the bodies.
    let force = ei / radius.powi(3) * 2.0 * PI * radius / bays as f64;
    for (k, &body) in bodies.iter().enumerate() {
        let tangential = if k % (bays / 4) == 0 {
            if (k / (bays / 4)) % 2 == 0 {
                [false, true]
            } else {
                [true, false]
            }
        } else {
            [false, false]
        };
        b.fix(
            body,
            [tangential[0], tangential[1], true, true, true, false],
        );
        b.add_load(body, -force * point(k) / radius, Vector3::zeros());
    }
    let (_, search) = search_limit(b, 8.0);
    assert_brackets(&search, 1.0, 4.0);
    // The mode: radial motion cos 2θ (its sign and scale aside).
    let radial: Vec<f64> = (0..bays)
        .map(|k| {
            let [x, y, _] = search.mode.translations_m()[bodies[k]];
            Vector3::new(x, y, 0.0).dot(&point(k)) / radius
        })
        .collect();
    let oval: Vec<f64> = (0..bays)
        .map(|k| (4.0 * PI * k as f64 / bays as f64).cos())
        .collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let correlation = dot(&radial, &oval) / (dot(&radial, &radial) * dot(&oval, &oval)).sqrt();
    assert!(
        correlation.abs() >= 0.99,
        "correlation with cos 2θ: {correlation}"
    );
}
