//! Property tests (issue 7): random nets with random positive force densities
//! balance every node; random rotations round-trip through exp/log and the
//! quaternion and matrix forms; random scenes within the documented ranges
//! (`ringmesh::scene`, "Ranges") build, and their design solves.
//!
//! Seeds are fixed, so a run is reproducible; the case counts keep the file
//! to a few seconds.

mod common;

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use ringmesh::design::scene_problem;
use ringmesh::fdm::solve_network;
use ringmesh::mechanics::rotation::{exp, log, skew};
use ringmesh::scene::Scene;
use ringmesh::uniformity::{SolverKind, Termination};
use ringmesh::Network;

const EPS: f64 = f64::EPSILON;

// ---------------------------------------------------------------------------
// Random nets

/// A connected random net: `anchors` fixed nodes, free nodes each tied to an
/// earlier node (so every free node has a cable path to an anchor), extra
/// random cables, force densities log-uniform over six decades, loads on
/// some nets.
fn random_net() -> impl Strategy<Value = Network> {
    (3usize..8, 2usize..60, 0usize..80, any::<bool>()).prop_flat_map(
        |(anchors, free, extra, loaded)| {
            let n = anchors + free;
            let point = || prop::array::uniform3(-10.0f64..10.0);
            (
                prop::collection::vec(point(), n),
                prop::collection::vec(0.0f64..1.0, free),
                prop::collection::vec((0..n, 0..n), extra),
                prop::collection::vec(-3.0f64..3.0, free + extra),
                prop::collection::vec(prop::array::uniform3(-5.0f64..5.0), n),
            )
                .prop_map(move |(nodes, parents, pairs, log_q, loads)| {
                    let mut edges: Vec<[usize; 2]> = parents
                        .iter()
                        .enumerate()
                        .map(|(f, &u)| {
                            let i = anchors + f;
                            [i, ((u * i as f64) as usize).min(i - 1)]
                        })
                        .collect();
                    edges.extend(pairs.iter().filter(|(a, b)| a != b).map(|&(a, b)| [a, b]));
                    let q = log_q
                        .iter()
                        .take(edges.len())
                        .map(|e| 10f64.powf(*e))
                        .collect();
                    Network {
                        nodes,
                        edges,
                        fixed: (0..anchors).collect(),
                        q,
                        loads: loaded.then_some(loads),
                        groups: None,
                    }
                })
        },
    )
}

proptest! {
    #![proptest_config(common::proptest_config(64, 0x5eed_0001))]

    /// Every free node balances: `‖p − Σ q u‖ ≤ 1e-9 × (largest force or load)`.
    #[test]
    fn random_nets_with_positive_q_balance_every_node(net in random_net()) {
        prop_assume!(net.validate().is_ok());
        let (_, eq) = solve_network(&net).unwrap();
        let load = net
            .loads
            .iter()
            .flatten()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let scale = eq.max_force_n().max(load);
        if scale == 0.0 {
            // One support and no load: every node at the support, no force.
            prop_assert_eq!(eq.max_residual_n(), 0.0);
            return Ok(());
        }
        let relative = eq.max_residual_n() / scale;
        prop_assert!(relative <= 1e-9, "residual {:e} × force scale {:e}", relative, scale);
        // Fixed nodes stay where they are.
        for &i in &net.fixed {
            prop_assert_eq!(eq.nodes_xyz_m[i], net.nodes[i]);
        }
    }
}

// ---------------------------------------------------------------------------
// Rotations

/// The angle of the rotation taking `a` to `b`, accurate to roundoff.
fn angle_between(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    let d = a.inverse() * b;
    2.0 * d.imag().norm().atan2(d.w.abs())
}

fn unit_axis() -> impl Strategy<Value = Vector3<f64>> {
    prop::array::uniform3(-1.0f64..1.0)
        .prop_filter("not too short to normalise", |v| {
            v.iter().map(|c| c * c).sum::<f64>() > 1e-4
        })
        .prop_map(|v| Vector3::from(v).normalize())
}

