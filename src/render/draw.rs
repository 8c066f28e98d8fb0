//! The drawing primitives every figure uses: the figure sizes, the font, the paper's
//! colours and the palette of curves, a curve's stroke and the marks of reported values
//! (and how either is drawn on a chart, with its legend entry), the helpers of axes and
//! labels, and the plane drawing of a cell — the deformed 2-D cell or a section of the 3-D
//! one, with its substrate, fibronectin layer, active regions and gravity arrow
//! (`draw_in_plane`, `PlaneDrawing`). What it may import of [`super`]: [`super::geometry`]
//! (pure geometry) and the error types of [`super`] — no figure module, so that every
//! figure module, 2-D or 3-D, can import it.

use plotters::chart::SeriesAnno;
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::DrawError;
use super::geometry::{Backdrop, Bounds, CellShape, Pt, Rect};
use crate::fem::Domain;
use crate::physics::Phases;

/// Pixel size of the time-series and bar figures.
pub const TIME_SIZE: (u32, u32) = (1200, 800);
/// Pixel size of the shape figures.
pub const SHAPE_SIZE: (u32, u32) = (1400, 1000);
/// Pixel size of the two-panel upside-down figure.
pub const UPSIDE_DOWN_SIZE: (u32, u32) = (1200, 1000);

/// Width of a curve's sample in a legend \[px\].
pub(super) const LEGEND_GLYPH: i32 = 40;

/// Font family of every text.
pub(crate) const FONT: &str = "sans-serif";

/// A text style of `size` px in [`FONT`], anchored at the point `h`, `v` of the text.
pub(super) fn anchored_text(size: i32, h: HPos, v: VPos) -> TextStyle<'static> {
    TextStyle::from((FONT, size).into_font()).pos(Pos::new(h, v))
}

/// A chart with `f64` coordinates on both axes, as every figure here draws.
pub(super) type Chart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Fill colour of the nucleus (the paper's red).
pub const NUCLEUS: RGBColor = RGBColor(214, 72, 66);
/// Fill colour of the cytoplasm (the paper's orange).
pub const CYTOPLASM: RGBColor = RGBColor(247, 182, 110);
/// Fill colour of the membrane (the paper's green).
pub const MEMBRANE: RGBColor = RGBColor(70, 160, 80);
/// Fill colour of the substrate.
pub const SUBSTRATE: RGBColor = RGBColor(160, 160, 160);
/// Fill colour of the fibronectin layer (the paper's yellow, Fig. 3).
pub const LAYER: RGBColor = RGBColor(255, 240, 150);
/// Fill colour of a pillar's foot: the undercut below the superellipse's rounded lower
/// corners, drawn so the pillar stands on its floor, but outside the model's substrate.
pub const FOOT: RGBColor = RGBColor(190, 190, 190);
/// Line colour of the fibronectin layer's edge.
pub const LAYER_EDGE: RGBColor = RGBColor(170, 130, 0);
/// Outline colour of the PAC region (the paper's blue).
pub const PAC: RGBColor = RGBColor(25, 80, 230);
/// Outline colour of the bottom region.
pub const BOTTOM: RGBColor = RGBColor(150, 30, 190);
/// Colours of successive curves in a time plot.
pub const PALETTE: [RGBColor; 6] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
];

/// Fill colour of a domain.
pub fn domain_color(d: Domain) -> RGBColor {
    match d {
        Domain::Nucleus => NUCLEUS,
        Domain::Cytoplasm => CYTOPLASM,
        Domain::Membrane => MEMBRANE,
    }
}

pub(crate) fn darker(c: RGBColor, f: f64) -> RGBColor {
    let s = |v: u8| (v as f64 * f).round().clamp(0.0, 255.0) as u8;
    RGBColor(s(c.0), s(c.1), s(c.2))
}

/// How a curve is stroked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stroke {
    /// Continuous.
    Solid,
    /// Long dashes.
    Dashed,
    /// Short dots.
    Dotted,
}

