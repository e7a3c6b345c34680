//! `ringmesh design`: the whole design job ([`crate::design::run`]) and its
//! files, each written atomically once everything is computed.

use std::path::{Path, PathBuf};
use std::time::Instant;

use super::{default_output_dir, read_scene, target_line, Summary};
use crate::design::{
    DesignObserver, DesignReport, DesignSettings, IterationRecord, RelaxationKind,
};
use crate::geometry::ReflectorMesh;
use crate::network::Network;
use crate::report::{
    assembly_vtu, cables_csv, convergence_csv, convergence_plot, decimal, json_name, readable,
    surface_plot, write_atomic, write_json, OutputSet, PanelContent, PanelRms, SurfaceFigure,
    SurfacePanel, WithRun,
};
use crate::resources::{check_scene, SceneCommand};
use crate::scene::Scene;
use crate::status::Termination;
use crate::surface::{PlacedParaboloid, RawAndBestFit, SurfaceBudget};
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
            "{}: {} after {} outer iterations of {}, boundary residual {} m, Tmax/Tmin {}",
            r.relaxation.name(),
            json_name(&r.termination),
            r.outer_iterations,
            r.solver,
            readable(r.boundary_residual_m, 4),
            readable(r.ratio, 7)
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
             comparison loops {:.2}, margin {:.2} (beside the next two), verification {:.2}, \
             conventional {:.2}, writing {:.2}",
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
        for w in r.net.warnings.iter().chain(&r.surface.warnings) {
            say!(s, "warning: {w}");
        }
        s.written(&self.written);
        if r.termination != Termination::Converged {
            s.ended_early = Some(format!(
                "the design loop ended before its tolerance: {} after {} outer iterations, \
                 boundary residual {} m against {} m (files written)",
                json_name(&r.termination),
                r.outer_iterations,
                readable(r.boundary_residual_m, 4),
                readable(r.tolerance_m, 4)
            ));
        }
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
        "{:>8} {:>3}  boundary change {} m  Tmax/Tmin {}  truss Newton iterations {}  {} s",
        relaxation.name(),
        r.iteration,
        readable(r.boundary_change_max_m, 4),
        readable(r.ratio, 7),
        r.oracle_newton_iterations,
        decimal(r.elapsed_s, 3)
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
/// `runs/<scene>/`), all together or none ([`OutputSet`]: the folder is
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
    design_observed(scene_path, settings, output_dir, &mut Iterations(observe))
}

/// An observer of the outer iterations alone.
struct Iterations<'a>(&'a mut dyn FnMut(RelaxationKind, &IterationRecord));

impl DesignObserver for Iterations<'_> {
    fn iteration(&mut self, relaxation: RelaxationKind, record: &IterationRecord) {
        (self.0)(relaxation, record)
    }
}

/// [`design`], with `observer` told of each outer iteration and of each
/// stage after the loop as it begins.
///
/// # Errors
/// As [`design`].
pub fn design_observed(
    scene_path: &Path,
    settings: &DesignSettings,
    output_dir: Option<&Path>,
    observer: &mut dyn DesignObserver,
) -> Result<DesignOutcome, Error> {
    let clock = Instant::now();
    let scene = read_scene(scene_path)?;
    let read_s = clock.elapsed().as_secs_f64();
    let dir = output_dir.map_or_else(|| default_output_dir(&scene), Path::to_path_buf);
    check_scene(&scene, SceneCommand::Design, 1)?;
    let set = OutputSet::begin(&dir, &FILES)?;
    let mut run = crate::design::run_observed(&scene, settings, observer)?;
    run.report.timings.read_s = read_s;
    let written = write_design(set, &scene, &run.mesh, &run.network, &mut run.report, clock)?;
    Ok(DesignOutcome {
        target: target_line(&scene, run.report.surface.facets.raw_mm),
        report: run.report,
        written,
    })
}

