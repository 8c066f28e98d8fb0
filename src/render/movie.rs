//! The deformation as an animated GIF (the paper's Movies 1–3): one frame per output
//! time — at most [`MAX_FRAMES`], evenly picked, the last one always — each the full cell
//! drawn as in the shape figures (plotters into an RGB buffer), over a fixed frame chosen
//! from the reference cell and the substrate, encoded with the `gif` crate.
//!
//! [`MovieOf`] is the GIF of either model: the encoder, the choice of frames and their
//! titles; a [`FramePainter`] draws each frame — [`ShapePainter`] the 2-D cell,
//! [`QuarterPainter`] a view of the 3-D cell ([`QuarterMovie`], `--gif` on a 3-D run).
//!
//! A 3-D frame is either the section z = 0 drawn as
//! [`super::cell3d_views::section_figure`] draws it (the default: cheap, and the 2-D
//! movie's picture), or any other [`MovieView`]: the diagonal section, or the shaded surface
//! view of the whole cell ([`super::cell3d_views::draw_surface`]; about three times the
//! cost of a section frame on the default mesh: 0.13 s against 0.04 s).

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;

use super::cell3d_views::{
    Camera, Coloring, Section, SectionBackdrop, SurfaceFrame, SurfaceStyleOptions, draw_section,
    draw_surface, gravity_at,
};
use super::draw::ShapeStyleOptions;
use super::geometry::{Backdrop, Bounds, substrate_floor};
use super::shapes::draw_shape;
use super::{DrawError, OutputError};
use crate::run_files::{MeshFile, QuarterMeshFile, QuarterSnapshot, Snapshot, Timed};

/// A movie frame's drawing area.
type Frame<'b> = DrawingArea<BitMapBackend<'b>, Shift>;

/// Pixel size of a frame.
pub const FRAME_SIZE: (u32, u32) = (800, 560);
/// Largest number of frames in a movie.
pub const MAX_FRAMES: usize = 120;
/// Display time of a frame \[ms\].
pub const FRAME_DELAY_MS: u32 = 80;
/// NeuQuant speed of the colour quantisation (1 best … 30 fastest): the drawings of the
/// cell (the 2-D cell, a section of the 3-D one) have few colours, so the fastest setting
/// loses nothing visible.
const QUANT_SPEED: i32 = 30;
/// NeuQuant speed for the surface view of the 3-D cell: its shading needs a finer palette.
const QUANT_SPEED_SURFACE: i32 = 10;

/// What draws the frames of a [`MovieOf`]: the 2-D cell ([`ShapePainter`]) or a view of
/// the 3-D cell ([`QuarterPainter`]).
pub trait FramePainter: Sized {
    /// The state of one output time.
    type State: Timed;
    /// The mesh of the run drawn.
    type Mesh;
    /// The painter of a run on `mesh` when no other view is asked for (the 2-D cell, the
    /// 3-D cell's section z = 0), with the run's phase end times T_g0, T_as0, T_a0 and the
    /// end time.
    fn for_run(mesh: &Self::Mesh) -> (Self, [f64; 4]);
    /// NeuQuant speed of the colour quantisation of a frame (1 best … 30 fastest).
    fn quant_speed(&self) -> i32;
    /// Draws `s` with the title `title` into the frame `area` (filled white).
    fn paint(&mut self, area: &Frame, s: &Self::State, title: String) -> Result<(), DrawError>;
}

/// An animated GIF being written, each frame drawn by the painter `P`.
pub struct MovieOf<P: FramePainter> {
    encoder: gif::Encoder<BufWriter<File>>,
    painter: P,
    phase_times: [f64; 4],
    name: String,
    path: PathBuf,
    stride: usize,
    offered: usize,
    frames: usize,
    skipped: Option<P::State>,
}

/// An animated GIF of a 2-D run being written.
pub type Movie = MovieOf<ShapePainter>;

/// Draws the frames of a 2-D movie: the full cell as in the shape figures, without legend
/// or mesh lines, over the fixed [`movie_view`].
pub struct ShapePainter {
    mesh: MeshFile,
    view: Bounds,
    backdrop: Option<Backdrop>,
}

impl FramePainter for ShapePainter {
    type State = Snapshot;
    type Mesh = MeshFile;

