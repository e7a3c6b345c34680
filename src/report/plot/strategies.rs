//! The strategies figure of the accuracy study: every uniformity solver the
//! study ran, its design's wall time against its surface RMS as built, on
//! one log–log axis pair, one series (marker, colour, legend entry) per
//! solver, each point labelled with its `Tmax/Tmin` as built.

use std::path::Path;

use plotters::element::ComposedElement;
use plotters::prelude::*;

use super::accuracy_vs_time::StudyRms;
use super::canvas::{png_and_svg, titled_with_legend, Area};
use super::labels::{label_font, place_labels};
use super::RMS_FLOOR_MM;
use crate::report::{readable, DrawError, ReportError};
use crate::study::{Knob, StudyRow};
use crate::uniformity::SolverKind;

/// One solver's series: the study's rows of the solver knob that ran it.
#[derive(Debug, Clone)]
pub struct StrategySeries<'a> {
    /// The solver.
    pub solver: SolverKind,
    /// Its rows (a failed one is listed in the legend, not drawn).
    pub rows: Vec<&'a StudyRow>,
}

/// The series of the strategies figure: one per solver the study's solver
/// knob ran, in the order they ran. Empty when the solver knob was not
/// swept.
pub fn strategy_series(rows: &[StudyRow]) -> Vec<StrategySeries<'_>> {
    let mut series: Vec<StrategySeries<'_>> = Vec::new();
    for row in rows.iter().filter(|r| r.knob == Knob::Solver) {
        let solver = row.settings.solver;
        match series.iter_mut().find(|s| s.solver == solver) {
            Some(s) => s.rows.push(row),
            None => series.push(StrategySeries {
                solver,
                rows: vec![row],
            }),
        }
    }
    series
}

/// The solver's colour: its place among every solver, so a solver has one
/// colour whichever others ran.
fn colour(solver: SolverKind) -> RGBAColor {
    let index = SolverKind::ALL
        .iter()
        .position(|&s| s == solver)
        .unwrap_or(0);
    Palette99::pick(index).to_rgba()
}

/// The solver's marker: its outline in pixels about the point (a square,
/// a circle, a triangle, a diamond, a cross).
fn marker(solver: SolverKind) -> Vec<(i32, i32)> {
    match solver {
        SolverKind::Lp => vec![(-5, -5), (5, -5), (5, 5), (-5, 5)],
        SolverKind::Bisection => (0..16)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 16.0;
                (
                    (6.0 * a.cos()).round() as i32,
                    (6.0 * a.sin()).round() as i32,
                )
            })
            .collect(),
        SolverKind::Gradient => vec![(0, -7), (6, 4), (-6, 4)],
        SolverKind::GradientSmooth => vec![(0, -7), (7, 0), (0, 7), (-7, 0)],
        SolverKind::LeastSquares => {
            let (a, w) = (6, 2);
            vec![
                (0, -w),
                (a - w, -a),
                (a, -a + w),
                (w, 0),
                (a, a - w),
                (a - w, a),
                (0, w),
                (-a + w, a),
                (-a, a - w),
                (-w, 0),
                (-a, -a + w),
                (-a + w, -a),
            ]
        }
    }
}

/// A marker: its inside and its outline, in pixels about a point `C`.
type Marker<C, DB> = ComposedElement<C, DB, Polygon<(i32, i32)>, PathElement<(i32, i32)>>;

/// The solver's marker at `at`: filled, or hollow (white inside) for a
/// point drawn at the RMS floor.
fn marker_at<DB: DrawingBackend, C>(solver: SolverKind, at: C, hollow: bool) -> Marker<C, DB> {
    let c = colour(solver);
    let outline = marker(solver);
    let mut closed = outline.clone();
    closed.push(outline[0]);
    let inside = if hollow { WHITE.filled() } else { c.filled() };
    EmptyElement::at(at)
        + Polygon::new(outline, inside)
        + PathElement::new(closed, c.stroke_width(2))
}

/// Ticks of a logarithmic time axis from `lo` to `hi`, s: 1, 2 and 5 of
/// each decade (1 alone over more than three decades), each once (plotters'
/// own key points list a decade's end twice when the axis spans less than
/// one).
fn time_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
    let steps: &[f64] = if last - first > 3 {
        &[1.0]
    } else {
        &[1.0, 2.0, 5.0]
    };
    (first..=last)
        .flat_map(|k| steps.iter().map(move |m| m * 10f64.powi(k)))
        .filter(|v| (lo..=hi).contains(v))
        .collect()
}

