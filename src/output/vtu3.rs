//! ParaView output of the 3-D quarter cell: one `.vtu` per output time and the `.pvd`
//! collection, as the 2-D [`super::vtu`] writes them.
//!
//! Each file holds the **reference** quarter mesh — points (X, Y, Z) in µm, the ten-node
//! tetrahedra as VTK quadratic tetrahedra (cell type 24) — with the arrays of the 2-D file
//! under the same names, so a ParaView state made for a 2-D run works on a 3-D one:
//! - point data `displacement` (u_x, u_y, u_z) [µm] (*Warp By Vector* on it shows the
//!   deformed cell; *Reflect* about x = 0 and then z = 0 gives the whole cell),
//!   `velocity` [µm/s] (the v unknowns with inertia, u̇ without), `mu_as` [pN/µm³] (0 off
//!   the membrane, where it is not an unknown, as in 2-D);
//! - cell data `domain` (0 nucleus, 1 cytoplasm, 2 membrane), `mean_E_norm` (the element's
//!   reference-volume mean of ‖E‖_F) and `det_F` (its mean det F).
//!
//! **Node order.** The mesh is in gmsh's order ([`crate::fem::tet10`]): vertices 0–3, then
//! the mid-edge nodes of (0,1), (1,2), (0,2), (0,3), (2,3), (1,3). VTK's quadratic
//! tetrahedron has the same vertices and the mid-edge nodes of (0,1), (1,2), (2,0), (0,3),
//! (1,3), (2,3): gmsh's nodes 8 and 9 are swapped ([`GMSH_OF_VTK`]). Both take a
//! tetrahedron as positive when vertex 3 lies on the side of the face (0, 1, 2) its
//! right-hand normal points to, so the orientation carries over unchanged.

use std::path::Path;

use vtkio::model::{CellType, Vtk};

use super::OutputError;
use super::vtu::{
    GridData, VtuMesh, VtuSeriesOf, VtuSummary, check_lengths, load_piece, summarise, vtk_err,
    write_vtu,
};
use crate::record::{Mesh3File, Snapshot3};

/// The VTK cell type of a ten-node tetrahedron (VTK_QUADRATIC_TETRA).
pub const QUADRATIC_TETRA: u8 = 24;

/// VTK's local node `a` of a quadratic tetrahedron is gmsh's local node `GMSH_OF_VTK[a]`.
pub const GMSH_OF_VTK: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];

/// Checks that the snapshot's arrays fit the mesh.
pub fn check_snapshot3(mesh: &Mesh3File, s: &Snapshot3) -> Result<(), String> {
    let ne = mesh.elements.len();
    check_lengths(
        mesh.nodes.len(),
        ne,
        [s.u.len(), s.v.len(), s.mu_as.len()],
        [s.element_strain.len(), s.element_jacobian.len()],
    )?;
    if mesh.domains.len() != ne {
        return Err(format!(
            "mesh has {} domains for {ne} elements",
            mesh.domains.len()
        ));
    }
    Ok(())
}

/// The VTK model of one output time of the 3-D cell (see the module documentation).
pub fn vtk_model3(mesh: &Mesh3File, s: &Snapshot3) -> Result<Vtk, String> {
    check_snapshot3(mesh, s)?;
    Ok(GridData {
        nodes: &mesh.nodes,
        elements: &mesh.elements,
        vtk_order: GMSH_OF_VTK,
        cell_type: CellType::QuadraticTetra,
        domains: &mesh.domains,
        u: &s.u,
        v: &s.v,
        mu_as: &s.mu_as,
        element_strain: &s.element_strain,
        element_jacobian: &s.element_jacobian,
        title: format!("cellsim 3-D t = {} s", s.t),
    }
    .into_vtk())
}

impl VtuMesh for Mesh3File {
    type Snapshot = Snapshot3;
    fn time(s: &Snapshot3) -> f64 {
        s.t
    }
    fn vtk_model(&self, s: &Snapshot3) -> Result<Vtk, String> {
        vtk_model3(self, s)
    }
}

/// Writes the `.vtu` of one output time of the 3-D cell at `path` ([`write_vtu`] on a
/// [`Mesh3File`]).
pub fn write_vtu3(path: &Path, mesh: &Mesh3File, s: &Snapshot3) -> Result<(), OutputError> {
    write_vtu(path, mesh, s)
}

/// A `.vtu` read back with its geometry, for checks.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuGrid {
    /// Counts, cell types, array names and the displacement.
    pub summary: VtuSummary,
    /// The points [µm].
    pub points: Vec<[f64; 3]>,
    /// Each cell's point indices, in the file's (VTK's) order.
    pub cells: Vec<Vec<usize>>,
}

/// Reads a `.vtu` back through vtkio: its [`VtuSummary`] (as [`super::vtu::read_vtu`]),
/// points and connectivity.
pub fn read_vtu_grid(path: &Path) -> Result<VtuGrid, OutputError> {
    let piece = load_piece(path)?;
    let summary = summarise(&piece);
    let coords: Vec<f64> = piece
        .points
        .cast_into::<f64>()
        .ok_or_else(|| vtk_err(path, "points are not numbers"))?;
    let points = coords.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect();
    let (connectivity, offsets) = piece.cells.cell_verts.into_xml();
    let mut cells = Vec::with_capacity(offsets.len());
    let mut start = 0usize;
    for &end in &offsets {
        let end = end as usize;
        if end < start || end > connectivity.len() {
            return Err(vtk_err(path, "cell offsets out of range"));
        }
        cells.push(
            connectivity[start..end]
                .iter()
                .map(|&i| i as usize)
                .collect(),
        );
        start = end;
    }
    Ok(VtuGrid {
        summary,
        points,
        cells,
    })
}

/// The `.vtu` files of one 3-D run and their `.pvd` collection (the 3-D
/// [`super::vtu::VtuSeries`]).
pub type VtuSeries3 = VtuSeriesOf<Mesh3File>;
