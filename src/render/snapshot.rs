//! What the run loop hands over at each output time, and the writer that turns it into a
//! `.vtu` file ([`super::vtu`]) and a GIF frame ([`super::movie`]).
//!
//! A [`Snapshot`] is plain data — the same kind a state file holds, plus velocities — so
//! these writers, like the figures, never see the solver.

use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use super::OutputError;
use super::movie::{FramePainter, Movie, MovieOf, QuarterMovie};
use super::vtu::{QuarterVtuSeries, VtuMesh, VtuSeries, VtuSeriesOf};
use crate::run_files::{QuarterSnapshot, Snapshot};

/// Which per-output-time files a run writes besides its CSV row.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SnapshotOptions {
    /// A `.vtu` per output time in `vtu/` and the collection `<case>.pvd`.
    pub vtu: bool,
    /// The deformation as `<case>.gif`.
    pub gif: bool,
}

impl SnapshotOptions {
    /// Whether anything is to be written.
    pub fn any(&self) -> bool {
        self.vtu || self.gif
    }
}

/// One of the per-output-time files: a VTU series or a GIF, of either model.
pub trait FrameSink<S>: Sized {
    /// The mesh the snapshots `S` live on.
    type Mesh;
    /// Starts the file of the run `name` in `out`; `outputs` is the number of output
    /// times expected (to space a GIF's frames).
    fn open(out: &Path, name: &str, mesh: &Self::Mesh, outputs: usize)
    -> Result<Self, OutputError>;
    /// Adds the output time `s`.
    fn add(&mut self, s: &S) -> Result<(), OutputError>;
    /// Closes the file; returns it (the `.pvd` of a VTU series, the `.gif`).
    fn close(self) -> Result<PathBuf, OutputError>;
}

impl<M: VtuMesh> FrameSink<M::Snapshot> for VtuSeriesOf<M> {
    type Mesh = M;
    fn open(out: &Path, name: &str, mesh: &M, _outputs: usize) -> Result<Self, OutputError> {
        Self::new(out, name, mesh)
    }
    fn add(&mut self, s: &M::Snapshot) -> Result<(), OutputError> {
        self.write(s).map(|_| ())
    }
    fn close(self) -> Result<PathBuf, OutputError> {
        Ok(self.pvd_path().to_path_buf())
    }
}

impl<P: FramePainter> FrameSink<P::State> for MovieOf<P> {
    type Mesh = P::Mesh;
    fn open(out: &Path, name: &str, mesh: &P::Mesh, outputs: usize) -> Result<Self, OutputError> {
        Self::new(&gif_path(out, name), name, mesh, outputs)
    }
    fn add(&mut self, s: &P::State) -> Result<(), OutputError> {
        self.frame(s)
    }
    fn close(self) -> Result<PathBuf, OutputError> {
        self.finish()
    }
}

/// Writes the per-output-time files of one run: its VTU series `V` and its GIF `M`, each
/// if asked for, from snapshots `S`.
pub struct SnapshotWriterOf<S, V, M> {
    vtu: Option<V>,
    movie: Option<M>,
    snapshot: PhantomData<fn(&S)>,
}

/// The writer of the half-plane models.
pub type SnapshotWriter = SnapshotWriterOf<Snapshot, VtuSeries, Movie>;
/// The writer of the 3-D model: quadratic tetrahedra and the section z = 0
/// ([`super::vtu`], [`super::movie`]).
pub type QuarterSnapshotWriter = SnapshotWriterOf<QuarterSnapshot, QuarterVtuSeries, QuarterMovie>;

/// The GIF of the run `name` in `out`.
fn gif_path(out: &Path, name: &str) -> PathBuf {
    out.join(format!("{name}.gif"))
}

impl<S, V: FrameSink<S>, M: FrameSink<S, Mesh = V::Mesh>> SnapshotWriterOf<S, V, M> {
    /// A writer into `out` for the run `name` on `mesh`; `outputs` is the number of
    /// output times expected (to space the GIF's frames).
    pub fn new(
        out: &Path,
        name: &str,
        mesh: &V::Mesh,
        opts: SnapshotOptions,
        outputs: usize,
    ) -> Result<Self, OutputError> {
        Ok(Self::of(
            opts.vtu
                .then(|| V::open(out, name, mesh, outputs))
                .transpose()?,
            opts.gif
                .then(|| M::open(out, name, mesh, outputs))
                .transpose()?,
        ))
    }
}

impl<S, V: FrameSink<S>, M: FrameSink<S>> SnapshotWriterOf<S, V, M> {
    fn of(vtu: Option<V>, movie: Option<M>) -> Self {
        Self {
            vtu,
            movie,
            snapshot: PhantomData,
        }
    }

    /// Whether anything is written (the run builds snapshots only then).
    pub fn is_active(&self) -> bool {
        self.vtu.is_some() || self.movie.is_some()
    }

    /// Writes the files of one output time.
    pub fn write(&mut self, s: &S) -> Result<(), OutputError> {
        if let Some(v) = &mut self.vtu {
            v.add(s)?;
        }
        if let Some(m) = &mut self.movie {
            m.add(s)?;
        }
        Ok(())
    }

    /// Closes the files (the GIF gets its last frame and trailer); returns the files
    /// written (the `.pvd` and the `.gif`).
    pub fn finish(self) -> Result<Vec<PathBuf>, OutputError> {
        let mut out = Vec::new();
        if let Some(v) = self.vtu {
            out.push(v.close()?);
        }
        if let Some(m) = self.movie {
            out.push(m.close()?);
        }
        Ok(out)
    }
}
