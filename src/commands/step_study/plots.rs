//! The figures of `cellsim study` ([`crate::commands::step_study`]), drawn from its report (the rows of
//! study.csv and the fits of study.json):
//!
//! - `work-precision.png`: relative error against wall time, log–log, one panel per
//!   quantity of interest, one line per integrator (BDF2 over its dt ladder, IDA over its
//!   rtol ladder), each point labelled with its dt or rtol;
//! - `dt-sensitivity.png`: left, BDF2's error against dt with the fitted slope of each
//!   quantity (and the fitted order, on the max-in-time error of uy(p_t)(t), printed); right, IDA's error
//!   against rtol with its slopes.

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

use crate::commands::step_study::{
    LogLogFit, ORDER_QUANTITY, Quantity, Role, StudyReport, StudyRow, TARGET_ERROR, fit_loglog,
    ladder_points, work_points,
};
use crate::render::figures::PALETTE;
use crate::render::{DrawError, OutputError, draw_png};

const FONT: &str = "sans-serif";
/// Pixel size of one panel.
const PANEL: (u32, u32) = (760, 600);
/// BDF2's colour.
const BDF2_COLOR: RGBColor = RGBColor(31, 119, 180);
/// IDA's colour.
const IDA_COLOR: RGBColor = RGBColor(214, 39, 40);
const GREY: RGBColor = RGBColor(110, 110, 110);

/// Draws both figures into `out`; returns their paths.
pub fn plot_study(report: &StudyReport, out: &Path) -> Result<Vec<PathBuf>, OutputError> {
    crate::render::create_dir(out)?;
    let wp = out.join("work-precision.png");
    work_precision_figure(&wp, report)?;
    let dt = out.join("dt-sensitivity.png");
    dt_sensitivity_figure(&dt, report)?;
    Ok(vec![wp, dt])
}

/// A log axis range covering `values` with a margin (a decade around a single value).
fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !(lo.is_finite() && hi > 0.0) {
        return (1e-3, 1.0);
    }
    // Whole-decade-ish padding: a factor 2 each side, and at least a decade shown.
    let (mut lo, mut hi) = (lo / 2.0, hi * 2.0);
    if hi / lo < 10.0 {
        let mid = (lo * hi).sqrt();
        lo = mid / 10f64.sqrt();
        hi = mid * 10f64.sqrt();
    }
    (lo, hi)
}

/// As [`log_range`], starting at a power of 10: plotters labels a log axis only from the
/// first power of 10 in range, so a range within one decade and a bit would show one or
/// two labels.
fn log_range_from_decade(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = log_range(values);
    (10f64.powf(lo.log10().floor()), hi)
}

/// Tick labels on a log axis: plain decimals between 1e-2 and 1e4, else 1e-5 style.
fn fmt_tick(v: &f64) -> String {
    let v = *v;
    if (1e-2..1e4).contains(&v) {
        let s = format!("{:.3}", v);
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.0e}")
    }
}

type LogChart<'a, 'b> = ChartContext<
    'a,
    BitMapBackend<'b>,
    Cartesian2d<
        plotters::coord::combinators::LogCoord<f64>,
        plotters::coord::combinators::LogCoord<f64>,
    >,
>;

fn log_chart<'a, 'b>(
    area: &'a DrawingArea<BitMapBackend<'b>, Shift>,
    title: &str,
    x: (f64, f64),
    y: (f64, f64),
    x_desc: &str,
    y_desc: &str,
) -> Result<LogChart<'a, 'b>, String> {
    let e = |x: DrawingAreaErrorKind<_>| x.to_string();
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 22))
        .margin(14)
        .margin_right(28)
        .x_label_area_size(55)
        .y_label_area_size(80)
        .build_cartesian_2d((x.0..x.1).log_scale(), (y.0..y.1).log_scale())
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        // Labels between the powers of 10 only on a short axis (they would crowd a long one).
        .x_labels(if x.1 / x.0 < 100.0 { 40 } else { 10 })
        .y_labels(12)
        .x_label_formatter(&fmt_tick)
        .y_label_formatter(&|v: &f64| format!("{v:.0e}"))
        .axis_desc_style((FONT, 18))
        .label_style((FONT, 15))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(e)?;
    Ok(chart)
}

