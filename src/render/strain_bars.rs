//! The strain bars (the numbers of the paper's Fig. 7): the mean ‖E‖ of the nucleus and of
//! the cytoplasm at the end of the active phase, per scene, the paper's value beside ours
//! ([`strain_bars_figure`]). What it may import of [`super`]: [`super::draw`] and
//! [`super::time_plots`] (the cytoplasm's legend text, shared with the strain curves), and
//! the error types and [`super::draw_png`] of [`super`].

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};

use super::draw::{FONT, TIME_SIZE, anchored_text, column_label};
use super::time_plots::CYTOPLASM_LABEL;
use super::{DrawError, OutputError, draw_png};

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
    let pick_n = |b: &StrainBars| (b.paper_nucleus, b.ours_nucleus);
    let pick_c = |b: &StrainBars| (b.paper_cytoplasm, b.ours_cytoplasm);
    // One scale for both panels, so a bar's height compares across them.
    let top = strain_bars_top(bars);
    draw_png(path, TIME_SIZE, |root| {
        let root = root.titled(
            "Mean Green-Lagrange strain norm at the end of the active phase (one scale)",
            (FONT, 28),
        )?;
        let (left, right) = root.split_horizontally(TIME_SIZE.0 / 2);
        let panels: [(_, _, BarPick<'_>); 2] = [
            (left, "nucleus", &pick_n),
            (right, CYTOPLASM_LABEL, &pick_c),
        ];
        for (area, title, pick) in panels {
            draw_bars(&area, title, bars, pick, top, ours_label, paper_label)?;
        }
        Ok(())
    })
}

/// The top of the value axis (%) shared by both panels of [`strain_bars_figure`]: 1.3 ×
/// the largest value of either domain, paper's or ours (at least 13 %).
pub fn strain_bars_top(bars: &[StrainBars]) -> f64 {
    bars.iter()
        .flat_map(|b| {
            [
                b.paper_nucleus,
                b.ours_nucleus,
                b.paper_cytoplasm,
                b.ours_cytoplasm,
            ]
        })
        .flatten()
        .map(|v| 100.0 * v)
        .filter(|v| v.is_finite())
        .fold(10.0f64, f64::max)
        * 1.3
}

type BarPick<'a> = &'a dyn Fn(&StrainBars) -> (Option<f64>, Option<f64>);

fn draw_bars<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    bars: &[StrainBars],
    pick: BarPick<'_>,
    top: f64,
    ours_label: &str,
    paper_label: &str,
) -> Result<(), DrawError> {
    let n = bars.len().max(1);
    let names: Vec<String> = bars.iter().map(|b| b.scene.clone()).collect();
    let mut chart = ChartBuilder::on(area)
        .caption(title, (FONT, 24))
        .margin(16)
        .x_label_area_size(50)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..n as f64, 0.0..top)?;
    let fmt = |x: &f64| column_label(&names, *x);
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(2 * n + 1)
        .x_label_formatter(&fmt)
        .y_desc("mean ‖E‖ (%)")
        .axis_desc_style((FONT, 22))
        .label_style((FONT, 20))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()?;
    let paper_color = RGBColor(170, 170, 170);
    let ours_color = RGBColor(31, 119, 180);
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
            .draw_series(rects.iter().map(|r| Rectangle::new(*r, color.filled())))?
            .label(label)
            .legend(move |(x, y)| Rectangle::new([(x, y - 8), (x + 24, y + 8)], color.filled()));
    }
    chart.draw_series(
        texts
            .into_iter()
            .map(|(s, p)| Text::new(s, p, anchored_text(18, HPos::Center, VPos::Bottom))),
    )?;
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .margin(10)
        .label_font((FONT, 18))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}
