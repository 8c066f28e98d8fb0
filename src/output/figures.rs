//! The figures, as PNG files drawn with plotters from a run's files ([`RunData`]).
//!
//! - time series ([`time_figure`] and its uses [`contact_radius_figure`],
//!   [`displacement_figure`], [`strain_time_figure`], [`upside_down_figure`]): one or
//!   more runs against time, the phase boundaries T_g0, T_as0, T_a0 marked and named, the
//!   paper's reported values as hollow circles;
//! - [`strain_bars_figure`]: mean ‖E‖ of nucleus and cytoplasm per scene, the paper's
//!   value beside ours (Fig. 7's numbers);
//! - [`shape_figure`]: the deformed cell at one state, mirrored to the full cell, with
//!   nucleus, cytoplasm and membrane filled in the paper's colours (red, orange, green),
//!   the active regions outlined, the substrate and the fibronectin layer drawn, in µm
//!   with equal aspect (Figs. 5, 6a, 8);
//! - [`plot_run`]: all of a single run's figures (`cellsim plot`).

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use super::OutputError;
use super::geometry::{Backdrop, Bounds, CellShape, Pt, Rect, substrate_floor};
use crate::fem::Domain;
use crate::record::Observables;
use crate::record::RunData;
use crate::record::{MeshFile, StateFile};

/// Pixel size of the time-series and bar figures.
pub const TIME_SIZE: (u32, u32) = (1200, 800);
/// Pixel size of the shape figures.
pub const SHAPE_SIZE: (u32, u32) = (1400, 1000);
/// Pixel size of the two-panel upside-down figure.
pub const UPSIDE_DOWN_SIZE: (u32, u32) = (1200, 1000);

/// Width of a curve's sample in a legend [px].
const LEGEND_GLYPH: i32 = 40;

/// Font family of every text.
const FONT: &str = "sans-serif";

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

fn darker(c: RGBColor, f: f64) -> RGBColor {
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
    /// (t [s], value) points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Stroke.
    pub stroke: Stroke,
}

/// Reported values drawn as hollow circles.
#[derive(Debug, Clone)]
pub struct Marks {
    /// Legend text (empty: no legend entry).
    pub label: String,
    /// (t [s], value) points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Circle radius [px] (concentric circles keep coinciding values of several runs
    /// visible).
    pub radius: i32,
}

/// A time plot: curves, reported values and the phases.
#[derive(Debug, Clone)]
pub struct TimePlot {
    /// Title above the plot.
    pub title: String,
    /// y-axis description, with units.
    pub y_desc: String,
    /// The curves.
    pub curves: Vec<Curve>,
    /// Reported values.
    pub marks: Vec<Marks>,
    /// T_g0, T_as0, T_a0 and the end time [s]: boundaries are drawn at the first three
    /// where they lie inside the time axis.
    pub phase_times: [f64; 4],
    /// Name of the interval after T_a0, if shown ("rest", "gravity flipped", …).
    pub after_active: String,
    /// Right end of the time axis [s].
    pub t_max: f64,
    /// Where the legend goes.
    pub legend: SeriesLabelPosition,
}