    fn for_run(mesh: &MeshFile) -> (Self, [f64; 4]) {
        let painter = ShapePainter {
            mesh: mesh.clone(),
            view: movie_view(mesh),
            backdrop: None,
        };
        (painter, mesh.phase_times)
    }

    fn quant_speed(&self) -> i32 {
        QUANT_SPEED
    }

    fn paint(&mut self, area: &Frame, s: &Snapshot, title: String) -> Result<(), DrawError> {
        let opts = ShapeStyleOptions {
            title,
            legend: false,
            font: 20,
            mesh_lines: false,
            gravity: None,
        };
        draw_shape(area, &self.mesh, &s.u, self.view, &opts, &mut self.backdrop).map(|_| ())
    }
}

/// The frame of a movie: the reference cell widened to 2.1 cell radii on each side of
/// the symmetry line (room for spreading) and down to the substrate's floor.
pub fn movie_view(mesh: &MeshFile) -> Bounds {
    let c = mesh.center;
    let r = mesh
        .nodes
        .iter()
        .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt())
        .fold(0.0f64, f64::max);
    movie_bounds(c[0].abs(), c[1], r, substrate_floor(&mesh.substrate))
}

/// The frame of a movie of a cell of radius `r` whose centre is at height `c_y` and at
/// `axis_offset` from the symmetry axis: `axis_offset` + 2.1 `r` on each side of the axis,
/// from 1 µm below the cell's bottom or the substrate's `floor` (the lower) to 1.5 µm
/// above the cell's top. Shared by [`movie_view`] and [`quarter_movie_view`].
pub(crate) fn movie_bounds(axis_offset: f64, c_y: f64, r: f64, floor: f64) -> Bounds {
    let half = axis_offset + 2.1 * r;
    Bounds {
        x_min: -half,
        x_max: half,
        y_min: floor.min(c_y - r) - 1.0,
        y_max: c_y + r + 1.5,
    }
}

fn gif_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write {
        path: path.display().to_string(),
        source: std::io::Error::other(e.to_string()),
    }
}

impl<P: FramePainter> MovieOf<P> {
    /// Starts a GIF at `path` of the run `name` on `mesh`, drawn by its default painter
    /// ([`FramePainter::for_run`]: the 2-D cell, the 3-D section z = 0); `outputs` is the
    /// number of output times expected.
    pub fn new(
        path: &Path,
        name: &str,
        mesh: &P::Mesh,
        outputs: usize,
    ) -> Result<Self, OutputError> {
        let (painter, phase_times) = P::for_run(mesh);
        Self::start(path, name, phase_times, outputs, painter)
    }

    /// Starts a GIF at `path` whose frames `painter` draws, titled with the run's `name`,
    /// the time and its phase (from `phase_times`: T_g0, T_as0, T_a0, the end time);
    /// `outputs` is the number of output times expected.
    pub fn start(
        path: &Path,
        name: &str,
        phase_times: [f64; 4],
        outputs: usize,
        painter: P,
    ) -> Result<Self, OutputError> {
        let file = File::create(path).map_err(|e| OutputError::write(path, e))?;
        let (w, h) = FRAME_SIZE;
        let mut encoder = gif::Encoder::new(BufWriter::new(file), w as u16, h as u16, &[])
            .map_err(|e| gif_err(path, e))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .map_err(|e| gif_err(path, e))?;
        Ok(Self {
            encoder,
            painter,
            phase_times,
            name: name.to_string(),
            path: path.to_path_buf(),
            stride: outputs.div_ceil(MAX_FRAMES).max(1),
            offered: 0,
            frames: 0,
            skipped: None,
        })
    }

