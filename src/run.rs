//! One function per CLI subcommand: read the inputs, call the pipeline, write the
//! outputs (atomically, and only once everything is computed), and return what
//! the command prints. `main.rs` only parses arguments and calls these.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::algebra::norm3;
use crate::design::{
    design_loop, DesignError, IterationRecord, LoopOutcome, LoopSettings, LoopTermination,
    Relaxation, TiedNets,
};
use crate::effects::CableSelfWeight;
use crate::fdm::solve_network;
use crate::frame::cantilever::{self, CantileverRow};
use crate::frame::{FrameFile, FrameFileError, NodeOrigin};
use crate::geometry::{build_mesh, ReflectorMesh};
use crate::mechanics::{
    rotation, ElementKind, LimitSearch, StaticSolver, StaticTermination, StepRecord,
};
use crate::network::{Network, NetworkSummary};
use crate::report::{
    assembly_vtu, cables_csv, convergence_plot, front_csv, front_plot, front_row, network_vtu,
    parse_front_row, parse_study_row, study_csv, study_plot, study_row, surface_plot, write_atomic,
    write_json, FrontRow, FRONT_COLUMNS, STUDY_COLUMNS,
};
use crate::scene::{Scene, TrussModel};
use crate::shard::{self, Shard, ShardError, ShardHeader};
use crate::study::{self, Knob, StudyRow, StudySettings};
use crate::truss::{RingTruss, SceneTrussResponse, TrussError};
use crate::uniformity::{
    design_front_points, front_jobs, Design, FrontPoint, SolverKind, SurfaceTarget, Termination,
    UniformityError, UniformityProblem, UniformitySet, UniformitySolver,
};
use crate::verify::{verify, AssemblyTruss, Verification};
use crate::Error;

/// Progress of a long command; the CLI attaches a progress bar, the library
/// never prints.
pub trait Progress: Sync {
    /// The command will report `total` steps.
    fn start(&self, _total: usize) {}
    /// One step finished.
    fn step(&self, _message: &str) {}
}

/// A [`Progress`] that ignores everything.
pub struct Silent;

impl Progress for Silent {}

/// Where a scene's results go by default: `results/<scene name>/`.
pub fn default_output_dir(scene: &Scene) -> PathBuf {
    Path::new("results").join(&scene.name)
}

/// What `ringmesh mesh` made.
#[derive(Debug, Clone)]
pub struct MeshOutcome {
    /// The scene's name.
    pub scene: String,
    /// Counts and extreme lengths.
    pub summary: NetworkSummary,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// `ringmesh mesh`: builds the nets of a scene and writes `network.json` (the
/// interchange format, design positions, initial q) and `mesh.vtu`.
pub fn mesh(scene_path: &Path, output_dir: Option<&Path>) -> Result<MeshOutcome, Error> {
    let scene = Scene::read(scene_path)?;
    let mesh = build_mesh(&scene)?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let summary = mesh.network.summary();
    let vtu = network_vtu(&mesh.network, None, None);
    let network_path = dir.join("network.json");
    let vtu_path = dir.join("mesh.vtu");
    write_json(&network_path, &mesh.network)?;
    write_atomic(&vtu_path, vtu.as_bytes())?;
    Ok(MeshOutcome {
        scene: scene.name,
        summary,
        written: vec![network_path, vtu_path],
    })
}

/// The output of `ringmesh fdm`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FdmOutput {
    /// Equilibrium positions, m: n_nodes × 3.
    pub nodes: Vec<[f64; 3]>,
    /// Cable lengths, m: n_edges.
    pub lengths: Vec<f64>,
    /// Cable tensions, N: n_edges.
    pub forces: Vec<f64>,
    /// Support reactions `C_gᵀ Q C x − p_g`, N, in the order of `fixed`.
    pub reactions: Vec<[f64; 3]>,
    /// Largest out-of-balance force at a free node, N.
    pub max_residual: f64,
}

/// `ringmesh fdm`: forward equilibrium of an interchange-format network.
pub fn fdm(network_path: &Path, output_path: &Path) -> Result<FdmOutput, Error> {
    let network = Network::read_json(network_path)?;
    let (_, equilibrium) = solve_network(&network)?;
    let output = FdmOutput {
        max_residual: equilibrium.max_residual_n(),
        nodes: equilibrium.nodes_xyz_m,
        lengths: equilibrium.edges_lengths_m,
        forces: equilibrium.edges_forces_n,
        reactions: equilibrium.reactions_n,
    };
    write_json(output_path, &output)?;
    Ok(output)
}

