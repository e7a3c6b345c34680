//! Pictures (plotters): the design front, the outer loop's convergence, the
//! surface error, and the accuracy study. Text is drawn with the DejaVu Sans
//! font shipped in the crate, so plots render on a machine without system fonts.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;

use super::atomic::write_atomic;
use super::csv::FrontRow;
use super::error::{DrawError, ReportError};
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
    failed: Option<&[(String, f64)]>,
    title: &str,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let ok: Vec<&FrontRow> = points.iter().filter(|p| p.ratio.is_finite()).collect();
    let (plot, legend) = titled_with_legend(&root, title, 60)?;
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
    let (x_lo, x_hi) = (x_lo / 2.0, (x_hi * 4.0).max(x_lo * 10.0));
    let (y_lo, y_hi) = ((y_lo * 0.95).max(1.0 - 1e-9), y_hi * 1.05 + 1e-9);
    let mut chart = ChartBuilder::on(&plot)
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
    let failures = failed.unwrap_or_default();
    for p in ok
        .iter()
        .map(|p| p.solver.as_str())
        .chain(failures.iter().map(|f| f.0.as_str()))
    {
        if !solvers.contains(&p) {
            solvers.push(p);
        }
    }
    let colour = |solver: &str| {
        Palette99::pick(solvers.iter().position(|s| *s == solver).unwrap_or(0)).to_rgba()
    };
    let mut anchors = Vec::new();
    for solver in &solvers {
        let c = colour(solver);
        let mut series: Vec<&FrontRow> =
            ok.iter().copied().filter(|p| p.solver == *solver).collect();
        series.sort_by(|a, b| x(a).total_cmp(&x(b)));
        chart.draw_series(LineSeries::new(
            series.iter().map(|p| (x(p), p.ratio)),
            c.stroke_width(2),
        ))?;
        // A point below the axis floor is drawn at it, hollow.
        chart.draw_series(series.iter().map(|p| {
            let style = if p.rms_mm < RMS_FLOOR_MM {
                c.stroke_width(2)
            } else {
                c.filled()
            };
            Circle::new((x(p), p.ratio), 4, style)
        }))?;
        anchors.extend(series.iter().map(|p| ((x(p), p.ratio), knob_label(p.knob))));
    }
    // Each point labelled with its knob, where the label has room.
    let pixels: Vec<((i32, i32), Option<&str>)> = anchors
        .iter()
        .map(|(p, label)| (chart.backend_coord(p), Some(label.as_str())))
        .collect();
    let offsets = place_labels(&pixels);
    chart.draw_series(
        anchors
            .iter()
            .zip(offsets)
            .filter_map(|((p, label), offset)| {
                let offset = offset?;
                Some(EmptyElement::at(*p) + Text::new(label.clone(), offset, label_font()))
            }),
    )?;
    // The legend below the plot: the solvers, the floor, the failures.
    let font = ("sans-serif", 14).into_font();
    let mut at = 70;
    for solver in &solvers {
        let c = colour(solver);
        legend.draw(&PathElement::new(
            vec![(at, 14), (at + 22, 14)],
            c.stroke_width(2),
        ))?;
        legend.draw(&Text::new(solver.to_string(), (at + 28, 6), font.clone()))?;
        at += 50 + 8 * solver.len() as i32;
    }
    legend.draw(&Circle::new((at, 14), 4, BLACK.stroke_width(2)))?;
    legend.draw(&Text::new(
        format!("RMS below {RMS_FLOOR_MM:.0e} mm, drawn at it; labels: the knob"),
        (at + 10, 6),
        font.clone(),
    ))?;
    let failures = match failed {
        None => "failed points: not recorded in shards (see each shard's run)".to_string(),
        Some([]) => "no failed point".to_string(),
        Some(failed) => {
            let list: Vec<String> = failed
                .iter()
                .map(|(solver, knob)| format!("{solver} at {knob:.0e}"))
                .collect();
            format!("failed, no design (not drawn): {}", list.join(", "))
        }
    };
    legend.draw(&Text::new(failures, (70, 32), font))?;
    Ok(root.present()?)
}

