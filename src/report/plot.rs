//! Pictures (plotters): the design front. Text is drawn with the DejaVu Sans font
//! shipped in the crate, so plots render on a machine without system fonts.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

use super::{write_atomic, write_atomic_with, ReportError};
use crate::uniformity::FrontPoint;

const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

fn register_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is valid by construction; a failure would only lose text.
        let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Floor for a logarithmic RMS axis, mm (an exact design has RMS ≈ 1e-12 mm).
const RMS_FLOOR_MM: f64 = 1e-9;

fn draw_front<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    points: &[FrontPoint],
    title: &str,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    let ok: Vec<&FrontPoint> = points
        .iter()
        .filter(|p| p.outcome.is_ok() && p.ratio.is_finite())
        .collect();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let x = |p: &FrontPoint| p.rms_mm.max(RMS_FLOOR_MM);
    let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in &ok {
        x_lo = x_lo.min(x(p));
        x_hi = x_hi.max(x(p));
        y_lo = y_lo.min(p.ratio);
        y_hi = y_hi.max(p.ratio);
    }
    if ok.is_empty() {
        (x_lo, x_hi, y_lo, y_hi) = (RMS_FLOOR_MM, 1.0, 1.0, 2.0);
    }
    let (x_lo, x_hi) = (x_lo / 2.0, (x_hi * 2.0).max(x_lo * 10.0));
    let (y_lo, y_hi) = ((y_lo * 0.95).max(1.0 - 1e-9), y_hi * 1.05 + 1e-9);
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d((x_lo..x_hi).log_scale(), y_lo..y_hi)
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("surface RMS from a forward solve (mm)")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_desc("Tmax / Tmin")
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())?;
    let mut solvers: Vec<_> = ok.iter().map(|p| p.solver).collect();
    solvers.dedup();
    for (index, solver) in solvers.into_iter().enumerate() {
        let colour = Palette99::pick(index).to_rgba();
        let mut series: Vec<(f64, f64)> = ok
            .iter()
            .filter(|p| p.solver == solver)
            .map(|p| (x(p), p.ratio))
            .collect();
        series.sort_by(|a, b| a.0.total_cmp(&b.0));
        let name = clap::ValueEnum::to_possible_value(&solver)
            .map(|v| v.get_name().to_string())
            .unwrap_or_default();
        chart
            .draw_series(LineSeries::new(series.clone(), colour.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(
                series
                    .into_iter()
                    .map(|p| Circle::new(p, 4, colour.filled())),
            )
            .map_err(|e| e.to_string())?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

/// Draws the design front (ratio against actual surface RMS, one curve per
/// solver) as PNG and SVG, each written atomically.
pub fn front_plot(
    points: &[FrontPoint],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    register_font();
    let failure = |path: &Path, message: String| ReportError::Plot {
        path: path.to_path_buf(),
        message,
    };
    let size = (900u32, 600u32);
    write_atomic_with(png, |temporary| {
        let root = BitMapBackend::new(temporary, size).into_drawing_area();
        draw_front(root, points, title)
    })
    .map_err(|m| failure(png, m))?;
    let mut text = String::new();
    draw_front(
        SVGBackend::with_string(&mut text, size).into_drawing_area(),
        points,
        title,
    )
    .map_err(|m| failure(svg, m))?;
    write_atomic(svg, text.as_bytes())
}

/// Floor of a logarithmic residual axis, m.
const RESIDUAL_FLOOR_M: f64 = 1e-12;

fn draw_convergence<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    series: &[(String, Vec<(usize, f64)>)],
    title: &str,
) -> Result<(), String>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let values = series
        .iter()
        .flat_map(|(_, s)| s.iter().map(|p| p.1.max(RESIDUAL_FLOOR_M)));
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
        .build_cartesian_2d(0..last.max(1), (lo..hi).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("outer iteration")
        .y_desc("max boundary change ‖G(C) − C‖∞ (m)")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())?;
    for (index, (name, points)) in series.iter().enumerate() {
        let colour = Palette99::pick(index).to_rgba();
        let points: Vec<(usize, f64)> = points
            .iter()
            .map(|&(k, v)| (k, v.max(RESIDUAL_FLOOR_M)))
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
            .map_err(|e| e.to_string())?
            .label(name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(
                points
                    .into_iter()
                    .map(|p| Circle::new(p, 3, colour.filled())),
            )
            .map_err(|e| e.to_string())?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|e| e.to_string())?;
    root.present().map_err(|e| e.to_string())
}

/// Draws the outer loop's fixed-point residual per iteration (log scale, one
/// line per relaxation policy) as PNG and SVG, each written atomically.
pub fn convergence_plot(
    series: &[(String, Vec<(usize, f64)>)],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    register_font();
    let failure = |path: &Path, message: String| ReportError::Plot {
        path: path.to_path_buf(),
        message,
    };
    let size = (900u32, 600u32);
    write_atomic_with(png, |temporary| {
        draw_convergence(
            BitMapBackend::new(temporary, size).into_drawing_area(),
            series,
            title,
        )
    })
    .map_err(|m| failure(png, m))?;
    let mut text = String::new();
    draw_convergence(
        SVGBackend::with_string(&mut text, size).into_drawing_area(),
        series,
        title,
    )
    .map_err(|m| failure(svg, m))?;
    write_atomic(svg, text.as_bytes())
}

/// Draws a top view of the surface nodes `(x, y, deviation_mm)`, coloured by
/// the deviation (blue below the paraboloid, red above, white on it; the
/// scale symmetric about zero), as a PNG written atomically.
pub fn surface_plot(
    points: &[(f64, f64, f64)],
    title: &str,
    png: &Path,
) -> Result<(), ReportError> {
    register_font();
    let draw =
        |temporary: &Path| -> Result<(), String> {
            let root = BitMapBackend::new(temporary, (800u32, 800u32)).into_drawing_area();
            root.fill(&WHITE).map_err(|e| e.to_string())?;
            let (mut x_lo, mut x_hi, mut y_lo, mut y_hi) = (
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            );
            let mut scale = 0.0f64;
            for &(x, y, d) in points {
                x_lo = x_lo.min(x);
                x_hi = x_hi.max(x);
                y_lo = y_lo.min(y);
                y_hi = y_hi.max(y);
                scale = scale.max(d.abs());
            }
            if !x_lo.is_finite() {
                (x_lo, x_hi, y_lo, y_hi) = (-1.0, 1.0, -1.0, 1.0);
            }
            let pad = 0.05 * (x_hi - x_lo).max(y_hi - y_lo).max(1e-9);
            let mut chart = ChartBuilder::on(&root)
                .caption(title, ("sans-serif", 18))
                .margin(15)
                .x_label_area_size(40)
                .y_label_area_size(50)
                .build_cartesian_2d((x_lo - pad)..(x_hi + pad), (y_lo - pad)..(y_hi + pad))
                .map_err(|e| e.to_string())?;
            chart
                .configure_mesh()
                .x_desc(format!("x (m); colour: deviation, ±{scale:.2e} mm"))
                .y_desc("y (m)")
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(|e| e.to_string())?;
            let colour = |d: f64| {
                let t = if scale > 0.0 {
                    (d / scale).clamp(-1.0, 1.0)
                } else {
                    0.0
                };
                let fade = |v: f64| (255.0 * (1.0 - v.abs())) as u8;
                if t >= 0.0 {
                    RGBColor(255, fade(t), fade(t))
                } else {
                    RGBColor(fade(t), fade(t), 255)
                }
            };
            chart
                .draw_series(points.iter().map(|&(x, y, d)| {
                    Circle::new((x, y), 6, ShapeStyle::from(&colour(d)).filled())
                }))
                .map_err(|e| e.to_string())?;
            chart
                .draw_series(
                    points
                        .iter()
                        .map(|&(x, y, _)| Circle::new((x, y), 6, BLACK.stroke_width(1))),
                )
                .map_err(|e| e.to_string())?;
            root.present().map_err(|e| e.to_string())
        };
    write_atomic_with(png, draw).map_err(|message| ReportError::Plot {
        path: png.to_path_buf(),
        message,
    })
}