/// The surface figure of a design run: the conventional design (when there
/// is one) and ours as built, and ours's flat facets raw and about their
/// best-fit paraboloid, each panel labelled with the RMS the report holds
/// (the surface error budget's, [`crate::surface`]).
fn surface_figure(
    scene: &Scene,
    mesh: &ReflectorMesh,
    network: &Network,
    report: &DesignReport,
) -> SurfaceFigure {
    let fixed = network.fixed_mask();
    let front = 0..mesh.n_front_nodes;
    let design = PlacedParaboloid::design(&mesh.paraboloid);
    let budget = &report.surface;
    let nodes = |v: &Verification| {
        PanelContent::Nodes(
            front
                .clone()
                .filter(|&i| !fixed[i])
                .map(|i| {
                    let p = v.nodes_xyz_m[i];
                    (p[0], p[1], 1e3 * design.deviation(p).axial_m)
                })
                .collect(),
        )
    };
    let ours = &report.verification;
    let plan = |i: usize| (ours.nodes_xyz_m[i][0], ours.nodes_xyz_m[i][1]);
    // Each facet cut into equal parts, each coloured by the axial deviation
    // at its centroid about `about`: a facet's bulge shows, and about the
    // best fit, its straddling of the surface.
    let per_side = facet_parts_per_side(mesh.front_triangles.len());
    let facets = |about: &PlacedParaboloid| PanelContent::Facets {
        parts_per_side: per_side,
        parts: mesh
            .front_triangles
            .iter()
            .flat_map(|t| facet_parts(t.map(|i| ours.nodes_xyz_m[i]), per_side))
            .map(|part| {
                let centroid: [f64; 3] =
                    std::array::from_fn(|c| part.iter().map(|p| p[c]).sum::<f64>() / 3.0);
                (
                    part.map(|p| (p[0], p[1])),
                    1e3 * about.deviation(centroid).axial_m,
                )
            })
            .collect(),
    };
    let mut panels: Vec<SurfacePanel> = report
        .conventional
        .iter()
        .map(|c| SurfacePanel {
            title: "conventional (rigid-truss) design as built".to_string(),
            rms: PanelRms::Node,
            rms_mm: c.rms_mm,
            content: nodes(c),
        })
        .collect();
    panels.extend([
        SurfacePanel {
            title: "design as built".to_string(),
            rms: PanelRms::Node,
            rms_mm: budget.design_as_built.raw_mm,
            content: nodes(ours),
        },
        SurfacePanel {
            title: "facets as built".to_string(),
            rms: PanelRms::Facet,
            rms_mm: budget.facets_as_built.raw_mm,
            content: facets(&design),
        },
        SurfacePanel {
            title: "facets as built, about their best-fit paraboloid".to_string(),
            rms: PanelRms::BestFitFacet,
            rms_mm: budget.facets_as_built.best_fit_mm,
            content: facets(&budget.best_fit),
        },
    ]);
    let cables = network
        .edges
        .iter()
        .filter(|e| e.iter().all(|&i| front.contains(&i)))
        .map(|e| e.map(plan))
        .collect();
    SurfaceFigure {
        title: format!(
            "{}: surface as built on the flexible truss, axial deviation (mm)",
            scene.name
        ),
        panels,
        cables,
        outline: mesh.truss.top_m.iter().map(|p| (p[0], p[1])).collect(),
    }
}

/// Parts of a facet drawn at most, over all the facets of a panel.
const MAX_FACET_PARTS: usize = 20_000;

/// The parts per side each facet of a net of `facets` is cut into for its
/// colours: as many as [`MAX_FACET_PARTS`] allows, 1 to 4.
fn facet_parts_per_side(facets: usize) -> usize {
    ((MAX_FACET_PARTS as f64 / facets.max(1) as f64).sqrt() as usize).clamp(1, 4)
}