proptest! {
    #![proptest_config(common::proptest_config(256, 0x5eed_0002))]

    /// `exp` then `log` gives back the same rotation, with the principal
    /// angle in [0, π]; for angles below π it gives back the vector itself.
    /// Any angle, several turns included.
    #[test]
    fn exp_log_round_trip(axis in unit_axis(), angle in 0.0f64..(6.0 * std::f64::consts::PI)) {
        let theta = axis * angle;
        let q = exp(&theta);
        let back = log(&q);
        prop_assert!(back.norm() <= std::f64::consts::PI * (1.0 + EPS));
        let error = angle_between(&exp(&back), &q);
        prop_assert!(error <= 16.0 * EPS * angle.max(1.0), "rotation off by {:e}", error);
        let principal = angle % std::f64::consts::TAU;
        if principal < std::f64::consts::PI - 1e-6 {
            let vector = (back - axis * principal).norm();
            prop_assert!(vector <= 16.0 * EPS * angle.max(1.0), "vector off by {:e}", vector);
        }
    }

    /// Quaternion and matrix forms are one rotation: Rodrigues' matrix
    /// (paper eq. 7) equals the quaternion's, is orthogonal with determinant
    /// 1, rotates vectors alike, converts back to the same quaternion, and
    /// products compose alike.
    #[test]
    fn quaternion_and_matrix_forms_agree(
        a in unit_axis(),
        b in unit_axis(),
        angles in (0.0f64..12.0, 0.0f64..12.0),
        v in prop::array::uniform3(-10.0f64..10.0),
    ) {
        let (ta, tb) = (a * angles.0, b * angles.1);
        let rodrigues = |theta: &Vector3<f64>| {
            let t = theta.norm();
            let s = skew(theta);
            if t == 0.0 {
                Matrix3::identity()
            } else {
                Matrix3::identity() + s * (t.sin() / t) + s * s * ((1.0 - t.cos()) / (t * t))
            }
        };
        let (qa, qb) = (exp(&ta), exp(&tb));
        let (ma, mb) = (qa.to_rotation_matrix().into_inner(), qb.to_rotation_matrix().into_inner());
        let scale = angles.0.max(1.0);
        prop_assert!((ma - rodrigues(&ta)).amax() <= 16.0 * EPS * scale);
        prop_assert!((ma.transpose() * ma - Matrix3::identity()).amax() <= 8.0 * EPS);
        prop_assert!((ma.determinant() - 1.0).abs() <= 8.0 * EPS);
        let v = Vector3::from(v);
        prop_assert!((qa * v - ma * v).amax() <= 8.0 * EPS * v.norm().max(1.0));
        prop_assert!(angle_between(&UnitQuaternion::from_matrix(&ma), &qa) <= 8.0 * EPS);
        let composed = (qa * qb).to_rotation_matrix().into_inner();
        prop_assert!((composed - ma * mb).amax() <= 16.0 * EPS);
    }
}

// ---------------------------------------------------------------------------
// Random valid scenes

/// A scene of `ringmesh::scene`'s documented ranges, from small-hex's cable
/// and tube data: aperture, focal ratio, offset, bays, rings, sag, rear focal
/// ratio, the truss 1.1 to 2 times as tall as the nets need, tensions.
fn random_scene() -> impl Strategy<Value = Scene> {
    (
        (1.0f64..100.0, 0.15f64..5.0, 0.0f64..0.5),
        (3usize..=36, 2usize..=8, 0.02f64..0.2),
        (1.0f64..4.0, 1.1f64..2.0),
        (1.0f64..1000.0, 1.0f64..1000.0),
    )
        .prop_map(
            |((d, f_over_d, offset), (bays, rings, sag), (rear, margin), (front_t, rear_t))| {
                let mut s = common::scene("small-hex");
                let f = f_over_d * d;
                s.name = "random".into();
                s.reflector.aperture_diameter_m = d;
                s.reflector.focal_length_m = f;
                s.reflector.offset_m = offset * d;
                s.truss.bays = bays;
                s.front_net.rings = rings;
                s.front_net.boundary_sag_ratio = sag;
                s.rear_net.focal_length_m = rear * f;
                let r = 0.5 * d;
                s.truss.height_m = margin * r * r * (1.0 / f + 1.0 / (rear * f)) / 4.0;
                s.front_net.mean_tension_n = front_t;
                s.rear_net.mean_tension_n = rear_t;
                s.cables.max_force_density_n_per_m = 1e9;
                s
            },
        )
}

proptest! {
    #![proptest_config(common::proptest_config(32, 0x5eed_0003))]

    /// Every scene of the documented ranges validates and builds, the forward
    /// solve of its initial q balances, and its `lp` design converges with
    /// positive q, the front net on the paraboloid and every node balanced.
    #[test]
    fn random_valid_scenes_build_and_solve(s in random_scene()) {
        s.validate().unwrap();
        let (mesh, problem) = scene_problem(&s).map_err(|e| {
            TestCaseError::fail(format!("{s:?}: {e}"))
        })?;
        let (_, eq) = solve_network(&mesh.network).unwrap();
        prop_assert!(eq.max_residual_n() <= 1e-9 * eq.max_force_n());
        let design = SolverKind::Lp.build(None).solve(&problem).map_err(|e| {
            TestCaseError::fail(format!("{s:?}: {e}"))
        })?;
        prop_assert_eq!(design.termination, Termination::Converged);
        prop_assert!(design.q.iter().all(|&q| q > 0.0 && q.is_finite()));
        prop_assert!(design.ratio >= 1.0 && design.ratio.is_finite());
        let max_tension = design.tensions_n.iter().copied().fold(0.0, f64::max);
        prop_assert!(
            design.max_residual_n <= 1e-8 * max_tension,
            "residual {:e} N, max tension {:e} N", design.max_residual_n, max_tension
        );
        let d = s.reflector.aperture_diameter_m;
        prop_assert!(
            design.surface_max_m <= 1e-10 * d,
            "surface {:e} m on a {} m aperture", design.surface_max_m, d
        );
    }
}
