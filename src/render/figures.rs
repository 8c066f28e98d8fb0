//! `cellsim plot`: which figures a run directory gets ([`plot_run`]: the time plots, then
//! the 2-D cell's shapes, or for a 3-D run the sections and surface views of
//! [`super::cell3d_views`]) and the time curves of several runs on the same axes
//! ([`compare_runs`]). The figures themselves are drawn by [`super::draw`] (the
//! primitives), [`super::time_plots`], [`super::strain_bars`] and [`super::shapes`] (the
//! 2-D figures: their public items are re-exported here, at the paths they had when this
//! file drew them) and [`super::cell3d_views`] (the 3-D cell). This file may import any of
//! them; none of them imports it.

use std::path::{Path, PathBuf};

use plotters::prelude::SeriesLabelPosition;

// The figure modules' public items, at their paths from before the split.
pub use super::draw::{
    BOTTOM, CYTOPLASM, Curve, FOOT, GravityMark, LAYER, LAYER_EDGE, MEMBRANE, MarkShape, Marks,
    NUCLEUS, PAC, PALETTE, SHAPE_SIZE, SUBSTRATE, ShapeScale, ShapeStyleOptions, Stroke, TIME_SIZE,
    UPSIDE_DOWN_SIZE, domain_color, phase_title,
};
pub use super::scenes::run_phases;
pub use super::shapes::{draw_shape, shape_figure, shape_figure_cached, shape_view};
pub use super::strain_bars::{StrainBars, strain_bars_figure, strain_bars_top};
pub use super::time_plots::{
    CONTACT_DEFORMED_LABEL, CONTACT_REFERENCE_LABEL, CYTOPLASM_LABEL, Compared, DisplacementMarks,
    FLIP_PHASE, NUCLEUS_LOWEST_LABEL, SpanNote, TimePlot, contact_radius_figure,
    contact_radius_plot, displacement_figure, draw_time_plot, draw_time_plot_on, identical_note,
    identical_until, points, run_label, short_names, strain_time_figure, strain_time_plot,
    time_figure, upside_down_figure, value_axis, value_range,
};

use super::OutputError;
use super::time_plots::after_active_name;
use crate::run_files::{RunData, StateFile};

/// The time curves of several runs on the same axes (a 3-D scene beside its 2-D one,
/// say), into `out`: `compare-contact-radius.png`, `compare-displacement.png`,
/// `compare-strain.png`. Returns the files written.
pub fn compare_runs(runs: &[&RunData], out: &Path) -> Result<Vec<PathBuf>, OutputError> {
    super::create_dir(out)?;
    let files = [
        out.join("compare-contact-radius.png"),
        out.join("compare-displacement.png"),
        out.join("compare-strain.png"),
    ];
    // Runs of one case (a 3-D scene and the same case in 2-D) go by their directories.
    let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
    let unique = names.iter().collect::<std::collections::HashSet<_>>().len() == names.len();
    let renamed: Vec<RunData> = runs
        .iter()
        .map(|r| {
            let mut r = (*r).clone();
            if !unique {
                if let Some(d) = r.dir.file_name() {
                    r.name = d.to_string_lossy().into_owned();
                }
            }
            r
        })
        .collect();
    let runs: Vec<&RunData> = renamed.iter().collect();
    contact_radius_figure(&files[0], &runs, &[], "")?;
    displacement_figure(&files[1], &runs, &[], "")?;
    strain_time_figure(&files[2], &runs)?;
    Ok(files.to_vec())
}

/// All of one run's figures into `out`: `contact-radius.png` (both frames), `displacement.png`
/// (p_t, c, p_b and the nucleus's lowest point), `strain.png` (mean ‖E‖ over time) and `shape-<phase>.png` for each
/// state file written; for a 3-D run, [`super::cell3d_views::plot_quarter_run`]'s instead
/// of the shapes. Works on partial runs (fewer rows, missing states). Returns the files
/// written.
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
            "{}: vertical displacement of p_t, c, p_b and the nucleus's lowest point",
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
            Curve {
                label: NUCLEUS_LOWEST_LABEL.into(),
                points: points(&run.series, |o| o.uy_nucleus_max),
                color: PALETTE[3],
                stroke: Stroke::Dotted,
            },
        ],
        marks: vec![],
        links: vec![],
        notes: vec![],
        from_zero: false,
        phase_times: run.mesh.phase_times,
        after_active: after_active_name(Some(run)),
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
    let phases = run_phases(run);
    for s in &run.states {
        let p = out.join(format!("shape-{}.png", s.phase));
        shape_figure(&p, &run.name, &run.mesh, s, view, phases.as_ref())?;
        written.push(p);
    }
    if let Some(r3) = &run.three_d {
        written.extend(super::cell3d_views::plot_quarter_run(run, r3, out)?);
    }
    Ok(written)
}