/// The flat triangle `corners` cut into `n²` equal triangles (`n` parts
/// a side), corners in space, m.
fn facet_parts(corners: [[f64; 3]; 3], n: usize) -> Vec<[[f64; 3]; 3]> {
    // The point (i, j) of the grid: corner 0 moved i/n along side 0→1 and
    // j/n along side 0→2.
    let at = |i: usize, j: usize| -> [f64; 3] {
        let (a, b) = (i as f64 / n as f64, j as f64 / n as f64);
        std::array::from_fn(|c| {
            corners[0][c]
                + a * (corners[1][c] - corners[0][c])
                + b * (corners[2][c] - corners[0][c])
        })
    };
    let mut parts = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n - i {
            parts.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
            if i + j + 2 <= n {
                parts.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    parts
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
    // Two halves of the files side by side, each file its own in the set:
    // the pictures and `cables.csv` beside `model.vtu` and the convergence
    // table (25 and 33 MB of text at 84 362 nodes).
    let r: &DesignReport = report;
    let (pictures, files) = rayon::join(
        || -> Result<(), Error> {
            convergence_plot(
                &series,
                &format!("{}: outer design loop", scene.name),
                r.tolerance_m,
                &path("convergence.png"),
                &path("convergence.svg"),
            )?;
            surface_plot(
                &surface_figure(scene, mesh, network, r),
                &path("surface-error.png"),
            )?;
            write_atomic(
                &path("cables.csv"),
                cables_csv(network, &r.net, &scene.cables).as_bytes(),
            )?;
            Ok(())
        },
        || -> Result<(), Error> {
            write_atomic(
                &path("model.vtu"),
                assembly_vtu(
                    network,
                    mesh,
                    &r.net,
                    &scene.cables,
                    &r.verification,
                    r.limit_margin.as_ref().map(|m| &m.mode),
                )
                .as_bytes(),
            )?;
            write_atomic(
                &path("convergence.csv"),
                convergence_csv(&r.runs).as_bytes(),
            )?;
            Ok(())
        },
    );
    pictures?;
    files?;
    let run = set.seal()?;
    report.timings.writing_s = writing.elapsed().as_secs_f64();
    report.timings.total_s = clock.elapsed().as_secs_f64();
    write_json(&path("design.json"), &WithRun { run: &run, report })?;
    Ok(set.commit()?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facet_parts_tile_the_facet_into_equal_triangles() {
        let corners = [[0.0, 0.0, 1.0], [3.0, 0.0, 2.0], [0.0, 3.0, 4.0]];
        let plan_area = |t: &[[f64; 3]; 3]| {
            0.5 * ((t[1][0] - t[0][0]) * (t[2][1] - t[0][1])
                - (t[2][0] - t[0][0]) * (t[1][1] - t[0][1]))
                .abs()
        };
        for n in 1..=4 {
            let parts = facet_parts(corners, n);
            assert_eq!(parts.len(), n * n);
            for part in &parts {
                let area = plan_area(part);
                assert!((area - 4.5 / (n * n) as f64).abs() < 1e-14, "n {n}: {area}");
                // Every corner of a part lies on the facet's plane z = 1 + x/3 + y.
                for p in part {
                    assert!((p[2] - (1.0 + p[0] / 3.0 + p[1])).abs() < 1e-14, "{p:?}");
                }
            }
        }
        assert_eq!(facet_parts_per_side(54), 4);
        assert_eq!(facet_parts_per_side(30_000), 1);
    }

    #[test]
    fn surface_figure_labels_each_panel_with_the_budget_s_numbers() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/small-hex.toml");
        let scene = read_scene(&path).unwrap();
        let run = crate::design::run(&scene, &DesignSettings::default(), &mut |_, _| {}).unwrap();
        let figure = surface_figure(&scene, &run.mesh, &run.network, &run.report);
        let budget = &run.report.surface;
        let printed = budget_lines(budget).join("\n");
        let conventional = run.report.conventional.as_ref().unwrap();
        let expected = [
            (
                "conventional (rigid-truss) design as built",
                PanelRms::Node,
                conventional.rms_mm,
            ),
            (
                "design as built",
                PanelRms::Node,
                budget.design_as_built.raw_mm,
            ),
            (
                "facets as built",
                PanelRms::Facet,
                budget.facets_as_built.raw_mm,
            ),
            (
                "facets as built, about their best-fit paraboloid",
                PanelRms::BestFitFacet,
                budget.facets_as_built.best_fit_mm,
            ),
        ];
        assert_eq!(figure.panels.len(), expected.len());
        for (panel, (title, rms, value)) in figure.panels.iter().zip(expected) {
            assert_eq!(
                (panel.title.as_str(), panel.rms, panel.rms_mm),
                (title, rms, value)
            );
            // The label's number is the one `design` prints.
            let number = readable(value, 4);
            assert!(panel
                .label()
                .contains(&format!("{} {number} mm (", rms.name())));
            if rms != PanelRms::Node || title == "design as built" {
                assert!(printed.contains(&number), "{number} not in\n{printed}");
            }
        }
        let labels: Vec<String> = figure.panels.iter().map(SurfacePanel::label).collect();
        assert_eq!(
            labels[2],
            format!(
                "facets as built: facet RMS {} mm (axial, plan-area weighted)",
                readable(budget.facets_as_built.raw_mm, 4)
            )
        );
        assert!(labels.iter().all(|l| !l.contains("centroid")), "{labels:?}");
        // The facets as built bulge above the design paraboloid everywhere
        // (their nodes are on it); about the best fit they straddle it.
        let parts = |panel: &SurfacePanel| match &panel.content {
            PanelContent::Facets { parts, .. } => parts.iter().map(|p| p.1).collect::<Vec<_>>(),
            PanelContent::Nodes(_) => panic!("{}: not facets", panel.title),
        };
        let (raw, best_fit) = (parts(&figure.panels[2]), parts(&figure.panels[3]));
        assert_eq!(raw.len(), 16 * run.mesh.front_triangles.len());
        assert!(raw.iter().all(|&d| d > 0.0));
        assert!(best_fit.iter().any(|&d| d > 0.0) && best_fit.iter().any(|&d| d < 0.0));
    }
}