/// Draws `$draw(area, args…)` — generic over the plotters backend — as a PNG
/// of `$size` pixels (drawn in memory) and as an SVG, each file written
/// atomically.
macro_rules! png_and_svg {
    ($draw:ident, $size:expr, $png:expr, $svg:expr $(, $arg:expr)*) => {{
        register_font();
        let (png, svg, size): (&Path, &Path, (u32, u32)) = ($png, $svg, $size);
        let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
        $draw(BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area() $(, $arg)*)
            .map_err(|source| ReportError::Plot {
                path: png.to_path_buf(),
                source,
            })?;
        write_atomic(png, &png_bytes(&rgb, size, png)?)?;
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
/// solver, each point labelled with its knob where there is room; a point
/// below the RMS floor drawn hollow at it) as PNG and SVG, each written
/// atomically; the legend, below the plot, lists the `failed` points
/// (solver, knob), or says they are unknown (`None`: a merged front).
pub fn front_plot(
    points: &[FrontRow],
    failed: Option<&[(String, f64)]>,
    title: &str,
    png: &Path,
    svg: &Path,
) -> Result<(), ReportError> {
    png_and_svg!(draw_front, (1000, 680), png, svg, points, failed, title)
}

/// A knob value as a point's label: one significant digit.
fn knob_label(knob: f64) -> String {
    if knob == 0.0 {
        "0".into()
    } else {
        format!("{knob:.0e}")
    }
}

/// The font of point labels.
fn label_font() -> TextStyle<'static> {
    ("sans-serif", LABEL_PX).into_font().into()
}

/// Height of a point label, px.
const LABEL_PX: i32 = 12;

/// Where to write each label beside its point (`anchors`: the point in
/// pixels and its label, if it has one), as a pixel offset from the point:
/// to the right or left, above or below, else stacked further down, at the
/// first place that overlaps no label already placed; `None` for a label
/// with no free place (left out rather than overprinted).
fn place_labels(anchors: &[((i32, i32), Option<&str>)]) -> Vec<Option<(i32, i32)>> {
    let mut placed: Vec<[i32; 4]> = Vec::new();
    anchors
        .iter()
        .map(|&((x, y), label)| {
            let label = label?;
            let width = 7 * label.chars().count() as i32;
            let h = LABEL_PX + 1;
            let candidates = [(7, -h), (7, 2), (-width - 7, -h), (-width - 7, 2)]
                .into_iter()
                .chain((1..=4).map(|k| (7, 2 + k * h)));
            let free = |(dx, dy): (i32, i32)| {
                let r = [x + dx, y + dy, x + dx + width, y + dy + h];
                !placed
                    .iter()
                    .any(|q| r[0] < q[2] && q[0] < r[2] && r[1] < q[3] && q[1] < r[3])
            };
            let (dx, dy) = candidates.into_iter().find(|&c| free(c))?;
            placed.push([x + dx, y + dy, x + dx + width, y + dy + h]);
            Some((dx, dy))
        })
        .collect()
}

/// A drawing area in pixels.
type Area<DB> = DrawingArea<DB, plotters::coord::Shift>;

/// `root` titled, split into the plots above and a legend strip of
/// `legend_px` below them (legends there cover no data).
fn titled_with_legend<DB: DrawingBackend>(
    root: &Area<DB>,
    title: &str,
    legend_px: i32,
) -> Result<(Area<DB>, Area<DB>), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let body = root.titled(title, ("sans-serif", 22))?;
    let height = body.dim_in_pixel().1 as i32;
    Ok(body.split_vertically(height - legend_px))
}

/// Floor of a logarithmic residual axis, m.
const RESIDUAL_FLOOR_M: f64 = 1e-12;

fn draw_convergence<DB: DrawingBackend>(
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

/// One panel of the surface figure: the assembled front net's free nodes,
/// `(x, y, deviation mm)`.
#[derive(Debug, Clone)]
pub struct NodePanel {
    /// The panel's title.
    pub title: String,
    /// The nodes: plan position, m, and axial deviation from the paraboloid, mm.
    pub nodes: Vec<(f64, f64, f64)>,
}

/// The surface figure of a design (issue 20): the designs as built side by
/// side and the facet error of ours, on one signed colour scale in mm.
#[derive(Debug, Clone)]
pub struct SurfaceFigure {
    /// The figure's title.
    pub title: String,
    /// Node panels, left to right (the conventional design as built, then
    /// ours).
    pub panels: Vec<NodePanel>,
    /// The flat facets of our design as built: plan corners, m, and the
    /// axial deviation of the facet's centroid from the paraboloid, mm.
    pub facets: Vec<([(f64, f64); 3], f64)>,
    /// The front net's cables in plan, m.
    pub cables: Vec<[(f64, f64); 2]>,
    /// The top hinges in plan, m, in ring order.
    pub outline: Vec<(f64, f64)>,
}

/// A signed, symmetric logarithmic colour scale of deviations in mm: linear
/// near zero (below `linear`), logarithmic beyond, so that the facets' error
/// (millimetres), the conventional design's (tenths) and ours (roundoff) show
/// on one bar.
#[derive(Debug, Clone, Copy)]
struct DeviationScale {
    /// The largest magnitude, mm.
    largest: f64,
    /// Below this magnitude the scale is linear, mm.
    linear: f64,
}

impl DeviationScale {
    /// Decades shown below the largest magnitude.
    const DECADES: f64 = 7.0;

    fn of(largest: f64) -> Self {
        let largest = if largest > 0.0 && largest.is_finite() {
            largest
        } else {
            1.0
        };
        DeviationScale {
            largest,
            linear: largest * 10f64.powf(-Self::DECADES),
        }
    }

    /// `ln(1 + m/linear)`: the bar's length of a magnitude `m`.
    fn stretch(&self, m: f64) -> f64 {
        (1.0 + m / self.linear).ln()
    }

    /// Position of `d` on the bar, in `[-1, 1]`.
    fn position(&self, d: f64) -> f64 {
        (d.signum() * self.stretch(d.abs()) / self.stretch(self.largest)).clamp(-1.0, 1.0)
    }

    /// The deviation at position `t` of the bar (the inverse of `position`).
    fn deviation_at(&self, t: f64) -> f64 {
        t.signum() * self.linear * ((t.abs() * self.stretch(self.largest)).exp() - 1.0)
    }

    /// Red above the paraboloid (towards the focus), blue below, white on it.
    fn colour(&self, d: f64) -> RGBColor {
        let t = self.position(d);
        let fade = |v: f64| (255.0 * (1.0 - v.abs())) as u8;
        if t >= 0.0 {
            RGBColor(255, fade(t), fade(t))
        } else {
            RGBColor(fade(t), fade(t), 255)
        }
    }
}

/// Cables drawn on a surface panel at most: beyond, only the colours.
const MAX_DRAWN_CABLES: usize = 3_000;

/// One plan-view panel: the truss outline, the cables, and either nodes or
/// facets coloured by deviation.
fn draw_surface_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &SurfaceFigure,
    title: &str,
    nodes: Option<&[(f64, f64, f64)]>,
    scale: DeviationScale,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for &(x, y) in figure.outline.iter().chain(figure.cables.iter().flatten()) {
        lo = (lo.0.min(x), lo.1.min(y));
        hi = (hi.0.max(x), hi.1.max(y));
    }
    if !lo.0.is_finite() {
        (lo, hi) = ((-1.0, -1.0), (1.0, 1.0));
    }
    let half = 0.55 * (hi.0 - lo.0).max(hi.1 - lo.1).max(1e-9);
    let centre = (0.5 * (lo.0 + hi.0), 0.5 * (lo.1 + hi.1));
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 17))
        .margin(10)
        .x_label_area_size(35)
        .y_label_area_size(45)
        .build_cartesian_2d(
            (centre.0 - half)..(centre.0 + half),
            (centre.1 - half)..(centre.1 + half),
        )?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .label_style(("sans-serif", 13))
        .draw()?;
    if nodes.is_none() {
        chart.draw_series(
            figure
                .facets
                .iter()
                .map(|(corners, d)| Polygon::new(corners.to_vec(), scale.colour(*d).filled())),
        )?;
    }
    // A dense net is drawn by its colours alone: its cables and node
    // outlines would cover them.
    if figure.cables.len() <= MAX_DRAWN_CABLES {
        let cable = RGBColor(120, 120, 120).stroke_width(1);
        chart.draw_series(
            figure
                .cables
                .iter()
                .map(|c| PathElement::new(c.to_vec(), cable)),
        )?;
    }
    if let Some(nodes) = nodes {
        let radius = (600.0 / (nodes.len().max(1) as f64).sqrt()).clamp(1.5, 5.0) as i32;
        chart.draw_series(
            nodes
                .iter()
                .map(|&(x, y, d)| Circle::new((x, y), radius, scale.colour(d).filled())),
        )?;
        if figure.cables.len() <= MAX_DRAWN_CABLES {
            chart.draw_series(
                nodes
                    .iter()
                    .map(|&(x, y, _)| Circle::new((x, y), radius, BLACK.stroke_width(1))),
            )?;
        }
    }
    let mut ring = figure.outline.clone();
    ring.extend(figure.outline.first());
    chart.draw_series(std::iter::once(PathElement::new(
        ring,
        BLACK.stroke_width(3),
    )))?;
    chart.draw_series(
        figure
            .outline
            .iter()
            .map(|&p| Rectangle::new([p, p], BLACK.stroke_width(6))),
    )?;
    Ok(())
}