/// One curve of a time plot.
#[derive(Debug, Clone)]
pub struct Curve {
    /// Legend text.
    pub label: String,
    /// (t \[s\], value) points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Stroke.
    pub stroke: Stroke,
}

/// Values drawn as circles: hollow for the paper's, filled for the cellsim value each is
/// compared with.
#[derive(Debug, Clone)]
pub struct Marks {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// (t \[s\], value) points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Circle radius \[px\].
    pub radius: i32,
    /// Filled (a cellsim value) instead of hollow (the paper's).
    pub filled: bool,
    /// Circle, or square (a second cellsim measure beside the compared one).
    pub shape: MarkShape,
}

/// The shape of a [`Marks`] point.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MarkShape {
    /// A circle of the mark's radius.
    #[default]
    Circle,
    /// A square with the mark's radius as half side.
    Square,
}

/// "12 345" for 12345.0 (thin grouping of thousands in axis labels).
pub(super) fn group_thousands(v: f64) -> String {
    let s = format!("{:.0}", v.abs());
    let mut out = String::new();
    for (i, ch) in s.chars().enumerate() {
        if i > 0 && (s.len() - i) % 3 == 0 {
            out.push(' ');
        }
        out.push(ch);
    }
    if v < -0.5 { format!("-{out}") } else { out }
}

/// One curve of a time plot in its colour and stroke, with a legend entry (a sample of
/// the stroke) if it has a label.
pub(super) fn draw_curve<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    c: &Curve,
) -> Result<(), DrawError> {
    let style = c.color.stroke_width(3);
    let pts = c.points.iter().copied();
    let anno = match c.stroke {
        Stroke::Solid => chart.draw_series(LineSeries::new(pts, style))?,
        Stroke::Dashed => chart.draw_series(DashedLineSeries::new(pts, 14, 8, style))?,
        Stroke::Dotted => chart.draw_series(DashedLineSeries::new(pts, 3, 6, style))?,
    };
    if c.label.is_empty() {
        return Ok(());
    }
    let (color, stroke) = (c.color, c.stroke);
    anno.label(&c.label).legend(move |(x, y)| {
        let s = color.stroke_width(3);
        match stroke {
            Stroke::Solid => PathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], s).into_dyn(),
            Stroke::Dashed => {
                DashedPathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], 10, 5, s).into_dyn()
            }
            Stroke::Dotted => {
                DashedPathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], 3, 5, s).into_dyn()
            }
        }
    });
    Ok(())
}

/// One set of marks of a time plot, circles or squares, filled or hollow, with a legend
/// entry if it has a label.
pub(super) fn draw_marks<'a, DB: DrawingBackend + 'a>(
    chart: &mut Chart<'a, DB>,
    m: &Marks,
) -> Result<(), DrawError> {
    let style = if m.filled {
        m.color.filled()
    } else {
        m.color.stroke_width(3)
    };
    let r = m.radius;
    let anno = match m.shape {
        MarkShape::Circle => {
            chart.draw_series(m.points.iter().map(|&p| Circle::new(p, r, style)))?
        }
        MarkShape::Square => chart.draw_series(
            m.points
                .iter()
                .map(|&p| EmptyElement::at(p) + Rectangle::new([(-r, -r), (r, r)], style)),
        )?,
    };
    if m.label.is_empty() {
        return Ok(());
    }
    let shape = m.shape;
    anno.label(&m.label).legend(move |(x, y)| {
        let c = (x + LEGEND_GLYPH / 2, y);
        match shape {
            MarkShape::Circle => Circle::new(c, 7, style).into_dyn(),
            MarkShape::Square => {
                Rectangle::new([(c.0 - 6, c.1 - 6), (c.0 + 6, c.1 + 6)], style).into_dyn()
            }
        }
    });
    Ok(())
}

