//! Pictures (plotters): the design front, the outer loop's convergence, the
//! surface error, and the accuracy study. Text is drawn with the DejaVu Sans
//! font shipped in the crate, so plots render on a machine without system fonts.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

use super::{write_atomic, write_atomic_with, DrawError, FrontRow, ReportError};
use crate::scene::TrussModel;
use crate::study::{pareto_optimal, ApertureResult, Knob, StudyRow};

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
    points: &[FrontRow],
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let ok: Vec<&FrontRow> = points.iter().filter(|p| p.ratio.is_finite()).collect();
    root.fill(&WHITE)?;
    let x = |p: &FrontRow| p.rms_mm.max(RMS_FLOOR_MM);
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
        .build_cartesian_2d((x_lo..x_hi).log_scale(), y_lo..y_hi)?;
    chart
        .configure_mesh()
        .x_desc("surface RMS from a forward solve (mm)")
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .y_desc("Tmax / Tmin")
        .label_style(("sans-serif", 14))
        .draw()?;
    let mut solvers: Vec<&str> = Vec::new();
    for p in &ok {
        if !solvers.contains(&p.solver.as_str()) {
            solvers.push(&p.solver);
        }
    }
    for (index, solver) in solvers.into_iter().enumerate() {
        let colour = Palette99::pick(index).to_rgba();
        let mut series: Vec<(f64, f64)> = ok
            .iter()
            .filter(|p| p.solver == solver)
            .map(|p| (x(p), p.ratio))
            .collect();
        series.sort_by(|a, b| a.0.total_cmp(&b.0));
        let name = solver.to_string();
        chart
            .draw_series(LineSeries::new(series.clone(), colour.stroke_width(2)))?
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(
            series
                .into_iter()
                .map(|p| Circle::new(p, 4, colour.filled())),
        )?;
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(root.present()?)
}

/// Draws `$draw(area, args…)` — generic over the plotters backend — as a PNG
/// of `$size` pixels and as an SVG, each file written atomically (the PNG
/// backend draws to the temporary path of `write_atomic_with`).
macro_rules! png_and_svg {
    ($draw:ident, $size:expr, $png:expr, $svg:expr $(, $arg:expr)*) => {{
        register_font();
        let (png, svg, size): (&Path, &Path, (u32, u32)) = ($png, $svg, $size);
        write_atomic_with(png, |temporary| {
            $draw(BitMapBackend::new(temporary, size).into_drawing_area() $(, $arg)*)
        })?;
        let mut text = String::new();
        $draw(SVGBackend::with_string(&mut text, size).into_drawing_area() $(, $arg)*)
            .map_err(|source| ReportError::Plot {
                path: svg.to_path_buf(),
                source,
            })?;
        write_atomic(svg, text.as_bytes())
    }};
}

/// Draws the design front (ratio against actual surface RMS, one curve per
/// solver) as PNG and SVG, each written atomically.
pub fn front_plot(
    points: &[FrontRow],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_front, (900, 600), png, svg, points, title)
}

/// Floor of a logarithmic residual axis, m.
const RESIDUAL_FLOOR_M: f64 = 1e-12;

fn draw_convergence<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    series: &[(String, Vec<(usize, f64)>)],
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
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
        .build_cartesian_2d(0..last.max(1), (lo..hi).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("outer iteration")
        .y_desc("max boundary change ‖G(C) − C‖∞ (m)")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style(("sans-serif", 14))
        .draw()?;
    for (index, (name, points)) in series.iter().enumerate() {
        let colour = Palette99::pick(index).to_rgba();
        let points: Vec<(usize, f64)> = points
            .iter()
            .map(|&(k, v)| (k, v.max(RESIDUAL_FLOOR_M)))
            .collect();
        chart
            .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))?
            .label(name.clone())
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart.draw_series(
            points
                .into_iter()
                .map(|p| Circle::new(p, 3, colour.filled())),
        )?;
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
/// line per relaxation policy) as PNG and SVG, each written atomically.
pub fn convergence_plot(
    series: &[(String, Vec<(usize, f64)>)],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_convergence, (900, 600), png, svg, series, title)
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
    let draw = |temporary: &Path| -> Result<(), DrawError> {
        let root = BitMapBackend::new(temporary, (800u32, 800u32)).into_drawing_area();
        root.fill(&WHITE)?;
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
            .build_cartesian_2d((x_lo - pad)..(x_hi + pad), (y_lo - pad)..(y_hi + pad))?;
        chart
            .configure_mesh()
            .x_desc(format!("x (m); colour: deviation, ±{scale:.2e} mm"))
            .y_desc("y (m)")
            .label_style(("sans-serif", 14))
            .draw()?;
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
        chart.draw_series(
            points
                .iter()
                .map(|&(x, y, d)| Circle::new((x, y), 6, ShapeStyle::from(&colour(d)).filled())),
        )?;
        chart.draw_series(
            points
                .iter()
                .map(|&(x, y, _)| Circle::new((x, y), 6, BLACK.stroke_width(1))),
        )?;
        Ok(root.present()?)
    };
    write_atomic_with(png, draw)
}