/// The signed colour bar of `scale`, labelled at every decade.
fn draw_colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    scale: DeviationScale,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let mut chart = ChartBuilder::on(area)
        .margin_top(45)
        .margin_bottom(45)
        .margin_right(5)
        .build_cartesian_2d(0.0..1.0, -1.0..1.0)?;
    let steps = 400;
    chart.draw_series((0..steps).map(|k| {
        let a = -1.0 + 2.0 * k as f64 / steps as f64;
        let b = a + 2.0 / steps as f64;
        let d = scale.deviation_at(0.5 * (a + b));
        Rectangle::new([(0.0, a), (0.25, b)], scale.colour(d).filled())
    }))?;
    let font = ("sans-serif", 13).into_font();
    let top = scale.largest.log10().floor() as i32;
    let mut labels = vec![(0.0, "0".to_string())];
    for k in (top - DeviationScale::DECADES as i32 + 1)..=top {
        let v = 10f64.powi(k);
        labels.push((v, format!("+1e{k}")));
        labels.push((-v, format!("−1e{k}")));
    }
    for (v, text) in labels {
        let t = scale.position(v);
        chart.draw_series(std::iter::once(PathElement::new(
            vec![(0.25, t), (0.32, t)],
            BLACK.stroke_width(1),
        )))?;
        chart.draw_series(std::iter::once(Text::new(text, (0.36, t), font.clone())))?;
    }
    area.draw(&Text::new(
        "mm (+ towards the focus)",
        (0, 20),
        ("sans-serif", 13).into_font(),
    ))?;
    Ok(())
}

