//! The surface error of a design: plan views of the designs as built (their
//! free nodes) and of the flat facets of ours, raw and about their best-fit
//! paraboloid, coloured by axial deviation on one signed logarithmic scale
//! in mm. Each panel is labelled with one RMS of [`crate::surface`], by its
//! one name, with the value the design's report holds (the plot computes no
//! RMS).

use std::path::Path;

use plotters::prelude::*;

use super::canvas::{png_bytes, register_font};
use crate::report::{readable, write_atomic, DrawError, ReportError};

/// The RMS a panel is labelled with: one quantity of [`crate::surface`], by
/// its one name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PanelRms {
    /// Node RMS ([`crate::surface::node_rms`]): the axial deviation of the
    /// front net's free nodes from the design paraboloid, each node counting
    /// once.
    Node,
    /// Facet RMS ([`crate::surface::facet_rms`]): the axial deviation of the
    /// flat facets from the design paraboloid, integrated over them and
    /// weighted by plan area.
    Facet,
    /// Best-fit facet RMS ([`crate::surface::best_fit_facets`]): the facet
    /// RMS about the paraboloid fitted to the facets.
    BestFitFacet,
}

impl PanelRms {
    /// The quantity's one name.
    pub fn name(self) -> &'static str {
        match self {
            PanelRms::Node => "node RMS",
            PanelRms::Facet => "facet RMS",
            PanelRms::BestFitFacet => "best-fit facet RMS",
        }
    }

    /// Which deviation, over what.
    fn qualifier(self) -> &'static str {
        match self {
            PanelRms::Node => "axial, free nodes",
            PanelRms::Facet | PanelRms::BestFitFacet => "axial, plan-area weighted",
        }
    }
}

/// What a panel colours: points of the front net in plan, m, each with an
/// axial deviation, mm, about the panel's paraboloid (the design one, or the
/// best fit for [`PanelRms::BestFitFacet`]).
#[derive(Debug, Clone)]
pub enum PanelContent {
    /// Free nodes `(x, y, deviation)`.
    Nodes(Vec<(f64, f64, f64)>),
    /// Flat facets, each cut into `parts_per_side²` equal triangles (1: the
    /// facets themselves): each part's plan corners and the deviation at
    /// its centroid.
    Facets {
        /// Parts a side of a facet.
        parts_per_side: usize,
        /// The parts.
        parts: Vec<([(f64, f64); 3], f64)>,
    },
}

impl PanelContent {
    /// The deviations coloured, mm.
    fn deviations(&self) -> Box<dyn Iterator<Item = f64> + '_> {
        match self {
            PanelContent::Nodes(nodes) => Box::new(nodes.iter().map(|n| n.2)),
            PanelContent::Facets { parts, .. } => Box::new(parts.iter().map(|f| f.1)),
        }
    }
}

/// One panel of the surface figure.
#[derive(Debug, Clone)]
pub struct SurfacePanel {
    /// What it shows, e.g. `facets as built`.
    pub title: String,
    /// The RMS it is labelled with …
    pub rms: PanelRms,
    /// … and its value, mm, as the design's report gives it.
    pub rms_mm: f64,
    /// What it colours.
    pub content: PanelContent,
}

impl SurfacePanel {
    /// The quantity and its value, e.g. `facet RMS 15.19 mm (axial,
    /// plan-area weighted)`: the number as `design` prints it.
    pub fn rms_line(&self) -> String {
        format!(
            "{} {} mm ({})",
            self.rms.name(),
            readable(self.rms_mm, 4),
            self.rms.qualifier()
        )
    }

    /// What a colour of the panel is (a colour, not a reported RMS), about
    /// the panel's paraboloid.
    pub fn colour_note(&self) -> String {
        match &self.content {
            PanelContent::Nodes(_) => "colour: axial deviation of each free node".to_string(),
            PanelContent::Facets {
                parts_per_side: 1, ..
            } => "colour: axial deviation at the facet's centroid".to_string(),
            PanelContent::Facets { parts_per_side, .. } => format!(
                "colour: axial deviation at the centroids of a facet's {} equal parts",
                parts_per_side * parts_per_side
            ),
        }
    }

    /// The panel's whole label, `title: quantity value (qualifier)`.
    pub fn label(&self) -> String {
        format!("{}: {}", self.title, self.rms_line())
    }
}

