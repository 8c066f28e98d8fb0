//! The deformation as an animated GIF (the paper's Movies 1–3): one frame per output
//! time — at most [`MAX_FRAMES`], evenly picked, the last one always — each the full cell
//! drawn as in the shape figures (plotters into an RGB buffer), over a fixed frame chosen
//! from the reference cell and the substrate, encoded with the `gif` crate.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use plotters::prelude::*;

use super::OutputError;
use super::figures::{ShapeStyleOptions, draw_shape};
use super::geometry::{Backdrop, Bounds, substrate_floor};
use crate::record::MeshFile;
use crate::record::Snapshot;

/// Pixel size of a frame.
pub const FRAME_SIZE: (u32, u32) = (800, 560);
/// Largest number of frames in a movie.
pub const MAX_FRAMES: usize = 120;
/// Display time of a frame [ms].
pub const FRAME_DELAY_MS: u32 = 80;
/// NeuQuant speed of the colour quantisation (1 best … 30 fastest): the drawings have few
/// colours, so the fastest setting loses nothing visible.
const QUANT_SPEED: i32 = 30;

/// An animated GIF being written.
pub struct Movie {
    encoder: gif::Encoder<BufWriter<File>>,
    mesh: MeshFile,
    view: Bounds,
    name: String,
    path: PathBuf,
    stride: usize,
    offered: usize,
    frames: usize,
    skipped: Option<Snapshot>,
    backdrop: Option<Backdrop>,
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
    let half = c[0].abs() + 2.1 * r;
    let floor = substrate_floor(&mesh.substrate);
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

impl Movie {
    /// Starts a GIF at `path`; `outputs` is the number of output times expected.
    pub fn new(
        path: &Path,
        name: &str,
        mesh: &MeshFile,
        outputs: usize,
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
            mesh: mesh.clone(),
            view: movie_view(mesh),
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

    fn draw(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        let path = self.path.clone();
        let (w, h) = FRAME_SIZE;
        let mut rgb = vec![0u8; 3 * (w * h) as usize];
        {
            let area = BitMapBackend::with_buffer(&mut rgb, FRAME_SIZE).into_drawing_area();
            area.fill(&WHITE).map_err(|e| OutputError::draw(&path, e))?;
            let opts = ShapeStyleOptions {
                title: format!(
                    "{}   t = {:.0} s ({})",
                    self.name,
                    s.t,
                    self.phase_name(s.t)
                ),
                legend: false,
                font: 20,
                mesh_lines: false,
                gravity: None,
            };
            draw_shape(
                &area,
                &self.mesh,
                &s.u,
                self.view,
                &opts,
                &mut self.backdrop,
            )
            .map_err(|e| OutputError::draw(&path, e))?;
            area.present().map_err(|e| OutputError::draw(&path, e))?;
        }
        let mut frame = gif::Frame::from_rgb_speed(w as u16, h as u16, &rgb, QUANT_SPEED);
        frame.delay = (FRAME_DELAY_MS / 10) as u16;
        self.encoder
            .write_frame(&frame)
            .map_err(|e| gif_err(&path, e))?;
        self.frames += 1;
        Ok(())
    }

    /// Offers the state of one output time; every `stride`-th becomes a frame.
    pub fn frame(&mut self, s: &Snapshot) -> Result<(), OutputError> {
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