fn draw_surface<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    figure: &SurfaceFigure,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let body = root.titled(&figure.title, ("sans-serif", 20))?;
    let width = body.dim_in_pixel().0 as i32;
    let (plots, bar) = body.split_horizontally(width - 170);
    let scale = DeviationScale::of(
        figure
            .panels
            .iter()
            .flat_map(|p| p.nodes.iter().map(|n| n.2.abs()))
            .chain(figure.facets.iter().map(|f| f.1.abs()))
            .filter(|d| d.is_finite())
            .fold(0.0, f64::max),
    );
    let areas = plots.split_evenly((1, figure.panels.len() + 1));
    for (panel, area) in figure.panels.iter().zip(&areas) {
        let rms = (panel.nodes.iter().map(|n| n.2 * n.2).sum::<f64>()
            / panel.nodes.len().max(1) as f64)
            .sqrt();
        let title = format!("{}: node RMS {rms:.2e} mm", panel.title);
        draw_surface_panel(area, figure, &title, Some(&panel.nodes), scale)?;
    }
    let facet_rms = (figure.facets.iter().map(|f| f.1 * f.1).sum::<f64>()
        / figure.facets.len().max(1) as f64)
        .sqrt();
    draw_surface_panel(
        &areas[figure.panels.len()],
        figure,
        &format!("flat facets of ours: centroid RMS {facet_rms:.2e} mm"),
        None,
        scale,
    )?;
    draw_colour_bar(&bar, scale)?;
    Ok(root.present()?)
}

/// Draws the surface figure as a PNG written atomically: a plan view per
/// design as built (nodes coloured by their axial deviation from the
/// paraboloid), then the flat facets of ours coloured by their centroid's,
/// all on one signed colour scale in mm, logarithmic over seven decades
/// below the largest magnitude (red above the paraboloid, towards the focus;
/// blue below), with the front net's cables and the ring truss (its top
/// hinges) drawn.
pub fn surface_plot(figure: &SurfaceFigure, png: &Path) -> Result<(), ReportError> {
    register_font();
    let size = (560 * (figure.panels.len() as u32 + 1) + 170, 640);
    let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
    draw_surface(
        BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area(),
        figure,
    )
    .map_err(|source| ReportError::Plot {
        path: png.to_path_buf(),
        source,
    })?;
    write_atomic(png, &png_bytes(&rgb, size, png)?)
}

/// The PNG file of an RGB image of `size` pixels, in memory: the file is
/// written by [`write_atomic`], whose errors name the cause plainly (the
/// bitmap backend's own writer reports `ImageError(IoError(…))`).
fn png_bytes(rgb: &[u8], size: (u32, u32), path: &Path) -> Result<Vec<u8>, ReportError> {
    use image::ImageEncoder;
    let mut bytes = Vec::new();
    image::codecs::png::PngEncoder::new(&mut bytes)
        .write_image(rgb, size.0, size.1, image::ColorType::Rgb8)
        .map_err(|e| ReportError::Plot {
            path: path.to_path_buf(),
            source: Box::new(e),
        })?;
    Ok(bytes)
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
    let (charts, legend) = titled_with_legend(&root, title, 35)?;
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
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()?;
    Ok(root.present()?)
}

/// Draws a followed equilibrium path (load factor against a recorded
/// displacement, critical points marked by kind) as PNG and SVG, each
/// written atomically.
pub fn path_plot(figure: &PathFigure, png: &Path, svg: &Path) -> Result<(), ReportError> {
    png_and_svg!(draw_path, (900, 600), png, svg, figure)
}