/// "12 345" for 12345.0 (thin grouping of thousands in axis labels).
fn group_thousands(v: f64) -> String {
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

/// Padded value range of the curves and marks (a unit range if there is nothing).
fn value_range(plot: &TimePlot) -> (f64, f64) {
    let vals = plot
        .curves
        .iter()
        .flat_map(|c| c.points.iter())
        .chain(plot.marks.iter().flat_map(|m| m.points.iter()))
        .map(|p| p.1)
        .filter(|v| v.is_finite());
    let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    if !(lo <= hi) {
        return (0.0, 1.0);
    }
    let span = (hi - lo).max(1e-6 * hi.abs().max(lo.abs())).max(1e-12);
    (lo - 0.08 * span, hi + 0.16 * span)
}

fn phase_intervals(plot: &TimePlot) -> Vec<(f64, f64, String)> {
    let [tg, tas, ta, _] = plot.phase_times;
    let names = ["gravity", "spreading", "active", plot.after_active.as_str()];
    let bounds = [0.0, tg, tas, ta, f64::INFINITY];
    let mut out = Vec::new();
    for k in 0..4 {
        let (a, b) = (bounds[k], bounds[k + 1].min(plot.t_max));
        if b > a && a < plot.t_max && !names[k].is_empty() {
            out.push((a, b, names[k].to_string()));
        }
    }
    out
}

/// Draws a time plot into `area`.
pub fn draw_time_plot<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    plot: &TimePlot,
) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let (lo, hi) = value_range(plot);
    let t_max = if plot.t_max > 0.0 { plot.t_max } else { 1.0 };
    // 3 % of room after the end, so marks at the end time are not cut.
    let t_axis_end = 1.03 * t_max;
    let mut chart = ChartBuilder::on(area)
        .caption(&plot.title, (FONT, 28))
        .margin(18)
        .margin_right(44)
        .x_label_area_size(60)
        .y_label_area_size(90)
        .build_cartesian_2d(0.0..t_axis_end, lo..hi)
        .map_err(e)?;
    let fmt_t = |v: &f64| group_thousands(*v);
    chart
        .configure_mesh()
        .x_desc("time t (s)")
        .y_desc(&plot.y_desc)
        .x_label_formatter(&fmt_t)
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 18))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;

    // Phases: dashed boundaries, names along the top.
    let grey = RGBColor(110, 110, 110);
    for (a, b, name) in phase_intervals(plot) {
        if a > 0.0 {
            chart
                .draw_series(DashedLineSeries::new(
                    vec![(a, lo), (a, hi)],
                    8,
                    6,
                    grey.stroke_width(2),
                ))
                .map_err(e)?;
        }
        let mid = 0.5 * (a + b);
        let style = TextStyle::from((FONT, 18).into_font()).color(&grey).pos(
            plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Center,
                plotters::style::text_anchor::VPos::Top,
            ),
        );
        chart
            .draw_series(std::iter::once(Text::new(
                name,
                (mid, hi - 0.01 * (hi - lo)),
                style,
            )))
            .map_err(e)?;
    }

    for c in &plot.curves {
        let style = c.color.stroke_width(3);
        let color = c.color;
        let anno = match c.stroke {
            Stroke::Solid => chart
                .draw_series(LineSeries::new(c.points.iter().copied(), style))
                .map_err(e)?,
            Stroke::Dashed => chart
                .draw_series(DashedLineSeries::new(
                    c.points.iter().copied(),
                    14,
                    8,
                    style,
                ))
                .map_err(e)?,
            Stroke::Dotted => chart
                .draw_series(DashedLineSeries::new(c.points.iter().copied(), 3, 6, style))
                .map_err(e)?,
        };
        let stroke = c.stroke;
        anno.label(&c.label).legend(move |(x, y)| {
            let s = color.stroke_width(3);
            match stroke {
                Stroke::Solid => {
                    PathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], s).into_dyn()
                }
                Stroke::Dashed => {
                    DashedPathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], 10, 5, s).into_dyn()
                }
                Stroke::Dotted => {
                    DashedPathElement::new(vec![(x, y), (x + LEGEND_GLYPH, y)], 3, 5, s).into_dyn()
                }
            }
        });
    }
    for m in &plot.marks {
        let color = m.color;
        let anno = chart
            .draw_series(
                m.points
                    .iter()
                    .map(|&p| Circle::new(p, m.radius, color.stroke_width(3))),
            )
            .map_err(e)?;
        if !m.label.is_empty() {
            anno.label(&m.label).legend(move |(x, y)| {
                Circle::new((x + LEGEND_GLYPH / 2, y), 7, color.stroke_width(3))
            });
        }
    }
    // Upper legends start below the row of phase names.
    let position = match plot.legend {
        SeriesLabelPosition::UpperLeft => SeriesLabelPosition::Coordinate(12, 40),
        ref other => other.clone(),
    };
    chart
        .configure_series_labels()
        .position(position)
        .legend_area_size(LEGEND_GLYPH + 12)
        .margin(12)
        .label_font((FONT, 18))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    Ok(())
}

