//! Mesh, P2 elements, quadrature.
//!
//! - [`quadrature`]: Gauss–Legendre on [0, 1], triangle and tetrahedron rules exact to a
//!   given degree, sub-divided rules for thin bands, edge rules.
//! - [`tri6`]: the six-node isoparametric triangle and the three-node edge.
//! - [`tet10`]: the ten-node isoparametric tetrahedron and the six-node surface triangle
//!   in 3-D.
//! - [`element`]: what is written once for both elements (the tabulation at quadrature
//!   points, the isoparametric Jacobian, the element geometry), and what a model needs of
//!   a mesh and of its element.
//! - [`mesh`]: the cell's meshes and what they share. [`mesh::half_cell`]: the conforming
//!   mesh of the reference half cell (nucleus, cytoplasm, membrane), graded from the cell
//!   bottom to the nucleus, with curved P2 interfaces. [`mesh::quarter_cell`]: the P2
//!   tetrahedral mesh of the quarter cell (MODEL.md §10), made by gmsh from a geometry
//!   written here and cached; the 2-D mesh extruded into a one-layer slab.
//! - [`gmsh`]: reading and writing such meshes as gmsh 4.1 ASCII files (2-D: both; 3-D:
//!   reading).
//! - [`assembly`]: sparse patterns built once from (row, col) entries and the positions
//!   of element blocks in them, for refilling assembled matrices.

pub mod assembly;
pub mod element;
pub mod gmsh;
pub mod mesh;
pub mod quadrature;
pub mod tet10;
pub mod tri6;

pub use element::{CellMesh, ElementGeometryError, ElementTabulation, GeometryOf, Lagrange};
pub use mesh::{
    Domain, Mesh, MeshError, MeshParams, TetMesh, TetMeshParams, TetMeshQuality, Wedge,
};
pub use mesh::{MeshQuality, NamedPoints};
pub use quadrature::{EdgeRule, TetRule, TriangleRule, gauss_legendre};
pub use tet10::{Tet10, TetError, TetGeometry, TetTabulation};
pub use tri6::{ElementGeometry, P2Error, P2Tabulation, Tri6};

/// The paper's cell and mesh for this layer's tests, taken from the case schema (the one
/// place the defaults live).
#[cfg(test)]
pub(crate) mod reference {
    pub fn mesh_params() -> super::MeshParams {
        crate::scene::terms::mesh_params(&crate::case::Case::reference())
    }

    pub fn tet_mesh_params() -> super::TetMeshParams {
        crate::scene::terms::tet_mesh_params(&crate::case::Case::reference())
    }
}
