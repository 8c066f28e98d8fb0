//! What the run loop hands over at each output time, and the writer that turns it into a
//! `.vtu` file ([`super::vtu`]) and a GIF frame ([`super::movie`]).
//!
//! A [`Snapshot`] is plain data — the same kind a state file holds, plus velocities — so
//! these writers, like the figures, never see the solver.

use std::marker::PhantomData;
use std::path::{Path, PathBuf};

use super::OutputError;
use super::movie::Movie;
use super::movie3::Movie3;
use super::vtu::VtuSeries;
use super::vtu3::VtuSeries3;
use crate::record::{Mesh3File, MeshFile, Snapshot, Snapshot3};

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
pub trait FrameSink<S> {
    /// Adds the output time `s`.
    fn add(&mut self, s: &S) -> Result<(), OutputError>;
    /// Closes the file; returns it (the `.pvd` of a VTU series, the `.gif`).
    fn close(self) -> Result<PathBuf, OutputError>;
}

impl FrameSink<Snapshot> for VtuSeries {
    fn add(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        self.write(s).map(|_| ())
    }
    fn close(self) -> Result<PathBuf, OutputError> {
        Ok(self.pvd_path().to_path_buf())
    }
}

impl FrameSink<Snapshot3> for VtuSeries3 {
    fn add(&mut self, s: &Snapshot3) -> Result<(), OutputError> {
        self.write(s).map(|_| ())
    }
    fn close(self) -> Result<PathBuf, OutputError> {
        Ok(self.pvd_path().to_path_buf())
    }
}

impl FrameSink<Snapshot> for Movie {
    fn add(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        self.frame(s)
    }
    fn close(self) -> Result<PathBuf, OutputError> {
        self.finish()
    }
}

impl FrameSink<Snapshot3> for Movie3 {
    fn add(&mut self, s: &Snapshot3) -> Result<(), OutputError> {
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
/// ([`super::vtu3`], [`super::movie3`]).
pub type SnapshotWriter3 = SnapshotWriterOf<Snapshot3, VtuSeries3, Movie3>;

impl SnapshotWriter {
    /// A writer into `out` for the run `name` on `mesh`; `outputs` is the number of
    /// output times expected (to space the GIF's frames).
    pub fn new(
        out: &Path,
        name: &str,
        mesh: &MeshFile,
        opts: SnapshotOptions,
        outputs: usize,
    ) -> Result<Self, OutputError> {
        let gif = out.join(format!("{name}.gif"));
        Ok(Self::of(
            opts.vtu
                .then(|| VtuSeries::new(out, name, mesh))
                .transpose()?,
            opts.gif
                .then(|| Movie::new(&gif, name, mesh, outputs))
                .transpose()?,
        ))
    }
}

impl SnapshotWriter3 {
    /// As [`SnapshotWriter::new`] for the 3-D mesh.
    pub fn new(
        out: &Path,
        name: &str,
        mesh: &Mesh3File,
        opts: SnapshotOptions,
        outputs: usize,
    ) -> Result<Self, OutputError> {
        let gif = out.join(format!("{name}.gif"));
        Ok(Self::of(
            opts.vtu
                .then(|| VtuSeries3::new(out, name, mesh))
                .transpose()?,
            opts.gif
                .then(|| Movie3::new(&gif, name, mesh, outputs))
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