/// One line with markers (squares or circles) and a legend entry.
fn draw_line<'a, 'b: 'a>(
    chart: &mut LogChart<'a, 'b>,
    pts: &[(f64, f64)],
    color: RGBColor,
    square: bool,
    label: &str,
) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<_>| x.to_string();
    let style = color.stroke_width(3);
    let anno = chart
        .draw_series(LineSeries::new(pts.iter().copied(), style))
        .map_err(e)?
        .label(label);
    let line = move |x: i32, y: i32| {
        EmptyElement::at((x, y)) + PathElement::new(vec![(0, 0), (30, 0)], color.stroke_width(3))
    };
    if square {
        anno.legend(move |(x, y)| line(x, y) + Rectangle::new([(10, -5), (20, 5)], color.filled()));
        chart
            .draw_series(
                pts.iter().map(|&p| {
                    EmptyElement::at(p) + Rectangle::new([(-5, -5), (5, 5)], color.filled())
                }),
            )
            .map_err(e)?;
    } else {
        anno.legend(move |(x, y)| line(x, y) + Circle::new((15, 0), 6, color.filled()));
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 6, color.filled())))
            .map_err(e)?;
    }
    Ok(())
}

/// Labels next to points.
fn draw_point_labels<'a, 'b: 'a>(
    chart: &mut LogChart<'a, 'b>,
    pts: &[(f64, f64)],
    labels: &[String],
    color: RGBColor,
) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<_>| x.to_string();
    let style = TextStyle::from((FONT, 13).into_font()).color(&color);
    chart
        .draw_series(
            pts.iter()
                .zip(labels)
                .map(|(&p, l)| EmptyElement::at(p) + Text::new(l.clone(), (8, -16), style.clone())),
        )
        .map_err(e)?;
    Ok(())
}

fn legend<'a, 'b: 'a>(
    chart: &mut LogChart<'a, 'b>,
    pos: SeriesLabelPosition,
) -> Result<(), String> {
    chart
        .configure_series_labels()
        .position(pos)
        .legend_area_size(40)
        .margin(10)
        .label_font((FONT, 15))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(|x| x.to_string())
}

fn knob_label(r: &StudyRow) -> String {
    match r.role {
        Role::Bdf2 => format!("dt={}", r.knob()),
        _ => format!("{:.0e}", r.rtol),
    }
}

/// (error, wall) points of a role with their labels, in ladder order.
fn labelled_work(rows: &[StudyRow], role: Role, q: Quantity) -> (Vec<(f64, f64)>, Vec<String>) {
    let pts = work_points(rows, role, q);
    let labels = rows
        .iter()
        .filter(|r| r.role == role && r.finished && r.error(q).is_some())
        .map(knob_label)
        .collect();
    (pts, labels)
}

fn grid(n: usize) -> (usize, usize) {
    match n {
        0 | 1 => (1, 1),
        2 => (1, 2),
        3 | 4 => (2, 2),
        _ => (n.div_ceil(3), 3),
    }
}