/// The uniformity problem of a scene's front net for its theoretical boundary,
/// under the cables' self weight when the scene asks for gravity.
pub fn scene_problem(scene: &Scene) -> Result<(ReflectorMesh, UniformityProblem), Error> {
    let mesh = build_mesh(scene)?;
    let mut problem = UniformityProblem::from_mesh(
        &mesh,
        &scene.uniformity_targets(),
        scene.cables.max_force_density_n_per_m,
    )?;
    problem.min_tension_fraction = scene.uniformity.min_tension_fraction;
    let weights =
        CableSelfWeight::of(scene).map(|w| w.nodal_loads(&mesh.network.nodes, &mesh.network.edges));
    Ok((mesh, problem.with_loads(weights)?))
}

/// A scene's nets ready for the outer loop: the mesh and its two-stage
/// design problem ([`TiedNets`]).
pub struct SceneNets {
    /// The scene's nets and truss layout.
    pub mesh: ReflectorMesh,
    /// The two-stage design problem on them.
    pub nets: TiedNets,
}

impl SceneNets {
    /// Builds the mesh and the design problem of `scene`.
    ///
    /// # Errors
    /// An invalid mesh or uniformity problem.
    pub fn new(scene: &Scene) -> Result<SceneNets, Error> {
        let (mesh, problem) = scene_problem(scene)?;
        let nets =
            TiedNets::new(&mesh, problem)?.with_cable_self_weight(CableSelfWeight::of(scene));
        Ok(SceneNets { mesh, nets })
    }

    /// One run of the outer loop (net design ⇄ truss response) with a fresh
    /// truss oracle of `model` (the scene's truss values), calling `observe`
    /// after every iteration.
    ///
    /// # Errors
    /// A truss that cannot be built, or the loop's errors.
    pub fn design_loop(
        &self,
        scene: &Scene,
        solver: &dyn UniformitySolver,
        model: TrussModel,
        settings: &LoopSettings,
        observe: &mut dyn FnMut(&IterationRecord),
    ) -> Result<LoopOutcome, Error> {
        let mut oracle = crate::truss::oracle(model, scene, &self.mesh.truss)?;
        Ok(design_loop(
            &self.nets,
            solver,
            oracle.as_mut(),
            settings,
            observe,
        )?)
    }
}

/// `design.json`: the scene's name and the design.
#[derive(Serialize)]
struct DesignFile<'a> {
    scene: &'a str,
    #[serde(flatten)]
    design: &'a Design,
}

/// `ringmesh optimize`: one design for the theoretical boundary, written as
/// `design.json` and `cables.csv` (with cut lengths).
pub fn optimize(
    scene_path: &Path,
    solver: SolverKind,
    output_dir: Option<&Path>,
) -> Result<(Design, Vec<PathBuf>), Error> {
    let scene = Scene::read(scene_path)?;
    let (mesh, problem) = scene_problem(&scene)?;
    let design = solver.build(None).solve(&problem)?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let csv = cables_csv(&mesh.network, &design, &scene.cables);
    let (json_path, csv_path) = (dir.join("design.json"), dir.join("cables.csv"));
    write_json(
        &json_path,
        &DesignFile {
            scene: &scene.name,
            design: &design,
        },
    )?;
    write_atomic(&csv_path, csv.as_bytes())?;
    Ok((design, vec![json_path, csv_path]))
}

/// The output of `ringmesh uniformity`.
#[derive(Debug, Clone, Serialize)]
pub struct UniformityOutput {
    /// Force densities, N/m.
    pub q: Vec<f64>,
    /// Tensions, N.
    pub tensions: Vec<f64>,
    /// `Tmax/Tmin` over the uniformity groups.
    pub ratio: f64,
    /// Out-of-balance force of `q` on the prescribed geometry, N.
    pub max_residual: f64,
    /// The solver.
    pub solver: String,
    /// How it stopped.
    pub termination: Termination,
    /// Its iterations.
    pub iterations: usize,
    /// Wall time, s.
    pub time_s: f64,
}