    fn phase_name(&self, t: f64) -> &'static str {
        let [tg, tas, ta, _] = self.phase_times;
        if t <= tg {
            "gravity"
        } else if t <= tas {
            "spreading"
        } else if t <= ta {
            "active"
        } else {
            "after the active phase"
        }
    }

    fn draw(&mut self, s: &P::State) -> Result<(), OutputError> {
        let path = self.path.clone();
        let (w, h) = FRAME_SIZE;
        let mut rgb = vec![0u8; 3 * (w * h) as usize];
        let t = s.time();
        let title = format!("{}   t = {:.0} s ({})", self.name, t, self.phase_name(t));
        {
            let area = BitMapBackend::with_buffer(&mut rgb, FRAME_SIZE).into_drawing_area();
            area.fill(&WHITE).map_err(|e| OutputError::draw(&path, e))?;
            self.painter
                .paint(&area, s, title)
                .map_err(|e| OutputError::draw(&path, e))?;
            area.present().map_err(|e| OutputError::draw(&path, e))?;
        }
        let speed = self.painter.quant_speed();
        let mut frame = gif::Frame::from_rgb_speed(w as u16, h as u16, &rgb, speed);
        frame.delay = (FRAME_DELAY_MS / 10) as u16;
        self.encoder
            .write_frame(&frame)
            .map_err(|e| gif_err(&path, e))?;
        self.frames += 1;
        Ok(())
    }

    /// Offers the state of one output time; every `stride`-th becomes a frame.
    pub fn frame(&mut self, s: &P::State) -> Result<(), OutputError> {
        let take = self.offered % self.stride == 0;
        self.offered += 1;
        if take {
            self.draw(s)?;
            self.skipped = None;
        } else {
            self.skipped = Some(s.clone());
        }
        Ok(())
    }

    /// Adds the last state offered if it was skipped, and closes the file (the GIF
    /// trailer is written when the encoder is dropped).
    pub fn finish(mut self) -> Result<PathBuf, OutputError> {
        if let Some(s) = self.skipped.take() {
            self.draw(&s)?;
        }
        Ok(self.path)
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }
}

/// What each frame of a [`QuarterMovie`] shows.
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
pub type QuarterMovie = MovieOf<QuarterPainter>;

/// Draws the frames of a 3-D movie: a section or the surface view ([`MovieView`]), over a
/// fixed frame.
pub struct QuarterPainter {
    mesh: QuarterMeshFile,
    framing: Framing,
    backdrop: Option<SectionBackdrop>,
}

impl QuarterPainter {
    /// The painter of `view` of the cell on `mesh`. A surface view is framed on the
    /// substrate around the cell and the reference cell ([`SurfaceFrame::new`]).
    fn with_view(mesh: &QuarterMeshFile, view: MovieView) -> Self {
        let framing = match view {
            MovieView::Section(plane) => Framing::Section(plane, quarter_movie_view(mesh)),
            MovieView::Surface(coloring) => Framing::Surface(
                coloring,
                Box::new(SurfaceFrame::new(mesh, &[], Camera::DEFAULT)),
            ),
        };
        QuarterPainter {
            mesh: mesh.clone(),
            framing,
            backdrop: None,
        }
    }
}

impl FramePainter for QuarterPainter {
    type State = QuarterSnapshot;
    type Mesh = QuarterMeshFile;

    fn for_run(mesh: &QuarterMeshFile) -> (Self, [f64; 4]) {
        let painter = QuarterPainter::with_view(mesh, MovieView::Section(Section::Z0));
        (painter, mesh.phase_times)
    }

    fn quant_speed(&self) -> i32 {
        match self.framing {
            Framing::Section(..) => QUANT_SPEED,
            Framing::Surface(..) => QUANT_SPEED_SURFACE,
        }
    }

    fn paint(&mut self, area: &Frame, s: &QuarterSnapshot, title: String) -> Result<(), DrawError> {
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
/// [`movie_view`]).
pub fn quarter_movie_view(mesh: &QuarterMeshFile) -> Bounds {
    let c = mesh.center;
    let r = mesh
        .nodes
        .iter()
        .map(|p| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt())
        .fold(0.0f64, f64::max);
    movie_bounds(0.0, c[1], r, substrate_floor(&mesh.substrate.plane))
}

impl QuarterMovie {
    /// Starts a GIF at `path` whose frames show `view`. A surface movie is framed on the
    /// substrate around the cell and the reference cell ([`SurfaceFrame::new`]).
    pub fn with_view(
        path: &Path,
        name: &str,
        mesh: &QuarterMeshFile,
        outputs: usize,
        view: MovieView,
    ) -> Result<Self, OutputError> {
        let painter = QuarterPainter::with_view(mesh, view);
        Self::start(path, name, mesh.phase_times, outputs, painter)
    }
}
