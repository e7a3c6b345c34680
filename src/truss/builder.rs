//! The ring-truss frame of a scene (paper §3.1, DESIGN §5): N vertical
//! battens, upper and lower longerons, one diagonal per bay made of a thick
//! and a thin tube, and 2N hinge bodies.
//!
//! Joints as the paper: batten–hinge fixed; longeron–hinge and diagonal–hinge
//! revolute about the bay's normal (the locked deployed state is held by the
//! triangulating diagonal); thick–thin diagonal fixed at mid-length. Supports:
//! an isostatic 3-2-1 set on three bottom hinges, so the self-equilibrated pull
//! of the net deforms the truss without reactions.
//!
//! The scene gives one tube: the thick and thin diagonal tubes use its section
//! (the paper gives no separate dimensions). A scene with
//! `[effects] rod_properties_csv` overrides the section of the rods its table
//! names ([`super::rod_properties`], which also documents the rod names and
//! their build order: bay by bay, batten, top and bottom longeron, thick and
//! thin diagonal).

use nalgebra::Vector3;

use crate::effects::{self, EffectKind, SceneEffects};
use crate::geometry::RingTrussLayout;
use crate::mechanics::{
    JointKind, MechanicsError, Model, ModelBuilder, NodalLoad, NodeId, RodSpec, Section,
};
use crate::scene::{RodKind, TrussRod};
use crate::scene::{Scene, Supports};

/// A ring-truss frame and where the net attaches to it.
#[derive(Debug, Clone)]
pub struct RingTruss {
    /// The frame.
    pub model: Model,
    /// Hinge bodies: top hinges `0..N` (front net), then bottom hinges (rear net).
    pub attachments: Vec<NodeId>,
    /// The supported bottom hinges and their fixed components `[x, y, z]`.
    pub supports: Vec<(usize, [bool; 3])>,
    /// Dead loads of the scene's effects (the truss's own weight under
    /// gravity; empty without), applied with every set of attachment loads.
    pub dead_loads: Vec<NodalLoad>,
}

fn v(p: &[f64; 3]) -> Vector3<f64> {
    Vector3::new(p[0], p[1], p[2])
}

/// The ring-truss frame before it is built, so that more items (the net's
/// points and cables, for an assembled model) can join it.
#[derive(Debug, Clone)]
pub struct RingTrussBuilder {
    /// The frame so far.
    pub builder: ModelBuilder,
    /// Hinge bodies: top hinges `0..N`, then bottom hinges.
    pub attachments: Vec<NodeId>,
    /// The supported bottom hinges and their fixed components `[x, y, z]`.
    pub supports: Vec<(usize, [bool; 3])>,
    /// Dead loads of the scene's effects (empty without gravity).
    pub dead_loads: Vec<NodalLoad>,
}

impl RingTruss {
    /// The frame of `scene`'s truss on the hinge layout `layout`, with the
    /// scene's `effects` (dead loads, rod sections).
    ///
    /// # Errors
    /// A degenerate layout (coincident hinges), named.
    pub fn new(
        scene: &Scene,
        layout: &RingTrussLayout,
        effects: &SceneEffects,
    ) -> Result<Self, MechanicsError> {
        Self::from_frame(Self::builder(scene, layout, effects))
    }

    /// The truss of a frame already constructed ([`RingTruss::builder`]):
    /// a run that needs the frame more than once constructs it once.
    ///
    /// # Errors
    /// A degenerate layout (coincident hinges), named.
    pub fn from_frame(frame: RingTrussBuilder) -> Result<Self, MechanicsError> {
        let RingTrussBuilder {
            builder,
            attachments,
            supports,
            dead_loads,
        } = frame;
        Ok(RingTruss {
            model: builder.build()?,
            attachments,
            supports,
            dead_loads,
        })
    }