/// The label at `x` of an axis of columns [k, k + 1) named `names`: column k's name at
/// its middle, nothing elsewhere.
pub(super) fn column_label(names: &[String], x: f64) -> String {
    let k = (x - 0.5).round();
    if (x - 0.5 - k).abs() < 1e-6 && k >= 0.0 {
        names.get(k as usize).cloned().unwrap_or_default()
    } else {
        String::new()
    }
}

/// What [`super::shapes::draw_shape`] (or a 3-D section) drew, for checks: pixels per µm
/// along x and along y (equal when the aspect is equal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeScale {
    /// Pixels per µm along x.
    pub px_per_um_x: f64,
    /// Pixels per µm along y.
    pub px_per_um_y: f64,
}

/// Options of [`super::shapes::draw_shape`].
#[derive(Debug, Clone)]
pub struct ShapeStyleOptions {
    /// Title above the drawing.
    pub title: String,
    /// Draw the legend.
    pub legend: bool,
    /// Font size of the title (other texts scale with it).
    pub font: u32,
    /// Draw the element edges (the mesh) in darker shades of the fills.
    pub mesh_lines: bool,
    /// Draw the direction of gravity (an arrow in the upper left corner).
    pub gravity: Option<GravityMark>,
}

/// The direction of gravity in a shape drawing, and what to say about it.
#[derive(Debug, Clone, PartialEq)]
pub struct GravityMark {
    /// Gravity's signed strength relative to g along −e_y: t_g(t) s_g(t) (1 = down, full;
    /// −1 = up, the cell upside down).
    pub factor: f64,
    /// Text beside the arrow.
    pub note: String,
}

impl GravityMark {
    /// Gravity at time `t` under `phases` (MODEL.md §5): down, ramping in over [0, T_g0],
    /// and with a flip, saying when the device is turned upside down.
    pub fn at(phases: &Phases, t: f64) -> Self {
        let factor = phases.t_g(t) * phases.gravity_sign(t);
        let note = match phases.flip {
            None => "gravity".to_string(),
            Some(f) => {
                let end = f.start + f.duration;
                let span = format!("{}–{} s", group_thousands(f.start), group_thousands(end));
                if t <= f.start {
                    format!("gravity (flipped later: upside down over t = {span})")
                } else if t < end {
                    format!("gravity flipping (upside down over t = {span})")
                } else {
                    format!("gravity flipped: upside down (turned over t = {span})")
                }
            }
        };
        GravityMark { factor, note }
    }
}

/// Points [x, y] as plotters' coordinate pairs.
fn xy(points: &[Pt]) -> Vec<(f64, f64)> {
    points.iter().map(|p| (p[0], p[1])).collect()
}

/// Checks that `u` holds one displacement per node of a mesh of `nodes` nodes.
pub(crate) fn check_displacements<const D: usize>(
    u: &[[f64; D]],
    nodes: usize,
) -> Result<(), DrawError> {
    if u.len() != nodes {
        return Err(DrawError(format!(
            "{} displacements for {} nodes",
            u.len(),
            nodes
        )));
    }
    Ok(())
}

/// What [`draw_in_plane`] draws: the deformed full cell in a drawing plane, borrowed from
/// the 2-D [`CellShape`] or a 3-D [`super::cell3d_views::SectionShape`] (mirrored), and what
/// else differs between the two drawings.
pub(crate) struct PlaneDrawing<'a> {
    /// Label of the horizontal axis.
    pub x_label: &'a str,
    /// Legend entry of the substrate.
    pub substrate_label: String,
    /// Whether the substrate carries a fibronectin layer (with adhesion).
    pub layer: bool,
    /// The cell: its filled pieces (the elements in 2-D, a section's cut polygons in 3-D),
    /// outline, interfaces, active regions and markers.
    pub shape: &'a CellShape,
    /// The elements' outlines, drawn in darker shades when the options ask for the mesh,
    /// if the pieces are not the elements (a section's cut polygons); `None` if they are
    /// (2-D): their own outlines, darker, are the mesh then.
    pub mesh_lines: Option<&'a [(Domain, Vec<Pt>)]>,
}

