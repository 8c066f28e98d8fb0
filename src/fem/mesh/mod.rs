//! The cell's meshes: [`half_cell`], the P2 triangle mesh of the 2-D half cell, and
//! [`quarter_cell`], the P2 tetrahedral mesh of the 3-D quarter cell (and the 2-D mesh
//! extruded into a slab); here what they share.

use serde::{Deserialize, Serialize};
use thiserror::Error;

pub mod half_cell;
pub mod quarter_cell;

pub(crate) use half_cell::MeshParts;
pub use half_cell::{MAX_ELEMENTS, MIN_ANGLE_DEG, Mesh, MeshParams, MeshQuality};
pub use quarter_cell::{TetMesh, TetMeshParams, TetMeshQuality, Wedge};

/// Which sub-domain of the cell a material point belongs to (MODEL.md §2), as the
/// meshes label their elements (conforming: each element lies in exactly one) and the
/// physics selects its terms (the active strain, the adhesion).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Domain {
    /// `|p − c| < r_n`: no active strain.
    Nucleus,
    /// `r_n < |p − c| < r_cp`: PAC and bottom active strains.
    Cytoplasm,
    /// `r_cp < |p − c| < r_c`: bottom active strain only; adhesion acts here.
    Membrane,
}

impl Domain {
    /// All domains, inside out.
    pub const ALL: [Domain; 3] = [Domain::Nucleus, Domain::Cytoplasm, Domain::Membrane];
}

impl std::fmt::Display for Domain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Domain::Nucleus => "nucleus",
            Domain::Cytoplasm => "cytoplasm",
            Domain::Membrane => "membrane",
        })
    }
}

/// Errors of mesh generation and mesh input.
#[derive(Debug, Error)]
pub enum MeshError {
    /// A mesh parameter is out of range.
    #[error("mesh parameter `{field}` = {value}: {rule}")]
    InvalidParam {
        /// Field name in [`MeshParams`].
        field: &'static str,
        /// Value given.
        value: f64,
        /// The rule it breaks.
        rule: &'static str,
    },
    /// The requested sizes would give an unreasonably large mesh.
    #[error("mesh too fine: about {estimate:.0} elements estimated, limit {limit:.0}")]
    TooFine {
        /// Estimated element count.
        estimate: f64,
        /// [`MAX_ELEMENTS`].
        limit: f64,
    },
    /// spade refused a vertex or a constraint.
    #[error("triangulation failed: {0}")]
    Triangulation(String),
    /// The Delaunay refinement ran out of vertices before meeting the angle limit.
    #[error("Delaunay refinement did not complete ({vertices} vertices); lower min_angle_deg")]
    RefinementIncomplete {
        /// Vertex count when it stopped.
        vertices: usize,
    },
    /// An element's isoparametric map is not orientation preserving somewhere.
    #[error("element {element}: isoparametric Jacobian {det:e} ≤ 0 at reference point {xi:?}")]
    NonPositiveJacobian {
        /// Element index.
        element: usize,
        /// The smallest det J found over the element.
        det: f64,
        /// Where it is attained (reference coordinates, two or three).
        xi: Vec<f64>,
    },
    /// A generated mesh failed an internal consistency check (a bug, not a user error).
    #[error("mesh generation inconsistency: {0}")]
    Inconsistent(String),
    /// Reading a mesh file failed.
    #[error("cannot read mesh file {path}: {source}")]
    Io {
        /// File path.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// Writing a mesh or a drawing of it failed.
    #[error("cannot write {path}: {source}")]
    Write {
        /// File path.
        path: String,
        /// Underlying error.
        source: std::io::Error,
    },
    /// A mesh file is malformed or does not fit the model.
    #[error("mesh file {path}, line {line}: {message}")]
    Format {
        /// File path.
        path: String,
        /// 1-based line number (0 when not tied to a line).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The gmsh executable (the 3-D mesher, [`quarter_cell`]) could not be started.
    #[error(
        "gmsh not found on PATH: install the Debian package `gmsh` (make deps does) (tried `{program}`)"
    )]
    GmshNotFound {
        /// The program that was run.
        program: String,
    },
    /// gmsh ran but failed.
    #[error("gmsh failed ({status}) on {input}: {stderr}")]
    GmshFailed {
        /// Its exit status.
        status: String,
        /// The geometry file it was given.
        input: String,
        /// The last lines of its error output.
        stderr: String,
    },
}

/// Node indices of the reference points used for output (MODEL.md §2); all are vertices on
/// the symmetry line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct NamedPoints {
    /// Cell centre c.
    pub centre: usize,
    /// Nucleus top p_t = c + (0, r_n).
    pub nucleus_top: usize,
    /// Nucleus bottom p_b = c − (0, r_n).
    pub nucleus_bottom: usize,
    /// Cell bottom c − (0, r_c).
    pub cell_bottom: usize,
    /// Cell top c + (0, r_c).
    pub cell_top: usize,
}

/// Fails with [`MeshError::InvalidParam`]: `field` = `value` breaks `rule`.
pub(crate) fn invalid(
    field: &'static str,
    value: f64,
    rule: &'static str,
) -> Result<(), MeshError> {
    Err(MeshError::InvalidParam { field, value, rule })
}

/// The checks both meshers' parameters begin with: every coordinate of `center` finite,
/// the radii, sizes (`h_surface` if given) and refinement of the section `p` finite and
/// positive, and
/// r_n < r_cp < r_c.
pub(crate) fn check_cell(center: &[f64], p: &MeshParams) -> Result<(), MeshError> {
    for (v, name) in center.iter().zip(["center[0]", "center[1]", "center[2]"]) {
        if !v.is_finite() {
            return invalid(name, *v, "must be finite");
        }
    }
    let positive = [
        ("r_n", p.r_n),
        ("r_cp", p.r_cp),
        ("r_c", p.r_c),
        ("h_bottom", p.h_bottom),
        ("h_nucleus", p.h_nucleus),
        ("refine", p.refine),
    ];
    let surface = p.h_surface.map(|h| ("h_surface", h));
    for (field, v) in positive.into_iter().chain(surface) {
        if !(v.is_finite() && v > 0.0) {
            return invalid(field, v, "must be finite and > 0");
        }
    }
    if p.r_cp <= p.r_n {
        return invalid("r_cp", p.r_cp, "must exceed r_n");
    }
    if p.r_c <= p.r_cp {
        return invalid("r_c", p.r_c, "must exceed r_cp");
    }
    Ok(())
}

/// The checks both meshers' parameters end with: the finest element size `h_min` not lost
/// in the round-off of coordinates as far as `far` from the origin, and at most `limit`
/// elements in the `estimate`.
pub(crate) fn check_scale(
    h_min: f64,
    far: f64,
    estimate: f64,
    limit: f64,
) -> Result<(), MeshError> {
    if h_min < 1e-9 * far {
        return Err(MeshError::InvalidParam {
            field: "center",
            value: far,
            rule: "too far from the origin for the element size (coordinates would lose precision)",
        });
    }
    if estimate > limit {
        return Err(MeshError::TooFine { estimate, limit });
    }
    Ok(())
}