/// `ringmesh uniformity`: the uniformity problem on a network whose node
/// positions are the prescribed geometry. `groups`: the uniformity set is their
/// union (default `front` when the file has groups, else every cable);
/// `mean_tension_n`: its target (default: the mean tension of the file's `q`);
/// `max_force_density_n_per_m`: the bound `[q]` on every cable (may be infinite).
pub fn uniformity(
    network_path: &Path,
    solver: SolverKind,
    groups: Option<&[String]>,
    mean_tension_n: Option<f64>,
    max_force_density_n_per_m: f64,
    output_path: &Path,
) -> Result<UniformityOutput, Error> {
    let network = Network::read_json(network_path)?;
    let default_groups = vec!["front".to_string()];
    let groups: Vec<String> = match (groups, &network.groups) {
        (Some(g), _) => g.to_vec(),
        (None, Some(_)) => default_groups,
        (None, None) => Vec::new(),
    };
    let edges: Vec<usize> = (0..network.n_edges())
        .filter(|&k| groups.is_empty() || groups.iter().any(|g| g == network.group_of(k)))
        .collect();
    if let Some(missing) = groups
        .iter()
        .find(|g| !(0..network.n_edges()).any(|k| network.group_of(k) == g.as_str()))
    {
        return Err(UniformityError::Invalid(format!(
            "--groups: no cable of the network is in group `{missing}`"
        ))
        .into());
    }
    let lengths: Vec<f64> = network.edges_vectors().into_iter().map(norm3).collect();
    let mean = match mean_tension_n {
        Some(t) => t,
        None => {
            edges
                .iter()
                .map(|&k| network.q[k] * lengths[k])
                .sum::<f64>()
                / edges.len().max(1) as f64
        }
    };
    let name = if groups.is_empty() {
        "all".to_string()
    } else {
        groups.join("+")
    };
    let fixed = network.fixed_mask();
    let surface = (0..network.n_nodes()).filter(|&i| !fixed[i]).collect();
    let set = UniformitySet {
        name,
        edges,
        mean_tension_n: mean,
    };
    let problem = UniformityProblem::new(
        network,
        vec![set],
        surface,
        SurfaceTarget::Prescribed,
        max_force_density_n_per_m,
    )?;
    let design = solver.build(None).solve(&problem)?;
    let output = UniformityOutput {
        ratio: design.ratio,
        max_residual: design.max_residual_n,
        tensions: problem
            .lengths_m()
            .iter()
            .zip(&design.q)
            .map(|(l, q)| l * q)
            .collect(),
        q: design.q,
        solver: design.solver,
        termination: design.termination,
        iterations: design.iterations,
        time_s: design.time_s,
    };
    write_json(output_path, &output)?;
    Ok(output)
}

/// `ringmesh front`: the design front of a scene (each solver's knob swept in
/// parallel), written as `front.csv`, `front.png` and `front.svg`; with a
/// `shard`, only that shard's points, written as `front.shard-I-of-N.csv`
/// (see [`crate::shard`]; `ringmesh merge` makes the table and the plot).
pub fn front(
    scene_path: &Path,
    solvers: &[SolverKind],
    points: usize,
    output_dir: Option<&Path>,
    shard: Option<Shard>,
    progress: &dyn Progress,
) -> Result<(Vec<FrontPoint>, Vec<PathBuf>), Error> {
    let scene = Scene::read(scene_path)?;
    let (_, problem) = scene_problem(&scene)?;
    let jobs = front_jobs(&problem, solvers, points);
    let indices = shard.unwrap_or(Shard::WHOLE).points(jobs.len());
    let mine: Vec<(SolverKind, f64)> = indices.iter().map(|&k| jobs[k]).collect();
    progress.start(mine.len());
    let front = design_front_points(&problem, &mine, &|p: &FrontPoint| {
        progress.step(&format!("{:?} knob {:.3e}", p.solver, p.knob));
    });
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    if let Some(shard) = shard {
        let settings = serde_json::json!({
            "solvers": solvers.iter().map(study::value_name).collect::<Vec<_>>(),
            "points": points,
        });
        let rows: Vec<(usize, String)> = indices
            .iter()
            .zip(&front)
            .filter_map(|(&k, p)| FrontRow::of(p).map(|r| (k, front_row(&r))))
            .collect();
        let path = write_shard(
            &dir,
            "front",
            "front",
            &scene,
            shard,
            jobs.len(),
            settings,
            FRONT_COLUMNS,
            &rows,
        )?;
        return Ok((front, vec![path]));
    }
    let rows: Vec<FrontRow> = front.iter().filter_map(FrontRow::of).collect();
    let paths = write_front(&dir, &scene.name, &rows, &front_csv(&rows))?;
    Ok((front, paths))
}

/// `front.csv` (the table `csv`), `front.png`, `front.svg` (drawn from `rows`).
fn write_front(
    dir: &Path,
    scene: &str,
    rows: &[FrontRow],
    csv: &str,
) -> Result<Vec<PathBuf>, Error> {
    let paths = [
        dir.join("front.csv"),
        dir.join("front.png"),
        dir.join("front.svg"),
    ];
    let title = format!("{scene}: tension uniformity against surface accuracy");
    front_plot(rows, &title, &paths[1], &paths[2])?;
    write_atomic(&paths[0], csv.as_bytes())?;
    Ok(paths.to_vec())
}