/// Draws a [`TimePlot`] into a PNG at `path` of [`TIME_SIZE`].
pub fn time_figure(path: &Path, plot: &TimePlot) -> Result<(), OutputError> {
    let root = BitMapBackend::new(path, TIME_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| OutputError::draw(path, x))?;
    draw_time_plot(&root, plot).map_err(|x| OutputError::draw(path, x))?;
    root.present().map_err(|x| OutputError::draw(path, x))
}

/// (t, value) points of one quantity.
pub fn points(rows: &[Observables], f: impl Fn(&Observables) -> f64) -> Vec<(f64, f64)> {
    rows.iter()
        .map(|o| (o.t, f(o)))
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect()
}

/// The largest end time among `runs` (the time axis shows where partial runs stopped).
fn t_axis(runs: &[&RunData]) -> f64 {
    runs.iter().map(|r| r.t_end()).fold(0.0, f64::max)
}

/// A run's label in a legend: its name, with "(stopped at t = … s)" if it did not finish.
pub fn run_label(r: &RunData) -> String {
    if r.finished() {
        r.name.clone()
    } else {
        format!(
            "{} (stopped at t = {} s)",
            r.name,
            group_thousands(r.t_last())
        )
    }
}

/// Contact radius against time for `runs` (the paper's Fig. 6b), with `reported` values
/// (t [s], radius [µm]) as hollow circles labelled `reported_label`.
pub fn contact_radius_figure(
    path: &Path,
    runs: &[&RunData],
    reported: &[(f64, f64)],
    reported_label: &str,
) -> Result<(), OutputError> {
    let curves = runs
        .iter()
        .enumerate()
        .map(|(k, r)| Curve {
            label: run_label(r),
            points: points(&r.series, |o| o.contact_radius),
            color: PALETTE[k % PALETTE.len()],
            stroke: Stroke::Solid,
        })
        .collect();
    let marks = if reported.is_empty() {
        vec![]
    } else {
        vec![Marks {
            label: reported_label.to_string(),
            points: reported.to_vec(),
            color: BLACK,
            radius: 8,
        }]
    };
    let plot = TimePlot {
        title: "Contact radius (half-width of the contact zone)".into(),
        y_desc: "contact radius (µm)".into(),
        curves,
        marks,
        phase_times: runs.first().map(|r| r.mesh.phase_times).unwrap_or([0.0; 4]),
        after_active: "rest".into(),
        t_max: t_axis(runs),
        legend: SeriesLabelPosition::UpperLeft,
    };
    time_figure(path, &plot)
}

/// Vertical displacement of p_t (solid) and c (dashed) against time for `runs` (the
/// paper's Fig. 9 kind of curve), with reported displacements of p_t per run (t [s],
/// u_y [µm]) as hollow circles in the run's colour, concentric (one radius per run) so
/// values shared by several runs stay visible.
pub fn displacement_figure(
    path: &Path,
    runs: &[&RunData],
    reported: &[Vec<(f64, f64)>],
    reported_label: &str,
) -> Result<(), OutputError> {
    let mut curves = Vec::new();
    let mut marks = Vec::new();
    for (k, r) in runs.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        curves.push(Curve {
            label: format!("{}: nucleus top p_t", run_label(r)),
            points: points(&r.series, |o| o.uy_top),
            color,
            stroke: Stroke::Solid,
        });
        curves.push(Curve {
            label: format!("{}: centre c", r.name),
            points: points(&r.series, |o| o.uy_centre),
            color,
            stroke: Stroke::Dashed,
        });
        if let Some(rep) = reported.get(k) {
            if !rep.is_empty() {
                marks.push(Marks {
                    label: String::new(),
                    points: rep.clone(),
                    color,
                    radius: 7 + 4 * k as i32,
                });
            }
        }
    }
    if !marks.is_empty() {
        marks.push(Marks {
            label: reported_label.to_string(),
            points: vec![],
            color: BLACK,
            radius: 8,
        });
    }
    let plot = TimePlot {
        title: "Vertical displacement of the nucleus top p_t and the cell centre c".into(),
        y_desc: "vertical displacement u_y (µm, negative = down)".into(),
        curves,
        marks,
        phase_times: runs.first().map(|r| r.mesh.phase_times).unwrap_or([0.0; 4]),
        after_active: "rest".into(),
        t_max: t_axis(runs),
        legend: SeriesLabelPosition::LowerLeft,
    };
    time_figure(path, &plot)
}

