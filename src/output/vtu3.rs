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
//! **Node order.** The mesh is in gmsh's order ([`crate::fem::tet`]): vertices 0–3, then
//! the mid-edge nodes of (0,1), (1,2), (0,2), (0,3), (2,3), (1,3). VTK's quadratic
//! tetrahedron has the same vertices and the mid-edge nodes of (0,1), (1,2), (2,0), (0,3),
//! (1,3), (2,3): gmsh's nodes 8 and 9 are swapped ([`GMSH_OF_VTK`]). Both take a
//! tetrahedron as positive when vertex 3 lies on the side of the face (0, 1, 2) its
//! right-hand normal points to, so the orientation carries over unchanged.

use std::path::{Path, PathBuf};

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};

use super::OutputError;
use super::vtu::{VtuSummary, domain_code, read_vtu, write_pvd};
use crate::record::{Mesh3File, Snapshot3};

/// The VTK cell type of a ten-node tetrahedron (VTK_QUADRATIC_TETRA).
pub const QUADRATIC_TETRA: u8 = 24;

/// VTK's local node `a` of a quadratic tetrahedron is gmsh's local node `GMSH_OF_VTK[a]`.
pub const GMSH_OF_VTK: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];

fn vtk_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Vtk {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Checks that the snapshot's arrays fit the mesh.
pub fn check_snapshot3(mesh: &Mesh3File, s: &Snapshot3) -> Result<(), String> {
    let (nn, ne) = (mesh.nodes.len(), mesh.elements.len());
    if s.u.len() != nn || s.v.len() != nn || s.mu_as.len() != nn {
        return Err(format!(
            "snapshot has per-node arrays of the wrong length ({nn} nodes)"
        ));
    }
    if s.element_strain.len() != ne || s.element_jacobian.len() != ne {
        return Err(format!(
            "snapshot has per-element arrays of the wrong length ({ne} elements)"
        ));
    }
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
    let ne = mesh.elements.len();
    let flat = |v: &[[f64; 3]]| -> Vec<f64> { v.iter().flatten().copied().collect() };
    let connectivity: Vec<u64> = mesh
        .elements
        .iter()
        .flat_map(|el| GMSH_OF_VTK.map(|a| el[a] as u64))
        .collect();
    let offsets: Vec<u64> = (1..=ne as u64).map(|k| 10 * k).collect();
    let mu: Vec<f64> = s.mu_as.iter().map(|m| m.unwrap_or(0.0)).collect();
    let domains: Vec<i32> = mesh.domains.iter().map(|&d| domain_code(d)).collect();
    let piece = UnstructuredGridPiece {
        points: flat(&mesh.nodes).into(),
        cells: Cells {
            cell_verts: VertexNumbers::XML {
                connectivity,
                offsets,
            },
            types: vec![CellType::QuadraticTetra; ne],
        },
        data: Attributes {
            point: vec![
                Attribute::generic("displacement", 3).with_data(flat(&s.u)),
                Attribute::generic("velocity", 3).with_data(flat(&s.v)),
                Attribute::scalars("mu_as", 1).with_data(mu),
            ],
            cell: vec![
                Attribute::scalars("domain", 1).with_data(domains),
                Attribute::scalars("mean_E_norm", 1).with_data(s.element_strain.clone()),
                Attribute::scalars("det_F", 1).with_data(s.element_jacobian.clone()),
            ],
        },
    };
    Ok(Vtk {
        version: Version::new_xml(1, 0),
        title: format!("cellsim 3-D t = {} s", s.t),
        byte_order: ByteOrder::LittleEndian,
        data: DataSet::inline(piece),
        file_path: None,
    })
}

/// Writes the `.vtu` of one output time of the 3-D cell at `path`.
pub fn write_vtu3(path: &Path, mesh: &Mesh3File, s: &Snapshot3) -> Result<(), OutputError> {
    let vtk = vtk_model3(mesh, s).map_err(|m| vtk_err(path, m))?;
    vtk.export(path).map_err(|e| vtk_err(path, e))
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

/// Reads a `.vtu` back through vtkio: its [`VtuSummary`] ([`read_vtu`]), points and
/// connectivity.
pub fn read_vtu_grid(path: &Path) -> Result<VtuGrid, OutputError> {
    let summary = read_vtu(path)?;
    let vtk = Vtk::import(path).map_err(|e| vtk_err(path, e))?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(vtk_err(path, "not an unstructured grid"));
    };
    let Some(piece) = pieces.into_iter().next() else {
        return Err(vtk_err(path, "no piece"));
    };
    let piece = piece
        .into_loaded_piece_data(Some(path))
        .map_err(|e| vtk_err(path, e))?;
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
pub struct VtuSeries3 {
    mesh: Mesh3File,
    dir: PathBuf,
    pvd: PathBuf,
    name: String,
    entries: Vec<(f64, String)>,
}

impl VtuSeries3 {
    /// A series written into `out/vtu/<name>_NNNNN.vtu`, collected in `out/<name>.pvd`.
    pub fn new(out: &Path, name: &str, mesh: &Mesh3File) -> Result<Self, OutputError> {
        let dir = out.join("vtu");
        super::create_dir(&dir)?;
        Ok(Self {
            mesh: mesh.clone(),
            dir,
            pvd: out.join(format!("{name}.pvd")),
            name: name.to_string(),
            entries: Vec::new(),
        })
    }

    /// The collection file.
    pub fn pvd_path(&self) -> &Path {
        &self.pvd
    }

    /// Writes the next output time and rewrites the collection; returns the `.vtu` path.
    pub fn write(&mut self, s: &Snapshot3) -> Result<PathBuf, OutputError> {
        let file = format!("{}_{:05}.vtu", self.name, self.entries.len());
        let path = self.dir.join(&file);
        write_vtu3(&path, &self.mesh, s)?;
        self.entries.push((s.t, format!("vtu/{file}")));
        write_pvd(&self.pvd, &self.entries)?;
        Ok(path)
    }
}