/// Writes a shard's CSV, `<stem>.shard-I-of-N.csv`, in `dir`.
#[allow(clippy::too_many_arguments)]
fn write_shard(
    dir: &Path,
    stem: &str,
    command: &str,
    scene: &Scene,
    shard: Shard,
    points: usize,
    settings: serde_json::Value,
    columns: &str,
    rows: &[(usize, String)],
) -> Result<PathBuf, Error> {
    let header = ShardHeader {
        command: command.to_string(),
        scene: scene.name.clone(),
        shard,
        points,
        settings,
        scene_file: serde_json::to_value(scene).expect("a scene serialises"),
    };
    let path = dir.join(shard.file_name(stem));
    write_atomic(&path, shard::shard_csv(&header, columns, rows).as_bytes())?;
    Ok(path)
}

/// Choices of `ringmesh study`, resolved by the CLI; `None` keeps the
/// default sweep of [`StudySettings::for_scene`].
#[derive(Debug, Clone)]
pub struct StudyOptions {
    /// The knobs swept (the others are left out).
    pub knobs: Vec<Knob>,
    /// Outer-loop tolerances, m.
    pub tolerances_m: Option<Vec<f64>>,
    /// Elements per truss rod.
    pub elements_per_rod: Option<Vec<usize>>,
    /// Front-net rings.
    pub rings: Option<Vec<usize>>,
    /// Truss models.
    pub truss_models: Option<Vec<TrussModel>>,
    /// Uniformity solvers.
    pub solvers: Option<Vec<SolverKind>>,
    /// Most outer iterations of a run.
    pub max_iterations: Option<usize>,
    /// Points run at once (1: one after the other, each timed alone).
    pub jobs: usize,
}

impl Default for StudyOptions {
    fn default() -> Self {
        StudyOptions {
            knobs: Knob::SWEPT.to_vec(),
            tolerances_m: None,
            elements_per_rod: None,
            rings: None,
            truss_models: None,
            solvers: None,
            max_iterations: None,
            jobs: 1,
        }
    }
}

impl StudyOptions {
    /// The study's settings for `scene`.
    pub fn settings(&self, scene: &Scene) -> StudySettings {
        let mut s = StudySettings::for_scene(scene);
        if let Some(v) = &self.tolerances_m {
            s.tolerances_m.clone_from(v);
        }
        if let Some(v) = &self.elements_per_rod {
            s.elements_per_rod.clone_from(v);
        }
        if let Some(v) = &self.rings {
            s.rings.clone_from(v);
        }
        if let Some(v) = &self.truss_models {
            s.truss_models.clone_from(v);
        }
        if let Some(v) = &self.solvers {
            s.solvers.clone_from(v);
        }
        if let Some(n) = self.max_iterations {
            s.max_iterations = n;
        }
        s.only(&self.knobs)
    }
}