/// Draws `cell` into `area` over `view`, with equal aspect: the view is widened along one
/// axis so 1 µm has the same length in pixels on both. The substrate drawing is
/// `backdrop_for(cached, final view [x0, x1, y0, y1], plotting area width in pixels)`,
/// `cached` taken from `backdrop`, which keeps the one drawn: a 2-D [`Backdrop`], or a 3-D
/// section's [`super::cell3d_views::SectionBackdrop`] (a [`Backdrop`] in the plane's
/// coordinates, with its plane). What [`super::shapes::draw_shape`] and
/// [`super::cell3d_views::draw_section`] share.
pub(crate) fn draw_in_plane<DB: DrawingBackend, B: AsRef<Backdrop>>(
    area: &DrawingArea<DB, Shift>,
    cell: &PlaneDrawing<'_>,
    view: Bounds,
    opts: &ShapeStyleOptions,
    backdrop: &mut Option<B>,
    backdrop_for: impl FnOnce(Option<B>, [f64; 4], usize) -> B,
) -> Result<ShapeScale, DrawError> {
    let fs = opts.font as f64;
    let area = area.titled(&opts.title, (FONT, opts.font as i32))?;
    let (mut chart, key, columns) = equal_aspect_chart(&area, view, cell.x_label, fs)?;
    // Substrate and fibronectin layer, one strip per pixel column (computed once per
    // view: a movie reuses it for every frame).
    let back = backdrop_for(backdrop.take(), key, columns);
    draw_backdrop(&mut chart, back.as_ref(), cell)?;
    draw_cell_fills(&mut chart, cell, opts.mesh_lines)?;
    draw_cell_lines(&mut chart, cell.shape)?;
    // The substrate's surface on top, as the paper's black line.
    draw_paths(&mut chart, &back.as_ref().surface, BLACK.stroke_width(2))?;
    *backdrop = Some(back);
    chart
        .draw_series(
            cell.shape
                .markers
                .iter()
                .map(|p| Circle::new((p[0], p[1]), 4, BLACK.filled())),
        )?
        .label("p_t, c, p_b")
        .legend(|(x, y)| Circle::new((x + 11, y), 4, BLACK.filled()));
    if let Some(g) = &opts.gravity {
        draw_gravity(&chart.plotting_area().strip_coord_spec(), g, fs)?;
    }
    if opts.legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .margin(10)
            .label_font((FONT, (0.65 * fs) as i32))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()?;
    }
    let o = chart.backend_coord(&(0.0, 0.0));
    let px = chart.backend_coord(&(10.0, 0.0));
    let py = chart.backend_coord(&(0.0, 10.0));
    Ok(ShapeScale {
        px_per_um_x: (px.0 - o.0).abs() as f64 / 10.0,
        px_per_um_y: (py.1 - o.1).abs() as f64 / 10.0,
    })
}

/// The axes of a drawing in `area` over `view` with equal aspect (texts scaled by the
/// font size `fs`, the horizontal axis labelled `x_label`), the view widened to the
/// plotting area's shape; with the widened view [x0, x1, y0, y1] and the plotting area's
/// width in pixels.
fn equal_aspect_chart<'a, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
    view: Bounds,
    x_label: &str,
    fs: f64,
) -> Result<(Chart<'a, DB>, [f64; 4], usize), DrawError> {
    let label_x = (2.6 * fs) as u32;
    let label_y = (3.2 * fs) as u32;
    let margin = (0.6 * fs) as u32;
    // First pass: the plotting area's pixel size; then ranges with equal aspect.
    let (pw, ph) = {
        let chart = ChartBuilder::on(area)
            .margin(margin)
            .x_label_area_size(label_x)
            .y_label_area_size(label_y)
            .build_cartesian_2d(view.x_min..view.x_max, view.y_min..view.y_max)?;
        chart.plotting_area().dim_in_pixel()
    };
    let (w, h) = (view.x_max - view.x_min, view.y_max - view.y_min);
    let s = (pw as f64 / w).min(ph as f64 / h);
    let (cx, cy) = (
        0.5 * (view.x_min + view.x_max),
        0.5 * (view.y_min + view.y_max),
    );
    let (hw, hh) = (0.5 * pw as f64 / s, 0.5 * ph as f64 / s);
    let (x0, x1, y0, y1) = (cx - hw, cx + hw, cy - hh, cy + hh);
    let mut chart = ChartBuilder::on(area)
        .margin(margin)
        .x_label_area_size(label_x)
        .y_label_area_size(label_y)
        .build_cartesian_2d(x0..x1, y0..y1)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc("y (µm)")
        .axis_desc_style((FONT, (0.8 * fs) as i32))
        .label_style((FONT, (0.65 * fs) as i32))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()?;
    Ok((chart, [x0, x1, y0, y1], pw as usize))
}

