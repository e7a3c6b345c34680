//! The label-overlap check of every figure the repository commits (issue
//! 37): each drawing function run on a backend that records where every
//! text lands — the box plotters' bitmap backend fills, from the font's own
//! layout box, the text's anchor and its rotation, in pixels — and no two
//! boxes may overlap. Point labels, legends, tick labels, captions: every
//! text of the picture.
//!
//! The data are the committed results' own (`results/**/*.csv`, `.json`),
//! so a label set that crowds a committed figure crowds the test.

use std::cell::RefCell;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use plotters::prelude::*;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{BackendColor, BackendCoord, BackendTextStyle, DrawingErrorKind};

use super::accuracy_vs_time::StudyRms;
use super::surface_error::{PanelContent, PanelRms, SurfaceFigure, SurfacePanel};
use super::{FrontRms, FrontY};
use crate::budget::{BudgetRow, BudgetTable, PointKind};
use crate::report::{parse_front_row, parse_study_row, DrawError, FrontRow};
use crate::scene::{Scene, TrussModel};
use crate::sizing::{SectionTrial, TubeSection};
use crate::study::{ApertureResult, ModelResult, StudyRow};

/// A text as drawn: what it says and its box `[x0, y0, x1, y1]`, px
/// (half-open).
#[derive(Debug, Clone)]
pub(super) struct TextBox {
    pub(super) text: String,
    pub(super) bounds: [i32; 4],
}

/// A backend that draws nothing and records the box of every text.
pub(super) struct TextRecorder {
    size: (u32, u32),
    boxes: Rc<RefCell<Vec<TextBox>>>,
}

/// The recorder never fails.
#[derive(Debug)]
pub(super) struct Never;

impl std::fmt::Display for Never {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("never")
    }
}

impl std::error::Error for Never {}

impl DrawingBackend for TextRecorder {
    type ErrorType = Never;

    fn get_size(&self) -> (u32, u32) {
        self.size
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Never>> {
        Ok(())
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<Never>> {
        Ok(())
    }

    fn draw_pixel(
        &mut self,
        _: BackendCoord,
        _: BackendColor,
    ) -> Result<(), DrawingErrorKind<Never>> {
        Ok(())
    }

    /// The box [`DrawingBackend::draw_text`]'s default (the bitmap
    /// backend's) fills: the layout box moved by the anchor, then rotated
    /// about the anchor point.
    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Never>> {
        if style.color().alpha == 0.0 || text.trim().is_empty() {
            return Ok(());
        }
        let ((min_x, min_y), (max_x, max_y)) = style
            .layout_box(text)
            .map_err(|e| DrawingErrorKind::FontError(Box::new(e)))?;
        let (w, h) = (max_x - min_x, max_y - min_y);
        let dx = match style.anchor().h_pos {
            HPos::Left => 0,
            HPos::Right => -w,
            HPos::Center => -w / 2,
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => 0,
            VPos::Center => -h / 2,
            VPos::Bottom => -h,
        };
        let t = style.transform();
        let (ax, ay) = t.transform(dx, dy);
        let (bx, by) = t.transform(dx + w, dy + h);
        self.boxes.borrow_mut().push(TextBox {
            text: text.to_string(),
            bounds: [
                pos.0 + ax.min(bx),
                pos.1 + ay.min(by),
                pos.0 + ax.max(bx),
                pos.1 + ay.max(by),
            ],
        });
        Ok(())
    }
}

/// The text boxes of a picture of `size` pixels drawn by `draw`.
///
/// # Panics
/// If the drawing fails.
#[track_caller]
pub(super) fn text_boxes(
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<TextRecorder, plotters::coord::Shift>) -> Result<(), DrawError>,
) -> Vec<TextBox> {
    super::canvas::register_font();
    let boxes = Rc::new(RefCell::new(Vec::new()));
    let recorder = TextRecorder {
        size,
        boxes: Rc::clone(&boxes),
    };
    draw(recorder.into_drawing_area()).expect("the picture draws");
    let boxes = boxes.borrow().clone();
    boxes
}

/// Every pair of boxes that overlap (share an area, not only an edge).
pub(super) fn overlaps(boxes: &[TextBox]) -> Vec<(TextBox, TextBox)> {
    let mut pairs = Vec::new();
    for (i, a) in boxes.iter().enumerate() {
        for b in &boxes[..i] {
            let (p, q) = (a.bounds, b.bounds);
            if p[0] < q[2] && q[0] < p[2] && p[1] < q[3] && q[1] < p[3] {
                pairs.push((b.clone(), a.clone()));
            }
        }
    }
    pairs
}

/// Asserts that the texts of `picture` do not overlap and that it has
/// some.
#[track_caller]
fn assert_apart(picture: &str, boxes: &[TextBox]) {
    assert!(boxes.len() >= 3, "{picture}: texts {boxes:?}");
    let pairs = overlaps(boxes);
    assert!(
        pairs.is_empty(),
        "{picture}: {} overlapping texts: {:#?}",
        pairs.len(),
        pairs
    );
}

/// The committed results' folders.
fn results() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("results")
}