/// What `ringmesh study` made.
#[derive(Debug)]
pub struct StudyOutcome {
    /// The scene's name.
    pub scene: String,
    /// `(point index, row)` of the points run, in sweep order.
    pub rows: Vec<(usize, StudyRow)>,
    /// Points of the whole sweep.
    pub points: usize,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// The name of the study's table and plots.
pub const STUDY_STEM: &str = "accuracy-vs-time";

/// `ringmesh study`: what accuracy costs in time ([`crate::study`]). Writes
/// `accuracy-vs-time.csv`, `.png` and `.svg`; with a `shard`, only that
/// shard's points (and the reference, run to judge them), written as
/// `accuracy-vs-time.shard-I-of-N.csv`.
pub fn study(
    scene_path: &Path,
    options: &StudyOptions,
    output_dir: Option<&Path>,
    shard: Option<Shard>,
    progress: &dyn Progress,
) -> Result<StudyOutcome, Error> {
    let scene = Scene::read(scene_path)?;
    let settings = options.settings(&scene);
    settings.validate()?;
    let total = study::points(&scene, &settings).len();
    let part = shard.unwrap_or(Shard::WHOLE);
    let runs = part.points(total).len() + usize::from(!part.includes(0));
    progress.start(runs);
    let rows = study::run_study(&scene, &settings, part, options.jobs, &|r: &StudyRow| {
        progress.step(&format!("{} {}", r.knob.name(), r.value));
    })?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let written = match shard {
        Some(shard) => {
            let lines: Vec<(usize, String)> =
                rows.iter().map(|(k, r)| (*k, study_row(r))).collect();
            let settings = serde_json::to_value(&settings).expect("settings serialise");
            vec![write_shard(
                &dir,
                STUDY_STEM,
                "study",
                &scene,
                shard,
                total,
                settings,
                STUDY_COLUMNS,
                &lines,
            )?]
        }
        None => {
            let table: Vec<StudyRow> = rows.iter().map(|(_, r)| r.clone()).collect();
            write_study(&dir, &scene.name, &table, &study_csv(&table))?
        }
    };
    Ok(StudyOutcome {
        scene: scene.name,
        rows,
        points: total,
        written,
    })
}

/// `accuracy-vs-time.csv` (the table `csv`), `.png`, `.svg` (drawn from `rows`).
fn write_study(
    dir: &Path,
    scene: &str,
    rows: &[StudyRow],
    csv: &str,
) -> Result<Vec<PathBuf>, Error> {
    let paths = [
        dir.join(format!("{STUDY_STEM}.csv")),
        dir.join(format!("{STUDY_STEM}.png")),
        dir.join(format!("{STUDY_STEM}.svg")),
    ];
    let title =
        format!("{scene}: what accuracy costs in time (designs as built on the reference truss)");
    study_plot(rows, &title, &paths[1], &paths[2])?;
    write_atomic(&paths[0], csv.as_bytes())?;
    Ok(paths.to_vec())
}

/// One sweep joined by `ringmesh merge`.
#[derive(Debug)]
pub struct MergeOutcome {
    /// The command whose shards were joined (`front`, `study`).
    pub command: String,
    /// The scene's name.
    pub scene: String,
    /// Shards joined.
    pub shards: usize,
    /// Rows of the merged table.
    pub rows: usize,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// `ringmesh merge`: joins the shard CSVs among `paths` (files, or folders
/// holding `*.shard-I-of-N.csv`) into each sweep's table and plots, exactly
/// as the unsharded run writes them, in `output_dir` (default
/// `results/<scene>/`). Shards of different scenes or settings, duplicate or
/// missing shards are refused before anything is written.
pub fn merge(paths: &[PathBuf], output_dir: Option<&Path>) -> Result<Vec<MergeOutcome>, Error> {
    let files = shard::find_shards(paths)?
        .iter()
        .map(|p| shard::read_shard(p))
        .collect::<Result<Vec<_>, _>>()?;
    let merged = shard::merge(files)?;
    // Parse every table before writing any.
    enum Table {
        Front(Vec<FrontRow>),
        Study(Vec<StudyRow>),
    }
    let mut tables = Vec::new();
    for m in &merged {
        let bad = |reason: String| ShardError::Format {
            path: m.files[0].clone(),
            reason,
        };
        let table = match m.header.command.as_str() {
            "front" => Table::Front(
                m.rows
                    .iter()
                    .map(|l| parse_front_row(l).map_err(&bad))
                    .collect::<Result<_, _>>()?,
            ),
            "study" => Table::Study(
                m.rows
                    .iter()
                    .map(|l| parse_study_row(l).map_err(&bad))
                    .collect::<Result<_, _>>()?,
            ),
            other => return Err(bad(format!("unknown command `{other}`")).into()),
        };
        tables.push(table);
    }
    let mut outcomes = Vec::new();
    for (m, table) in merged.iter().zip(tables) {
        let dir = output_dir.map_or_else(
            || Path::new("results").join(&m.header.scene),
            Path::to_path_buf,
        );
        // The plots are drawn from the parsed rows; the table is the shards' text.
        let written = match table {
            Table::Front(rows) => write_front(&dir, &m.header.scene, &rows, &m.csv())?,
            Table::Study(rows) => write_study(&dir, &m.header.scene, &rows, &m.csv())?,
        };
        outcomes.push(MergeOutcome {
            command: m.header.command.clone(),
            scene: m.header.scene.clone(),
            shards: m.files.len(),
            rows: m.rows.len(),
            written,
        });
    }
    Ok(outcomes)
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

/// Where `ringmesh frame FILE` writes by default: `results/<file stem>/frame.json`.
pub fn default_frame_output(frame_path: &Path) -> PathBuf {
    let stem = frame_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frame".into());
    Path::new("results").join(stem).join("frame.json")
}

/// `ringmesh frame`: reads a frame file, solves its statics and writes every
/// node's position, displacement and rotation, the reactions and the solver's
/// statistics as JSON (`output_path`, default [`default_frame_output`]).
/// Not converging is a termination status in the output, not an error.
pub fn frame(
    frame_path: &Path,
    output_path: Option<&Path>,
) -> Result<(FrameOutput, PathBuf), Error> {
    let file = FrameFile::read(frame_path)?;
    let output_path =
        output_path.map_or_else(|| default_frame_output(frame_path), Path::to_path_buf);
    let counts = FrameCounts {
        nodes: file.model.node_count(),
        rods: file.model.rods().len(),
        elements: file.model.element_count(),
        bodies: file.bodies.len(),
        joints: file.model.joint_count(),
    };
    let solver = StaticSolver::new(file.model.clone()).map_err(FrameFileError::from)?;
    let solution = solver.solve(&file.settings).map_err(FrameFileError::from)?;
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
    };
    write_json(&output_path, &output)?;
    Ok((output, output_path))
}

/// One row of `ringmesh cantilever`: the engine's row and the paper's result
/// where the paper gives one.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CantileverTableRow {
    /// Ours, the closed form, the error and the solver's statistics.
    #[serde(flatten)]
    pub row: CantileverRow,
    /// The paper's tip axial displacement (Tables 1–2, 10 elements), m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_axial_m: Option<f64>,
    /// The paper's tip vertical displacement, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper_vertical_m: Option<f64>,
}

/// The output of `ringmesh cantilever`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CantileverTable {
    /// Elements along the cantilever.
    pub elements: usize,
    /// The element type.
    pub element: String,
    /// One row per load `ML/(πEI)` of [`cantilever::M_RATIOS`].
    pub rows: Vec<CantileverTableRow>,
}