/// Floor of a logarithmic ratio-error axis (the reference itself has 0).
const RATIO_ERROR_FLOOR: f64 = 1e-12;

/// One panel of the study plot: accuracy `error` against time.
struct StudyPanel<'a> {
    y_desc: &'a str,
    floor: f64,
    error: fn(&StudyRow) -> f64,
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
    // Labels of nearby points are stacked downwards rather than overprinted.
    let mut placed: Vec<(i32, i32)> = Vec::new();
    let mut offsets = Vec::with_capacity(ok.len());
    for (r, label) in &ok {
        let (px, mut py) = chart.backend_coord(&(r.time_s, y(r)));
        py -= 14;
        if label.is_some() {
            while placed
                .iter()
                .any(|&(qx, qy)| (qx - px).abs() < 45 && (qy - py).abs() < 12)
            {
                py += 13;
            }
            placed.push((px, py));
        }
        offsets.push(py - chart.backend_coord(&(r.time_s, y(r))).1);
    }
    chart.draw_series(ok.iter().zip(offsets).map(|((r, label), dy)| {
        EmptyElement::at((r.time_s, y(r)))
            + Circle::new((0, 0), 5, knob_colour(r.knob).filled())
            + Text::new(
                label.as_deref().unwrap_or_default().to_string(),
                (7, dy),
                ("sans-serif", 12).into_font(),
            )
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
        font,
    ))?;
    Ok(())
}

fn draw_study<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    rows: &[StudyRow],
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let body = root.titled(title, ("sans-serif", 22))?;
    let height = body.dim_in_pixel().1 as i32;
    let (charts, legend) = body.split_vertically(height - 35);
    let panels = charts.split_evenly((1, 2));
    let rms = StudyPanel {
        y_desc: "surface RMS as built on the reference truss (mm)",
        floor: RMS_FLOOR_MM,
        error: |r| r.rms_mm,
    };
    let ratio = StudyPanel {
        y_desc: "ratio error |Tmax/Tmin − reference| / reference, as built",
        floor: RATIO_ERROR_FLOOR,
        error: |r| r.ratio_error,
    };
    draw_study_panel(&panels[0], rows, &rms)?;
    draw_study_panel(&panels[1], rows, &ratio)?;
    draw_study_legend(&legend, rows)?;
    Ok(root.present()?)
}

/// Draws the accuracy study as PNG and SVG, each written atomically: two
/// log–log panels, surface RMS and ratio error (as built) against the
/// design's wall time, one colour per knob, each point labelled with its
/// value (the scene's own settings, which every sweep contains, once as
/// `baseline`); the Pareto-optimal points among the designs of the
/// reference's net ringed and joined. Values below the axis floors
/// (1e-9 mm, 1e-12) are drawn at the floor.
pub fn study_plot(
    rows: &[StudyRow],
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_study, (1600, 720), png, svg, rows, title)
}

/// Floor of the aperture study's logarithmic axes.
const APERTURE_FLOOR: f64 = 1e-9;

/// One panel of the aperture study: a figure of each design model against
/// the aperture, log y.
fn draw_aperture_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    results: &[ApertureResult],
    y_desc: &str,
    figure: fn(&crate::study::ModelResult) -> f64,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let value = |m: &crate::study::ModelResult| figure(m).max(APERTURE_FLOOR);
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

fn draw_apertures<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    results: &[ApertureResult],
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let body = root.titled(title, ("sans-serif", 22))?;
    let height = body.dim_in_pixel().1 as i32;
    let (charts, legend) = body.split_vertically(height - 35);
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