/// The surface figure of a design (issues 20, 34): the designs as built
/// (nodes) on one row, the flat facets of ours raw and about their best fit
/// on the next, on one signed colour scale in mm.
#[derive(Debug, Clone)]
pub struct SurfaceFigure {
    /// The figure's title.
    pub title: String,
    /// The panels: node panels drawn on the first row, facet panels on the
    /// second, each row left to right in this order.
    pub panels: Vec<SurfacePanel>,
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

/// Height of a panel's label (title, RMS, colour note), px.
const PANEL_LABEL_PX: i32 = 62;

/// A panel's label, three lines: what it shows, its RMS, what a colour is.
fn draw_panel_label<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    panel: &SurfacePanel,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let centre = area.dim_in_pixel().0 as i32 / 2;
    let centred = |size: f64, colour: RGBColor| {
        ("sans-serif", size)
            .into_font()
            .color(&colour)
            .pos(plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Center,
                plotters::style::text_anchor::VPos::Top,
            ))
    };
    area.draw(&Text::new(
        panel.title.clone(),
        (centre, 4),
        centred(17.0, BLACK),
    ))?;
    area.draw(&Text::new(
        panel.rms_line(),
        (centre, 25),
        centred(16.0, BLACK),
    ))?;
    area.draw(&Text::new(
        panel.colour_note(),
        (centre, 45),
        centred(13.0, RGBColor(90, 90, 90)),
    ))?;
    Ok(())
}

/// One plan-view panel: its label, the truss outline, the cables, and its
/// nodes or facets coloured by deviation.
fn draw_surface_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    figure: &SurfaceFigure,
    panel: &SurfacePanel,
    scale: DeviationScale,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    let (label, plot) = area.split_vertically(PANEL_LABEL_PX);
    draw_panel_label(&label, panel)?;
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
    let mut chart = ChartBuilder::on(&plot)
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
    if let PanelContent::Facets { parts, .. } = &panel.content {
        chart.draw_series(
            parts
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
    if let PanelContent::Nodes(nodes) = &panel.content {
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

/// Size of one panel, px.
const PANEL_PX: (u32, u32) = (580, 660);

/// Width of the colour bar, px.
const BAR_PX: u32 = 170;

/// Height of the figure's title, px.
const TITLE_PX: u32 = 36;

/// The figure's rows: node panels, then facet panels (a row with none is
/// left out).
fn rows(figure: &SurfaceFigure) -> Vec<Vec<&SurfacePanel>> {
    let (nodes, facets): (Vec<&SurfacePanel>, Vec<&SurfacePanel>) = figure
        .panels
        .iter()
        .partition(|p| matches!(p.content, PanelContent::Nodes(_)));
    [nodes, facets]
        .into_iter()
        .filter(|row| !row.is_empty())
        .collect()
}

/// The figure's size, px: the longest row's panels side by side, the rows
/// one above the other, the title above and the colour bar to the right.
pub(super) fn figure_size(figure: &SurfaceFigure) -> (u32, u32) {
    let rows = rows(figure);
    let columns = rows.iter().map(Vec::len).max().unwrap_or(1) as u32;
    (
        PANEL_PX.0 * columns + BAR_PX,
        PANEL_PX.1 * rows.len().max(1) as u32 + TITLE_PX,
    )
}

pub(super) fn draw_surface<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    figure: &SurfaceFigure,
) -> Result<(), DrawError>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE)?;
    let body = root.titled(&figure.title, ("sans-serif", 20))?;
    let width = body.dim_in_pixel().0 as i32;
    let (plots, bar) = body.split_horizontally(width - BAR_PX as i32);
    let scale = DeviationScale::of(
        figure
            .panels
            .iter()
            .flat_map(|p| p.content.deviations())
            .map(f64::abs)
            .filter(|d| d.is_finite())
            .fold(0.0, f64::max),
    );
    let rows = rows(figure);
    let columns = rows.iter().map(Vec::len).max().unwrap_or(1);
    for (row, area) in rows.iter().zip(plots.split_evenly((rows.len().max(1), 1))) {
        // A shorter row is centred under the longer one.
        let indent = (columns - row.len()) as i32 * PANEL_PX.0 as i32 / 2;
        let area = area.margin(0, 0, indent, indent);
        for (panel, cell) in row.iter().zip(area.split_evenly((1, row.len()))) {
            draw_surface_panel(&cell, figure, panel, scale)?;
        }
    }
    draw_colour_bar(&bar, scale)?;
    Ok(root.present()?)
}

/// Draws the surface figure as a PNG written atomically: a plan view per
/// panel — the designs as built (free nodes coloured by their axial
/// deviation from the paraboloid) on one row, the flat facets of ours
/// (coloured by the axial deviation at their centroid, from the design
/// paraboloid and from the best fit) on the next —, each labelled with its
/// RMS, all on one signed colour scale in mm, logarithmic over seven
/// decades below the largest magnitude (red above the paraboloid, towards
/// the focus; blue below), with the front net's cables and the ring truss
/// (its top hinges) drawn.
pub fn surface_plot(figure: &SurfaceFigure, png: &Path) -> Result<(), ReportError> {
    register_font();
    let size = figure_size(figure);
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