/// `ringmesh cantilever`: the paper's Tables 1–2 (§3.4) with `elements`
/// elements of `kind`, every load from 0.2 to the full circle.
pub fn cantilever(elements: usize, kind: ElementKind) -> Result<CantileverTable, Error> {
    let rows = cantilever::table(elements, kind)
        .map_err(FrameFileError::from)?
        .into_iter()
        .map(|row| {
            let paper = cantilever::PAPER.iter().find(|p| p.0 == row.m_ratio);
            CantileverTableRow {
                paper_axial_m: paper.map(|p| p.1),
                paper_vertical_m: paper.map(|p| p.2),
                row,
            }
        })
        .collect();
    Ok(CantileverTable {
        elements,
        element: kind.name().to_string(),
        rows,
    })
}

/// `ringmesh truss`: the scene's truss model (default: the scene's
/// `[effects] truss`) under the pull of its net (forward FDM with the initial
/// q) or under the loads of a file; writes `truss-<model>.json` beside the
/// scene's other results.
pub fn truss(
    scene_path: &Path,
    model: Option<TrussModel>,
    loads_path: Option<&Path>,
    output_path: Option<&Path>,
) -> Result<(SceneTrussResponse, PathBuf), Error> {
    let scene = Scene::read(scene_path)?;
    let model = model.unwrap_or(scene.effects.truss);
    let loads = match loads_path {
        Some(p) => Some((p.display().to_string(), crate::truss::read_loads(p)?)),
        None => None,
    };
    let response = crate::truss::respond(&scene, model, loads)?;
    let path = output_path.map_or_else(
        || default_output_dir(&scene).join(format!("truss-{}.json", response.model)),
        Path::to_path_buf,
    );
    write_json(&path, &response)?;
    Ok((response, path))
}

/// Choices of `ringmesh design`, resolved by the CLI.
#[derive(Debug, Clone)]
pub struct DesignOptions {
    /// The uniformity solver.
    pub solver: SolverKind,
    /// The truss model (default: the scene's `[effects] truss`).
    pub truss: Option<TrussModel>,
    /// Relaxation policies: the first makes the design; the others only add
    /// their convergence histories for comparison.
    pub relaxations: Vec<Relaxation>,
    /// Stopping tolerance on `‖G(C) − C‖∞`, m.
    pub tolerance_m: f64,
    /// Most outer iterations.
    pub max_iterations: usize,
}

impl Default for DesignOptions {
    fn default() -> Self {
        let loop_settings = LoopSettings::default();
        DesignOptions {
            solver: SolverKind::Lp,
            truss: None,
            relaxations: vec![loop_settings.relaxation],
            tolerance_m: loop_settings.tolerance_m,
            max_iterations: loop_settings.max_iterations,
        }
    }
}

/// One relaxation policy's run of the outer loop.
#[derive(Debug, Clone, Serialize)]
pub struct LoopRun {
    /// The policy.
    pub relaxation: Relaxation,
    /// How it ended.
    pub termination: LoopTermination,
    /// Outer iterations (designs made).
    pub outer_iterations: usize,
    /// Final `‖G(C) − C‖∞`, m.
    pub boundary_residual_m: f64,
    /// Wall time, s.
    pub time_s: f64,
    /// Per iteration.
    pub history: Vec<IterationRecord>,
    /// Why a comparison run stopped without a result (the truss found no
    /// equilibrium once the iteration ran away, say).
    pub error: Option<String>,
}