/// A legend's colour swatch at `(x, y)`.
fn swatch(color: RGBColor, (x, y): (i32, i32)) -> Rectangle<(i32, i32)> {
    Rectangle::new([(x, y - 7), (x + 22, y + 7)], color.filled())
}

/// The substrate drawing `back` under `cell`: the fibronectin layer and its edge (if the
/// substrate carries one), the pillars' feet and the substrate, with legend entries.
fn draw_backdrop<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    back: &Backdrop,
    cell: &PlaneDrawing<'_>,
) -> Result<(), DrawError> {
    let rect = |r: &Rect, c: RGBColor| Rectangle::new([(r[0], r[3]), (r[1], r[2])], c.filled());
    if cell.layer {
        chart
            .draw_series(back.layer.iter().map(|r| rect(r, LAYER)))?
            .label("fibronectin layer")
            .legend(|p| swatch(LAYER, p));
        // The layer's edge under the cell: the cell hides it where it lies in the layer.
        draw_paths(chart, &back.layer_edge, LAYER_EDGE.stroke_width(2))?;
    }
    if !back.foot.is_empty() {
        chart
            .draw_series(back.foot.iter().map(|r| rect(r, FOOT)))?
            .label("pillar foot (not substrate in the model)")
            .legend(|p| swatch(FOOT, p));
    }
    chart
        .draw_series(back.substrate.iter().map(|r| rect(r, SUBSTRATE)))?
        .label(cell.substrate_label.as_str())
        .legend(|p| swatch(SUBSTRATE, p));
    Ok(())
}

/// The pieces of `cell` filled in their domains' colours, with legend entries, each
/// outlined; with `mesh_lines`, the mesh in darker shades.
fn draw_cell_fills<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    cell: &PlaneDrawing<'_>,
    mesh_lines: bool,
) -> Result<(), DrawError> {
    for d in Domain::ALL {
        let color = domain_color(d);
        let edge = darker(color, 0.82);
        let polys: Vec<&Vec<Pt>> = cell
            .shape
            .elements
            .iter()
            .filter(|(dd, _)| *dd == d)
            .map(|(_, p)| p)
            .collect();
        chart
            .draw_series(polys.iter().map(|p| Polygon::new(xy(p), color.filled())))?
            .label(d.to_string())
            .legend(move |p| swatch(color, p));
        // Each piece's outline closes the hairline gaps between neighbouring fills; in the
        // darker shade it shows the mesh, where the pieces are the elements.
        let line_color = if mesh_lines && cell.mesh_lines.is_none() {
            edge
        } else {
            color
        };
        chart.draw_series(polys.iter().map(|p| {
            let mut v = xy(p);
            if let Some(f) = v.first().copied() {
                v.push(f);
            }
            PathElement::new(v, line_color.stroke_width(1))
        }))?;
        if let (true, Some(lines)) = (mesh_lines, cell.mesh_lines) {
            chart.draw_series(
                lines
                    .iter()
                    .filter(|(dd, _)| *dd == d)
                    .map(|(_, l)| PathElement::new(xy(l), edge.stroke_width(1))),
            )?;
        }
    }
    Ok(())
}

