//! What the run loop hands over at each output time, and the writer that turns it into a
//! `.vtu` file ([`super::vtu`]) and a GIF frame ([`super::movie`]).
//!
//! A [`Snapshot`] is plain data — the same kind a state file holds, plus velocities — so
//! these writers, like the figures, never see the solver.

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

/// Writes the per-output-time files of one run.
pub struct SnapshotWriter {
    vtu: Option<VtuSeries>,
    movie: Option<Movie>,
}

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
        let vtu = if opts.vtu {
            Some(VtuSeries::new(out, name, mesh)?)
        } else {
            None
        };
        let movie = if opts.gif {
            Some(Movie::new(
                &out.join(format!("{name}.gif")),
                name,
                mesh,
                outputs,
            )?)
        } else {
            None
        };
        Ok(Self { vtu, movie })
    }

    /// Whether anything is written (the run builds snapshots only then).
    pub fn is_active(&self) -> bool {
        self.vtu.is_some() || self.movie.is_some()
    }

    /// Writes the files of one output time.
    pub fn write(&mut self, s: &Snapshot) -> Result<(), OutputError> {
        if let Some(v) = &mut self.vtu {
            v.write(s)?;
        }
        if let Some(m) = &mut self.movie {
            m.frame(s)?;
        }
        Ok(())
    }

    /// Closes the files (the GIF gets its last frame and trailer); returns the files
    /// written (the `.pvd` and the `.gif`).
    pub fn finish(self) -> Result<Vec<PathBuf>, OutputError> {
        let mut out = Vec::new();
        if let Some(v) = self.vtu {
            out.push(v.pvd_path().to_path_buf());
        }
        if let Some(m) = self.movie {
            out.push(m.finish()?);
        }
        Ok(out)
    }
}

/// Writes the per-output-time files of one 3-D run: the `.vtu` files of quadratic
/// tetrahedra with their `.pvd` ([`super::vtu3`]) and the GIF of the section z = 0
/// ([`super::movie3`]).
pub struct SnapshotWriter3 {
    vtu: Option<VtuSeries3>,
    movie: Option<Movie3>,
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
        let vtu = if opts.vtu {
            Some(VtuSeries3::new(out, name, mesh)?)
        } else {
            None
        };
        let movie = if opts.gif {
            Some(Movie3::new(
                &out.join(format!("{name}.gif")),
                name,
                mesh,
                outputs,
            )?)
        } else {
            None
        };
        Ok(Self { vtu, movie })
    }

    /// Whether anything is written.
    pub fn is_active(&self) -> bool {
        self.vtu.is_some() || self.movie.is_some()
    }

    /// Writes the files of one output time.
    pub fn write(&mut self, s: &Snapshot3) -> Result<(), OutputError> {
        if let Some(v) = &mut self.vtu {
            v.write(s)?;
        }
        if let Some(m) = &mut self.movie {
            m.frame(s)?;
        }
        Ok(())
    }

    /// Closes the files; returns those written (the `.pvd` and the `.gif`).
    pub fn finish(self) -> Result<Vec<PathBuf>, OutputError> {
        let mut out = Vec::new();
        if let Some(v) = self.vtu {
            out.push(v.pvd_path().to_path_buf());
        }
        if let Some(m) = self.movie {
            out.push(m.finish()?);
        }
        Ok(out)
    }
}