/// `design.json`: the outer loop's design, its verification by assembly, and
/// the conventional (rigid-truss) design verified on the same truss.
#[derive(Debug, Clone, Serialize)]
pub struct DesignReport {
    /// The scene's name.
    pub scene: String,
    /// The uniformity solver.
    pub solver: String,
    /// The truss model of the loop.
    pub truss: TrussModel,
    /// The relaxation policy that made the design.
    pub relaxation: Relaxation,
    /// How the loop ended.
    pub termination: LoopTermination,
    /// Outer iterations.
    pub outer_iterations: usize,
    /// Final fixed-point residual `‖G(C) − C‖∞`, m.
    pub boundary_residual_m: f64,
    /// The design's largest set ratio `Tmax/Tmin`.
    pub ratio: f64,
    /// Wall time of the whole run (every loop, verifications), s.
    pub time_s: f64,
    /// The design loop's iterations.
    pub history: Vec<IterationRecord>,
    /// Every policy run, the design's first.
    pub runs: Vec<LoopRun>,
    /// The design cut to length and assembled.
    pub verification: Verification,
    /// The rigid-truss design assembled on the same truss (absent when the
    /// loop's truss is rigid: then it is the design itself).
    pub conventional: Option<Verification>,
    /// The flexible truss's limit load under the design's pull (DESIGN §9):
    /// stable up to `stable_to` × the pull (absent for a rigid truss).
    pub limit_margin: Option<LimitSearch>,
    /// The boundary the design is made for, `C` (top hinges, then bottom), m.
    pub boundary_m: Vec<[f64; 3]>,
    /// The design: q, tensions, lengths, nodes, reactions, spreads.
    pub net: Design,
}

/// What `ringmesh design` made.
#[derive(Debug)]
pub struct DesignOutcome {
    /// The report (also in `design.json`).
    pub report: DesignReport,
    /// Files written.
    pub written: Vec<PathBuf>,
}

/// `ringmesh design`: the outer design loop (net design ⇄ truss response) with
/// each relaxation asked for, the design verified by assembly, the
/// conventional design verified on the same truss, and every output written
/// once all is computed. `observe` sees each outer iteration.
pub fn design(
    scene_path: &Path,
    options: &DesignOptions,
    output_dir: Option<&Path>,
    observe: &mut dyn FnMut(Relaxation, &IterationRecord),
) -> Result<DesignOutcome, Error> {
    let clock = std::time::Instant::now();
    let scene = Scene::read(scene_path)?;
    let model = options.truss.unwrap_or(scene.effects.truss);
    let scene_nets = SceneNets::new(&scene)?;
    let (mesh, nets) = (&scene_nets.mesh, &scene_nets.nets);
    let solver = options.solver.build(None);
    let relaxations = if options.relaxations.is_empty() {
        vec![Relaxation::default()]
    } else {
        options.relaxations.clone()
    };
    let mut runs = Vec::new();
    let mut outcome = None;
    for &relaxation in &relaxations {
        let settings = LoopSettings {
            relaxation,
            tolerance_m: options.tolerance_m,
            max_iterations: options.max_iterations,
            ..LoopSettings::default()
        };
        let mut history = Vec::new();
        let result = scene_nets.design_loop(&scene, solver.as_ref(), model, &settings, &mut |r| {
            history.push(r.clone());
            observe(relaxation, r)
        });
        match result {
            Ok(result) => {
                runs.push(LoopRun {
                    relaxation,
                    termination: result.termination,
                    outer_iterations: result.history.len(),
                    boundary_residual_m: result.boundary_residual_m(),
                    time_s: result.time_s,
                    history: result.history.clone(),
                    error: None,
                });
                outcome.get_or_insert(result);
            }
            // A comparison run may fail without losing the design.
            Err(e) if outcome.is_some() => runs.push(LoopRun {
                relaxation,
                termination: LoopTermination::Diverged,
                outer_iterations: history.len(),
                boundary_residual_m: history.last().map_or(f64::NAN, |r| r.boundary_change_max_m),
                time_s: history.last().map_or(0.0, |r| r.elapsed_s),
                history,
                error: Some(e.to_string()),
            }),
            // No truss equilibrium: say how far below the pull the truss's
            // stability ends (the rigid-truss design's pull, the loop's first).
            Err(
                e @ Error::Design(DesignError::Truss {
                    source: TrussError::NoEquilibrium { .. },
                    ..
                }),
            ) => {
                let first =
                    nets.design(solver.as_ref(), &crate::truss::layout_points(&mesh.truss))?;
                return Err(match design_margin(&scene, mesh, &first.design) {
                    Err(past) => past,
                    Ok(_) => e,
                });
            }
            Err(e) => return Err(e),
        }
    }
    let outcome = outcome.expect("at least one relaxation");
    let assembly = if model == TrussModel::Rigid {
        AssemblyTruss::Rigid
    } else {
        AssemblyTruss::Flexible
    };
    let limit_margin = match assembly {
        AssemblyTruss::Rigid => None,
        AssemblyTruss::Flexible => Some(design_margin(&scene, mesh, &outcome.design)?),
    };
    let network = outcome.problem.network();
    let verification = verify(&scene, mesh, network, &outcome.design, assembly)?;
    let conventional = match assembly {
        AssemblyTruss::Rigid => None,
        AssemblyTruss::Flexible => {
            let rigid = nets.design(solver.as_ref(), &crate::truss::layout_points(&mesh.truss))?;
            Some(verify(
                &scene,
                mesh,
                rigid.problem.network(),
                &rigid.design,
                AssemblyTruss::Flexible,
            )?)
        }
    };

    let report = DesignReport {
        scene: scene.name.clone(),
        solver: solver.name().to_string(),
        truss: model,
        relaxation: relaxations[0],
        termination: outcome.termination,
        outer_iterations: outcome.history.len(),
        boundary_residual_m: outcome.boundary_residual_m(),
        ratio: outcome.design.ratio,
        time_s: clock.elapsed().as_secs_f64(),
        history: outcome.history.clone(),
        runs,
        verification,
        conventional,
        limit_margin,
        boundary_m: outcome.boundary_m.clone(),
        net: outcome.design.clone(),
    };
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let written = write_design(&dir, &scene, mesh, network, &report)?;
    Ok(DesignOutcome { report, written })
}

