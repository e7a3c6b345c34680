//! `ringmesh design`: the whole design job ([`crate::design::run`]) and its
//! files, each written atomically once everything is computed.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::{default_output_dir, read_scene, target_line, Summary};
use crate::design::{DesignReport, DesignSettings, IterationRecord, RelaxationKind};
use crate::geometry::ReflectorMesh;
use crate::network::Network;
use crate::report::{
    assembly_vtu, cables_csv, convergence_csv, convergence_plot, json_name, readable, surface_plot,
    write_atomic, write_json, NodePanel, OutputSet, SurfaceFigure, WithRun,
};
use crate::resources::{check_scene, SceneCommand};
use crate::scene::Scene;
use crate::surface::{RawAndBestFit, SurfaceBudget};
use crate::verify::{CableModel, Verification};
use crate::Error;

/// What `ringmesh design` made.
#[derive(Debug)]
pub struct DesignOutcome {
    /// The report (also in `design.json`).
    pub report: DesignReport,
    /// What the scene's surface target says of the net, if it has one.
    pub target: Option<String>,
    /// Files written.
    pub written: Vec<PathBuf>,
}

impl DesignOutcome {
    /// What `ringmesh design` prints: how the loop ended, the design and the
    /// conventional one as built, the truss's margin, where the time went,
    /// the net's warnings, the files written.
    pub fn summary(&self) -> Summary {
        let r = &self.report;
        let mut s = Summary::default();
        say!(
            s,
            "{}: {} after {} outer iterations of {}, boundary residual {:.3e} m, ratio {:.6}",
            r.relaxation.name(),
            json_name(&r.termination),
            r.outer_iterations,
            r.solver,
            r.boundary_residual_m,
            r.ratio
        );
        let v = &r.verification;
        say!(
            s,
            "assembled{}: RMS {} mm (max {} mm), tension change {} %, boundary {} mm, {} slack cables",
            cables_note(v),
            readable(v.rms_mm, 4),
            readable(v.max_deviation_mm, 4),
            readable(v.max_tension_change_pct, 4),
            readable(v.boundary_deviation_mm, 4),
            v.slack_cables.len()
        );
        if let Some(c) = &r.conventional {
            say!(
                s,
                "conventional (rigid-truss) design assembled{}: RMS {} mm (max {} mm), tension change {} %, {} slack cables",
                cables_note(c),
                readable(c.rms_mm, 4),
                readable(c.max_deviation_mm, 4),
                readable(c.max_tension_change_pct, 4),
                c.slack_cables.len()
            );
        }
        if let Some(m) = &r.limit_margin {
            say!(s, "truss under the design's pull: {m}");
        }
        for line in budget_lines(&r.surface) {
            say!(s, "{line}");
        }
        if let Some(t) = &self.target {
            say!(s, "{t}");
        }
        let t = &r.timings;
        say!(
            s,
            "time: {:.2} s — mesh {:.2}, loop {:.2} (uniformity {:.2}, truss {:.2}), \
             comparison loops {:.2}, margin {:.2}, verification {:.2}, conventional {:.2}, \
             writing {:.2}",
            t.total_s,
            t.mesh_s,
            t.design_loop_s(),
            t.uniformity_s.iter().sum::<f64>(),
            t.truss_s.iter().sum::<f64>(),
            t.comparison_loops_s,
            t.margin_s,
            t.verification_s,
            t.conventional_s,
            t.writing_s
        );
        for w in &r.net.warnings {
            say!(s, "warning: {w}");
        }
        s.written(&self.written);
        s
    }
}

/// The surface error budget as printed: each term's axial RMS raw and about
/// its best-fit paraboloid, the gain loss at the scene's frequency.
fn budget_lines(b: &SurfaceBudget) -> Vec<String> {
    let pair = |p: RawAndBestFit| {
        format!(
            "{} / {} mm",
            readable(p.raw_mm, 4),
            readable(p.best_fit_mm, 4)
        )
    };
    let mut lines = vec![
        "surface error budget (axial RMS, raw / about the best-fit paraboloid):".to_string(),
        format!("  facets (design surface)      {}", pair(b.facets)),
        format!("  design as built (free nodes) {}", pair(b.design_as_built)),
        format!("  total (root-sum-square)      {}", pair(b.total)),
        format!("  facets as built              {}", pair(b.facets_as_built)),
    ];
    if let (Some(ghz), Some(db)) = (b.frequency_ghz, b.gain_loss_db) {
        lines.push(format!(
            "gain loss at {} GHz: {} dB (Ruze, half-path RMS {} mm of the facets as built \
             about their best fit)",
            readable(ghz, 4),
            readable(db, 4),
            readable(b.half_path_best_fit_mm, 4)
        ));
    }
    lines
}

/// One outer iteration of a design run, on one line (the CLI's progress on
/// stderr).
pub fn iteration_line(relaxation: RelaxationKind, r: &IterationRecord) -> String {
    format!(
        "{:>8} {:>3}  boundary change {:.3e} m  ratio {:.6}  truss Newton {}  {:.2} s",
        relaxation.name(),
        r.iteration,
        r.boundary_change_max_m,
        r.ratio,
        r.oracle_newton_iterations,
        r.elapsed_s
    )
}