/// The rows of a committed table (its comment lines and header skipped).
fn table(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .map(str::to_string)
        .collect()
}

/// The committed files called `name` in the results' scene folders.
fn committed(name: &str) -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(results())
        .unwrap()
        .map(|e| e.unwrap().path().join(name))
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    assert!(!found.is_empty(), "no committed {name}");
    found
}

fn study_rows(path: &Path) -> Vec<StudyRow> {
    table(path)
        .iter()
        .map(|l| parse_study_row(l).unwrap())
        .collect()
}

#[test]
fn a_recorded_box_is_where_the_bitmap_backend_draws_the_text() {
    // Left-top anchored, unrotated: the box starts at the anchor and is as
    // wide as the font measures the text.
    let boxes = text_boxes((200, 100), |area| {
        area.draw(&Text::new("1e-2", (20, 30), super::labels::label_font()))?;
        area.draw(&Text::new(
            "1e-2",
            (20, 30),
            super::labels::label_font().transform(FontTransform::Rotate270),
        ))?;
        Ok(())
    });
    let w = super::labels::label_width("1e-2") - 1;
    assert_eq!(boxes[0].bounds[..2], [20, 30]);
    assert_eq!(boxes[0].bounds[2] - boxes[0].bounds[0], w);
    // Rotated a quarter turn: as tall as the text is wide, above the
    // anchor, meeting the first along an edge only.
    assert_eq!(boxes[1].bounds[0], 20);
    assert_eq!(boxes[1].bounds[3], 30);
    assert_eq!(boxes[1].bounds[3] - boxes[1].bounds[1], w);
    assert!(overlaps(&boxes).is_empty());
    // A text moved by less than its size onto the first overlaps it.
    let moved = TextBox {
        text: "moved".into(),
        bounds: boxes[0].bounds.map(|v| v + 3),
    };
    let pairs = overlaps(&[boxes[0].clone(), boxes[1].clone(), moved]);
    assert_eq!(pairs.len(), 1);
    assert_eq!(pairs[0].1.text, "moved");
}

#[test]
fn front_labels_never_overlap() {
    for path in committed("front.csv") {
        let rows: Vec<FrontRow> = table(&path)
            .iter()
            .map(|l| parse_front_row(l).unwrap())
            .collect();
        for y_axis in [FrontY::Ratio, FrontY::Time] {
            let boxes = text_boxes((1000, 680), |area| {
                super::front::draw_front(
                    area,
                    &rows,
                    Some(&[]),
                    (&FrontRms::Design, y_axis),
                    "paper-26m: design front (Tmax/Tmin against surface RMS)",
                )
            });
            assert_apart(&format!("{} ({y_axis:?})", path.display()), &boxes);
        }
    }
}

#[test]
fn study_and_strategies_labels_never_overlap() {
    for path in committed("accuracy-vs-time.csv") {
        let rows = study_rows(&path);
        let boxes = text_boxes((1600, 720), |area| {
            super::accuracy_vs_time::draw_study(
                area,
                &rows,
                &StudyRms::Design,
                "paper-26m: what accuracy costs in time (designs as built on the reference truss)",
            )
        });
        assert_apart(&path.display().to_string(), &boxes);
        let boxes = text_boxes((1100, 700), |area| {
            super::strategies::draw_strategies(
                area,
                &rows,
                &StudyRms::Design,
                "paper-26m: each solver's time against its accuracy (designs as built on the \
                 reference truss)",
            )
        });
        assert_apart(&format!("strategies of {}", path.display()), &boxes);
    }
}