/// Mean ‖E‖ of nucleus (solid) and cytoplasm (dashed) against time for `runs`, in %.
pub fn strain_time_figure(path: &Path, runs: &[&RunData]) -> Result<(), OutputError> {
    let mut curves = Vec::new();
    for (k, r) in runs.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        curves.push(Curve {
            label: format!("{}: nucleus", run_label(r)),
            points: points(&r.series, |o| 100.0 * o.strain_nucleus),
            color,
            stroke: Stroke::Solid,
        });
        curves.push(Curve {
            label: format!("{}: cytoplasm", r.name),
            points: points(&r.series, |o| 100.0 * o.strain_cytoplasm),
            color,
            stroke: Stroke::Dashed,
        });
    }
    let plot = TimePlot {
        title: "Mean Green-Lagrange strain norm per domain".into(),
        y_desc: "mean ‖E‖ over the domain (%)".into(),
        curves,
        marks: vec![],
        phase_times: runs.first().map(|r| r.mesh.phase_times).unwrap_or([0.0; 4]),
        after_active: "rest".into(),
        t_max: t_axis(runs),
        legend: SeriesLabelPosition::UpperLeft,
    };
    time_figure(path, &plot)
}

/// The upside-down experiment (the paper's Fig. 9): top, u_y(p_t) of the control (red,
/// dotted) and of the upside-down run (blue, dashed); bottom, their difference
/// upside-down − control, with the paper's reported difference (`reported` µm at the end)
/// as a hollow circle. The control's rows are interpolated at the upside-down run's times.
pub fn upside_down_figure(
    path: &Path,
    control: &RunData,
    upside: &RunData,
    reported: Option<f64>,
) -> Result<(), OutputError> {
    let red = RGBColor(214, 39, 40);
    let blue = RGBColor(31, 90, 200);
    let t_max = control.t_end().max(upside.t_end());
    let top = TimePlot {
        title: "Nucleus top p_t: control (push-pull) and upside down after T_a0".into(),
        y_desc: "u_y(p_t) (µm, negative = down)".into(),
        curves: vec![
            Curve {
                label: format!("control: {}", run_label(control)),
                points: points(&control.series, |o| o.uy_top),
                color: red,
                stroke: Stroke::Dotted,
            },
            Curve {
                label: format!("upside down: {}", run_label(upside)),
                points: points(&upside.series, |o| o.uy_top),
                color: blue,
                stroke: Stroke::Dashed,
            },
        ],
        marks: vec![],
        phase_times: upside.mesh.phase_times,
        after_active: "gravity flipped".into(),
        t_max,
        legend: SeriesLabelPosition::LowerLeft,
    };
    let diff: Vec<(f64, f64)> = upside
        .series
        .iter()
        .filter_map(|o| {
            crate::record::observables::interpolate(&control.series, o.t)
                .map(|c| (o.t, o.uy_top - c.uy_top))
        })
        .collect();
    let mut marks = vec![];
    if let Some(d) = reported {
        marks.push(Marks {
            label: format!("paper: |difference| = {d} µm at the end (Sect. 3.3)"),
            points: vec![(t_max, d), (t_max, -d)],
            color: BLACK,
            radius: 8,
        });
    }
    let bottom = TimePlot {
        title: "Difference upside down − control".into(),
        y_desc: "Δu_y(p_t) (µm)".into(),
        curves: vec![Curve {
            label: "upside down − control".into(),
            points: diff,
            color: BLACK,
            stroke: Stroke::Solid,
        }],
        marks,
        phase_times: upside.mesh.phase_times,
        after_active: "gravity flipped".into(),
        t_max,
        legend: SeriesLabelPosition::UpperLeft,
    };
    let root = BitMapBackend::new(path, UPSIDE_DOWN_SIZE).into_drawing_area();
    let err = |x: String| OutputError::draw(path, x);
    root.fill(&WHITE).map_err(|x| OutputError::draw(path, x))?;
    let (a, b) = root.split_vertically(UPSIDE_DOWN_SIZE.1 * 3 / 5);
    draw_time_plot(&a, &top).map_err(err)?;
    draw_time_plot(&b, &bottom).map_err(err)?;
    root.present().map_err(|x| OutputError::draw(path, x))
}

