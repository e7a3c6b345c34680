//! `ringmesh frame`: the statics of a frame file, every node's position,
//! displacement and rotation, the reactions and the solver's statistics.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::Summary;
use crate::algebra::norm3;
use crate::frame::{FrameFile, FrameFileError, NodeOrigin};
use crate::mechanics::{
    rotation, CriticalKind, CriticalPoint, MechanicsError, PathPoint, PathTarget, StaticSolver,
    StaticTermination, StepRecord,
};
use crate::report::{
    decimal, json_name, path_plot, readable, write_atomic, write_json, OutputPath, OutputSet,
    PathFigure,
};
use crate::Error;

/// The path files written beside the frame's JSON `json_name`, named after
/// it (`frame.json` → `frame-path.csv`, `.png`, `.svg`).
fn path_file_names(json_name: &str) -> [String; 3] {
    let stem = Path::new(json_name)
        .file_stem()
        .map_or_else(|| "frame".into(), |s| s.to_string_lossy().into_owned());
    ["csv", "png", "svg"].map(|e| format!("{stem}-path.{e}"))
}

/// The followed path in `ringmesh frame`'s output.
#[derive(Debug, Clone, Serialize)]
pub struct FramePath {
    /// The recorded nodes (`[output] nodes`), in the order of each point's
    /// displacements.
    pub nodes: Vec<String>,
    /// Every converged step, the unloaded frame first.
    pub points: Vec<PathPoint>,
}

/// One node of `ringmesh frame`'s output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameNodeOutput {
    /// Node id in the model.
    pub id: usize,
    /// The rod it belongs to (name, or `rods[i]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rod: Option<String>,
    /// Its place along the rod, 0 (start) … elements (end).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rod_node: Option<usize>,
    /// The rigid body it is (name, or `bodies[i]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// Deformed position, m.
    pub position_m: [f64; 3],
    /// Position minus reference position, m.
    pub displacement_m: [f64; 3],
    /// Rotation vector of `R R₀ᵀ` (spatial, relative to the reference), rad,
    /// angle in [0, π] (a full turn reads as zero).
    pub rotation_rad: [f64; 3],
}

/// A support reaction in `ringmesh frame`'s output.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameReaction {
    /// Node id.
    pub node: usize,
    /// What the node is (`rod beam node 0`, `body h0`).
    pub member: String,
    /// Force the support exerts, N (zero on free components).
    pub force_n: [f64; 3],
    /// Moment the support exerts, N·m (zero on free components).
    pub moment_nm: [f64; 3],
}

/// The output of `ringmesh frame`.
#[derive(Debug, Clone, Serialize)]
pub struct FrameOutput {
    /// The frame file.
    pub file: String,
    /// How the solve ended.
    pub termination: StaticTermination,
    /// The last converged load factor (1 when converged).
    pub load_factor: f64,
    /// Converged load steps.
    pub load_steps: usize,
    /// Newton iterations in all, rejected steps included.
    pub newton_iterations: usize,
    /// Load steps that were cut.
    pub rejected_steps: usize,
    /// Wall time of the solve, s.
    pub time_s: f64,
    /// Largest nodal displacement, m.
    pub max_displacement_m: f64,
    /// The node of the largest displacement.
    pub max_displacement_node: usize,
    /// Counts: nodes, rods, elements, bodies, joints.
    pub counts: FrameCounts,
    /// Every node, by id.
    pub nodes: Vec<FrameNodeOutput>,
    /// Every supported node's reaction, in the order of `[[supports]]`.
    pub reactions: Vec<FrameReaction>,
    /// Converged steps: load factor, Newton iterations, `‖F‖∞` per iteration.
    pub steps: Vec<StepRecord>,
    /// The equilibrium path followed: each step's load factor, the
    /// recorded nodes' displacements and the lowest eigenvalue.
    pub path: FramePath,
    /// Limit and bifurcation points located on the path, in path order.
    pub critical_points: Vec<CriticalPoint>,
    /// The path's target, in words (`the full load (load factor 1)`, `the
    /// y displacement -0.5 m of rod beam node 10`, `40 steps`).
    pub target: String,
    /// How many eigenvalues of the stiffness on the joints' constraints
    /// are negative at the last point (the tangent's inertia): more than
    /// 0, the path ended on an unstable branch; `None` where not counted.
    pub final_negative_eigenvalues: Option<usize>,
}

/// The size of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct FrameCounts {
    /// Nodes of the model (rods' nodes and bodies).
    pub nodes: usize,
    /// Rods.
    pub rods: usize,
    /// Beam elements.
    pub elements: usize,
    /// Rigid bodies.
    pub bodies: usize,
    /// Joints.
    pub joints: usize,
}