#[test]
fn convergence_labels_never_overlap() {
    for path in committed("convergence.csv") {
        // relaxation,iteration,boundary_change_max_m,…
        let mut series: Vec<(String, Vec<(usize, f64)>)> = Vec::new();
        for line in table(&path) {
            let f: Vec<&str> = line.split(',').collect();
            let point = (f[1].parse().unwrap(), f[2].parse().unwrap());
            match series.iter_mut().find(|(name, _)| name == f[0]) {
                Some((_, points)) => points.push(point),
                None => series.push((f[0].to_string(), vec![point])),
            }
        }
        let boxes = text_boxes((900, 600), |area| {
            super::convergence::draw_convergence(
                area,
                &series,
                "realistic-26m: outer design loop",
                1e-6,
            )
        });
        assert_apart(&path.display().to_string(), &boxes);
    }
}

#[test]
fn sizing_labels_never_overlap() {
    for path in committed("sizing.csv") {
        // outer_diameter_m,inner_diameter_m,youngs_modulus_pa,
        // density_kg_per_m3,mass_kg,margin,bound,outer_iterations,
        // termination,rms_mm,carries,time_s,failure
        let trials: Vec<SectionTrial> = table(&path)
            .iter()
            .map(|line| {
                let f: Vec<&str> = line.split(',').collect();
                let n = |k: usize| f[k].parse::<f64>().unwrap();
                SectionTrial {
                    section: TubeSection {
                        outer_diameter_m: n(0),
                        inner_diameter_m: n(1),
                        youngs_modulus_pa: n(2),
                        density_kg_per_m3: n(3),
                    },
                    mass_kg: n(4),
                    margin: n(5),
                    bound: None,
                    summary: None,
                    rms_mm: Some(n(9)),
                    time_s: n(11),
                    carries: f[10] == "true",
                    failure: None,
                }
            })
            .collect();
        let chosen = (0..trials.len())
            .filter(|&k| trials[k].carries)
            .min_by(|&a, &b| trials[a].mass_kg.total_cmp(&trials[b].mass_kg))
            .unwrap();
        let boxes = text_boxes((1100, 700), |area| {
            super::sizing::draw_sizing(
                area,
                &trials,
                chosen,
                2.0,
                "paper-26m: tube sections tried for a limit margin of 2",
            )
        });
        assert_apart(&path.display().to_string(), &boxes);
    }
}

#[test]
fn aperture_labels_never_overlap() {
    for path in committed("apertures/apertures.json") {
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        let scene =
            Scene::read(&Path::new(env!("CARGO_MANIFEST_DIR")).join("problems/paper-26m.toml"))
                .unwrap();
        let n = |v: &serde_json::Value, key: &str| v[key].as_f64().unwrap_or(f64::NAN);
        let results: Vec<ApertureResult> = json
            .as_array()
            .unwrap()
            .iter()
            .map(|r| ApertureResult {
                aperture_m: n(r, "aperture_m"),
                scene: scene.clone(),
                rings: 4,
                nodes: 0,
                section: TubeSection {
                    outer_diameter_m: 0.1,
                    inner_diameter_m: 0.09,
                    youngs_modulus_pa: 1.6e11,
                    density_kg_per_m3: 1600.0,
                },
                truss_mass_kg: n(r, "truss_mass_kg"),
                margin: n(r, "margin"),
                sizing_designs: 0,
                sizing_time_s: 0.0,
                hinge_motion_mm: n(r, "hinge_motion_mm"),
                models: r["models"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|m| ModelResult {
                        model: match m["model"].as_str().unwrap() {
                            "rigid" => TrussModel::Rigid,
                            "linear" => TrussModel::Linear,
                            _ => TrussModel::Exact,
                        },
                        outer_iterations: 1,
                        ratio: n(m, "ratio"),
                        built_ratio: n(m, "built_ratio"),
                        rms_mm: n(m, "rms_mm"),
                        max_deviation_mm: n(m, "max_deviation_mm"),
                        tension_change_pct: n(m, "tension_change_pct"),
                        cut_length_error_mm: n(m, "cut_length_error_mm"),
                        boundary_deviation_mm: n(m, "boundary_deviation_mm"),
                        slack_cables: 0,
                        design_time_s: 0.0,
                        assembly_time_s: 0.0,
                    })
                    .collect(),
            })
            .collect();
        assert!(
            results.iter().all(|r| r.models.len() == 3),
            "{}",
            path.display()
        );
        let boxes = text_boxes((1600, 650), |area| {
            super::aperture::draw_apertures(
                area,
                &results,
                "paper-26m (F/D 0.154): designs as built on the exact truss, tubes sized for \
                 a margin of 2",
            )
        });
        assert_apart(&path.display().to_string(), &boxes);
    }
}