/// One scene's strain norms for [`strain_bars_figure`] (fractions; `None` = no value).
#[derive(Debug, Clone)]
pub struct StrainBars {
    /// Scene label.
    pub scene: String,
    /// Paper's mean ‖E‖ of the nucleus.
    pub paper_nucleus: Option<f64>,
    /// Ours.
    pub ours_nucleus: Option<f64>,
    /// Paper's mean ‖E‖ of the cytoplasm.
    pub paper_cytoplasm: Option<f64>,
    /// Ours.
    pub ours_cytoplasm: Option<f64>,
}

/// Mean ‖E‖ of the nucleus (left panel) and the cytoplasm (right) as grouped bars, the
/// paper's value (grey) beside ours (blue) for each scene, values printed on the bars.
pub fn strain_bars_figure(
    path: &Path,
    bars: &[StrainBars],
    ours_label: &str,
    paper_label: &str,
) -> Result<(), OutputError> {
    let root = BitMapBackend::new(path, TIME_SIZE).into_drawing_area();
    let derr = |x: String| OutputError::draw(path, x);
    root.fill(&WHITE).map_err(|x| OutputError::draw(path, x))?;
    let root = root
        .titled(
            "Mean Green-Lagrange strain norm at the end of the active phase",
            (FONT, 28),
        )
        .map_err(|x| OutputError::draw(path, x))?;
    let (left, right) = root.split_horizontally(TIME_SIZE.0 / 2);
    let pick_n = |b: &StrainBars| (b.paper_nucleus, b.ours_nucleus);
    let pick_c = |b: &StrainBars| (b.paper_cytoplasm, b.ours_cytoplasm);
    draw_bars(&left, "nucleus", bars, &pick_n, ours_label, paper_label).map_err(derr)?;
    draw_bars(&right, "cytoplasm", bars, &pick_c, ours_label, paper_label).map_err(derr)?;
    root.present().map_err(|x| OutputError::draw(path, x))
}

type BarPick<'a> = &'a dyn Fn(&StrainBars) -> (Option<f64>, Option<f64>);