/// Draws `work-precision.png`.
pub fn work_precision_figure(path: &Path, report: &StudyReport) -> Result<(), OutputError> {
    let qs = &report.settings.quantities;
    let (nr, nc) = grid(qs.len());
    let size = (PANEL.0 * nc as u32, PANEL.1 * nr as u32 + 50);
    draw_png(path, size, |root| {
        let title = format!(
            "Work-precision, {}: relative error against the reference (IDA, rtol {:.0e}) vs wall time",
            report.case, report.reference.rtol
        );
        let root = root.titled(&title, (FONT, 26))?;
        let panels = root.split_evenly((nr, nc));
        for (k, &q) in qs.iter().enumerate() {
            let rows = &report.runs;
            let (bp, bl) = labelled_work(rows, Role::Bdf2, q);
            let (ip, il) = labelled_work(rows, Role::Ida, q);
            let x = log_range_from_decade(bp.iter().chain(&ip).map(|p| p.1));
            let mut ys: Vec<f64> = bp.iter().chain(&ip).map(|p| p.0).collect();
            // The errors at which the speed-up was measured on this quantity: the final uy_top
            // at the target, the curve at each error both ladders reach.
            let measured: Vec<f64> = match q {
                Quantity::UyTop if report.ida_speedup.is_some() => vec![TARGET_ERROR],
                Quantity::UyTopCurve => report
                    .speedup_curve
                    .iter()
                    .filter(|p| p.ratio.is_some())
                    .map(|p| p.error)
                    .collect(),
                _ => Vec::new(),
            };
            ys.extend(&measured);
            let y = log_range(ys.into_iter());
            // Headroom above the data for the legend.
            let y = (y.0, y.1 * 30.0);
            // Error on x is conventional in SciML's work-precision diagrams; here the wall
            // time is on x so that "cheaper" is left and "more accurate" is down.
            let mut chart = log_chart(
                &panels[k],
                &format!("error of the {}", q.title()),
                x,
                y,
                "wall time of the integration (s)",
                "relative error (–)",
            )
            .map_err(DrawError)?;
            if !measured.is_empty() {
                let at = measured
                    .iter()
                    .map(|t| format!("{t:.0e}"))
                    .collect::<Vec<_>>()
                    .join(", ");
                chart
                    .draw_series(measured.iter().map(|&t| {
                        DashedPathElement::new(vec![(x.0, t), (x.1, t)], 8, 6, GREY.stroke_width(2))
                    }))?
                    .label(format!("speed-up measured at {at}"))
                    .legend(|(x, y)| {
                        DashedPathElement::new(
                            vec![(x, y), (x + 30, y)],
                            6,
                            4,
                            GREY.stroke_width(2),
                        )
                    });
            }
            // Points as (wall, error).
            let swap = |v: &[(f64, f64)]| v.iter().map(|p| (p.1, p.0)).collect::<Vec<_>>();
            if !bp.is_empty() {
                draw_line(&mut chart, &swap(&bp), BDF2_COLOR, false, "BDF2 (fixed dt)")
                    .map_err(DrawError)?;
                draw_point_labels(&mut chart, &swap(&bp), &bl, BDF2_COLOR).map_err(DrawError)?;
            }
            if !ip.is_empty() {
                draw_line(&mut chart, &swap(&ip), IDA_COLOR, true, "IDA (rtol ladder)")
                    .map_err(DrawError)?;
                draw_point_labels(&mut chart, &swap(&ip), &il, IDA_COLOR).map_err(DrawError)?;
            }
            legend(&mut chart, SeriesLabelPosition::UpperRight).map_err(DrawError)?;
        }
        Ok(())
    })
}

/// Draws `dt-sensitivity.png`.
pub fn dt_sensitivity_figure(path: &Path, report: &StudyReport) -> Result<(), OutputError> {
    let size = (PANEL.0 * 2 + 120, PANEL.1 + 100);
    draw_png(path, size, |root| {
        let title = format!(
            "Time-step sensitivity, {}: relative error against the reference (IDA, rtol {:.0e})",
            report.case, report.reference.rtol
        );
        let root = root.titled(&title, (FONT, 26))?;
        let panels = root.split_evenly((1, 2));
        for (k, role) in [Role::Bdf2, Role::Ida].into_iter().enumerate() {
            ladder_panel(&panels[k], report, role).map_err(DrawError)?;
        }
        Ok(())
    })
}