/// The margin of `scene`'s truss to its limit load under `design`'s pull.
///
/// # Errors
/// A pull the truss cannot carry stably ([`TrussError::PastLimitLoad`]).
fn design_margin(
    scene: &Scene,
    mesh: &ReflectorMesh,
    design: &Design,
) -> Result<LimitSearch, Error> {
    // The net pulls on its supports with −F_g.
    let pull = design.pull_n();
    let truss = RingTruss::new(scene, &mesh.truss).map_err(TrussError::from)?;
    let margin = crate::truss::limit_margin(truss, &pull)?;
    match margin.unstable_from {
        Some(unstable_from) if margin.stable_to < 1.0 => Err(TrussError::PastLimitLoad {
            stable_to: margin.stable_to,
            unstable_from,
        }
        .into()),
        _ => Ok(margin),
    }
}

/// The files of `ringmesh design`, each written atomically.
fn write_design(
    dir: &Path,
    scene: &Scene,
    mesh: &ReflectorMesh,
    network: &Network,
    report: &DesignReport,
) -> Result<Vec<PathBuf>, Error> {
    let path = |name: &str| dir.join(name);
    let series: Vec<(String, Vec<(usize, f64)>)> = report
        .runs
        .iter()
        .map(|run| {
            (
                run.relaxation.name().to_string(),
                run.history
                    .iter()
                    .map(|r| (r.iteration, r.boundary_change_max_m))
                    .collect(),
            )
        })
        .collect();
    convergence_plot(
        &series,
        &format!("{}: outer design loop", scene.name),
        &path("convergence.png"),
        &path("convergence.svg"),
    )?;
    let fixed = network.fixed_mask();
    let surface: Vec<(f64, f64, f64)> = (0..mesh.n_front_nodes)
        .filter(|&i| !fixed[i])
        .map(|i| {
            let p = report.verification.nodes_xyz_m[i];
            (p[0], p[1], 1e3 * mesh.paraboloid.axial_deviation(p))
        })
        .collect();
    surface_plot(
        &surface,
        &format!(
            "{}: assembled surface error (mm), RMS {:.2e} mm",
            scene.name, report.verification.rms_mm
        ),
        &path("surface-error.png"),
    )?;
    write_atomic(
        &path("model.vtu"),
        assembly_vtu(network, &report.net.q, &report.verification).as_bytes(),
    )?;
    write_atomic(
        &path("convergence.csv"),
        convergence_csv(&report.runs).as_bytes(),
    )?;
    write_atomic(
        &path("cables.csv"),
        cables_csv(network, &report.net, &scene.cables).as_bytes(),
    )?;
    write_json(&path("design.json"), report)?;
    Ok([
        "design.json",
        "cables.csv",
        "convergence.csv",
        "convergence.png",
        "convergence.svg",
        "surface-error.png",
        "model.vtu",
    ]
    .iter()
    .map(|n| path(n))
    .collect())
}

/// `relaxation,iteration,…`: one row per outer iteration of every run.
fn convergence_csv(runs: &[LoopRun]) -> String {
    use std::fmt::Write;
    let mut s = String::from(
        "relaxation,iteration,boundary_change_max_m,boundary_change_rms_m,xi_change_m,ratio,\
         relaxation_factor,oracle_newton_iterations,design_time_s,truss_time_s,elapsed_s\n",
    );
    for run in runs {
        for r in &run.history {
            let _ = writeln!(
                s,
                "{},{},{:e},{:e},{},{:.12e},{:e},{},{:e},{:e},{:e}",
                run.relaxation.name(),
                r.iteration,
                r.boundary_change_max_m,
                r.boundary_change_rms_m,
                r.xi_change_m.map_or(String::new(), |v| format!("{v:e}")),
                r.ratio,
                r.relaxation_factor,
                r.oracle_newton_iterations,
                r.design_time_s,
                r.truss_time_s,
                r.elapsed_s
            );
        }
    }
    s
}
