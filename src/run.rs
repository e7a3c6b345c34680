//! One function per CLI subcommand: read the inputs, call the pipeline, write the
//! outputs (atomically, and only once everything is computed), and return what
//! the command prints. `main.rs` only parses arguments and calls these.

use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::fdm::solve_network;
use crate::geometry::{build_mesh, ReflectorMesh};
use crate::network::{norm3, Network, NetworkSummary};
use crate::report::{cables_csv, front_csv, front_plot, network_vtu, write_atomic, write_json};
use crate::scene::Scene;
use crate::uniformity::{
    design_front, Design, FrontPoint, SolverKind, SurfaceTarget, Termination, UniformityError,
    UniformityProblem, UniformitySet,
};
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

/// The uniformity problem of a scene's front net for its theoretical boundary.
pub fn scene_problem(scene: &Scene) -> Result<(ReflectorMesh, UniformityProblem), Error> {
    let mesh = build_mesh(scene)?;
    let mut problem = UniformityProblem::from_mesh(
        &mesh,
        &scene.uniformity_targets(),
        scene.cables.max_force_density_n_per_m,
    )?;
    problem.min_tension_fraction = scene.uniformity.min_tension_fraction;
    Ok((mesh, problem))
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
/// parallel), written as `front.csv`, `front.png` and `front.svg`.
pub fn front(
    scene_path: &Path,
    solvers: &[SolverKind],
    points: usize,
    output_dir: Option<&Path>,
    progress: &dyn Progress,
) -> Result<(Vec<FrontPoint>, Vec<PathBuf>), Error> {
    let scene = Scene::read(scene_path)?;
    let (_, problem) = scene_problem(&scene)?;
    let total: usize = solvers
        .iter()
        .map(|&s| crate::uniformity::knob_values(s, &problem, points).len())
        .sum();
    progress.start(total);
    let front = design_front(&problem, solvers, points, &|p: &FrontPoint| {
        progress.step(&format!("{:?} knob {:.3e}", p.solver, p.knob));
    });
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    let paths = [
        dir.join("front.csv"),
        dir.join("front.png"),
        dir.join("front.svg"),
    ];
    let title = format!(
        "{}: tension uniformity against surface accuracy",
        scene.name
    );
    front_plot(&front, &title, &paths[1], &paths[2])?;
    write_atomic(&paths[0], front_csv(&front).as_bytes())?;
    Ok((front, paths.to_vec()))
}
