//! The figures of a sweep, drawn from the rows of `sweep.csv` (and the design in
//! `sweep.json`) only:
//!
//! - a Grid over two axes: `heatmap-<quantity>.png`, the quantity (default: penetration
//!   depth) on the grid, each cell labelled with its value; points that stopped early
//!   crossed, in the colour of their `stop_class` and with it under the value,
//!   invalid ones grey and labelled "invalid", missing ones blank;
//! - one axis (a Grid or a Zip; a Zip's first axis): `line-<quantity>.png`;
//! - a Latin hypercube: `scatter-<quantity>.png`, the quantity against each axis;
//! - one at a time: `tornado.png`, the normalised sensitivity S = (ΔQ/Q)/(Δp/p) of each
//!   quantity to each parameter, from the lowest and highest value of the parameter
//!   (central difference around the base), and `sensitivities.csv` with the numbers.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::coord::ranged1d::SegmentedCoord;
use plotters::coord::types::{RangedCoordf64, RangedCoordusize};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::Record;
use super::design::Kind;
use super::table::{Row, Status};
use crate::render::OutputError;

const FONT: &str = "sans-serif";
const GREY: RGBColor = RGBColor(190, 190, 190);
const RED: RGBColor = RGBColor(214, 39, 40);
const BLUE: RGBColor = RGBColor(31, 119, 180);

/// The quantities of the tornado chart.
pub const TORNADO_QUANTITIES: [&str; 6] = [
    "penetration_depth",
    "uy_top",
    "uy_bottom",
    "contact_radius",
    "strain_nucleus",
    "strain_cytoplasm",
];

/// Draws the figures the design calls for into `dir`; returns their paths.
pub fn draw(
    dir: &Path,
    record: &Record,
    rows: &[Row],
    quantity: Option<&str>,
) -> Result<Vec<PathBuf>, OutputError> {
    let q = quantity.unwrap_or("penetration_depth");
    let axes = record.axes();
    let mut out = Vec::new();
    match record.design.kind {
        Kind::Grid if axes.len() == 2 => {
            let p = dir.join(format!("heatmap-{q}.png"));
            heat_map(&p, record, rows, q)?;
            out.push(p);
        }
        Kind::Zip => {
            let p = dir.join(format!("line-{q}.png"));
            line_plot(&p, &record.name, &axes[..1], rows, q, true)?;
            out.push(p);
        }
        Kind::Grid if axes.len() == 1 => {
            let p = dir.join(format!("line-{q}.png"));
            line_plot(&p, &record.name, &axes[..1], rows, q, true)?;
            out.push(p);
        }
        Kind::LatinHypercube => {
            let p = dir.join(format!("scatter-{q}.png"));
            line_plot(&p, &record.name, &axes, rows, q, false)?;
            out.push(p);
        }
        Kind::OneAtATime => {
            let s = sensitivities(&axes, rows);
            let csv = dir.join("sensitivities.csv");
            let mut text = String::from("quantity,parameter,p0,p_low,p_high,q0,q_low,q_high,s\n");
            for x in &s {
                text += &format!(
                    "{},{},{},{},{},{},{},{},{}\n",
                    x.quantity, x.axis, x.p0, x.p_lo, x.p_hi, x.q0, x.q_lo, x.q_hi, x.s
                );
            }
            std::fs::write(&csv, text).map_err(|e| OutputError::write(&csv, e))?;
            out.push(csv);
            let p = dir.join("tornado.png");
            tornado(&p, &record.name, &axes, &s)?;
            out.push(p);
        }
        // Three or more grid axes: no figure (sweep.csv holds the numbers).
        Kind::Grid => {}
    }
    Ok(out)
}

/// Viridis, through five anchors; `t` in [0, 1].
fn colormap(t: f64) -> RGBColor {
    const A: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (A.len() - 1) as f64;
    let k = (x.floor() as usize).min(A.len() - 2);
    let w = x - k as f64;
    let (a, b) = (A[k], A[k + 1]);
    let mix = |p: f64, q: f64| (p + w * (q - p)).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A value for a cell label: 3 significant digits.
fn fmt_value(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    let a = v.abs();
    if (1e-2..1e4).contains(&a) {
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.2e}")
    }
}

fn quantity_label(q: &str) -> String {
    match q {
        "penetration_depth" => "penetration depth of p_b below the pillar tops [µm]".into(),
        "uy_top" => "u_y(p_t) [µm]".into(),
        "uy_bottom" => "u_y(p_b) [µm]".into(),
        "uy_centre" => "u_y(c) [µm]".into(),
        "contact_radius" => "contact radius [µm]".into(),
        "strain_nucleus" => "mean ‖E‖ nucleus".into(),
        "strain_cytoplasm" => "mean ‖E‖ cytoplasm with membrane".into(),
        "contact_radius_ref" => "contact radius, reference contour [µm]".into(),
        "strain_membrane" => "mean ‖E‖ membrane".into(),
        "uy_nucleus_max" => "largest u_y over the nucleus [µm]".into(),
        "wall_seconds" => "wall time [s]".into(),
        "t" => "last output time [s]".into(),
        other => other.into(),
    }
}