fn draw_bars<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    bars: &[StrainBars],
    pick: BarPick<'_>,
    ours_label: &str,
    paper_label: &str,
) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    let n = bars.len().max(1);
    let top = bars
        .iter()
        .flat_map(|b| {
            let (p, o) = pick(b);
            [p, o]
        })
        .flatten()
        .map(|v| 100.0 * v)
        .filter(|v| v.is_finite())
        .fold(10.0f64, f64::max)
        * 1.3;
    let names: Vec<String> = bars.iter().map(|b| b.scene.clone()).collect();
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 24))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..n as f64, 0.0..top)
        .map_err(e)?;
    let fmt = |x: &f64| {
        let k = (x - 0.5).round();
        if (x - 0.5 - k).abs() < 1e-6 && k >= 0.0 {
            names.get(k as usize).cloned().unwrap_or_default()
        } else {
            String::new()
        }
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(2 * n + 1)
        .x_label_formatter(&fmt)
        .y_desc("mean ‖E‖ (%)")
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 20))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    let paper_color = RGBColor(170, 170, 170);
    let ours_color = RGBColor(31, 119, 180);
    let text_style = |s: i32| {
        TextStyle::from((FONT, s).into_font()).pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Bottom,
        ))
    };
    let mut paper_rects = Vec::new();
    let mut ours_rects = Vec::new();
    let mut texts = Vec::new();
    for (k, b) in bars.iter().enumerate() {
        let (p, o) = pick(b);
        let x0 = k as f64;
        for (val, (a, z), rects) in [
            (p, (x0 + 0.12, x0 + 0.48), &mut paper_rects),
            (o, (x0 + 0.52, x0 + 0.88), &mut ours_rects),
        ] {
            let label = match val.filter(|v| v.is_finite()) {
                Some(v) => {
                    rects.push([(a, 0.0), (z, 100.0 * v)]);
                    (format!("{:.0} %", 100.0 * v), 100.0 * v)
                }
                None => ("n/a".to_string(), 0.0),
            };
            texts.push((label.0, (0.5 * (a + z), label.1 + 0.01 * top)));
        }
    }
    for (rects, color, label) in [
        (&paper_rects, paper_color, paper_label),
        (&ours_rects, ours_color, ours_label),
    ] {
        chart
            .draw_series(rects.iter().map(|r| Rectangle::new(*r, color.filled())))
            .map_err(e)?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 8), (x + 24, y + 8)], color.filled()));
    }
    chart
        .draw_series(
            texts
                .into_iter()
                .map(|(s, p)| Text::new(s, p, text_style(18))),
        )
        .map_err(e)?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .margin(10)
        .label_font((FONT, 18))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(e)?;
    Ok(())
}

/// The region a set of shape drawings shares: the deformed full cells of `states` and
/// the substrate below them, with a margin of 1.5 µm, symmetric about x = 0.
pub fn shape_view(mesh: &MeshFile, states: &[&StateFile]) -> Bounds {
    let mut b = Bounds::empty();
    // The reference cell, so an empty state list still gives a frame.
    for p in &mesh.nodes {
        b.include(*p);
    }
    for s in states {
        if s.u.len() == mesh.nodes.len() {
            b = b.union(CellShape::new(mesh, &s.u).bounds());
        }
    }
    let half = b.x_max.abs().max(b.x_min.abs()) + 1.5;
    let floor = substrate_floor(&mesh.substrate);
    Bounds {
        x_min: -half,
        x_max: half,
        y_min: b.y_min.min(floor) - 1.5,
        y_max: b.y_max + 1.5,
    }
}

/// What [`draw_shape`] drew, for checks: pixels per µm along x and along y (equal when
/// the aspect is equal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeScale {
    /// Pixels per µm along x.
    pub px_per_um_x: f64,
    /// Pixels per µm along y.
    pub px_per_um_y: f64,
}

/// Options of [`draw_shape`].
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
}

/// Points [x, y] as plotters' coordinate pairs.
fn xy(points: &[Pt]) -> Vec<(f64, f64)> {
    points.iter().map(|p| (p[0], p[1])).collect()
}

