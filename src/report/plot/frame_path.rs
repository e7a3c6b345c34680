//! A frame's followed equilibrium path: load factor against a recorded
//! displacement, critical points marked by kind.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{png_and_svg, Area};
use crate::report::{DrawError, ReportError};

/// A followed equilibrium path: `(displacement, load factor)` per step and
/// the critical points `(displacement, load factor, kind)`.
#[derive(Debug, Clone)]
pub struct PathFigure {
    /// The figure's title.
    pub title: String,
    /// The horizontal axis's name.
    pub x_label: String,
    /// Every converged step.
    pub points: Vec<(f64, f64)>,
    /// Critical points: position, load factor, kind (`limit_maximum`, …).
    pub critical: Vec<(f64, f64, String)>,
}

fn draw_path<DB: DrawingBackend>(root: Area<DB>, figure: &PathFigure) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let all = figure
        .points
        .iter()
        .map(|&(x, y)| (x, y))
        .chain(figure.critical.iter().map(|&(x, y, _)| (x, y)));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64, 0.0f64);
    for (x, y) in all {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    if !(x0.is_finite() && x1.is_finite()) {
        (x0, x1) = (0.0, 1.0);
    }
    let pad = |lo: f64, hi: f64| {
        let d = if hi > lo { 0.05 * (hi - lo) } else { 0.5 };
        (lo - d, hi + d)
    };
    let ((x0, x1), (y0, y1)) = (pad(x0, x1), pad(y0, y1));
    let mut chart = ChartBuilder::on(&root)
        .caption(&figure.title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(figure.x_label.as_str())
        .y_desc("load factor λ")
        .label_style(("sans-serif", 14))
        .draw()?;
    let line = BLUE.stroke_width(2);
    chart
        .draw_series(LineSeries::new(figure.points.clone(), line))?
        .label("equilibrium path")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], line));
    chart.draw_series(
        figure
            .points
            .iter()
            .map(|&p| Circle::new(p, 2, BLUE.filled())),
    )?;
    for (kind, colour) in [
        ("limit_maximum", RED),
        ("limit_minimum", MAGENTA),
        ("bifurcation", GREEN),
    ] {
        let marks: Vec<(f64, f64)> = figure
            .critical
            .iter()
            .filter(|c| c.2 == kind)
            .map(|c| (c.0, c.1))
            .collect();
        if marks.is_empty() {
            continue;
        }
        chart
            .draw_series(
                marks
                    .iter()
                    .map(|&p| TriangleMarker::new(p, 8, colour.filled())),
            )?
            .label(kind.replace('_', " "))
            .legend(move |(x, y)| TriangleMarker::new((x + 10, y), 6, colour.filled()));
    }
    chart
        .configure_series_labels()
        .position(legend_corner(&figure.points, (x0, x1), (y0, y1)))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(root.present()?)
}

/// The corner of the plot the legend covers least of the path: not the one
/// the path starts in, then the one holding the fewest of its points (each
/// corner a box of 40 % of either range).
fn legend_corner(
    points: &[(f64, f64)],
    (x0, x1): (f64, f64),
    (y0, y1): (f64, f64),
) -> SeriesLabelPosition {
    let fraction = |v: f64, lo: f64, hi: f64| if hi > lo { (v - lo) / (hi - lo) } else { 0.5 };
    let corner_of = |&(x, y): &(f64, f64)| {
        let (fx, fy) = (fraction(x, x0, x1), fraction(y, y0, y1));
        let side = |f: f64| {
            if f <= 0.4 {
                Some(false)
            } else if f >= 0.6 {
                Some(true)
            } else {
                None
            }
        };
        Some((side(fx)?, side(fy)?))
    };
    let start = points.first().and_then(corner_of);
    // (right, upper) for each corner.
    let corners = [
        ((false, true), SeriesLabelPosition::UpperLeft),
        ((true, true), SeriesLabelPosition::UpperRight),
        ((true, false), SeriesLabelPosition::LowerRight),
        ((false, false), SeriesLabelPosition::LowerLeft),
    ];
    corners
        .into_iter()
        .filter(|(c, _)| Some(*c) != start)
        .min_by_key(|(c, _)| points.iter().filter(|p| corner_of(p) == Some(*c)).count())
        .map_or(SeriesLabelPosition::UpperRight, |(_, position)| position)
}

/// Draws a followed equilibrium path (load factor against a recorded
/// displacement, critical points marked by kind) as PNG and SVG, each
/// written atomically.
pub fn path_plot(figure: &PathFigure, png: &Path, svg: &Path) -> Result<(), ReportError> {
    png_and_svg!(draw_path, (900, 600), png, svg, figure)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path that starts at the lower left and climbs to the upper right
    /// gets its legend in a corner it leaves empty, never over its start.
    #[test]
    fn the_legend_never_covers_the_paths_start() {
        let points: Vec<(f64, f64)> = (0..=20).map(|k| (k as f64, k as f64)).collect();
        let corner = legend_corner(&points, (0.0, 20.0), (0.0, 20.0));
        assert!(matches!(
            corner,
            SeriesLabelPosition::UpperLeft | SeriesLabelPosition::LowerRight
        ));
        let start_upper_left: Vec<(f64, f64)> =
            (0..=20).map(|k| (k as f64, 20.0 - k as f64)).collect();
        let corner = legend_corner(&start_upper_left, (0.0, 20.0), (0.0, 20.0));
        assert!(!matches!(corner, SeriesLabelPosition::UpperLeft));
    }
}
