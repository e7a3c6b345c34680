//! The surface error of a design: plan views of the designs as built and of
//! our flat facets, coloured by their axial deviation from the paraboloid on
//! one signed logarithmic scale in mm.

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{png_bytes, register_font};
use crate::report::{write_atomic, DrawError, ReportError};

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