/// A sweep axis as a reader names it: the quantity and its unit for the case fields the
/// sweeps vary ("pillar spacing s \[µm\]"), else the axis's path or variant name itself.
pub fn axis_label(path: &str) -> String {
    let label = match path {
        "substrate.width" => "pillar width w [µm]",
        "substrate.spacing" => "pillar spacing s [µm]",
        "substrate.height" => "pillar height h [µm]",
        "substrate.y_s" => "substrate height y_s [µm]",
        "active.pac.e" => "PAC contraction e_PAC (push)",
        "active.bottom.e" => "bottom contraction e_bottom (pull)",
        "adhesion.e_f" => "fibronectin layer e_f [µm]",
        "adhesion.mu_as_max_n_m3" => "adhesion cap μ_as,max [N/m³]",
        "adhesion.mu_as0_n_m3s" => "adhesion rate μ_as0 [N/(m³·s)]",
        "contact.eps_ct" => "contact band ε_ct [µm]",
        "contact.mu_ct_n_m3" => "contact penalty μ_ct [N/m³]",
        "materials.nucleus.e" => "nucleus modulus E_n [Pa]",
        "materials.nucleus.nu" => "nucleus Poisson ratio ν_n",
        "materials.cytoplasm.e" => "cytoplasm modulus E_cp [Pa]",
        "materials.cytoplasm.nu" => "cytoplasm Poisson ratio ν_cp",
        "materials.gamma" => "Yeoh stiffening γ",
        "materials.fibres.k1_pa" => "fibre stiffness k₁ [Pa]",
        "phases.adhesion_start" => "adhesion starts when",
        "phases.active_start" => "contraction starts when",
        "mesh.refine" => "mesh refinement",
        "solver.rtol" => "relative tolerance rtol",
        other => other,
    };
    label.to_string()
}

fn draw_err(path: &Path) -> impl Fn(String) -> OutputError + '_ {
    move |m| OutputError::draw(path, m)
}

/// The chart of a heat map: one segment per value on each of the two axes.
type GridChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<SegmentedCoord<RangedCoordusize>, SegmentedCoord<RangedCoordusize>>,
>;

/// What a heat map shows: a value per row (`None`: not shown) and its label (the quantity
/// and unit, for the colour bar and the title).
pub struct Shown<'a> {
    /// The value of a row.
    pub value: &'a dyn Fn(&Row) -> Option<f64>,
    /// The quantity and its unit.
    pub label: String,
}

/// Draws `heatmap-<q>.png`: `q` over a Grid of two axes, each cell coloured and labelled
/// with its value or its status, with a colour bar.
fn heat_map(path: &Path, record: &Record, rows: &[Row], q: &str) -> Result<(), OutputError> {
    let value = |r: &Row| r.quantity(q);
    let shown = Shown {
        value: &value,
        label: quantity_label(q),
    };
    heat_map_of(path, record, rows, &shown, &record.name)
}

/// Draws a heat map of `shown` over the Grid of two axes of `record`, titled `name`.
pub fn heat_map_of(
    path: &Path,
    record: &Record,
    rows: &[Row],
    shown: &Shown<'_>,
    name: &str,
) -> Result<(), OutputError> {
    let e = draw_err(path);
    let xs = &record.design.axes[0].values;
    let ys = &record.design.axes[1].values;
    let (lo, hi) = colour_range(rows, shown);
    let title = heat_map_title(name, rows, &shown.label);
    // The title over the whole figure, which is widened to hold it.
    let title_font = (FONT, 22).into_font();
    let title_w = title_font.box_size(&title).map_or(0, |(w, _)| w);
    let size = HeatMapSize::of(xs, ys, title_w);
    let root = BitMapBackend::new(path, (size.w, size.h)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(x.to_string()))?;
    let root = root
        .titled(&title, title_font)
        .map_err(|x| e(x.to_string()))?;
    let (main, side) = root.split_horizontally(size.w - COLORBAR_W);
    let mut chart = grid_chart(&main, record, size.label_w).map_err(&e)?;
    let cell = |r: &Row| {
        let i = xs.iter().position(|v| *v == r.values[0])?;
        let j = ys.iter().position(|v| *v == r.values[1])?;
        Some((i, j))
    };
    for r in rows {
        let Some((i, j)) = cell(r) else { continue };
        let (fill, text) = cell_look(r, shown, lo, hi);
        let stop = (r.status == Status::Failed).then_some(r.stopped.class.as_str());
        draw_grid_cell(&mut chart, (i, j), fill, stop, text).map_err(&e)?;
    }
    colorbar(&side, lo, hi, &shown.label).map_err(&e)?;
    root.present().map_err(|x| e(x.to_string()))?;
    Ok(())
}