/// Draws the deformed full cell of `mesh` displaced by `u` into `area` over `view`, with
/// equal aspect: the view is widened along one axis so 1 µm has the same length in
/// pixels on both. `backdrop` caches the substrate drawing between calls with the same
/// view (pass `&mut None` for a single drawing).
pub fn draw_shape<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    mesh: &MeshFile,
    u: &[[f64; 2]],
    view: Bounds,
    opts: &ShapeStyleOptions,
    backdrop: &mut Option<Backdrop>,
) -> Result<ShapeScale, String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| x.to_string();
    if u.len() != mesh.nodes.len() {
        return Err(format!(
            "{} displacements for {} nodes",
            u.len(),
            mesh.nodes.len()
        ));
    }
    let fs = opts.font as f64;
    let label_x = (2.6 * fs) as u32;
    let label_y = (3.2 * fs) as u32;
    let area = area
        .titled(&opts.title, (FONT, opts.font as i32))
        .map_err(e)?;
    let margin = (0.6 * fs) as u32;
    // First pass: the plotting area's pixel size; then ranges with equal aspect.
    let (pw, ph) = {
        let chart = ChartBuilder::on(&area)
            .margin(margin)
            .x_label_area_size(label_x)
            .y_label_area_size(label_y)
            .build_cartesian_2d(view.x_min..view.x_max, view.y_min..view.y_max)
            .map_err(e)?;
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
    let mut chart = ChartBuilder::on(&area)
        .margin(margin)
        .x_label_area_size(label_x)
        .y_label_area_size(label_y)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("x (µm)")
        .y_desc("y (µm)")
        .axis_desc_style((FONT, (0.8 * fs) as i32))
        .label_style((FONT, (0.65 * fs) as i32))
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()
        .map_err(e)?;

    // Substrate and fibronectin layer, one strip per pixel column (computed once per
    // view: a movie reuses it for every frame).
    let key = [x0, x1, y0, y1];
    let back = match backdrop.take() {
        Some(b) if b.view == key => b,
        _ => Backdrop::new(&mesh.substrate, mesh.layer_thickness, key, pw as usize),
    };
    let rect = |r: &Rect, c: RGBColor| Rectangle::new([(r[0], r[3]), (r[1], r[2])], c.filled());
    if mesh.layer_thickness.is_some() {
        chart
            .draw_series(back.layer.iter().map(|r| rect(r, LAYER)))
            .map_err(e)?
            .label("fibronectin layer")
            .legend(|(x, y)| Rectangle::new([(x, y - 7), (x + 22, y + 7)], LAYER.filled()));
    }
    chart
        .draw_series(back.substrate.iter().map(|r| rect(r, SUBSTRATE)))
        .map_err(e)?
        .label("substrate")
        .legend(|(x, y)| Rectangle::new([(x, y - 7), (x + 22, y + 7)], SUBSTRATE.filled()));

    // The cell, mirrored to the full cell.
    let shape = CellShape::new(mesh, u).mirrored();
    for d in Domain::ALL {
        let color = domain_color(d);
        let edge = darker(color, 0.82);
        let polys: Vec<&Vec<Pt>> = shape
            .elements
            .iter()
            .filter(|(dd, _)| *dd == d)
            .map(|(_, p)| p)
            .collect();
        chart
            .draw_series(polys.iter().map(|p| Polygon::new(xy(p), color.filled())))
            .map_err(e)?
            .label(d.to_string())
            .legend(move |(x, y)| Rectangle::new([(x, y - 7), (x + 22, y + 7)], color.filled()));
        // Element edges in a darker shade: shows the mesh and closes the hairline gaps
        // between neighbouring fills.
        let line_color = if opts.mesh_lines { edge } else { color };
        chart
            .draw_series(polys.iter().map(|p| {
                let mut v = xy(p);
                if let Some(f) = v.first().copied() {
                    v.push(f);
                }
                PathElement::new(v, line_color.stroke_width(1))
            }))
            .map_err(e)?;
    }
    // Each polyline of a list (points [x, y]) as one path in a style.
    macro_rules! paths {
        ($lines:expr, $style:expr) => {
            chart
                .draw_series($lines.iter().map(|l| PathElement::new(xy(&l[..]), $style)))
                .map_err(e)?
        };
    }
    paths!(shape.interfaces, RGBColor(40, 40, 40).stroke_width(2));
    paths!(shape.outer, BLACK.stroke_width(2));
    for (segs, color, name) in [
        (&shape.pac, PAC, "active: PAC (push)"),
        (&shape.bottom, BOTTOM, "active: bottom (pull)"),
    ] {
        if segs.is_empty() {
            continue;
        }
        paths!(segs, color.stroke_width(3))
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(3))
            });
    }
    // Layer edge and substrate surface on top, as the paper's black lines.
    paths!(back.layer_edge, LAYER_EDGE.stroke_width(2));
    paths!(back.surface, BLACK.stroke_width(2));
    *backdrop = Some(back);
    chart
        .draw_series(
            shape
                .markers
                .iter()
                .map(|p| Circle::new((p[0], p[1]), 4, BLACK.filled())),
        )
        .map_err(e)?
        .label("p_t, c, p_b")
        .legend(|(x, y)| Circle::new((x + 11, y), 4, BLACK.filled()));
    if opts.legend {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .margin(10)
            .label_font((FONT, (0.65 * fs) as i32))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .draw()
            .map_err(e)?;
    }
    let o = chart.backend_coord(&(0.0, 0.0));
    let px = chart.backend_coord(&(10.0, 0.0));
    let py = chart.backend_coord(&(0.0, 10.0));
    Ok(ShapeScale {
        px_per_um_x: (px.0 - o.0).abs() as f64 / 10.0,
        px_per_um_y: (py.1 - o.1).abs() as f64 / 10.0,
    })
}

