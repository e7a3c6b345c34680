//! The outer loop's convergence: the fixed-point residual per iteration, one
//! line per relaxation policy, with the stopping tolerance.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::png_and_svg;
use crate::report::{DrawError, ReportError};

/// Floor of a logarithmic residual axis, m.
const RESIDUAL_FLOOR_M: f64 = 1e-12;

pub(super) fn draw_convergence<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    series: &[(String, Vec<(usize, f64)>)],
    title: &str,
    tolerance_m: f64,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let values = series
        .iter()
        .flat_map(|(_, s)| s.iter().map(|p| p.1.max(RESIDUAL_FLOOR_M)))
        .chain(std::iter::once(tolerance_m.max(RESIDUAL_FLOOR_M)));
    let (lo, hi) = values.fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    let (lo, hi) = if lo.is_finite() {
        (lo / 3.0, hi * 3.0)
    } else {
        (1e-9, 1.0)
    };
    let last = series
        .iter()
        .flat_map(|(_, s)| s.iter().map(|p| p.0))
        .max()
        .unwrap_or(1);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(0..last.max(1), (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("outer iteration")
        .y_desc("max boundary change ‖G(C) − C‖∞ (m)")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()?;
    // The tolerance, and each policy drawn thinner than the one before and
    // with its own marker, so that one that follows another stays visible.
    let tolerance = BLACK.stroke_width(2);
    chart
        .draw_series(DashedLineSeries::new(
            [(0, tolerance_m), (last.max(1), tolerance_m)],
            8,
            6,
            tolerance,
        ))?
        .label(format!("tolerance {tolerance_m:.0e} m"))
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 8, y)], tolerance));
    for (index, (name, points)) in series.iter().enumerate() {
        let colour = Palette99::pick(index).to_rgba();
        let width = (4 - index.min(3) as u32).max(1);
        let points: Vec<(usize, f64)> = points
            .iter()
            .map(|&(k, v)| (k, v.max(RESIDUAL_FLOOR_M)))
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(width)))?
            .label(name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(width))
            });
        match index % 3 {
            0 => chart.draw_series(
                points
                    .into_iter()
                    .map(|p| Circle::new(p, 5, colour.filled()).into_dyn()),
            )?,
            1 => chart.draw_series(
                points
                    .into_iter()
                    .map(|p| TriangleMarker::new(p, 6, colour.filled()).into_dyn()),
            )?,
            _ => chart.draw_series(
                points
                    .into_iter()
                    .map(|p| Cross::new(p, 5, colour.stroke_width(2)).into_dyn()),
            )?,
        };
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(root.present()?)
}

/// Draws the outer loop's fixed-point residual per iteration (log scale, one
/// line per relaxation policy, each with its own marker and width) with the
/// stopping tolerance as PNG and SVG, each written atomically.
pub fn convergence_plot(
    series: &[(String, Vec<(usize, f64)>)],
    title: &str,
    tolerance_m: f64,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(
        draw_convergence,
        (900, 600),
        png,
        svg,
        series,
        title,
        tolerance_m
    )
}