/// The range of the colour scale: that of the finite values shown of the runs (finished
/// or failed), widened around a single value; [0, 1] without any.
fn colour_range(rows: &[Row], shown: &Shown<'_>) -> (f64, f64) {
    let shown: Vec<f64> = rows
        .iter()
        .filter(|r| matches!(r.status, Status::Finished | Status::Failed))
        .filter_map(|r| (shown.value)(r))
        .filter(|v| v.is_finite())
        .collect();
    let (mut lo, mut hi) = shown
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    if !(lo.is_finite() && hi.is_finite()) {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-12 * (1.0 + hi.abs()) {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    (lo, hi)
}

/// The heat map's title: the sweep, the quantity, and what a cross means if a run failed
/// (its colour and the word under the value say how it stopped).
fn heat_map_title(name: &str, rows: &[Row], label: &str) -> String {
    format!(
        "{name}: {label}{}",
        if rows.iter().any(|r| r.status == Status::Failed) {
            " (crossed: stopped early, how under the value; last value written)"
        } else {
            ""
        }
    )
}

/// The size of a heat map \[px\].
struct HeatMapSize {
    /// Width of the figure.
    w: u32,
    /// Height of the figure.
    h: u32,
    /// Width of the area of the y labels.
    label_w: u32,
}

impl HeatMapSize {
    /// Room for the axes' values `xs` and `ys`, the colour bar and a title `title_w` wide.
    fn of(xs: &[String], ys: &[String], title_w: u32) -> HeatMapSize {
        // Room for the labels: a variant axis's names are longer than numbers.
        let chars = |v: &[String]| v.iter().map(|s| s.chars().count()).max().unwrap_or(0) as u32;
        let cell_w = (9 * chars(xs) + 20).clamp(110, 260);
        let label_w = (9 * chars(ys) + 30).clamp(90, 300);
        let w = ((70 + label_w + cell_w * xs.len() as u32).max(700) + COLORBAR_W).max(title_w + 40);
        let h = (180 + 90 * ys.len() as u32).max(520);
        HeatMapSize { w, h, label_w }
    }
}

/// The heat map's chart on `area`, its axes labelled with the design's values and paths.
fn grid_chart<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    record: &Record,
    label_w: u32,
) -> Result<GridChart<'a, 'b>, String> {
    let (ax, ay) = (&record.design.axes[0], &record.design.axes[1]);
    let (nx, ny) = (ax.values.len(), ay.values.len());
    let mut chart = ChartBuilder::on(area)
        .margin(16)
        .x_label_area_size(60)
        .y_label_area_size(label_w)
        .build_cartesian_2d(
            (0..nx.max(1) - 1).into_segmented(),
            (0..ny.max(1) - 1).into_segmented(),
        )
        .map_err(|x| x.to_string())?;
    let label = |vals: &[String], v: &SegmentValue<usize>| match v {
        SegmentValue::CenterOf(i) => vals.get(*i).cloned().unwrap_or_default(),
        _ => String::new(),
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(nx + 1)
        .y_labels(ny + 1)
        .x_label_formatter(&|v| label(&ax.values, v))
        .y_label_formatter(&|v| label(&ay.values, v))
        .x_desc(axis_label(&ax.path))
        .y_desc(axis_label(&ay.path))
        .axis_desc_style((FONT, 18))
        .label_style((FONT, 16))
        .draw()
        .map_err(|x| x.to_string())?;
    Ok(chart)
}

/// A cell's fill and label: the value's colour and the value for a run, else grey or
/// white and the status.
fn cell_look(r: &Row, shown: &Shown<'_>, lo: f64, hi: f64) -> (RGBColor, String) {
    let v = (shown.value)(r).filter(|v| v.is_finite());
    match (r.status, v) {
        (Status::Finished | Status::Failed, Some(v)) => {
            (colormap((v - lo) / (hi - lo)), fmt_value(v))
        }
        (Status::Invalid, _) => (GREY, "invalid".to_string()),
        (Status::Missing, _) => (WHITE, "missing".to_string()),
        (Status::Interrupted, _) => (WHITE, "interrupted".to_string()),
        (_, None) => (WHITE, r.status.as_str().to_string()),
    }
}

/// The colour of the cross over a point that stopped early, by its `stop_class`: an
/// inverted element red, a stalled step size orange, any other stop (the step limit, the
/// wall-clock budget, an integration failure) black.
fn stop_colour(class: &str) -> RGBColor {
    match class {
        "inverted" => RED,
        "stalled" => RGBColor(230, 120, 0),
        _ => BLACK,
    }
}

/// Draws cell (i, j): its fill, a white border, and for a run that stopped early
/// (`stop`: its class) a cross in the class's colour ([`stop_colour`]), and its label in
/// black or white, whichever reads on the fill, the class under it.
fn draw_grid_cell(
    chart: &mut GridChart<'_, '_>,
    (i, j): (usize, usize),
    fill: RGBColor,
    stop: Option<&str>,
    text: String,
) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<_>| x.to_string();
    let corners = |i: usize, j: usize| {
        [
            (SegmentValue::Exact(i), SegmentValue::Exact(j)),
            (SegmentValue::Exact(i + 1), SegmentValue::Exact(j + 1)),
        ]
    };
    chart
        .draw_series(std::iter::once(Rectangle::new(
            corners(i, j),
            fill.filled(),
        )))
        .map_err(e)?;
    chart
        .draw_series(std::iter::once(Rectangle::new(
            corners(i, j),
            WHITE.stroke_width(2),
        )))
        .map_err(e)?;
    if let Some(class) = stop {
        // A cross over the cell: the value is the last one written before it stopped.
        let (a, b) = (corners(i, j)[0].clone(), corners(i, j)[1].clone());
        let style = stop_colour(class).stroke_width(3);
        chart
            .draw_series([
                PathElement::new(vec![a.clone(), b.clone()], style),
                PathElement::new(vec![(a.0, b.1), (b.0, a.1)], style),
            ])
            .map_err(e)?;
    }
    let luminance = 0.299 * fill.0 as f64 + 0.587 * fill.1 as f64 + 0.114 * fill.2 as f64;
    let color = if luminance < 140.0 { WHITE } else { BLACK };
    let centre = (SegmentValue::CenterOf(i), SegmentValue::CenterOf(j));
    let font = |size: u32, v: VPos| {
        (FONT, size)
            .into_font()
            .color(&color)
            .pos(Pos::new(HPos::Center, v))
    };
    let class = stop.filter(|c| !c.is_empty());
    let value_pos = if class.is_some() {
        VPos::Bottom
    } else {
        VPos::Center
    };
    chart
        .draw_series(std::iter::once(Text::new(
            text,
            centre.clone(),
            font(17, value_pos),
        )))
        .map_err(e)?;
    if let Some(c) = class {
        chart
            .draw_series(std::iter::once(Text::new(
                c.replace('_', " "),
                centre,
                font(14, VPos::Top),
            )))
            .map_err(e)?;
    }
    Ok(())
}

/// Width of a heat map's colour bar with its ticks and label \[px\].
const COLORBAR_W: u32 = 190;

/// The colour bar from `lo` to `hi`, its ticks and its `label` (the quantity and unit).
fn colorbar(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    lo: f64,
    hi: f64,
    label: &str,
) -> Result<(), String> {
    let mut chart = ChartBuilder::on(area)
        .margin_top(30)
        .margin_bottom(76)
        .margin_right(10)
        .y_label_area_size(110)
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(|x| x.to_string())?;
    chart
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_labels(8)
        // A tick at zero computed as lo + k·step is a round-off away from it.
        .y_label_formatter(&|v| fmt_value(if v.abs() < 1e-9 * (hi - lo) { 0.0 } else { *v }))
        .y_desc(label)
        .axis_desc_style((FONT, 16))
        .label_style((FONT, 14))
        .draw()
        .map_err(|x| x.to_string())?;
    let n = 100;
    chart
        .draw_series((0..n).map(|k| {
            let a = lo + (hi - lo) * k as f64 / n as f64;
            let b = lo + (hi - lo) * (k + 1) as f64 / n as f64;
            Rectangle::new(
                [(0.0, a), (1.0, b)],
                colormap((k as f64 + 0.5) / n as f64).filled(),
            )
        }))
        .map_err(|x| x.to_string())?;
    Ok(())
}

/// The axes, their descriptions and the light grid of a line or scatter chart; with
/// `log_x` the x coordinate is log₁₀ of the value and labelled with the value.
fn draw_axes<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    x_desc: &str,
    y_desc: &str,
    log_x: bool,
) -> Result<(), String> {
    let value = |v: &f64| {
        let x = 10f64.powf(*v);
        if x >= 1.0 {
            format!("{x:.0}")
        } else {
            format!("{x:.2e}")
        }
    };
    let mut mesh = chart.configure_mesh();
    mesh.x_desc(x_desc)
        .y_desc(y_desc)
        .axis_desc_style((FONT, 17))
        .label_style((FONT, 15))
        .light_line_style(RGBColor(235, 235, 235));
    if log_x {
        mesh.x_label_formatter(&value);
    }
    mesh.draw().map_err(|x| x.to_string())
}

