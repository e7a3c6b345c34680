//! `ringmesh uniformity`: the uniformity problem on an interchange-format
//! network whose node positions are the prescribed geometry.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::Summary;
use crate::algebra::norm3;
use crate::network::Network;
use crate::report::{json_bytes, json_name, readable, OutputPath, OutputSet};
use crate::uniformity::{
    Route, SolverKind, SurfaceTarget, Termination, UniformityError, UniformityProblem,
    UniformitySet,
};
use crate::Error;

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
    /// How the solver got there, when it has several routes (`lp`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub route: Option<Route>,
    /// Everything the solver reported other than plain success (a fallback
    /// and its reason among them).
    pub warnings: Vec<String>,
}

/// What `ringmesh uniformity` made.
#[derive(Debug, Clone)]
pub struct UniformityOutcome {
    /// The output (also in the file written).
    pub output: UniformityOutput,
    /// The file written.
    pub written: PathBuf,
}

impl UniformityOutcome {
    /// What `ringmesh uniformity` prints: the ratio, the residual, how the
    /// solver ended, its route and warnings, the file written.
    pub fn summary(&self) -> Summary {
        let o = &self.output;
        let mut s = Summary::default();
        say!(s, "Tmax/Tmin: {}", readable(o.ratio, 7));
        say!(s, "max residual: {} N", readable(o.max_residual, 4));
        say!(
            s,
            "termination: {} after {} iterations of {}, {:.3} s",
            json_name(&o.termination),
            o.iterations,
            o.solver,
            o.time_s
        );
        if let Some(route) = o.route {
            say!(s, "route: {route}");
        }
        for w in &o.warnings {
            say!(s, "warning: {w}");
        }
        s.written(std::slice::from_ref(&self.written));
        s
    }
}

/// `ringmesh uniformity`: the uniformity problem on a network whose node
/// positions are the prescribed geometry. `groups`: the uniformity set is their
/// union (default `front` when the file has groups, else every cable);
/// `mean_tension_n`: its target (default: the mean tension of the file's `q`);
/// `max_force_density_n_per_m`: the bound `[q]` on every cable (may be infinite);
/// `solver` defaults to [`SolverKind::default_for`] one unloaded set (`lp`).
/// `output_path`: a `.json` file, or a folder that receives
/// `uniformity.json` ([`OutputPath`]), whose folder is checked before
/// computing.
pub fn uniformity(
    network_path: &Path,
    solver: Option<SolverKind>,
    groups: Option<&[String]>,
    mean_tension_n: Option<f64>,
    max_force_density_n_per_m: f64,
    output_path: &Path,
) -> Result<UniformityOutcome, Error> {
    let (dir, file_name) = OutputPath::resolve(output_path)?.folder_and_name("uniformity.json");
    OutputSet::check_folder(&dir)?;
    let network = Network::read_json(network_path)?;
    crate::resources::check_network(
        network_path,
        network.n_nodes(),
        network.edges.len(),
        crate::resources::SceneCommand::Optimize,
    )?;
    let output = uniformity_of(
        network,
        solver,
        &serde_json::Map::new(),
        groups,
        mean_tension_n,
        max_force_density_n_per_m,
    )?;
    let bytes = json_bytes(&dir.join(&file_name), &output)?;
    let written = OutputSet::write_one(&dir, &file_name, &bytes)?;
    Ok(UniformityOutcome { output, written })
}

/// The work of [`uniformity`] on a network in memory (validated here), the
/// solver configured with `settings` ([`SolverKind::configure`]): what a
/// library user (the Python bindings) calls.
///
/// # Errors
/// An invalid network, group, setting or problem; a solver that fails or
/// finds no feasible design.
pub fn uniformity_of(
    network: Network,
    solver: Option<SolverKind>,
    settings: &serde_json::Map<String, serde_json::Value>,
    groups: Option<&[String]>,
    mean_tension_n: Option<f64>,
    max_force_density_n_per_m: f64,
) -> Result<UniformityOutput, Error> {
    let problem = uniformity_problem(network, groups, mean_tension_n, max_force_density_n_per_m)?;
    let solver = solver.unwrap_or_else(|| SolverKind::default_for(1, problem.has_loads()));
    let design = solver.configure(settings)?.solve(&problem)?.feasible()?;
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
        route: design.route,
        warnings: design.warnings,
    };
    Ok(output)
}

/// The uniformity problem of [`uniformity_of`]: `network` (validated here)
/// at its own geometry, the set the union of `groups` (default `front`
/// when the network has groups, else every cable), its mean tension
/// `mean_tension_n` (default: the network's own), every free node a
/// prescribed surface node.
///
/// # Errors
/// An invalid network or group.
pub fn uniformity_problem(
    network: Network,
    groups: Option<&[String]>,
    mean_tension_n: Option<f64>,
    max_force_density_n_per_m: f64,
) -> Result<UniformityProblem, Error> {
    network.validate()?;
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
        return Err(UniformityError::invalid(
            "--groups",
            format!("no cable of the network is in group `{missing}`"),
        )
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
    Ok(problem)
}
