//! Inputs of the statics engine ([`crate::mechanics`], which knows nothing of
//! files): the frame file, and the paper's cantilever benchmark.
//!
//! * [`FrameFile`] — the frame file (TOML): any structure of rods, rigid
//!   bodies, joints, supports and dead loads, read, validated with the key at
//!   fault named ([`FrameFileError`]), and built into a
//!   [`Model`](crate::mechanics::Model) (DESIGN §5: "a generic frame input runs
//!   on the same engine");
//! * [`cantilever`] — the paper's cantilever rolled up by a tip moment
//!   (§3.4, Tables 1–2), built in code, and its closed form.
//!
//! The files, bottom up: `error` (the error), `schema` (the TOML syntax),
//! `file` (what a built file is), `build` (validation and building), `read`
//! (text to a built file), `cantilever`.
//!
//! # Format
//!
//! SI units in key names; unknown keys are rejected. Items of a list are named
//! in errors by their index (`rods[2].elements: must be at least 1`).
//!
//! * `[[nodes]]` — points of the geometry: `position_m`, optional `name`.
//!   Referenced by name (`"tip"`) or by index (`3`). A node is only a place:
//!   rods, bodies and joints are located at nodes, and what is attached there is
//!   decided by joints.
//! * `[sections.NAME]` — a named section, reused by rods with `section = "NAME"`.
//!   Either `tube = { outer_diameter_m, inner_diameter_m, youngs_modulus_pa,
//!   shear_modulus_pa }` (a circular tube,
//!   [`Section::tube`](crate::mechanics::Section::tube)) or the four
//!   stiffnesses directly: `axial_n` (EA), `shear_n = [GA₂, GA₃]`,
//!   `torsion_nm2` (GJ), `bending_nm2 = [EI₂, EI₃]`.
//! * `[[rods]]` — rods from node `start` to node `end`, straight or along a
//!   circular arc (`arc`, below); the section is
//!   either `section = "NAME"`, or `tube = { … }`, or the four stiffnesses
//!   written on the rod. `elements` (default 1), `element = "se3"` (default) or
//!   `"crisfield-jelenic"`, optional `up` (the second axis of the section is the
//!   one closest to `up`; default `[0, 0, 1]`; one along the rod is refused,
//!   and so is the default on a rod along z whose two bending stiffnesses
//!   differ), optional `name`. Every rod is
//!   meshed with nodes of its own: its ends are connected to anything else only
//!   by joints.
//! * `arc` on a rod — the rod follows a circular arc from `start` to `end`:
//!   `arc = { centre_m = [x, y, z] }`, the shorter arc about that centre;
//!   `arc = { centre_m = [x, y, z], normal = [nx, ny, nz] }`, the arc turning
//!   from start to end about `normal` (right-hand rule: `normal = [0, 0, -1]`
//!   goes clockwise seen from +z, the long way if that is longer), which a
//!   half circle needs (its start, centre and end are on one line); or
//!   `arc = { through_m = [x, y, z] }`, the circle through start, that point
//!   and end, from start via that point to end. Both ends must be at one
//!   distance from the centre and the normal across the arc's plane, to 1e-9
//!   relative. The nodes are equally spaced in angle, at most 90° apart
//!   (`elements ≥ 2` for a half circle), each node's frame the start's turned
//!   about the normal ([`CircularArc`](crate::mechanics::CircularArc)): the
//!   elements have the exact initial curvature `1/R`, not chords, and their
//!   arc lengths. `up` holds at the start and is carried along the arc.
//! * `[[bodies]]` — rigid bodies (hinges, paper §3.3) at a node (`at = "h0"`) or
//!   a point (`at_m = [x, y, z]`), optional `name`.
//! * Members: the things joints, supports and loads act on, written
//!   `{ rod = "beam", end = "start" | "end" }`, `{ body = "h0" }`, or
//!   `{ node = "tip" }` — the one rod end or body located at that node (an error
//!   when several are there: say which).
//! * `[[joints]]` — `kind = "fixed" | "revolute" | "spherical"` between members
//!   `a` and `b`; `axis = [x, y, z]` for a revolute joint (global, reference
//!   configuration); the joint's point is `at = NODE` or `at_m = [x, y, z]`,
//!   by default the reference position of `a`.
//! * `[[supports]]` — `on = MEMBER`, `fixed = ["x", "y", "z", "rx", "ry", "rz"]`
//!   (global components; `"all"` for the six).
//! * `[[loads]]` — dead loads at load factor 1: `on = MEMBER`, `force_n`,
//!   `moment_nm` (global, fixed in direction; each defaults to zero).
//! * `[solver]` — [`StaticSettings`](crate::mechanics::StaticSettings):
//!   `tolerance`, `max_iterations`, `initial_step`, `min_step`, `max_steps`,
//!   `path = "load" | "arc_length" | "displacement"`; for path following
//!   (arc length, displacement control) `max_step` (the largest change of
//!   the load factor per step, default 0.1), `stability` (the lowest
//!   eigenvalue at every step and bifurcations located, default true),
//!   `branch_switch` (leave the path for the branch of the first
//!   bifurcation, default false).
//! * `[path]` — where the path ends, `target = { load_factor = 1.0 }` (the
//!   default), `{ on = MEMBER, component = "x" | "y" | "z", displacement_m
//!   = … }` or `{ steps = N }`; `control = { on = MEMBER, component = … }`,
//!   the translation `path = "displacement"` drives (refused under another
//!   path, which would ignore it). Load control ends at
//!   the full load (or a limit point); arc length follows the path through
//!   limit points in load and displacement, across λ ≤ 0 and back.
//! * `[output]` — `nodes = ["tip", { rod = "beam", end = "end" }, …]`: the
//!   `[[nodes]]` (the one member there) or members whose displacements every
//!   step of the path records (`frame.json`'s `path`, `frame-path.csv`,
//!   `frame-path.png/.svg` — the load factor against the first one's
//!   displacement).
//!
//! # Example
//!
//! A portal: two clamped columns, a beam pinned to a rigid knee at each top,
//! a lateral force and a moment.
//!
//! ```toml
//! [[nodes]]
//! name = "a"
//! position_m = [0.0, 0.0, 0.0]
//! [[nodes]]
//! name = "b"
//! position_m = [0.0, 0.0, 3.0]
//! [[nodes]]
//! name = "c"
//! position_m = [4.0, 0.0, 3.0]
//! [[nodes]]
//! name = "d"
//! position_m = [4.0, 0.0, 0.0]
//!
//! [sections.steel]
//! tube = { outer_diameter_m = 0.1, inner_diameter_m = 0.09, youngs_modulus_pa = 2.1e11, shear_modulus_pa = 8.1e10 }
//!
//! [[rods]]
//! name = "left"
//! start = "a"
//! end = "b"
//! section = "steel"
//! elements = 4
//! up = [1.0, 0.0, 0.0]
//!
//! [[rods]]
//! name = "beam"
//! start = "b"
//! end = "c"
//! axial_n = 1e8
//! shear_n = [4e7, 4e7]
//! torsion_nm2 = 2e5
//! bending_nm2 = [1.5e5, 1.5e5]
//! elements = 6
//! element = "crisfield-jelenic"
//!
//! [[rods]]
//! name = "right"
//! start = 3
//! end = 2
//! tube = { outer_diameter_m = 0.1, inner_diameter_m = 0.09, youngs_modulus_pa = 2.1e11, shear_modulus_pa = 8.1e10 }
//! elements = 4
//!
//! [[bodies]]
//! name = "knee-left"
//! at = "b"
//! [[bodies]]
//! name = "knee-right"
//! at_m = [4.0, 0.0, 3.0]
//!
//! [[joints]]
//! kind = "fixed"
//! a = { rod = "left", end = "end" }
//! b = { body = "knee-left" }
//! [[joints]]
//! kind = "revolute"
//! axis = [0.0, 1.0, 0.0]
//! a = { rod = "beam", end = "start" }
//! b = { body = "knee-left" }
//! at = "b"
//! [[joints]]
//! kind = "revolute"
//! axis = [0.0, 1.0, 0.0]
//! a = { rod = "beam", end = "end" }
//! b = { body = "knee-right" }
//! [[joints]]
//! kind = "fixed"
//! a = { rod = "right", end = "end" }
//! b = { body = "knee-right" }
//!
//! [[supports]]
//! on = { node = "a" }
//! fixed = ["all"]
//! [[supports]]
//! on = { rod = "right", end = "start" }
//! fixed = ["x", "y", "z", "rx", "ry", "rz"]
//!
//! [[loads]]
//! on = { body = "knee-left" }
//! force_n = [1000.0, 0.0, 0.0]
//! [[loads]]
//! on = { rod = "beam", end = "end" }
//! moment_nm = [0.0, 500.0, 0.0]
//!
//! [solver]
//! tolerance = 1e-10
//! path = "load"
//! ```
//!
//! A semicircular arch of radius 2 m in the x–z plane, clamped at both feet:
//! two quarter circles, one given by its centre and one by a point it passes
//! through, fixed to each other at the crown, which carries a load.
//!
//! ```toml
//! [[nodes]]
//! name = "left"
//! position_m = [-2.0, 0.0, 0.0]
//! [[nodes]]
//! name = "crown"
//! position_m = [0.0, 0.0, 2.0]
//! [[nodes]]
//! name = "right"
//! position_m = [2.0, 0.0, 0.0]
//!
//! [sections.steel]
//! tube = { outer_diameter_m = 0.1, inner_diameter_m = 0.09, youngs_modulus_pa = 2.1e11, shear_modulus_pa = 8.1e10 }
//!
//! [[rods]]
//! name = "west"
//! start = "left"
//! end = "crown"
//! section = "steel"
//! elements = 4
//! up = [0.0, 1.0, 0.0]
//! arc = { centre_m = [0.0, 0.0, 0.0] }
//!
//! [[rods]]
//! name = "east"
//! start = "crown"
//! end = "right"
//! section = "steel"
//! elements = 4
//! up = [0.0, 1.0, 0.0]
//! arc = { through_m = [1.2, 0.0, 1.6] }
//!
//! [[joints]]
//! kind = "fixed"
//! a = { rod = "west", end = "end" }
//! b = { rod = "east", end = "start" }
//!
//! [[supports]]
//! on = { node = "left" }
//! fixed = ["all"]
//! [[supports]]
//! on = { node = "right" }
//! fixed = ["all"]
//!
//! [[loads]]
//! on = { rod = "west", end = "end" }
//! force_n = [0.0, 0.0, -1000.0]
//! ```

mod build;
pub mod cantilever;
mod error;
mod file;
mod read;
mod schema;

pub use build::{MAX_FRAME_ELEMENTS, MAX_ROD_ELEMENTS};
pub use error::FrameFileError;
pub use file::{FrameFile, NodeOrigin};
