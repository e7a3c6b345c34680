//! `ringmesh optimize`: one design of a scene's nets for its theoretical
//! boundary (no truss): the two-stage design of the design loop's iteration
//! 0, both nets at the scene's mean tensions.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{default_output_dir, read_scene, Summary};
use crate::design::{default_solver, SceneNets};
use crate::report::{
    cables_csv, json_name, readable, write_atomic, write_json, OutputSet, WithRun,
};
use crate::resources::{check_scene, SceneCommand};
use crate::truss::layout_points;
use crate::uniformity::{Design, SolverKind};
use crate::Error;

/// `design.json`: the scene's name and the design.
#[derive(Serialize)]
struct DesignFile<'a> {
    scene: &'a str,
    #[serde(flatten)]
    design: &'a Design,
}

/// What `ringmesh optimize` made.
#[derive(Debug, Clone)]
pub struct OptimizeOutcome {
    /// The design (also in `design.json`).
    pub design: Design,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl OptimizeOutcome {
    /// What `ringmesh optimize` prints: the ratio of each uniformity set, the
    /// surface RMS, how the solver ended, its route and warnings, the files
    /// written.
    pub fn summary(&self) -> Summary {
        let d = &self.design;
        let mut s = Summary::default();
        for set in &d.sets {
            say!(
                s,
                "Tmax/Tmin over {}: {} ({} cables)",
                set.name,
                readable(set.ratio, 7),
                set.cables
            );
        }
        say!(
            s,
            "surface RMS: {} mm (max {} mm)",
            readable(1e3 * d.surface_rms_m, 4),
            readable(1e3 * d.surface_max_m, 4)
        );
        say!(
            s,
            "termination: {} after {} iterations of {}, {:.3} s",
            json_name(&d.termination),
            d.iterations,
            d.solver,
            d.time_s
        );
        if let Some(route) = d.route {
            say!(s, "route: {route}");
        }
        for w in &d.warnings {
            say!(s, "warning: {w}");
        }
        s.written(&self.written);
        s
    }
}

/// `ringmesh optimize`: one design for the theoretical boundary, written as
/// `design.json` and `cables.csv` (with cut lengths); `solver` defaults to
/// the scene's ([`default_solver`]).
pub fn optimize(
    scene_path: &Path,
    solver: Option<SolverKind>,
    output_dir: Option<&Path>,
) -> Result<OptimizeOutcome, Error> {
    let scene = read_scene(scene_path)?;
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    check_scene(&scene, SceneCommand::Optimize, 1)?;
    let set = OutputSet::begin(&dir, &["design.json", "cables.csv"])?;
    // The two-stage design `design` makes at its iteration 0 (front net by
    // the solver, rear net by its plan balance), so both nets hold the
    // scene's mean tensions.
    let nets = SceneNets::new(&scene)?;
    let solver = solver.unwrap_or_else(|| default_solver(&scene));
    let boundary = layout_points(&nets.mesh.truss);
    let tied = nets.nets.design(solver.build(None).as_ref(), &boundary)?;
    let mut design = tied.design.feasible()?;
    // The path the solver took is the first stage's.
    design.route = design.route.or(tied.front.route);
    let csv = cables_csv(&nets.mesh.network, &design, &scene.cables);
    write_atomic(&set.path("cables.csv"), csv.as_bytes())?;
    let run = set.seal()?;
    let file = DesignFile {
        scene: &scene.name,
        design: &design,
    };
    write_json(
        &set.path("design.json"),
        &WithRun {
            run: &run,
            report: &file,
        },
    )?;
    Ok(OptimizeOutcome {
        design,
        written: set.commit()?,
    })
}