#[test]
fn surface_error_labels_never_overlap() {
    for path in committed("design.json") {
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        let surface = &json["surface"];
        let mm = |part: &str, key: &str| surface[part][key].as_f64().unwrap();
        // A few nodes and facets: the texts depend on the panels' RMS and
        // the largest deviation, not on the points.
        let nodes = |scale: f64| {
            PanelContent::Nodes(
                (0..12)
                    .map(|k| {
                        let a = k as f64 * 0.5;
                        (5.0 * a.cos(), 5.0 * a.sin(), scale * (a - 3.0))
                    })
                    .collect(),
            )
        };
        let facets = |scale: f64| PanelContent::Facets {
            parts_per_side: 2,
            parts: (0..6)
                .map(|k| {
                    let a = k as f64;
                    (
                        [
                            (0.0, 0.0),
                            (a.cos(), a.sin()),
                            ((a + 1.0).cos(), (a + 1.0).sin()),
                        ],
                        scale * (a - 2.5),
                    )
                })
                .collect(),
        };
        let mut panels = Vec::new();
        if let Some(rms) = json["conventional"]["rms_mm"].as_f64() {
            panels.push(SurfacePanel {
                title: "conventional (rigid-truss) design as built".into(),
                rms: PanelRms::Node,
                rms_mm: rms,
                content: nodes(rms),
            });
        }
        panels.extend([
            SurfacePanel {
                title: "design as built".into(),
                rms: PanelRms::Node,
                rms_mm: mm("design_as_built", "raw_mm"),
                content: nodes(mm("design_as_built", "raw_mm")),
            },
            SurfacePanel {
                title: "facets as built".into(),
                rms: PanelRms::Facet,
                rms_mm: mm("facets_as_built", "raw_mm"),
                content: facets(mm("facets_as_built", "raw_mm")),
            },
            SurfacePanel {
                title: "facets as built, about their best-fit paraboloid".into(),
                rms: PanelRms::BestFitFacet,
                rms_mm: mm("facets_as_built", "best_fit_mm"),
                content: facets(mm("facets_as_built", "best_fit_mm")),
            },
        ]);
        let figure = SurfaceFigure {
            title: "paper-26m: surface as built on the flexible truss, axial deviation (mm)".into(),
            panels,
            cables: vec![[(0.0, 0.0), (5.0, 0.0)]],
            outline: (0..8)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::FRAC_PI_4;
                    (6.0 * a.cos(), 6.0 * a.sin())
                })
                .collect(),
        };
        let boxes = text_boxes(super::surface_error::figure_size(&figure), |area| {
            super::surface_error::draw_surface(area, &figure)
        });
        assert_apart(&path.display().to_string(), &boxes);
    }
}

#[test]
fn budget_labels_never_overlap() {
    // Every committed budget (`results/<scene>/budget*/`), drawn from its
    // points' table as `budget` and `merge` draw it.
    let mut found: Vec<PathBuf> = std::fs::read_dir(results())
        .unwrap()
        .flat_map(|scene| {
            std::fs::read_dir(scene.unwrap().path())
                .into_iter()
                .flatten()
        })
        .map(|e| e.unwrap().path().join("budget-samples.csv"))
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    assert!(!found.is_empty(), "no committed budget");
    for path in found {
        let rows: Vec<BudgetRow> = table(&path)
            .iter()
            .map(|l| BudgetRow::parse(l).unwrap())
            .collect();
        let table = BudgetTable::of(&rows, Some(8.0));
        let samples: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.kind == PointKind::Sample)
            .filter_map(|r| {
                let linear = r.linear.as_ref()?.as_ref().ok()?;
                Some((r.nonlinear.as_ref().ok()?.best_fit_mm, linear.best_fit_mm))
            })
            .collect();
        let boxes = text_boxes((1600, 700), |area| {
            super::budget::draw_budget(
                area,
                &table,
                &samples,
                "super-60m: error budget of the conventional design as built on the flexible truss",
            )
        });
        assert_apart(&path.display().to_string(), &boxes);
    }
}