/// Human name of a phase-end state.
pub fn phase_title(phase: &str) -> &str {
    match phase {
        "gravity" => "end of the gravity phase",
        "spreading" => "end of the spreading phase",
        "active" => "end of the active phase",
        "end" => "end of the run",
        other => other,
    }
}

/// The deformed cell of `state` as a PNG of [`SHAPE_SIZE`] at `path` (see
/// [`draw_shape`]); `view` from [`shape_view`].
pub fn shape_figure(
    path: &Path,
    name: &str,
    mesh: &MeshFile,
    state: &StateFile,
    view: Bounds,
) -> Result<ShapeScale, OutputError> {
    let root = BitMapBackend::new(path, SHAPE_SIZE).into_drawing_area();
    root.fill(&WHITE).map_err(|x| OutputError::draw(path, x))?;
    let opts = ShapeStyleOptions {
        title: format!(
            "{name}: {}, t = {} s",
            phase_title(&state.phase),
            group_thousands(state.t)
        ),
        legend: true,
        font: 28,
        mesh_lines: true,
    };
    let scale = draw_shape(&root, mesh, &state.u, view, &opts, &mut None)
        .map_err(|x| OutputError::draw(path, x))?;
    root.present().map_err(|x| OutputError::draw(path, x))?;
    Ok(scale)
}

/// All of one run's figures into `out`: `contact-radius.png`, `displacement.png`
/// (p_t, c and p_b), `strain.png` (mean ‖E‖ over time) and `shape-<phase>.png` for each
/// state file written. Works on partial runs (fewer rows, missing states). Returns the
/// files written.
pub fn plot_run(run: &RunData, out: &Path) -> Result<Vec<PathBuf>, OutputError> {
    super::create_dir(out)?;
    let mut written = Vec::new();
    let runs = [run];
    let p = out.join("contact-radius.png");
    contact_radius_figure(&p, &runs, &[], "")?;
    written.push(p);

    let p = out.join("displacement.png");
    let color = PALETTE[0];
    let plot = TimePlot {
        title: format!(
            "{}: vertical displacement of p_t, c and p_b",
            run_label(run)
        ),
        y_desc: "vertical displacement u_y (µm, negative = down)".into(),
        curves: vec![
            Curve {
                label: "nucleus top p_t".into(),
                points: points(&run.series, |o| o.uy_top),
                color,
                stroke: Stroke::Solid,
            },
            Curve {
                label: "centre c".into(),
                points: points(&run.series, |o| o.uy_centre),
                color: PALETTE[1],
                stroke: Stroke::Dashed,
            },
            Curve {
                label: "nucleus bottom p_b".into(),
                points: points(&run.series, |o| o.uy_bottom),
                color: PALETTE[2],
                stroke: Stroke::Dotted,
            },
        ],
        marks: vec![],
        phase_times: run.mesh.phase_times,
        after_active: "rest".into(),
        t_max: run.t_end(),
        legend: SeriesLabelPosition::LowerLeft,
    };
    time_figure(&p, &plot)?;
    written.push(p);

    let p = out.join("strain.png");
    strain_time_figure(&p, &runs)?;
    written.push(p);

    let states: Vec<&StateFile> = run.states.iter().collect();
    let view = shape_view(&run.mesh, &states);
    for s in &run.states {
        let p = out.join(format!("shape-{}.png", s.phase));
        shape_figure(&p, &run.name, &run.mesh, s, view)?;
        written.push(p);
    }
    Ok(written)
}