/// The quantity against the axes' values: one panel per axis; `joined` draws lines
/// between the points (a Grid or Zip axis), else markers only (a sample).
fn line_plot(
    path: &Path,
    name: &str,
    axes: &[String],
    rows: &[Row],
    q: &str,
    joined: bool,
) -> Result<(), OutputError> {
    let e = draw_err(path);
    let panels = axes.len().max(1);
    let root = BitMapBackend::new(path, (760 * panels as u32, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(x.to_string()))?;
    let areas = root.split_evenly((1, panels));
    for (j, (area, axis)) in areas.iter().zip(axes).enumerate() {
        let mut pts: Vec<(f64, f64, Status)> = rows
            .iter()
            .filter(|r| matches!(r.status, Status::Finished | Status::Failed))
            .filter_map(|r| {
                let x = super::parse_number(r.values.get(j)?)?;
                let y = r.quantity(q)?;
                (x.is_finite() && y.is_finite()).then_some((x, y, r.status))
            })
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        // Positive values spanning two decades or more (a stiffness 10, 100, 1000): on a
        // log axis, so that the small ones are not crowded at one end.
        let log_x = pts.len() >= 3 && pts[0].0 > 0.0 && pts[pts.len() - 1].0 >= 100.0 * pts[0].0;
        if log_x {
            for p in &mut pts {
                p.0 = p.0.log10();
            }
        }
        let range = |v: &mut dyn Iterator<Item = f64>| {
            let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
            if !lo.is_finite() {
                return (0.0, 1.0);
            }
            let pad = ((hi - lo) * 0.08)
                .max(1e-9 * (1.0 + hi.abs()))
                .max(if hi == lo { 0.5 } else { 0.0 });
            (lo - pad, hi + pad)
        };
        let (x0, x1) = range(&mut pts.iter().map(|p| p.0));
        let (y0, y1) = range(&mut pts.iter().map(|p| p.1));
        let not_run: Vec<&str> = rows
            .iter()
            .filter(|r| !matches!(r.status, Status::Finished | Status::Failed))
            .map(|r| r.id.as_str())
            .collect();
        let mut caption = format!("{name}: {}", quantity_label(q));
        if !not_run.is_empty() {
            caption += &format!(" ({} not run or invalid)", not_run.len());
        }
        let mut chart = ChartBuilder::on(area)
            .caption(caption, (FONT, 20))
            .margin(16)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|x| e(x.to_string()))?;
        let x_desc = if log_x {
            format!("{} (log scale)", axis_label(axis))
        } else {
            axis_label(axis)
        };
        draw_axes(&mut chart, &x_desc, &quantity_label(q), log_x).map_err(&e)?;
        if joined {
            chart
                .draw_series(LineSeries::new(
                    pts.iter()
                        .filter(|p| p.2 == Status::Finished)
                        .map(|p| (p.0, p.1)),
                    BLUE.stroke_width(2),
                ))
                .map_err(|x| e(x.to_string()))?;
        }
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.2 == Status::Finished)
                    .map(|p| Circle::new((p.0, p.1), 5, BLUE.filled())),
            )
            .map_err(|x| e(x.to_string()))?;
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.2 == Status::Failed)
                    .map(|p| Cross::new((p.0, p.1), 7, RED.stroke_width(3))),
            )
            .map_err(|x| e(x.to_string()))?;
    }
    root.present().map_err(|x| e(x.to_string()))?;
    Ok(())
}

