//! Everything drawn or exported from what a run wrote: figures (PNG), the paper's
//! comparison, ParaView files and animations.
//!
//! The rule of this module: **plotting reads only files a run wrote** (`timeseries.csv`,
//! `mesh.json`, `state_<phase>.json`, `summary.json`, loaded by [`crate::run_files::read`] as a [`RunData`], tolerant of
//! partial files), never the
//! solver's memory, so every figure can be redrawn from a finished or an interrupted run.
//! The per-output-time writers ([`snapshot`]: VTU and GIF) are handed a
//! [`crate::run_files::Snapshot`], the
//! same kind of plain data a state file holds, by the run loop.
//!
//! Module map:
//! - [`geometry`]: the deformed cell as polygons (curved P2 edges), active-region outlines,
//!   substrate and fibronectin-layer profiles — pure geometry, no drawing;
//! - [`draw`]: the drawing primitives every figure uses — sizes, font, colours, curves
//!   and marks, axis helpers, and the plane drawing of the 2-D cell or a 3-D section;
//! - [`time_plots`]: the time plots (contact radius, displacement, strain, upside down);
//! - [`strain_bars`]: the paper's strain norms beside ours, as bars;
//! - [`shapes`]: the 2-D cell's shape figures;
//! - [`figures`]: `cellsim plot` — which figures a run gets ([`figures::plot_run`]), and
//!   the curves of several runs compared; it re-exports the figure modules' public items;
//! - [`cell3d_views`]: the figures of the 3-D quarter cell (a
//!   [`crate::run_files::QuarterMeshFile`] and its [`crate::run_files::QuarterSnapshot`]s):
//!   sections through the axis and a shaded view of the whole cell;
//! - [`vtu`]: `.vtu` files (quadratic triangles or tetrahedra) and the `.pvd` collection,
//!   for either model;
//! - [`movie`]: the deformation as an animated GIF, for either model;
//! - [`snapshot`]: what the run loop hands over at each output time, and the writer that
//!   feeds [`vtu`] and [`movie`];
//! - [`scenes`]: the paper's five scenes compiled in, the control's name, and a run's
//!   loading phases recovered from its case file or its scene;
//! - [`paper`]: `cellsim paper` — the paper's reported values, its figures and the
//!   comparison table;
//! - [`table`]: `cellsim table` — a markdown row per run from its summary.

pub mod cell3d_views;
pub mod draw;
pub mod figures;
pub mod geometry;
pub mod movie;
pub mod paper;
pub mod scenes;
pub mod shapes;
pub mod snapshot;
pub mod strain_bars;
pub mod table;
pub mod time_plots;
pub mod vtu;

pub use crate::run_files::RunData;
pub use snapshot::{
    FrameSink, QuarterSnapshotWriter, SnapshotOptions, SnapshotWriter, SnapshotWriterOf,
};

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::{BitMapBackend, DrawingArea, IntoDrawingArea, WHITE};

/// Why an output could not be read, drawn or written. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// A run's file could not be loaded (missing, unreadable or not what a run writes).
    #[error(transparent)]
    Read(#[from] crate::run_files::ReadError),
    /// A file could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: String,
        /// Cause.
        source: std::io::Error,
    },
    /// Drawing a figure failed (backend or font error).
    #[error("cannot draw {path}: {message}")]
    Draw {
        /// The figure file.
        path: String,
        /// The backend's message.
        message: String,
    },
    /// Writing or reading a VTK file failed.
    #[error("VTK file {path}: {message}")]
    Vtk {
        /// The file.
        path: String,
        /// vtkio's message.
        message: String,
    },
}

impl OutputError {
    /// A [`OutputError::Write`] for `path`.
    pub fn write(path: &Path, source: std::io::Error) -> Self {
        OutputError::Write {
            path: path.display().to_string(),
            source,
        }
    }

    /// A [`OutputError::Draw`] for `path` from any displayable backend error.
    pub fn draw(path: &Path, e: impl std::fmt::Display) -> Self {
        OutputError::Draw {
            path: path.display().to_string(),
            message: e.to_string(),
        }
    }
}

/// Why a figure could not be drawn into its drawing area: the backend's message (plotters'
/// errors are generic over the backend, so the message is what is kept) or a mismatch
/// between the state drawn and its mesh.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct DrawError(pub String);

impl<E: std::error::Error + Send + Sync> From<plotters::drawing::DrawingAreaErrorKind<E>>
    for DrawError
{
    fn from(e: plotters::drawing::DrawingAreaErrorKind<E>) -> Self {
        DrawError(e.to_string())
    }
}

/// Creates `dir` (and its parents) if needed.
pub fn create_dir(dir: &Path) -> Result<(), OutputError> {
    std::fs::create_dir_all(dir).map_err(|e| OutputError::write(dir, e))
}

/// The drawing area of a PNG figure.
pub type PngArea<'a> = DrawingArea<BitMapBackend<'a>, Shift>;

/// Draws a PNG of `size` pixels at `path`: `draw` paints on a white canvas, which is then
/// written; whatever fails is an [`OutputError::Draw`] naming the file.
pub fn draw_png<T>(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&PngArea<'_>) -> Result<T, DrawError>,
) -> Result<T, OutputError> {
    let root = BitMapBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|x| OutputError::draw(path, x))?;
    let value = draw(&root).map_err(|x| OutputError::draw(path, x))?;
    root.present().map_err(|x| OutputError::draw(path, x))?;
    Ok(value)
}
