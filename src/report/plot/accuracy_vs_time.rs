//! The accuracy study's figure: surface RMS (the design's as built, or the
//! total with each net's facet RMS) and ratio error as built against the
//! design's wall time, one colour per knob, the Pareto front ringed.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{png_and_svg, titled_with_legend};
use super::labels::{label_font, place_labels};
use super::{total_rms_mm, RMS_FLOOR_MM};
use crate::report::{DrawError, ReportError};
use crate::study::{pareto_optimal, Knob, StudyRow};

/// The surface RMS the study's points are drawn at (`--rms`,
/// [`super::RmsAxis`]).
#[derive(Debug, Clone, PartialEq)]
pub enum StudyRms {
    /// Each point's RMS as built.
    Design,
    /// The total `√(facets² + RMS as built²)` ([`total_rms_mm`]), with the
    /// facet RMS of the design surface of each point's net.
    Total {
        /// `(front-net rings, facet RMS of that net's design surface, mm)`,
        /// for every net of the rows drawn (a row whose net is missing is
        /// not drawn).
        facets_mm: Vec<(usize, f64)>,
    },
}

impl StudyRms {
    /// The RMS `row` is drawn at, mm.
    pub fn of(&self, row: &StudyRow) -> f64 {
        match self {
            StudyRms::Design => row.rms_mm,
            StudyRms::Total { facets_mm } => facets_mm
                .iter()
                .find(|(rings, _)| *rings == row.settings.rings)
                .map_or(f64::NAN, |&(_, f)| total_rms_mm(f, row.rms_mm)),
        }
    }

    /// The axis's caption.
    pub(super) fn caption(&self) -> &'static str {
        match self {
            StudyRms::Design => "surface RMS as built on the reference truss (mm)",
            StudyRms::Total { .. } => {
                "total RMS √(facets² + as built²) (mm); facets: each net's design surface"
            }
        }
    }
}

/// Floor of a logarithmic ratio-error axis (the reference itself has 0).
const RATIO_ERROR_FLOOR: f64 = 1e-12;

/// One panel of the study plot: accuracy `error` against time.
struct StudyPanel<'a> {
    y_desc: &'a str,
    floor: f64,
    error: &'a dyn Fn(&StudyRow) -> f64,
}

fn knob_colour(knob: Knob) -> RGBAColor {
    match knob {
        Knob::Reference => BLACK.to_rgba(),
        other => {
            let index = Knob::SWEPT.iter().position(|&k| k == other).unwrap_or(0);
            Palette99::pick(index).to_rgba()
        }
    }
}

/// The label of each row on the plot: `ref`, the knob's value, or
/// `baseline` once for the scene's own settings (which every sweep has).
fn study_labels(rows: &[StudyRow]) -> Vec<Option<String>> {
    let mut baseline_shown = false;
    rows.iter()
        .map(|r| {
            if r.knob == Knob::Reference {
                return Some("ref".to_string());
            }
            let shared = rows
                .iter()
                .any(|o| o.knob != r.knob && o.knob != Knob::Reference && o.settings == r.settings);
            if !shared {
                Some(r.value.clone())
            } else if !baseline_shown {
                baseline_shown = true;
                Some("baseline".to_string())
            } else {
                None
            }
        })
        .collect()
}