/// Where `ringmesh frame FILE` writes by default: `runs/<file stem>/frame.json`.
pub fn default_frame_output(frame_path: &Path) -> PathBuf {
    let stem = frame_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frame".into());
    super::default_dir_named(&stem).join("frame.json")
}

impl FrameOutput {
    /// Why the run ended before its target (named), or reached it on an
    /// unstable branch (past a bifurcation it did not leave: not a plain
    /// success); `None` when it reached it on a stable one. The CLI exits 3
    /// then, after writing what it found.
    pub fn ended_early(&self) -> Option<String> {
        match self.termination {
            StaticTermination::Converged => {
                let negative = self.final_negative_eigenvalues.filter(|&n| n > 0)?;
                let past = self
                    .critical_points
                    .iter()
                    .rfind(|c| c.kind == CriticalKind::Bifurcation && !c.switched_branch)
                    .map(|c| format!(", past the bifurcation at load factor {:.9}", c.load_factor))
                    .unwrap_or_default();
                Some(format!(
                    "reached {} on an UNSTABLE branch: the stiffness there has {negative} \
                     negative eigenvalue{}{past}; the equilibrium is not one the frame keeps \
                     (follow the path by arc length with branch_switch = true for the stable \
                     branch)",
                    self.target,
                    if negative == 1 { "" } else { "s" }
                ))
            }
            ref t => Some(format!("ended before {}: {t}", self.target)),
        }
    }
}