/// The lines of `shape`: the domain interfaces (dark grey), the outline (black) and the
/// active regions (blue, purple, with legend entries).
fn draw_cell_lines<DB: DrawingBackend>(
    chart: &mut Chart<'_, DB>,
    shape: &CellShape,
) -> Result<(), DrawError> {
    draw_paths(
        chart,
        &shape.interfaces,
        RGBColor(40, 40, 40).stroke_width(2),
    )?;
    draw_paths(chart, &shape.outer, BLACK.stroke_width(2))?;
    for (segs, color, name) in [
        (&shape.pac, PAC, "active: PAC (push)"),
        (&shape.bottom, BOTTOM, "active: bottom (pull)"),
    ] {
        if segs.is_empty() {
            continue;
        }
        draw_paths(chart, segs, color.stroke_width(3))?
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
            });
    }
    Ok(())
}

/// Each polyline of `lines` (points [x, y]) as one path in `style`; the series, to give
/// it a legend entry.
fn draw_paths<'c, 'a, DB: DrawingBackend, L: AsRef<[Pt]>>(
    chart: &'c mut Chart<'a, DB>,
    lines: &[L],
    style: ShapeStyle,
) -> Result<&'c mut SeriesAnno<'a, DB>, DrawError> {
    chart
        .draw_series(
            lines
                .iter()
                .map(|l| PathElement::new(xy(l.as_ref()), style)),
        )
        .map_err(DrawError::from)
}

/// Draws the gravity arrow of `g` in the upper left corner of `chart`'s plotting area: a
/// vertical arrow pointing along gravity (its length scales with |factor|), "g" beside it
/// and the note to its right, on a white box.
pub(crate) fn draw_gravity<DB: DrawingBackend>(
    raw: &DrawingArea<DB, Shift>,
    g: &GravityMark,
    fs: f64,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let full = 2.4 * fs; // arrow length at full gravity [px]
    let (bx, by) = ((0.6 * fs) as i32, (0.5 * fs) as i32); // box corner within the area
    let cx = bx + (0.7 * fs) as i32;
    let mid = by + (0.2 * fs + 0.5 * full) as i32;
    let half = (0.5 * full * g.factor.abs().min(1.0)) as i32;
    let dir = if g.factor >= 0.0 { 1 } else { -1 }; // +1: down on screen
    let (tail, tip) = (mid - dir * half, mid + dir * half);
    let font = (0.65 * fs) as i32;
    let style = anchored_text(font, HPos::Left, VPos::Center);
    let text_w = raw.estimate_text_size(&g.note, &style)?.0 as i32;
    let box_w = (1.6 * fs) as i32 + text_w;
    let box_h = (0.4 * fs + full) as i32;
    raw.draw(&Rectangle::new(
        [(bx, by), (bx + box_w, by + box_h)],
        WHITE.mix(0.9).filled(),
    ))?;
    raw.draw(&Rectangle::new([(bx, by), (bx + box_w, by + box_h)], BLACK))?;
    if half > 0 {
        let head = (0.35 * fs) as i32;
        raw.draw(&PathElement::new(
            vec![(cx, tail), (cx, tip - dir * head)],
            BLACK.stroke_width(4),
        ))?;
        raw.draw(&Polygon::new(
            vec![
                (cx - head / 2 - 2, tip - dir * head),
                (cx + head / 2 + 2, tip - dir * head),
                (cx, tip),
            ],
            BLACK.filled(),
        ))?;
    }
    raw.draw(&Text::new(
        g.note.clone(),
        (cx + (0.6 * fs) as i32, mid),
        style,
    ))?;
    Ok(())
}

/// Human name of a phase-end state.
pub fn phase_title(phase: &str) -> &str {
    match phase {
        "gravity" => "end of the gravity phase",
        "spreading" => "end of the spreading phase",
        "active" => "end of the active phase",
        "end" => "end of the run",
        "stopped" => "where the run stopped",
        other => other,
    }
}