fn draw_study_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    rows: &[StudyRow],
    panel: &StudyPanel<'_>,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let y = |r: &StudyRow| (panel.error)(r).max(panel.floor);
    let labels = study_labels(rows);
    let ok: Vec<(&StudyRow, &Option<String>)> = rows
        .iter()
        .zip(&labels)
        .filter(|(r, _)| r.error.is_none() && r.time_s > 0.0 && (panel.error)(r).is_finite())
        .collect();
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (r, _) in &ok {
        x_lo = x_lo.min(r.time_s);
        x_hi = x_hi.max(r.time_s);
        y_lo = y_lo.min(y(r));
        y_hi = y_hi.max(y(r));
    }
    if ok.is_empty() {
        (x_lo, x_hi, y_lo, y_hi) = (1e-3, 1.0, panel.floor, 1.0);
    }
    let (x_lo, x_hi) = (x_lo / 1.5, (x_hi * 2.0).max(x_lo * 10.0));
    let (y_lo, y_hi) = (y_lo / 3.0, (y_hi * 5.0).max(y_lo * 100.0));
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((x_lo..x_hi).log_scale(), (y_lo..y_hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("wall time of the design (s)")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_desc(panel.y_desc)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()?;

    // The Pareto front among the designs of the reference's net (the
    // reference itself is the yardstick, not a contender).
    let reference = rows.iter().find(|r| r.knob == Knob::Reference);
    let pairs: Vec<(f64, f64)> = ok
        .iter()
        .filter(|(r, _)| {
            r.knob != Knob::Reference && reference.is_none_or(|reference| r.same_net_as(reference))
        })
        .map(|(r, _)| (r.time_s, y(r)))
        .collect();
    let mut front: Vec<(f64, f64)> = pairs
        .iter()
        .zip(pareto_optimal(&pairs))
        .filter_map(|(p, optimal)| optimal.then_some(*p))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart.draw_series(LineSeries::new(
        front.clone(),
        BLACK.mix(0.5).stroke_width(1),
    ))?;
    chart.draw_series(
        front
            .iter()
            .map(|&p| Circle::new(p, 9, BLACK.stroke_width(2))),
    )?;
    let anchors: Vec<((i32, i32), Option<&str>)> = ok
        .iter()
        .map(|(r, label)| (chart.backend_coord(&(r.time_s, y(r))), label.as_deref()))
        .collect();
    let offsets = place_labels(&anchors);
    chart.draw_series(ok.iter().zip(offsets).map(|((r, label), offset)| {
        let text = offset.and(label.as_deref()).unwrap_or_default().to_string();
        EmptyElement::at((r.time_s, y(r)))
            + Circle::new((0, 0), 5, knob_colour(r.knob).filled())
            + Text::new(text, offset.unwrap_or((0, 0)), label_font())
    }))?;
    Ok(())
}

/// The legend, one row: a dot per knob present, and the Pareto ring.
fn draw_study_legend<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    rows: &[StudyRow],
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let font = ("sans-serif", 15).into_font();
    let mut x = 90;
    let y = 15;
    for knob in std::iter::once(Knob::Reference).chain(Knob::SWEPT) {
        if !rows.iter().any(|r| r.knob == knob) {
            continue;
        }
        area.draw(&Circle::new((x, y), 5, knob_colour(knob).filled()))?;
        area.draw(&Text::new(knob.name(), (x + 10, y - 8), font.clone()))?;
        x += 40 + 9 * knob.name().len() as i32;
    }
    area.draw(&Circle::new((x, y), 8, BLACK.stroke_width(2)))?;
    area.draw(&Text::new(
        "Pareto-optimal among the designs of the reference's net (the reference excluded)",
        (x + 14, y - 8),
        font.clone(),
    ))?;
    area.draw(&Text::new(
        format!(
            "An error below an axis's floor — RMS {RMS_FLOOR_MM:e} mm, ratio error \
             {RATIO_ERROR_FLOOR:e}, an exact zero among them — is drawn at the floor."
        ),
        (90, y + 14),
        font,
    ))?;
    Ok(())
}

pub(super) fn draw_study<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    rows: &[StudyRow],
    rms: &StudyRms,
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (charts, legend) = titled_with_legend(&root, title, 55)?;
    let panels = charts.split_evenly((1, 2));
    let surface = StudyPanel {
        y_desc: rms.caption(),
        floor: RMS_FLOOR_MM,
        error: &|r| rms.of(r),
    };
    let ratio = StudyPanel {
        y_desc: "ratio error |Tmax/Tmin − reference| / reference, as built",
        floor: RATIO_ERROR_FLOOR,
        error: &|r| r.ratio_error,
    };
    draw_study_panel(&panels[0], rows, &surface)?;
    draw_study_panel(&panels[1], rows, &ratio)?;
    draw_study_legend(&legend, rows)?;
    Ok(root.present()?)
}

/// Draws the accuracy study as PNG and SVG, each written atomically: two
/// log–log panels, surface RMS (`rms`: the design's, or the total with each
/// net's facet RMS) and ratio error (as built) against the
/// design's wall time, one colour per knob, each point labelled with its
/// value (the scene's own settings, which every sweep contains, once as
/// `baseline`); the Pareto-optimal points among the designs of the
/// reference's net ringed and joined. Values below the axis floors
/// (1e-9 mm, 1e-12) are drawn at the floor.
pub fn study_plot(
    rows: &[StudyRow],
    rms: &StudyRms,
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_study, (1600, 720), png, svg, rows, rms, title)
}