    /// The frame of `scene`'s truss on `layout`, not yet built (validated by
    /// [`ModelBuilder::build`]): the one place a beam model of the truss is
    /// constructed ([`crate::effects`] logs it), with the dead loads and rod
    /// sections of `effects`.
    pub fn builder(
        scene: &Scene,
        layout: &RingTrussLayout,
        effects: &SceneEffects,
    ) -> RingTrussBuilder {
        effects::record(EffectKind::BeamModel);
        let t = &scene.truss;
        let nominal = RodSpec {
            section: Section::tube(
                t.tube_outer_diameter_m,
                t.tube_inner_diameter_m,
                t.youngs_modulus_pa,
                t.shear_modulus_pa,
            ),
            elements: t.elements_per_rod,
            kind: t.element,
        };
        // The nominal tube, as the effects leave it (measured rods).
        let spec = |kind: RodKind, bay: usize| RodSpec {
            section: effects.rod_section(TrussRod::new(kind, bay), nominal.section),
            ..nominal
        };
        let n = layout.bays();
        let top: Vec<Vector3<f64>> = layout.top_m.iter().map(v).collect();
        let bottom: Vec<Vector3<f64>> = layout.bottom_m.iter().map(v).collect();
        let mut b = ModelBuilder::new();
        let top_hinges: Vec<NodeId> = top.iter().map(|p| b.add_body(*p)).collect();
        let bottom_hinges: Vec<NodeId> = bottom.iter().map(|p| b.add_body(*p)).collect();
        let mut rods = Vec::new();

        for k in 0..n {
            let next = (k + 1) % n;
            // The bay's normal: across the plane of its longeron and batten.
            let normal = (top[next] - top[k]).cross(&(top[k] - bottom[k]));
            let radial_up = top[k] - bottom[k];

            let batten = b.add_rod(bottom[k], top[k], normal, &spec(RodKind::Batten, k));
            b.add_joint(
                JointKind::Fixed,
                batten.start(),
                bottom_hinges[k],
                bottom[k],
            );
            b.add_joint(JointKind::Fixed, batten.end(), top_hinges[k], top[k]);
            rods.push(batten);

            let hinge = JointKind::Revolute { axis: normal };
            for (hinges, points, kind) in [
                (&top_hinges, &top, RodKind::TopLongeron),
                (&bottom_hinges, &bottom, RodKind::BottomLongeron),
            ] {
                let longeron = b.add_rod(points[k], points[next], radial_up, &spec(kind, k));
                b.add_joint(hinge, longeron.start(), hinges[k], points[k]);
                b.add_joint(hinge, longeron.end(), hinges[next], points[next]);
                rods.push(longeron);
            }

            let middle = (bottom[k] + top[next]) * 0.5;
            let thick = b.add_rod(bottom[k], middle, normal, &spec(RodKind::DiagonalThick, k));
            let thin = b.add_rod(middle, top[next], normal, &spec(RodKind::DiagonalThin, k));
            b.add_joint(hinge, thick.start(), bottom_hinges[k], bottom[k]);
            b.add_joint(JointKind::Fixed, thick.end(), thin.start(), middle);
            b.add_joint(hinge, thin.end(), top_hinges[next], top[next]);
            rods.extend([thick, thin]);
        }

        let supports = match t.supports {
            Supports::Isostatic => isostatic(&bottom),
        };
        for &(k, fixed) in &supports {
            b.fix(
                bottom_hinges[k],
                [fixed[0], fixed[1], fixed[2], false, false, false],
            );
        }
        let attachments: Vec<NodeId> = top_hinges.into_iter().chain(bottom_hinges).collect();
        let dead_loads = effects.truss_dead_loads(&b, &rods, &attachments);
        RingTrussBuilder {
            builder: b,
            attachments,
            supports,
            dead_loads,
        }
    }
}

/// A 3-2-1 support on bottom hinges `0`, `N/3`, `2N/3`: all translations of the
/// first; at the second, the vertical and the horizontal component that a
/// rotation about the vertical through the first would move most; the vertical
/// of the third. Rigid motions are removed and nothing more.
fn isostatic(bottom: &[Vector3<f64>]) -> Vec<(usize, [bool; 3])> {
    let n = bottom.len();
    let (a, b, c) = (0, n / 3, (2 * n) / 3);
    let ab = bottom[b] - bottom[a];
    // ẑ × (B − A) = (−Δy, Δx): fix y when |Δx| dominates.
    let fix_y = ab.x.abs() >= ab.y.abs();
    vec![
        (a, [true, true, true]),
        (b, [!fix_y, fix_y, true]),
        (c, [false, false, true]),
    ]
}