pub(super) fn draw_strategies<DB: DrawingBackend>(
    root: Area<DB>,
    rows: &[StudyRow],
    rms: &StudyRms,
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let series = strategy_series(rows);
    let (plot, legend) = titled_with_legend(&root, title, 80)?;
    let drawn = |r: &StudyRow| r.error.is_none() && r.time_s > 0.0 && rms.of(r).is_finite();
    let y = |r: &StudyRow| rms.of(r).max(RMS_FLOOR_MM);
    let points: Vec<(SolverKind, &StudyRow)> = series
        .iter()
        .flat_map(|s| s.rows.iter().map(move |r| (s.solver, *r)))
        .filter(|(_, r)| drawn(r))
        .collect();
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (_, r) in &points {
        x_lo = x_lo.min(r.time_s);
        x_hi = x_hi.max(r.time_s);
        y_lo = y_lo.min(y(r));
        y_hi = y_hi.max(y(r));
    }
    if points.is_empty() {
        (x_lo, x_hi, y_lo, y_hi) = (1e-2, 1.0, RMS_FLOOR_MM, 1.0);
    }
    let (x_lo, x_hi) = (x_lo / 2.0, (x_hi * 3.0).max(x_lo * 10.0));
    let (y_lo, y_hi) = (y_lo / 5.0, (y_hi * 10.0).max(y_lo * 100.0));
    let mut chart = ChartBuilder::on(&plot)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (x_lo..x_hi)
                .log_scale()
                .with_key_points(time_ticks(x_lo, x_hi)),
            (y_lo..y_hi).log_scale(),
        )?;
    chart
        .configure_mesh()
        .x_desc("wall time of the design (s)")
        .x_label_formatter(&|v| readable(*v, 3))
        .y_desc(rms.caption())
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()?;
    let below = |r: &StudyRow| rms.of(r) < RMS_FLOOR_MM;
    for s in &series {
        let at = |r: &&StudyRow| (r.time_s, y(r));
        let mine = || {
            points
                .iter()
                .filter(|(k, _)| *k == s.solver)
                .map(|(_, r)| r)
        };
        chart.draw_series(mine().map(|r| marker_at(s.solver, at(r), below(r))))?;
    }
    let labels: Vec<String> = points
        .iter()
        .map(|(_, r)| format!("Tmax/Tmin {}", readable(r.built_ratio, 5)))
        .collect();
    let anchors: Vec<((i32, i32), Option<&str>)> = points
        .iter()
        .zip(&labels)
        .map(|((_, r), l)| (chart.backend_coord(&(r.time_s, y(r))), Some(l.as_str())))
        .collect();
    let offsets = place_labels(&anchors);
    chart.draw_series(points.iter().zip(&labels).zip(offsets).filter_map(
        |(((_, r), label), offset)| {
            let offset = offset?;
            Some(
                EmptyElement::at((r.time_s, y(r))) + Text::new(label.clone(), offset, label_font()),
            )
        },
    ))?;
    draw_legend(&legend, &series, rows)?;
    Ok(root.present()?)
}

/// The legend below the plot: a marker and name per solver (its failure,
/// if it failed), the floor's convention, what the labels are.
fn draw_legend<DB: DrawingBackend>(
    legend: &Area<DB>,
    series: &[StrategySeries<'_>],
    rows: &[StudyRow],
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let font = ("sans-serif", 14).into_font();
    let width = |text: &str| {
        font.box_size(text)
            .map_or(9 * text.chars().count() as i32, |(w, _)| w as i32)
    };
    let mut x = 80;
    for s in series {
        let failed = s.rows.iter().all(|r| r.error.is_some());
        let name = if failed {
            format!("{} (failed, not drawn)", s.solver.name())
        } else {
            s.solver.name().to_string()
        };
        legend.draw(&marker_at(s.solver, (x, 12), false))?;
        legend.draw(&Text::new(name.clone(), (x + 12, 5), font.clone()))?;
        x += 12 + width(&name) + 28;
    }
    if series.is_empty() {
        let swept = rows.iter().any(|r| r.knob == Knob::Solver);
        let note = if swept {
            "no solver ran"
        } else {
            "the study did not sweep the solver knob (--knobs solver): no strategy to compare"
        };
        legend.draw(&Text::new(note, (80, 5), font.clone()))?;
    }
    let notes = [
        "Each solver at the baseline's other settings, its design assembled on the reference \
         truss."
            .to_string(),
        format!(
            "An RMS below {RMS_FLOOR_MM:e} mm (an exact 0 among them) is drawn hollow at that \
             floor. Point labels: Tmax/Tmin of the tensions as built."
        ),
    ];
    for (k, note) in notes.into_iter().enumerate() {
        legend.draw(&Text::new(note, (80, 28 + 20 * k as i32), font.clone()))?;
    }
    Ok(())
}

/// Draws the strategies figure of a study as PNG and SVG, each written
/// atomically: every uniformity solver the study ran (its solver knob), the
/// design's wall time against its surface RMS (`rms`: as built, or the
/// total with the net's facet RMS), log–log, one marker and colour per
/// solver, each point labelled with its `Tmax/Tmin` as built; an RMS below
/// 1e-9 mm drawn hollow at that floor, as the legend says.
pub fn strategies_plot(
    rows: &[StudyRow],
    rms: &StudyRms,
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_strategies, (1100, 700), png, svg, rows, rms, title)
}
