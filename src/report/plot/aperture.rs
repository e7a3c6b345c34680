//! The aperture study's figure: surface RMS and largest tension change as
//! built on the exact truss against the aperture, one line per design model.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{png_and_svg, titled_with_legend};
use crate::report::{DrawError, ReportError};
use crate::scene::TrussModel;
use crate::study::{ApertureResult, ModelResult};

/// Floor of the aperture study's logarithmic axes.
const APERTURE_FLOOR: f64 = 1e-9;

/// One panel of the aperture study: a figure of each design model against
/// the aperture, log y.
fn draw_aperture_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    results: &[ApertureResult],
    y_desc: &str,
    figure: fn(&ModelResult) -> f64,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let value = |m: &ModelResult| figure(m).max(APERTURE_FLOOR);
    let values = results.iter().flat_map(|r| r.models.iter().map(value));
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let (lo, hi) = if lo.is_finite() {
        (lo / 3.0, hi * 3.0)
    } else {
        (APERTURE_FLOOR, 1.0)
    };
    let (x0, x1) = results.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| {
        (a.min(r.aperture_m), b.max(r.aperture_m))
    });
    let pad = 0.05 * (x1 - x0).max(1.0);
    let mut chart = ChartBuilder::on(area)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(75)
        .build_cartesian_2d((x0 - pad)..(x1 + pad), (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("aperture D (m)")
        .y_desc(y_desc)
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()?;
    for (model, _, colour) in aperture_models() {
        let points: Vec<(f64, f64)> = results
            .iter()
            .filter_map(|r| {
                let m = r.models.iter().find(|m| m.model == model)?;
                Some((r.aperture_m, value(m)))
            })
            .collect();
        chart.draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?;
        chart.draw_series(
            points
                .into_iter()
                .map(|p| Circle::new(p, 4, colour.filled())),
        )?;
    }
    Ok(())
}

/// The aperture study's design models: name and colour.
fn aperture_models() -> [(TrussModel, &'static str, RGBAColor); 3] {
    [
        (
            TrussModel::Rigid,
            "conventional (rigid truss)",
            RED.to_rgba(),
        ),
        (TrussModel::Linear, "linear truss", BLUE.to_rgba()),
        (TrussModel::Exact, "exact truss", BLACK.to_rgba()),
    ]
}

pub(super) fn draw_apertures<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    results: &[ApertureResult],
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (charts, legend) = titled_with_legend(&root, title, 35)?;
    let panels = charts.split_evenly((1, 2));
    // The legend below the panels: the lines cross every part of them.
    let font = ("sans-serif", 15).into_font();
    let mut x = 90;
    for (_, name, colour) in aperture_models() {
        legend.draw(&PathElement::new(
            vec![(x, 15), (x + 25, 15)],
            colour.stroke_width(2),
        ))?;
        legend.draw(&Text::new(name, (x + 32, 7), font.clone()))?;
        x += 60 + 9 * name.len() as i32;
    }
    draw_aperture_panel(
        &panels[0],
        results,
        "surface RMS as built on the exact truss (mm)",
        |m| m.rms_mm,
    )?;
    draw_aperture_panel(
        &panels[1],
        results,
        "largest tension change as built (%)",
        |m| m.tension_change_pct,
    )?;
    Ok(root.present()?)
}

/// Draws the aperture study as PNG and SVG, each written atomically: surface
/// RMS and largest tension change as built on the exact truss (log y)
/// against the aperture, one line per design model. Values below 1e-9 are
/// drawn at that floor.
pub fn aperture_plot(
    results: &[ApertureResult],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_apertures, (1600, 650), png, svg, results, title)
}