/// The title and x axis label of the panel of `role`'s ladder (BDF2's with its order).
fn ladder_panel_title(report: &StudyReport, role: Role) -> (String, &'static str) {
    match role {
        Role::Bdf2 => (
            match report.bdf2_order {
                Some(p) => {
                    format!("BDF2: error vs step dt — fitted order (uy(p_t)(t) curve) {p:.2}")
                }
                None => "BDF2: error vs step dt (no fit: fewer than 2 rungs)".into(),
            },
            "BDF2 time step dt (s)",
        ),
        _ => (
            "IDA: error vs relative tolerance rtol".to_string(),
            "IDA relative tolerance rtol (–)",
        ),
    }
}

/// One panel of `dt-sensitivity.png`: the error of each quantity against the knob of
/// `role`'s ladder (dt or rtol) with its slope, and the fit on [`ORDER_QUANTITY`].
fn ladder_panel(
    area: &DrawingArea<BitMapBackend<'_>, Shift>,
    report: &StudyReport,
    role: Role,
) -> Result<(), String> {
    let qs = &report.settings.quantities;
    let rows = &report.runs;
    let lines: Vec<(Quantity, Vec<(f64, f64)>)> = qs
        .iter()
        .map(|&q| (q, ladder_points(rows, role, q)))
        .collect();
    let x = log_range(lines.iter().flat_map(|l| l.1.iter().map(|p| p.0)));
    let y = log_range(lines.iter().flat_map(|l| l.1.iter().map(|p| p.1)));
    // Headroom above the data for the legend.
    let y = (y.0, y.1 * 300.0);
    let (title, x_desc) = ladder_panel_title(report, role);
    let mut chart = log_chart(area, &title, x, y, x_desc, "relative error (–)")?;
    for (j, (q, pts)) in lines.iter().enumerate() {
        if pts.is_empty() {
            continue;
        }
        let color = PALETTE[j % PALETTE.len()];
        let slope = fit_loglog(pts)
            .map(|f| format!("slope {:.2}", f.slope))
            .unwrap_or_else(|| "no fit".into());
        draw_line(
            &mut chart,
            pts,
            color,
            role == Role::Ida,
            &format!("{} ({slope})", q.title()),
        )?;
        if *q == ORDER_QUANTITY {
            if let Some(f) = fit_loglog(pts) {
                draw_fit(&mut chart, pts, f, role)?;
            }
        }
    }
    legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// The fitted line of a ladder's `pts` over their span (dashed), the theory's slope beside
/// it, and the fitted slope printed by the line.
fn draw_fit<'a, 'b: 'a>(
    chart: &mut LogChart<'a, 'b>,
    pts: &[(f64, f64)],
    f: LogLogFit,
    role: Role,
) -> Result<(), String> {
    let e = |x: DrawingAreaErrorKind<_>| x.to_string();
    let (a, b) = pts.iter().fold((f64::INFINITY, 0.0_f64), |(a, b), p| {
        (a.min(p.0), b.max(p.0))
    });
    let line: Vec<(f64, f64)> = (0..=20)
        .map(|i| {
            let xx = a * (b / a).powf(i as f64 / 20.0);
            (xx, f.eval(xx))
        })
        .collect();
    chart
        .draw_series(std::iter::once(DashedPathElement::new(
            line,
            10,
            6,
            BLACK.stroke_width(2),
        )))
        .map_err(e)?
        .label(format!(
            "fit: error ∝ {}^{:.2}",
            if role == Role::Bdf2 { "dt" } else { "rtol" },
            f.slope
        ))
        .legend(move |(x, y)| {
            DashedPathElement::new(vec![(x, y), (x + 30, y)], 6, 4, BLACK.stroke_width(2))
        });
    chart
        .draw_series(std::iter::once(DashedPathElement::new(
            theory_guide(pts, role, (a, b)),
            3,
            5,
            GREY.stroke_width(2),
        )))
        .map_err(e)?
        .label(match role {
            Role::Bdf2 => "slope 2 (BDF2's order), through the smallest dt",
            _ => "error = rtol",
        })
        .legend(|(x, y)| {
            DashedPathElement::new(vec![(x, y), (x + 30, y)], 3, 4, GREY.stroke_width(2))
        });
    // The slope printed on the plot, beside the middle of the fitted line.
    let mid = (a * b).sqrt();
    let style = TextStyle::from((FONT, 22).into_font()).color(&BLACK);
    chart
        .draw_series(std::iter::once(
            EmptyElement::at((mid, f.eval(mid)))
                + Text::new(format!("slope {:.2}", f.slope), (12, 14), style),
        ))
        .map_err(e)?;
    Ok(())
}