/// A point of a [`GeometryCurve`]: (spacing, value, finished).
pub type CurvePoint = (f64, f64, bool);

/// A point's pillar geometry: (width, spacing, on the `Gap` lattice); `None` off pillars.
pub type PillarGeometry = Option<(f64, f64, bool)>;

/// One sweep for [`geometry_curves`]: the model's dimension (2 or 3), its rows and each
/// row's pillar geometry.
pub type GeometrySet = (usize, Vec<Row>, Vec<PillarGeometry>);

/// One line of [`by_spacing`]: a width in one model, the points by spacing.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometryCurve {
    /// 2 (plane strain) or 3.
    pub dim: usize,
    /// Pillar width \[µm\].
    pub width: f64,
    /// The 3-D cell above the gap between two pillars (`Gap` lattice).
    pub gap: bool,
    /// (spacing, value, finished), by spacing; a point that stopped early at its last value.
    pub points: Vec<CurvePoint>,
}

impl GeometryCurve {
    /// The legend's text.
    pub fn label(&self) -> String {
        let model = match (self.dim, self.gap) {
            (2, _) => "plane strain",
            (_, false) => "3-D, four pillars",
            (_, true) => "3-D, gap lattice",
        };
        format!("{model}, w = {} µm", self.width)
    }
}