/// What `ringmesh frame` made.
#[derive(Debug, Clone)]
pub struct FrameOutcome {
    /// The output (also in the JSON written).
    pub output: FrameOutput,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl FrameOutcome {
    /// What `ringmesh frame` prints: one paragraph (size, how the solve
    /// ended, its largest results, the critical points), the files written;
    /// a run short of its target has ended early.
    pub fn summary(&self) -> Summary {
        let mut s = Summary::default();
        say!(s, "{}", frame_summary(&self.output));
        s.written(&self.written);
        s.ended_early = self.output.ended_early();
        s
    }
}

/// One paragraph: size, how the solve ended, and its largest results.
fn frame_summary(o: &FrameOutput) -> String {
    let c = &o.counts;
    let ending = match o.termination {
        StaticTermination::Converged => {
            format!("reached its target at load factor {:.6}", o.load_factor)
        }
        StaticTermination::Stalled { load_factor } => {
            format!("STALLED: the load step fell below the minimum at load factor {load_factor:.6}")
        }
        StaticTermination::LimitPoint { limit_load_factor } => {
            format!("passed a LIMIT POINT at load factor {limit_load_factor:.6}")
        }
        StaticTermination::MaxSteps { load_factor } => {
            format!("ran out of steps (MAX STEPS) at load factor {load_factor:.6}")
        }
        StaticTermination::Overflow { load_factor } => {
            format!("OVERFLOWED beyond load factor {load_factor:.6}")
        }
    };
    let reaction = o
        .reactions
        .iter()
        .map(|r| norm3(r.force_n))
        .fold(0.0, f64::max);
    let moment = o
        .reactions
        .iter()
        .map(|r| norm3(r.moment_nm))
        .fold(0.0, f64::max);
    let at = match o.nodes.get(o.max_displacement_node) {
        Some(largest) => match (&largest.rod, largest.rod_node, &largest.body) {
            (Some(rod), Some(i), _) => format!("rod {rod} node {i}"),
            (_, _, Some(body)) => format!("body {body}"),
            _ => format!("node {}", largest.id),
        },
        None => "no node".to_string(),
    };
    format!(
        "{}: {} nodes ({} rods, {} elements, {} bodies, {} joints); {} in {} load steps, \
         {} Newton iterations, {} rejected steps, {} ms; largest displacement {} m \
         at {at}; largest reaction {} N, {} N·m.",
        o.file,
        c.nodes,
        c.rods,
        c.elements,
        c.bodies,
        c.joints,
        ending,
        o.load_steps,
        o.newton_iterations,
        o.rejected_steps,
        decimal(1e3 * o.time_s, 4),
        readable(o.max_displacement_m, 7),
        readable(reaction, 7),
        readable(moment, 7)
    ) + &o
        .critical_points
        .iter()
        .map(|c| {
            format!(
                "\n  {} at load factor {:.9}{}",
                json_name(&c.kind).replace('_', " "),
                c.load_factor,
                if c.switched_branch {
                    " (followed its branch)"
                } else {
                    ""
                }
            )
        })
        .collect::<String>()
}

/// The frame file's path target, in words.
fn target_text(file: &FrameFile) -> String {
    match file.path.target {
        PathTarget::LoadFactor(1.0) => "the full load (load factor 1)".into(),
        PathTarget::LoadFactor(l) => format!("the target load factor {l}"),
        PathTarget::Displacement {
            node,
            component,
            value_m,
        } => format!(
            "the target {} displacement {value_m} m of {}",
            ["x", "y", "z"].get(component).unwrap_or(&"?"),
            file.nodes_origins
                .get(node)
                .map_or_else(|| format!("node {node}"), ToString::to_string)
        ),
        PathTarget::Steps(n) => format!("the target of {n} steps"),
    }
}

/// `ringmesh frame`: reads a frame file, follows its equilibrium path to
/// the target (`[path]`, by default the full load) and writes every node's
/// position, displacement and rotation, the reactions, the solver's
/// statistics and the path with its critical points as JSON, and beside it
/// the path as `<stem>-path.csv` and `<stem>-path.png/.svg` (load factor
/// against the first recorded node's displacement), all or none. Where:
/// `output_path` by [`OutputPath`]'s rule — a folder (by default that of
/// [`default_frame_output`]) receives `frame.json` and `frame-path.*` as one
/// set swapped in; a `.json` file is written with its path files beside it,
/// each renamed into its folder, which is never swapped. Not reaching the
/// target is a termination status in the output, not an error. Returns the
/// output and the files written.
pub fn frame(frame_path: &Path, output_path: Option<&Path>) -> Result<FrameOutcome, Error> {
    let target = match output_path {
        Some(p) => OutputPath::resolve(p)?,
        None => OutputPath::Folder(
            default_frame_output(frame_path)
                .parent()
                .map_or_else(|| PathBuf::from("."), Path::to_path_buf),
        ),
    };
    let (dir, json_name) = target.folder_and_name("frame.json");
    let [path_csv_name, path_png, path_svg] = path_file_names(&json_name);
    let file = FrameFile::read(frame_path)?;
    let counts = FrameCounts {
        nodes: file.model.node_count(),
        rods: file.model.rods().len(),
        elements: file.model.element_count(),
        bodies: file.bodies.len(),
        joints: file.model.joint_count(),
    };
    crate::resources::check_memory(
        &format!("the frame's {} elements", counts.elements),
        "the factorised stiffness",
        crate::resources::frame_memory(counts.elements as u64),
    )?;
    let names = [json_name.as_str(), &path_csv_name, &path_png, &path_svg];
    let set = match target {
        OutputPath::Folder(_) => OutputSet::begin(&dir, &names)?,
        OutputPath::File { .. } => OutputSet::begin_beside(&dir, &names)?,
    };
    let solver = StaticSolver::new(file.model.clone()).map_err(FrameFileError::from)?;
    let followed = solver
        .follow_path(&file.path, &file.settings)
        .map_err(FrameFileError::from)?;
    let solution = followed.solution;
    if let StaticTermination::Overflow { .. } = solution.termination {
        return Err(FrameFileError::from(MechanicsError::NotFinite {
            detail: format!("the path {}", solution.termination),
        })
        .into());
    }
    let reference = file.model.reference();
    let nodes: Vec<FrameNodeOutput> = solution
        .state
        .frames
        .iter()
        .zip(reference)
        .zip(&file.nodes_origins)
        .enumerate()
        .map(|(id, ((now, then), origin))| {
            let (rod, rod_node, body) = match origin {
                NodeOrigin::Rod { rod, index } => (Some(rod.clone()), Some(*index), None),
                NodeOrigin::Body { body } => (None, None, Some(body.clone())),
            };
            let rotation = rotation::log(&(now.rotation * then.rotation.inverse()));
            FrameNodeOutput {
                id,
                rod,
                rod_node,
                body,
                position_m: now.position_m.into(),
                displacement_m: (now.position_m - then.position_m).into(),
                rotation_rad: rotation.into(),
            }
        })
        .collect();
    let (max_displacement_node, max_displacement_m) = nodes
        .iter()
        .map(|n| (n.id, norm3(n.displacement_m)))
        .fold((0, 0.0), |best, d| if d.1 > best.1 { d } else { best });
    let reactions = file
        .supported_nodes
        .iter()
        .map(|&n| {
            let r = solution.reactions.get(n).copied().unwrap_or([0.0; 6]);
            FrameReaction {
                node: n,
                member: file.nodes_origins[n].to_string(),
                force_n: [r[0], r[1], r[2]],
                moment_nm: [r[3], r[4], r[5]],
            }
        })
        .collect();
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let bad_node = nodes
        .iter()
        .find(|n| !finite(&n.position_m) || !finite(&n.rotation_rad));
    let bad_reaction = solution.reactions.iter().position(|r| !finite(r));
    if let Some(what) = bad_node
        .map(|n| format!("position of node {}", n.id))
        .or(bad_reaction.map(|n| format!("reaction at node {n}")))
    {
        return Err(FrameFileError::from(MechanicsError::NotFinite {
            detail: format!("the solved {what} is not finite"),
        })
        .into());
    }
    let output = FrameOutput {
        file: frame_path.display().to_string(),
        termination: solution.termination,
        load_factor: solution.load_factor,
        load_steps: solution.steps.len(),
        newton_iterations: solution.newton_iterations,
        rejected_steps: solution.rejected_steps,
        time_s: solution.time_s,
        max_displacement_m,
        max_displacement_node,
        counts,
        nodes,
        reactions,
        steps: solution.steps,
        path: FramePath {
            nodes: file.recorded_labels.clone(),
            points: followed.points,
        },
        critical_points: followed.critical_points,
        target: target_text(&file),
        final_negative_eigenvalues: followed.final_negative_eigenvalues,
    };
    let finite_path = output.path.points.iter().all(|p| {
        p.load_factor.is_finite() && p.displacements_m.iter().flatten().all(|v| v.is_finite())
    });
    if !finite_path {
        return Err(FrameFileError::from(MechanicsError::NotFinite {
            detail: "a load factor or displacement on the path is not finite".into(),
        })
        .into());
    }
    write_atomic(&set.path(&path_csv_name), path_csv(&output).as_bytes())?;
    path_plot(
        &path_figure(&output),
        &set.path(&path_png),
        &set.path(&path_svg),
    )?;
    write_json(&set.path(&json_name), &output)?;
    Ok(FrameOutcome {
        output,
        written: set.commit()?,
    })
}

/// `frame-path.csv`: one row per converged step (`kind` = `step`) and per
/// critical point (its kind, after the step before it): load factor, the
/// lowest eigenvalue, each recorded node's displacement.
fn path_csv(output: &FrameOutput) -> String {
    let mut csv = String::from("kind,step,load_factor,lowest_stiffness_n_per_m");
    for n in &output.path.nodes {
        for c in ["x", "y", "z"] {
            csv.push_str(&format!(",{n}_u{c}_m"));
        }
    }
    csv.push('\n');
    let row = |kind: &str, step: usize, lambda: f64, lowest: Option<f64>, u: &[[f64; 3]]| {
        let mut line = format!(
            "{kind},{step},{},{}",
            readable(lambda, 13),
            lowest.map_or(String::new(), |v| readable(v, 7))
        );
        for v in u.iter().flatten() {
            line.push(',');
            line.push_str(&readable(*v, 13));
        }
        line.push('\n');
        line
    };
    for (i, p) in output.path.points.iter().enumerate() {
        csv.push_str(&row(
            "step",
            i,
            p.load_factor,
            p.lowest_stiffness_n_per_m,
            &p.displacements_m,
        ));
        for c in output.critical_points.iter().filter(|c| c.after_point == i) {
            csv.push_str(&row(
                json_name(&c.kind).as_str(),
                i,
                c.load_factor,
                c.lowest_stiffness_n_per_m,
                &c.displacements_m,
            ));
        }
    }
    csv
}

/// The path plot: load factor against the first recorded node's
/// displacement component that moves most (the step number without one).
fn path_figure(output: &FrameOutput) -> PathFigure {
    let points = &output.path.points;
    let component = (0..3)
        .max_by(|&a, &b| {
            let range = |c: usize| {
                let v = points
                    .iter()
                    .filter_map(|p| p.displacements_m.first().map(|u| u[c]));
                v.clone().fold(f64::MIN, f64::max) - v.fold(f64::MAX, f64::min)
            };
            range(a).total_cmp(&range(b))
        })
        .unwrap_or(0);
    let x = |u: &[[f64; 3]], step: usize| u.first().map_or(step as f64, |u| u[component]);
    let x_label = output.path.nodes.first().map_or("step".to_string(), |n| {
        format!(
            "displacement {} of node \"{n}\" (the first [output] node), m",
            ["x", "y", "z"][component]
        )
    });
    PathFigure {
        title: format!("equilibrium path of {}", output.file),
        x_label,
        points: points
            .iter()
            .enumerate()
            .map(|(i, p)| (x(&p.displacements_m, i), p.load_factor))
            .collect(),
        critical: output
            .critical_points
            .iter()
            .map(|c| {
                (
                    x(&c.displacements_m, c.after_point),
                    c.load_factor,
                    json_name(&c.kind),
                )
            })
            .collect(),
    }
}
