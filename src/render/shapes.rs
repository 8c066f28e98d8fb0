//! The shape figures of the 2-D cell (the paper's Figs. 5, 6a, 8): the deformed cell of
//! one state file, mirrored to the full cell, drawn by the plane drawing of
//! [`super::draw`] over a view that several states can share ([`shape_view`],
//! [`draw_shape`], [`shape_figure`]). What it may import of [`super`]: [`super::draw`] and
//! [`super::geometry`], and the error types and [`super::draw_png`] of [`super`].

use std::path::Path;
use std::sync::Mutex;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::draw::{
    GravityMark, PlaneDrawing, SHAPE_SIZE, ShapeScale, ShapeStyleOptions, check_displacements,
    draw_in_plane, group_thousands, phase_title,
};
use super::geometry::{Backdrop, Bounds, CellShape, substrate_floor};
use super::{DrawError, OutputError, draw_png};
use crate::physics::Phases;
use crate::run_files::{MeshFile, StateFile};

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
    b.around_axis(substrate_floor(&mesh.substrate))
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
) -> Result<ShapeScale, DrawError> {
    check_displacements(u, mesh.nodes.len())?;
    // The cell, mirrored to the full cell.
    let shape = CellShape::new(mesh, u).mirrored();
    let cell = PlaneDrawing {
        x_label: "x (µm)",
        substrate_label: "substrate".to_string(),
        layer: mesh.layer_thickness.is_some(),
        shape: &shape,
        mesh_lines: None,
    };
    draw_in_plane(
        area,
        &cell,
        view,
        opts,
        backdrop,
        |cached, key, columns| match cached {
            Some(b) if b.view == key => b,
            _ => Backdrop::new(&mesh.substrate, mesh.layer_thickness, key, columns),
        },
    )
}

/// The deformed cell of `state` as a PNG of [`SHAPE_SIZE`] at `path` (see
/// [`draw_shape`]); `view` from [`shape_view`].
pub fn shape_figure(
    path: &Path,
    name: &str,
    mesh: &MeshFile,
    state: &StateFile,
    view: Bounds,
    phases: Option<&Phases>,
) -> Result<ShapeScale, OutputError> {
    shape_figure_cached(path, name, mesh, state, view, phases, &Mutex::new(None))
}

/// As [`shape_figure`], with the substrate drawing shared through `cache` by figures of
/// the same view and substrate (figures drawn at once: each takes a copy, and the first
/// computed is kept).
pub fn shape_figure_cached(
    path: &Path,
    name: &str,
    mesh: &MeshFile,
    state: &StateFile,
    view: Bounds,
    phases: Option<&Phases>,
    cache: &Mutex<Option<Backdrop>>,
) -> Result<ShapeScale, OutputError> {
    let mut backdrop = cache.lock().ok().and_then(|c| c.clone());
    let opts = ShapeStyleOptions {
        title: format!(
            "{name}: {}, t = {} s",
            phase_title(&state.phase),
            group_thousands(state.t)
        ),
        legend: true,
        font: 28,
        mesh_lines: true,
        gravity: phases.map(|p| GravityMark::at(p, state.t)),
    };
    let scale = draw_png(path, SHAPE_SIZE, |root| {
        draw_shape(root, mesh, &state.u, view, &opts, &mut backdrop)
    })?;
    if let Ok(mut c) = cache.lock() {
        if c.is_none() {
            *c = backdrop;
        }
    }
    Ok(scale)
}