/// The curves of [`by_spacing`] from sweeps' rows and their points' pillar geometry
/// (width, spacing, `Gap` lattice; `None` off pillars): one per (model, lattice, width),
/// ordered by model, lattice, width; points finished or failed (at the last value), by
/// spacing.
pub fn geometry_curves(sets: &[GeometrySet], q: &str) -> Vec<GeometryCurve> {
    let mut curves: Vec<GeometryCurve> = Vec::new();
    for (dim, rows, geometry) in sets {
        for (r, g) in rows.iter().zip(geometry) {
            let (Some((width, spacing, gap)), Some(v)) = (*g, r.quantity(q)) else {
                continue;
            };
            if !matches!(r.status, Status::Finished | Status::Failed) || !v.is_finite() {
                continue;
            }
            let gap = gap && *dim == 3;
            let point = (spacing, v, r.status == Status::Finished);
            match curves
                .iter_mut()
                .find(|c| c.dim == *dim && c.gap == gap && c.width == width)
            {
                Some(c) => c.points.push(point),
                None => curves.push(GeometryCurve {
                    dim: *dim,
                    width,
                    gap,
                    points: vec![point],
                }),
            }
        }
    }
    for c in &mut curves {
        c.points.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    curves.sort_by(|a, b| {
        (a.dim, a.gap)
            .cmp(&(b.dim, b.gap))
            .then(a.width.total_cmp(&b.width))
    });
    curves
}

/// Draws `curves` (quantity `q` against the spacing) into `path`: a colour per width,
/// plane strain dashed with hollow circles, 3-D solid with filled circles, the `Gap`
/// lattice dotted with triangles; points that stopped early as red crosses.
pub fn by_spacing(path: &Path, curves: &[GeometryCurve], q: &str) -> Result<(), OutputError> {
    let e = draw_err(path);
    let root = BitMapBackend::new(path, (900, 620)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(x.to_string()))?;
    let all = || curves.iter().flat_map(|c| c.points.iter());
    let span = |f: &dyn Fn(&CurvePoint) -> f64| {
        let (lo, hi) = all()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                (a.min(x), b.max(x))
            });
        if lo.is_finite() {
            let pad = ((hi - lo) * 0.08).max(0.5);
            (lo - pad, hi + pad)
        } else {
            (0.0, 1.0)
        }
    };
    let (x0, x1) = span(&|p| p.0);
    let (y0, y1) = span(&|p| p.1);
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{} against the pillar spacing", quantity_label(q)),
            (FONT, 22),
        )
        .margin(16)
        .x_label_area_size(55)
        .y_label_area_size(80)
        .build_cartesian_2d(x0..x1, y0.min(0.0)..y1)
        .map_err(|x| e(x.to_string()))?;
    draw_axes(
        &mut chart,
        "pillar spacing s [µm]",
        &quantity_label(q),
        false,
    )
    .map_err(&e)?;
    let mut widths: Vec<f64> = curves.iter().map(|c| c.width).collect();
    widths.sort_by(f64::total_cmp);
    widths.dedup();
    const PALETTE: [RGBColor; 6] = [
        BLUE,
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(23, 190, 207),
    ];
    for c in curves {
        let k = widths.iter().position(|w| *w == c.width).unwrap_or(0);
        let colour = PALETTE[k % PALETTE.len()];
        let line: Vec<(f64, f64)> = c.points.iter().map(|p| (p.0, p.1)).collect();
        let style = colour.stroke_width(if c.dim == 3 { 3 } else { 2 });
        let drawn = match (c.dim, c.gap) {
            (2, _) => chart.draw_series(DashedLineSeries::new(line, 14, 8, style)),
            (_, true) => chart.draw_series(DashedLineSeries::new(line, 3, 6, style)),
            _ => chart.draw_series(LineSeries::new(line, style)),
        }
        .map_err(|x| e(x.to_string()))?;
        drawn
            .label(c.label())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], style));
        for &(x, y, done) in &c.points {
            if !done {
                chart
                    .draw_series(std::iter::once(Cross::new((x, y), 7, RED.stroke_width(3))))
                    .map_err(|x| e(x.to_string()))?;
            } else if c.gap {
                chart
                    .draw_series(std::iter::once(TriangleMarker::new(
                        (x, y),
                        7,
                        colour.filled(),
                    )))
                    .map_err(|x| e(x.to_string()))?;
            } else if c.dim == 2 {
                chart
                    .draw_series(std::iter::once(Circle::new(
                        (x, y),
                        5,
                        colour.stroke_width(2),
                    )))
                    .map_err(|x| e(x.to_string()))?;
            } else {
                chart
                    .draw_series(std::iter::once(Circle::new((x, y), 5, colour.filled())))
                    .map_err(|x| e(x.to_string()))?;
            }
        }
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerRight)
        .background_style(WHITE.mix(0.85))
        .border_style(GREY)
        .label_font((FONT, 15))
        .draw()
        .map_err(|x| e(x.to_string()))?;
    root.present().map_err(|x| e(x.to_string()))?;
    Ok(())
}

/// A normalised sensitivity of one quantity to one parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensitivity {
    /// The quantity.
    pub quantity: String,
    /// The parameter (axis path).
    pub axis: String,
    /// Base value of the parameter and of the quantity.
    pub p0: f64,
    /// Lowest and highest parameter value run (one of them may be the base's).
    pub p_lo: f64,
    pub p_hi: f64,
    /// Base value of the quantity.
    pub q0: f64,
    /// The quantity at p_lo and p_hi.
    pub q_lo: f64,
    pub q_hi: f64,
    /// (ΔQ/Q0)/(Δp/p0) over [p_lo, p_hi]; NaN when Q0 or p0 is 0.
    pub s: f64,
}

