//! The 3-D cell's deformation as an animated GIF (`--gif` on a 3-D run), the
//! [`super::movie::MovieOf`] of the 2-D movie with a painter of its own ([`View3Painter`]):
//! one frame per output time — at most [`MAX_FRAMES`], evenly picked, the last one always —
//! over a fixed frame, encoded with the `gif` crate.
//!
//! A frame is either the section z = 0 drawn as [`super::figures3::section_figure`] draws it
//! (the default: cheap, and the 2-D movie's picture), or any other [`MovieView`]: the
//! diagonal section, or the shaded surface view of the whole cell
//! ([`super::figures3::draw_surface`]; about three times the cost of a section frame on
//! the default mesh: 0.13 s against 0.04 s).

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use super::OutputError;
use super::figures::ShapeStyleOptions;
use super::figures3::{
    Camera, Coloring, Section, SectionBackdrop, SurfaceFrame, SurfaceStyleOptions, draw_section,
    draw_surface, gravity_at,
};
use super::geometry::{Bounds, substrate_floor};
pub use super::movie::{FRAME_DELAY_MS, FRAME_SIZE, MAX_FRAMES};
use super::movie::{FramePainter, MovieOf, movie_bounds};
use crate::record::{Mesh3File, Snapshot3};

/// NeuQuant speed of the colour quantisation of a section frame (few colours: the fastest
/// setting loses nothing visible).
const QUANT_SPEED_SECTION: i32 = 30;
/// NeuQuant speed for the surface view: its shading needs a finer palette.
const QUANT_SPEED_SURFACE: i32 = 10;

/// What each frame of a [`Movie3`] shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MovieView {
    /// The cell cut by a plane through its axis.
    Section(Section),
    /// The shaded surface of the whole cell on its substrate.
    Surface(Coloring),
}

/// What a movie shows, with its fixed frame.
enum Framing {
    Section(Section, Bounds),
    Surface(Coloring, Box<SurfaceFrame>),
}

/// An animated GIF of a 3-D run being written.
pub type Movie3 = MovieOf<View3Painter>;

/// Draws the frames of a 3-D movie: a section or the surface view ([`MovieView`]), over a
/// fixed frame.
pub struct View3Painter {
    mesh: Mesh3File,
    framing: Framing,
    backdrop: Option<SectionBackdrop>,
}

impl FramePainter for View3Painter {
    type State = Snapshot3;

    fn time(s: &Snapshot3) -> f64 {
        s.t
    }

    fn quant_speed(&self) -> i32 {
        match self.framing {
            Framing::Section(..) => QUANT_SPEED_SECTION,
            Framing::Surface(..) => QUANT_SPEED_SURFACE,
        }
    }

    fn paint(
        &mut self,
        area: &DrawingArea<BitMapBackend<'_>, Shift>,
        s: &Snapshot3,
        title: String,
    ) -> Result<(), String> {
        match &self.framing {
            Framing::Section(plane, view) => {
                let opts = ShapeStyleOptions {
                    title,
                    legend: false,
                    font: 20,
                    mesh_lines: false,
                    gravity: Some(gravity_at(&self.mesh, s.t)),
                };
                draw_section(
                    area,
                    &self.mesh,
                    &s.u,
                    *plane,
                    *view,
                    &opts,
                    &mut self.backdrop,
                )
                .map(|_| ())
            }
            Framing::Surface(coloring, frame) => {
                let opts = SurfaceStyleOptions {
                    title,
                    coloring: *coloring,
                    font: 20,
                    legend: false,
                };
                draw_surface(area, &self.mesh, s, frame, &opts)
            }
        }
    }
}

/// The frame of a section movie: the reference cell widened to 2.1 cell radii on each side
/// of the axis (room for spreading) and down to the substrate's floor (as the 2-D
/// [`super::movie::movie_view`]).
pub fn movie_view3(mesh: &Mesh3File) -> Bounds {
    let c = mesh.center;
    let r = mesh
        .nodes
        .iter()
        .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
        .fold(0.0f64, f64::max);
    movie_bounds(0.0, c[1], r, substrate_floor(&mesh.substrate.plane))
}

impl Movie3 {
    /// Starts a GIF of the section z = 0 at `path`; `outputs` is the number of output times
    /// expected.
    pub fn new(
        path: &Path,
        name: &str,
        mesh: &Mesh3File,
        outputs: usize,
    ) -> Result<Self, OutputError> {
        Self::with_view(path, name, mesh, outputs, MovieView::Section(Section::Z0))
    }

    /// Starts a GIF at `path` whose frames show `view`. A surface movie is framed on the
    /// substrate around the cell and the reference cell ([`SurfaceFrame::new`]).
    pub fn with_view(
        path: &Path,
        name: &str,
        mesh: &Mesh3File,
        outputs: usize,
        view: MovieView,
    ) -> Result<Self, OutputError> {
        let framing = match view {
            MovieView::Section(plane) => Framing::Section(plane, movie_view3(mesh)),
            MovieView::Surface(coloring) => Framing::Surface(
                coloring,
                Box::new(SurfaceFrame::new(mesh, &[], Camera::DEFAULT)),
            ),
        };
        let painter = View3Painter {
            mesh: mesh.clone(),
            framing,
            backdrop: None,
        };
        Self::start(path, name, mesh.phase_times, outputs, painter)
    }
}