/// How the assembly's cables were modelled, when not as built (`[effects]
/// cable_elasticity = false`).
fn cables_note(v: &Verification) -> &'static str {
    match v.cable_model {
        CableModel::Elastic => "",
        CableModel::Inextensible => " with inextensible cables",
    }
}

/// `ringmesh design`: reads the scene, runs [`crate::design::run`] and writes
/// `design.json`, `cables.csv`, `convergence.csv/.png/.svg`,
/// `surface-error.png` and `model.vtu` into `output_dir` (default
/// `results/<scene>/`), all together or none ([`OutputSet`]: the folder is
/// locked and checked before any computing). `observe` sees each outer
/// iteration.
///
/// # Errors
/// The scene's, the design's and the writers' errors, and a folder in use
/// or not writable (before computing); nothing is written unless
/// everything was computed.
pub fn design(
    scene_path: &Path,
    settings: &DesignSettings,
    output_dir: Option<&Path>,
    observe: &mut dyn FnMut(RelaxationKind, &IterationRecord),
) -> Result<DesignOutcome, Error> {
    let clock = Instant::now();
    let scene = read_scene(scene_path)?;
    let read_s = clock.elapsed().as_secs_f64();
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    check_scene(&scene, SceneCommand::Design, 1)?;
    let set = OutputSet::begin(&dir, &FILES)?;
    let mut run = crate::design::run(&scene, settings, observe)?;
    run.report.timings.read_s = read_s;
    let written = write_design(set, &scene, &run.mesh, &run.network, &mut run.report, clock)?;
    Ok(DesignOutcome {
        target: target_line(&scene, run.report.surface.facets.raw_mm),
        report: run.report,
        written,
    })
}

/// The surface figure of a design run: the conventional design (when there
/// is one) and ours as built, and ours's flat facets.
fn surface_figure(
    scene: &Scene,
    mesh: &ReflectorMesh,
    network: &Network,
    report: &DesignReport,
) -> SurfaceFigure {
    let fixed = network.fixed_mask();
    let front = 0..mesh.n_front_nodes;
    let deviation_mm = |p: [f64; 3]| 1e3 * mesh.paraboloid.axial_deviation(p);
    let panel = |title: &str, v: &Verification| NodePanel {
        title: title.to_string(),
        nodes: front
            .clone()
            .filter(|&i| !fixed[i])
            .map(|i| {
                let p = v.nodes_xyz_m[i];
                (p[0], p[1], deviation_mm(p))
            })
            .collect(),
    };
    let ours = &report.verification;
    let mut panels: Vec<NodePanel> = report
        .conventional
        .iter()
        .map(|c| panel("conventional (rigid-truss) design as built", c))
        .collect();
    panels.push(panel("this design as built", ours));
    let plan = |i: usize| (ours.nodes_xyz_m[i][0], ours.nodes_xyz_m[i][1]);
    let facets = mesh
        .front_triangles
        .iter()
        .map(|t| {
            let centroid: [f64; 3] = std::array::from_fn(|c| {
                t.iter().map(|&i| ours.nodes_xyz_m[i][c]).sum::<f64>() / 3.0
            });
            (t.map(plan), deviation_mm(centroid))
        })
        .collect();
    let cables = network
        .edges
        .iter()
        .filter(|e| e.iter().all(|&i| front.contains(&i)))
        .map(|e| e.map(plan))
        .collect();
    SurfaceFigure {
        title: format!(
            "{}: surface as built on the flexible truss, axial deviation from the paraboloid (mm)",
            scene.name
        ),
        panels,
        facets,
        cables,
        outline: mesh.truss.top_m.iter().map(|p| (p[0], p[1])).collect(),
    }
}

/// The files of `ringmesh design`.
const FILES: [&str; 7] = [
    "design.json",
    "cables.csv",
    "convergence.csv",
    "convergence.png",
    "convergence.svg",
    "surface-error.png",
    "model.vtu",
];

/// The files of `ringmesh design` written into `set` and swapped in as one:
/// `design.json` last, with the run's record of the others (identifier,
/// sizes, hashes), the time spent writing them and the command's wall time
/// since `clock` in its timings.
fn write_design(
    set: OutputSet,
    scene: &Scene,
    mesh: &ReflectorMesh,
    network: &Network,
    report: &mut DesignReport,
    clock: Instant,
) -> Result<Vec<PathBuf>, Error> {
    let writing = Instant::now();
    let path = |name: &str| set.path(name);
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
        report.tolerance_m,
        &path("convergence.png"),
        &path("convergence.svg"),
    )?;
    surface_plot(
        &surface_figure(scene, mesh, network, report),
        &path("surface-error.png"),
    )?;
    write_atomic(
        &path("model.vtu"),
        assembly_vtu(
            network,
            &report.net.q,
            &report.verification,
            report.limit_margin.as_ref().map(|m| &m.mode),
        )
        .as_bytes(),
    )?;
    write_atomic(
        &path("convergence.csv"),
        convergence_csv(&report.runs).as_bytes(),
    )?;
    write_atomic(
        &path("cables.csv"),
        cables_csv(network, &report.net, &scene.cables).as_bytes(),
    )?;
    let run = set.seal()?;
    report.timings.writing_s = writing.elapsed().as_secs_f64();
    report.timings.total_s = clock.elapsed().as_secs_f64();
    write_json(&path("design.json"), &WithRun { run: &run, report })?;
    Ok(set.commit()?)
}