/// The theory's slope for comparison over the span (a, b) of a ladder's `pts`: order 2
/// for BDF2 (through the smallest dt), error = rtol for IDA.
fn theory_guide(pts: &[(f64, f64)], role: Role, (a, b): (f64, f64)) -> Vec<(f64, f64)> {
    match role {
        Role::Bdf2 => {
            let p0 = pts
                .iter()
                .fold(pts[0], |m, p| if p.0 < m.0 { *p } else { m });
            [a, b]
                .iter()
                .map(|&xx| (xx, p0.1 * (xx / p0.0).powi(2)))
                .collect()
        }
        _ => [a, b].iter().map(|&xx| (xx, xx)).collect(),
    }
}

/// One series of a [`loglog_figure`] panel: measured points (markers and a line) and, when
/// given, the least-squares power law through them (dashed, its exponent in the legend).
pub struct LogLogSeries {
    /// Legend label.
    pub label: String,
    /// (x, y) points, both positive.
    pub points: Vec<(f64, f64)>,
    /// Draw the fitted power law y = c x^α and write α in the label.
    pub fit: bool,
}

/// One panel of a [`loglog_figure`].
pub struct LogLogPanel {
    /// Panel title.
    pub title: String,
    /// x axis label.
    pub x_desc: String,
    /// y axis label.
    pub y_desc: String,
    /// The series, each in its own colour.
    pub series: Vec<LogLogSeries>,
}

/// Draws `panels` side by side, log–log, under `title`, into the PNG `path`.
pub fn loglog_figure(path: &Path, title: &str, panels: &[LogLogPanel]) -> Result<(), OutputError> {
    let n = panels.len().max(1);
    let size = (PANEL.0 * n as u32, PANEL.1 + 50);
    draw_png(path, size, |root| {
        let root = root.titled(title, (FONT, 24))?;
        let areas = root.split_evenly((1, n));
        for (panel, area) in panels.iter().zip(&areas) {
            let all = || panel.series.iter().flat_map(|s| s.points.iter());
            let x = log_range_from_decade(all().map(|p| p.0));
            let y = log_range(all().map(|p| p.1));
            // Headroom above the data for the legend.
            let y = (y.0, y.1 * 8.0);
            let mut chart = log_chart(area, &panel.title, x, y, &panel.x_desc, &panel.y_desc)
                .map_err(DrawError)?;
            for (k, s) in panel.series.iter().enumerate() {
                let color = PALETTE[k % PALETTE.len()];
                let fit = if s.fit { fit_loglog(&s.points) } else { None };
                let label = match &fit {
                    Some(f) => format!("{} (fit: ∝ n^{:.2})", s.label, f.slope),
                    None => s.label.clone(),
                };
                draw_line(&mut chart, &s.points, color, k % 2 == 1, &label).map_err(DrawError)?;
                if let Some(f) = fit {
                    let ends = [x.0, x.1].map(|v| (v, (f.intercept + f.slope * v.ln()).exp()));
                    chart.draw_series(std::iter::once(DashedPathElement::new(
                        ends.to_vec(),
                        8,
                        6,
                        color.stroke_width(1),
                    )))?;
                }
            }
            legend(&mut chart, SeriesLabelPosition::UpperLeft).map_err(DrawError)?;
        }
        Ok(())
    })
}
