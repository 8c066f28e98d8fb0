//! The 3-D cell's deformation as an animated GIF (`--gif` on a 3-D run), with the interface
//! of the 2-D [`super::movie::Movie`]: one frame per output time — at most [`MAX_FRAMES`],
//! evenly picked, the last one always — over a fixed frame, encoded with the `gif` crate.
//!
//! A frame is either the section z = 0 drawn as [`super::figures3::section_figure`] draws it
//! (the default: cheap, and the 2-D movie's picture), or any other [`MovieView`]: the
//! diagonal section, or the shaded surface view of the whole cell
//! ([`super::figures3::draw_surface`]; about three times the cost of a section frame on
//! the default mesh: 0.13 s against 0.04 s).

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::OutputError;
use super::figures::ShapeStyleOptions;
use super::figures3::{
    Camera, Coloring, Section, SectionBackdrop, SurfaceFrame, SurfaceStyleOptions, draw_section,
    draw_surface, gravity_at,
};
use super::geometry::{Bounds, substrate_floor};
pub use super::movie::{FRAME_DELAY_MS, FRAME_SIZE, MAX_FRAMES};
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
pub struct Movie3 {
    encoder: gif::Encoder<BufWriter<File>>,
    mesh: Mesh3File,
    framing: Framing,
    name: String,
    path: PathBuf,
    stride: usize,
    offered: usize,
    frames: usize,
    skipped: Option<Snapshot3>,
    backdrop: Option<SectionBackdrop>,
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
    let half = 2.1 * r;
    let floor = substrate_floor(&mesh.substrate.plane);
    Bounds {
        x_min: -half,
        x_max: half,
        y_min: floor.min(c[1] - r) - 1.0,
        y_max: c[1] + r + 1.5,
    }
}

fn gif_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Write {
        path: path.display().to_string(),
        source: std::io::Error::other(e.to_string()),
    }
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
        let file = File::create(path).map_err(|e| OutputError::write(path, e))?;
        let (w, h) = FRAME_SIZE;
        let mut encoder = gif::Encoder::new(BufWriter::new(file), w as u16, h as u16, &[])
            .map_err(|e| gif_err(path, e))?;
        encoder
            .set_repeat(gif::Repeat::Infinite)
            .map_err(|e| gif_err(path, e))?;
        let framing = match view {
            MovieView::Section(plane) => Framing::Section(plane, movie_view3(mesh)),
            MovieView::Surface(coloring) => Framing::Surface(
                coloring,
                Box::new(SurfaceFrame::new(mesh, &[], Camera::DEFAULT)),
            ),
        };
        Ok(Self {
            encoder,
            mesh: mesh.clone(),
            framing,
            name: name.to_string(),
            path: path.to_path_buf(),
            stride: outputs.div_ceil(MAX_FRAMES).max(1),
            offered: 0,
            frames: 0,
            skipped: None,
            backdrop: None,
        })
    }

    fn phase_name(&self, t: f64) -> &'static str {
        let [tg, tas, ta, _] = self.mesh.phase_times;
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

    fn draw(&mut self, s: &Snapshot3) -> Result<(), OutputError> {
        let path = self.path.clone();
        let (w, h) = FRAME_SIZE;
        let mut rgb = vec![0u8; 3 * (w * h) as usize];
        let title = format!(
            "{}   t = {:.0} s ({})",
            self.name,
            s.t,
            self.phase_name(s.t)
        );
        {
            let area = BitMapBackend::with_buffer(&mut rgb, FRAME_SIZE).into_drawing_area();
            area.fill(&WHITE).map_err(|e| OutputError::draw(&path, e))?;
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
                        &area,
                        &self.mesh,
                        &s.u,
                        *plane,
                        *view,
                        &opts,
                        &mut self.backdrop,
                    )
                    .map_err(|e| OutputError::draw(&path, e))?;
                }
                Framing::Surface(coloring, frame) => {
                    let opts = SurfaceStyleOptions {
                        title,
                        coloring: *coloring,
                        font: 20,
                        legend: false,
                    };
                    draw_surface(&area, &self.mesh, s, frame, &opts)
                        .map_err(|e| OutputError::draw(&path, e))?;
                }
            }
            area.present().map_err(|e| OutputError::draw(&path, e))?;
        }
        let speed = match self.framing {
            Framing::Section(..) => QUANT_SPEED_SECTION,
            Framing::Surface(..) => QUANT_SPEED_SURFACE,
        };
        let mut frame = gif::Frame::from_rgb_speed(w as u16, h as u16, &rgb, speed);
        frame.delay = (FRAME_DELAY_MS / 10) as u16;
        self.encoder
            .write_frame(&frame)
            .map_err(|e| gif_err(&path, e))?;
        self.frames += 1;
        Ok(())
    }

    /// Offers the state of one output time; every `stride`-th becomes a frame.
    pub fn frame(&mut self, s: &Snapshot3) -> Result<(), OutputError> {
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