/// The sensitivities of a one-at-a-time sweep from its rows: the base row is the one with
/// id `base`; a parameter's rows are the finished ones that differ from the base on its
/// axis only.
pub fn sensitivities(axes: &[String], rows: &[Row]) -> Vec<Sensitivity> {
    let Some(base) = rows
        .iter()
        .find(|r| r.id == "base" && r.status == Status::Finished)
    else {
        return Vec::new();
    };
    let mut out = Vec::new();
    for q in TORNADO_QUANTITIES {
        let Some(q0) = base.quantity(q) else { continue };
        for (j, axis) in axes.iter().enumerate() {
            let Some(p0) = base.values.get(j).and_then(|v| super::parse_number(v)) else {
                continue;
            };
            let mut pts: Vec<(f64, f64)> = vec![(p0, q0)];
            for r in rows {
                let alone = r
                    .values
                    .iter()
                    .enumerate()
                    .all(|(k, v)| (k == j) != (*v == base.values[k]));
                if r.status != Status::Finished || !alone {
                    continue;
                }
                if let (Some(p), Some(v)) = (super::parse_number(&r.values[j]), r.quantity(q)) {
                    pts.push((p, v));
                }
            }
            if pts.len() < 2 {
                continue;
            }
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let (lo, hi) = (pts[0], pts[pts.len() - 1]);
            let s = if q0 != 0.0 && p0 != 0.0 && hi.0 != lo.0 {
                ((hi.1 - lo.1) / q0) / ((hi.0 - lo.0) / p0)
            } else {
                f64::NAN
            };
            out.push(Sensitivity {
                quantity: q.to_string(),
                axis: axis.clone(),
                p0,
                p_lo: lo.0,
                p_hi: hi.0,
                q0,
                q_lo: lo.1,
                q_hi: hi.1,
                s,
            });
        }
    }
    out
}

fn tornado(path: &Path, name: &str, axes: &[String], s: &[Sensitivity]) -> Result<(), OutputError> {
    let e = draw_err(path);
    let (cols, rows_n) = (2usize, 3usize);
    let panel_h = (120 + 44 * axes.len() as u32).max(320);
    let root = BitMapBackend::new(path, (1500, panel_h * rows_n as u32 + 50)).into_drawing_area();
    root.fill(&WHITE).map_err(|x| e(x.to_string()))?;
    let (title, body) = root.split_vertically(50);
    title
        .draw(&Text::new(
            format!("{name}: normalised sensitivities S = (ΔQ/Q) / (Δp/p), central over each parameter's range"),
            (20, 14),
            (FONT, 22).into_font(),
        ))
        .map_err(|x| e(x.to_string()))?;
    let areas = body.split_evenly((rows_n, cols));
    for (area, q) in areas.iter().zip(TORNADO_QUANTITIES) {
        let mut bars: Vec<&Sensitivity> = s.iter().filter(|x| x.quantity == q).collect();
        // Largest |S| on top; undefined ones last.
        bars.sort_by(|a, b| {
            let key = |x: &Sensitivity| if x.s.is_finite() { x.s.abs() } else { -1.0 };
            key(a).total_cmp(&key(b))
        });
        let m = bars
            .iter()
            .map(|b| b.s.abs())
            .filter(|v| v.is_finite())
            .fold(0.0_f64, f64::max)
            .max(1e-3)
            * 1.25;
        let n = bars.len().max(1);
        let labels: Vec<String> = bars.iter().map(|b| axis_label(&b.axis)).collect();
        let mut chart = ChartBuilder::on(area)
            .caption(quantity_label(q), (FONT, 18))
            .margin(10)
            .margin_right(24)
            .x_label_area_size(36)
            .y_label_area_size(230)
            .build_cartesian_2d(-m..m, (0..n - 1).into_segmented())
            .map_err(|x| e(x.to_string()))?;
        chart
            .configure_mesh()
            .y_labels(n + 1)
            .y_label_formatter(&|v| match v {
                SegmentValue::CenterOf(i) => labels.get(*i).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .x_label_formatter(&|v| fmt_value(*v))
            .label_style((FONT, 14))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(|x| e(x.to_string()))?;
        for (i, b) in bars.iter().enumerate() {
            let y0 = SegmentValue::Exact(i);
            let y1 = SegmentValue::Exact(i + 1);
            if b.s.is_finite() {
                let color = if b.s >= 0.0 { BLUE } else { RED };
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(0.0, y0), (b.s, y1)],
                        color.mix(0.8).filled(),
                    )))
                    .map_err(|x| e(x.to_string()))?;
            }
            let text = if b.s.is_finite() {
                fmt_value(b.s)
            } else {
                "n/a (Q = 0)".into()
            };
            let (x, anchor) = if b.s.is_finite() && b.s < 0.0 {
                (b.s - 0.02 * m, HPos::Right)
            } else {
                (
                    if b.s.is_finite() { b.s } else { 0.0 } + 0.02 * m,
                    HPos::Left,
                )
            };
            chart
                .draw_series(std::iter::once(Text::new(
                    text,
                    (x, SegmentValue::CenterOf(i)),
                    (FONT, 14)
                        .into_font()
                        .color(&BLACK)
                        .pos(Pos::new(anchor, VPos::Center)),
                )))
                .map_err(|x| e(x.to_string()))?;
        }
        // The zero line.
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(0.0, SegmentValue::Exact(0)), (0.0, SegmentValue::Exact(n))],
                BLACK.stroke_width(1),
            )))
            .map_err(|x| e(x.to_string()))?;
    }
    root.present().map_err(|x| e(x.to_string()))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run_files::Observables;

    fn row(id: &str, values: &[&str], uy_top: f64) -> Row {
        Row {
            id: id.into(),
            values: values.iter().map(|v| v.to_string()).collect(),
            status: Status::Finished,
            last: Some(Observables {
                uy_top,
                ..Default::default()
            }),
            penetration: Some(0.0),
            wall_seconds: Some(1.0),
            steps: Some(10),
            stopped: Default::default(),
            extras: [None; 3],
            events: None,
            reason: String::new(),
        }
    }

    #[test]
    fn geometry_curves_group_by_model_lattice_and_width_and_sort_by_spacing() {
        let mut failed = row("f", &[], -1.0);
        failed.status = Status::Failed;
        let mut invalid = row("i", &[], -1.0);
        invalid.status = Status::Invalid;
        let plane = vec![
            row("a", &[], -3.0),
            row("b", &[], -2.0),
            row("c", &[], -5.0),
        ];
        let plane_g = vec![Some((8.0, 12.0, false)), Some((8.0, 4.0, false)), None];
        let three = vec![row("d", &[], -4.0), failed, row("e", &[], -6.0), invalid];
        let three_g = vec![
            Some((8.0, 6.0, false)),
            Some((8.0, 4.0, false)),
            Some((8.0, 6.0, true)),
            Some((4.0, 6.0, false)),
        ];
        let curves = geometry_curves(&[(2, plane, plane_g), (3, three, three_g)], "uy_top");
        let summary: Vec<(String, Vec<CurvePoint>)> = curves
            .iter()
            .map(|c| (c.label(), c.points.clone()))
            .collect();
        assert_eq!(
            summary,
            vec![
                (
                    "plane strain, w = 8 µm".to_string(),
                    vec![(4.0, -2.0, true), (12.0, -3.0, true)]
                ),
                (
                    "3-D, four pillars, w = 8 µm".to_string(),
                    vec![(4.0, -1.0, false), (6.0, -4.0, true)]
                ),
                (
                    "3-D, gap lattice, w = 8 µm".to_string(),
                    vec![(6.0, -6.0, true)]
                ),
            ]
        );
        let path = std::env::temp_dir().join(format!("by-spacing-{}.png", std::process::id()));
        by_spacing(&path, &curves, "uy_top").expect("drawn");
        assert!(std::fs::metadata(&path).expect("written").len() > 1000);
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn sensitivities_are_central_differences_normalised_by_the_base() {
        let axes = vec!["a".to_string(), "b".to_string()];
        let rows = vec![
            row("base", &["2.0", "10.0"], -4.0),
            row("o0_0", &["1.0", "10.0"], -3.0),
            row("o0_1", &["3.0", "10.0"], -6.0),
            row("o1_0", &["2.0", "20.0"], -4.4),
        ];
        let s = sensitivities(&axes, &rows);
        let a = s
            .iter()
            .find(|x| x.quantity == "uy_top" && x.axis == "a")
            .unwrap();
        // ((−6 − −3)/−4) / ((3 − 1)/2) = 0.75
        assert!((a.s - 0.75).abs() < 1e-12, "{a:?}");
        let b = s
            .iter()
            .find(|x| x.quantity == "uy_top" && x.axis == "b")
            .unwrap();
        // One-sided: ((−4.4 − −4)/−4) / ((20 − 10)/10) = 0.1
        assert!((b.s - 0.1).abs() < 1e-12, "{b:?}");
        // Penetration 0 at the base: undefined.
        let p = s
            .iter()
            .find(|x| x.quantity == "penetration_depth")
            .unwrap();
        assert!(p.s.is_nan());
    }

    #[test]
    fn labels_have_three_significant_digits() {
        assert_eq!(fmt_value(1.23456), "1.23");
        assert_eq!(fmt_value(-0.0123456), "-0.0123");
        assert_eq!(fmt_value(123.456), "123");
        assert_eq!(fmt_value(0.0), "0");
        assert_eq!(colormap(0.0), RGBColor(68, 1, 84));
        assert_eq!(colormap(1.0), RGBColor(253, 231, 37));
    }
}
