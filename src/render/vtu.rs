//! ParaView output of either model: one `.vtu` (VTK XML unstructured grid) per output time and a `.pvd`
//! collection that lists them with their times, written through vtkio.
//!
//! **The 2-D cell.** Each file holds the **reference** mesh — points (X, Y, 0) in µm, the six-node P2
//! triangles as VTK quadratic triangles (cell type 22, whose node order — three corners
//! counter-clockwise, then the mid-sides of edges 0–1, 1–2, 2–0 — is ours) — with
//! - point data `displacement` (u_x, u_y, 0) \[µm\] (ParaView: *Warp By Vector* on it shows
//!   the deformed cell), `velocity` (v_x, v_y, 0) \[µm/s\] (the v unknowns with inertia, u̇
//!   without), `mu_as` [pN/µm³] (0 off the membrane, where it is not an unknown);
//! - cell data `domain` (0 nucleus, 1 cytoplasm, 2 membrane), `mean_E_norm` (the element's
//!   reference-area mean of ‖E‖_F) and `det_F` (its mean det F).
//!
//! The `.pvd` is rewritten after each file, so it lists every file written even when the
//! run stops early.
//!
//! **The 3-D quarter cell.** Each file holds the **reference** quarter mesh — points (X, Y, Z) in µm, the ten-node
//! tetrahedra as VTK quadratic tetrahedra (cell type 24) — with the arrays of the 2-D file
//! under the same names, so a ParaView state made for a 2-D run works on a 3-D one:
//! - point data `displacement` (u_x, u_y, u_z) \[µm\] (*Warp By Vector* on it shows the
//!   deformed cell; *Reflect* about x = 0 and then z = 0 gives the whole cell),
//!   `velocity` \[µm/s\] (the v unknowns with inertia, u̇ without), `mu_as` [pN/µm³] (0 off
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

use std::path::{Path, PathBuf};

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};

use super::OutputError;
use crate::fem::Domain;
use crate::run_files::{MeshFile, QuarterMeshFile, QuarterSnapshot, Snapshot, Timed};

/// The VTK cell type of a six-node triangle.
pub const QUADRATIC_TRIANGLE: u8 = 22;

/// The VTK cell type of a ten-node tetrahedron (VTK_QUADRATIC_TETRA).
pub const QUADRATIC_TETRA: u8 = 24;

/// VTK's local node `a` of a quadratic tetrahedron is gmsh's local node `GMSH_OF_VTK[a]`.
pub const GMSH_OF_VTK: [usize; 10] = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8];

/// Why a snapshot's arrays do not fit its mesh.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SnapshotMismatch {
    /// `u`, `v` or `mu_as` has not one entry per node.
    #[error("snapshot has per-node arrays of the wrong length ({nodes} nodes)")]
    PerNode {
        /// Nodes of the mesh.
        nodes: usize,
    },
    /// `element_strain` or `element_jacobian` has not one entry per element.
    #[error("snapshot has per-element arrays of the wrong length ({elements} elements)")]
    PerElement {
        /// Elements of the mesh.
        elements: usize,
    },
    /// The mesh has not one domain per element (checked on 3-D meshes).
    #[error("mesh has {domains} domains for {elements} elements")]
    Domains {
        /// Domains listed.
        domains: usize,
        /// Elements of the mesh.
        elements: usize,
    },
}

impl From<SnapshotMismatch> for super::DrawError {
    fn from(e: SnapshotMismatch) -> Self {
        super::DrawError(e.to_string())
    }
}

/// Integer code of a domain in the `domain` cell array.
pub fn domain_code(d: Domain) -> i32 {
    match d {
        Domain::Nucleus => 0,
        Domain::Cytoplasm => 1,
        Domain::Membrane => 2,
    }
}

/// A [`OutputError::Vtk`] for `path`.
fn vtk_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Vtk {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// One output time of either model as the `.vtu` holds it: a mesh whose points have `D`
/// coordinates and whose elements have `N` nodes, and a snapshot on it (arrays already
/// checked against the mesh): what [`VtuMesh::grid`] hands to [`vtk_model`].
pub(crate) struct GridData<'a, const D: usize, const N: usize> {
    /// Reference node coordinates \[µm\] (z = 0 when `D` is 2).
    pub nodes: &'a [[f64; D]],
    /// The elements' nodes, in the mesh's local order.
    pub elements: &'a [[usize; N]],
    /// VTK's local node `a` of a cell is the element's local node `vtk_order[a]`.
    pub vtk_order: [usize; N],
    /// The VTK type of every cell.
    pub cell_type: CellType,
    /// Domain of each element.
    pub domains: &'a [Domain],
    /// Displacement of every node \[µm\].
    pub u: &'a [[f64; D]],
    /// Velocity of every node \[µm/s\].
    pub v: &'a [[f64; D]],
    /// μ_as per node [pN/µm³] (`None`: written as 0).
    pub mu_as: &'a [Option<f64>],
    /// Per element: the mean of ‖E‖_F.
    pub element_strain: &'a [f64],
    /// Per element: the mean of det F.
    pub element_jacobian: &'a [f64],
    /// The file's title.
    pub title: String,
}

/// Vectors of `D` components as VTK's three per point (z = 0 when `D` is 2).
fn xyz<const D: usize>(v: &[[f64; D]]) -> Vec<f64> {
    v.iter()
        .flat_map(|a| std::array::from_fn::<f64, 3, _>(|k| if k < D { a[k] } else { 0.0 }))
        .collect()
}

impl<const D: usize, const N: usize> GridData<'_, D, N> {
    /// The VTK model: the points, the cells, the point arrays `displacement`, `velocity`,
    /// `mu_as` and the cell arrays `domain`, `mean_E_norm`, `det_F`.
    pub fn into_vtk(self) -> Vtk {
        let ne = self.elements.len();
        let connectivity: Vec<u64> = self
            .elements
            .iter()
            .flat_map(|el| self.vtk_order.map(|a| el[a] as u64))
            .collect();
        let offsets: Vec<u64> = (1..=ne as u64).map(|k| N as u64 * k).collect();
        let mu: Vec<f64> = self.mu_as.iter().map(|m| m.unwrap_or(0.0)).collect();
        let domains: Vec<i32> = self.domains.iter().map(|&d| domain_code(d)).collect();
        let piece = UnstructuredGridPiece {
            points: xyz(self.nodes).into(),
            cells: Cells {
                cell_verts: VertexNumbers::XML {
                    connectivity,
                    offsets,
                },
                types: vec![self.cell_type; ne],
            },
            data: Attributes {
                point: vec![
                    Attribute::generic("displacement", 3).with_data(xyz(self.u)),
                    Attribute::generic("velocity", 3).with_data(xyz(self.v)),
                    Attribute::scalars("mu_as", 1).with_data(mu),
                ],
                cell: vec![
                    Attribute::scalars("domain", 1).with_data(domains),
                    Attribute::scalars("mean_E_norm", 1).with_data(self.element_strain.to_vec()),
                    Attribute::scalars("det_F", 1).with_data(self.element_jacobian.to_vec()),
                ],
            },
        };
        Vtk {
            version: Version::new_xml(1, 0),
            title: self.title,
            byte_order: ByteOrder::LittleEndian,
            data: DataSet::inline(piece),
            file_path: None,
        }
    }
}

/// A mesh whose output times are written as `.vtu` files: the 2-D [`MeshFile`] with its
/// [`Snapshot`]s, the 3-D [`QuarterMeshFile`] with its [`QuarterSnapshot`]s.
pub trait VtuMesh: Clone {
    /// The state of one output time on this mesh.
    type Snapshot: Timed;
    /// Checks that the arrays of `s` fit the mesh.
    fn check(&self, s: &Self::Snapshot) -> Result<(), SnapshotMismatch>;
    /// The VTK model of `s`, its arrays already checked (`GridData::into_vtk`).
    fn grid(&self, s: &Self::Snapshot) -> Vtk;
}

/// Implements [`VtuMesh`] for a mesh file and its snapshot: the VTK node order and cell
/// type of its elements, the title of its files, whether its domains are checked too.
macro_rules! vtu_mesh {
    ($mesh:ty, $snapshot:ty, $order:expr, $cell:expr, $title:literal, $domains:literal) => {
        impl VtuMesh for $mesh {
            type Snapshot = $snapshot;

            fn check(&self, s: &$snapshot) -> Result<(), SnapshotMismatch> {
                let (nodes, elements) = (self.nodes.len(), self.elements.len());
                if [s.u.len(), s.v.len(), s.mu_as.len()]
                    .iter()
                    .any(|&n| n != nodes)
                {
                    return Err(SnapshotMismatch::PerNode { nodes });
                }
                let per_element = [s.element_strain.len(), s.element_jacobian.len()];
                if per_element.iter().any(|&n| n != elements) {
                    return Err(SnapshotMismatch::PerElement { elements });
                }
                if $domains && self.domains.len() != elements {
                    let domains = self.domains.len();
                    return Err(SnapshotMismatch::Domains { domains, elements });
                }
                Ok(())
            }

            fn grid(&self, s: &$snapshot) -> Vtk {
                GridData {
                    nodes: &self.nodes,
                    elements: &self.elements,
                    vtk_order: $order,
                    cell_type: $cell,
                    domains: &self.domains,
                    u: &s.u,
                    v: &s.v,
                    mu_as: &s.mu_as,
                    element_strain: &s.element_strain,
                    element_jacobian: &s.element_jacobian,
                    title: format!($title, s.t),
                }
                .into_vtk()
            }
        }
    };
}

// Our triangles' node order is VTK's (see the module documentation).
vtu_mesh!(
    MeshFile,
    Snapshot,
    [0, 1, 2, 3, 4, 5],
    CellType::QuadraticTriangle,
    "cellsim t = {} s",
    false
);
vtu_mesh!(
    QuarterMeshFile,
    QuarterSnapshot,
    GMSH_OF_VTK,
    CellType::QuadraticTetra,
    "cellsim 3-D t = {} s",
    true
);

/// The VTK model of one output time of either model (see the module documentation for
/// its arrays); an error if the snapshot's arrays do not fit the mesh.
pub fn vtk_model<M: VtuMesh>(mesh: &M, s: &M::Snapshot) -> Result<Vtk, SnapshotMismatch> {
    mesh.check(s)?;
    Ok(mesh.grid(s))
}

/// Writes the `.vtu` of one output time at `path` (of either model: [`VtuMesh`]).
pub fn write_vtu<M: VtuMesh>(path: &Path, mesh: &M, s: &M::Snapshot) -> Result<(), OutputError> {
    let vtk = vtk_model(mesh, s).map_err(|m| vtk_err(path, m))?;
    vtk.export(path).map_err(|e| vtk_err(path, e))
}

/// What a `.vtu` read back holds, for checks.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuSummary {
    /// Number of points.
    pub points: usize,
    /// Number of cells.
    pub cells: usize,
    /// VTK type code of every cell.
    pub cell_types: Vec<u8>,
    /// Names of the point arrays.
    pub point_arrays: Vec<String>,
    /// Names of the cell arrays.
    pub cell_arrays: Vec<String>,
    /// The `displacement` array (3 per point), if present.
    pub displacement: Option<Vec<f64>>,
}

/// The first piece of the unstructured grid in the `.vtu` at `path`, with its data loaded
/// (shared by [`read_vtu_grid`]).
fn load_piece(path: &Path) -> Result<UnstructuredGridPiece, OutputError> {
    let vtk = Vtk::import(path).map_err(|e| vtk_err(path, e))?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(vtk_err(path, "not an unstructured grid"));
    };
    let Some(piece) = pieces.into_iter().next() else {
        return Err(vtk_err(path, "no piece"));
    };
    piece
        .into_loaded_piece_data(Some(path))
        .map_err(|e| vtk_err(path, e))
}

/// The [`VtuSummary`] of a piece read back.
fn summarise(piece: &UnstructuredGridPiece) -> VtuSummary {
    let name = |a: &Attribute| a.name().to_string();
    let displacement = piece.data.point.iter().find_map(|a| match a {
        Attribute::DataArray(d) if d.name == "displacement" => d.data.clone().cast_into::<f64>(),
        _ => None,
    });
    VtuSummary {
        points: piece.num_points(),
        cells: piece.cells.types.len(),
        cell_types: piece.cells.types.iter().map(|t| *t as u8).collect(),
        point_arrays: piece.data.point.iter().map(name).collect(),
        cell_arrays: piece.data.cell.iter().map(name).collect(),
        displacement,
    }
}

/// Reads a `.vtu` back through vtkio and summarises it.
pub fn read_vtu(path: &Path) -> Result<VtuSummary, OutputError> {
    Ok(summarise(&load_piece(path)?))
}

/// A `.vtu` read back with its geometry, for checks.
#[derive(Debug, Clone, PartialEq)]
pub struct VtuGrid {
    /// Counts, cell types, array names and the displacement.
    pub summary: VtuSummary,
    /// The points \[µm\].
    pub points: Vec<[f64; 3]>,
    /// Each cell's point indices, in the file's (VTK's) order.
    pub cells: Vec<Vec<usize>>,
}

/// Reads a `.vtu` back through vtkio: its [`VtuSummary`] (as [`read_vtu`]),
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

/// The `.vtu` files of one run on a mesh `M` ([`VtuMesh`]: either model) and their `.pvd`
/// collection.
pub struct VtuSeriesOf<M> {
    mesh: M,
    dir: PathBuf,
    pvd: PathBuf,
    name: String,
    entries: Vec<(f64, String)>,
}

/// The `.vtu` files of one 2-D run and their `.pvd` collection.
pub type VtuSeries = VtuSeriesOf<MeshFile>;

/// The `.vtu` files of one 3-D run and their `.pvd` collection.
pub type QuarterVtuSeries = VtuSeriesOf<QuarterMeshFile>;

impl<M: VtuMesh> VtuSeriesOf<M> {
    /// A series written into `out/vtu/<name>_NNNNN.vtu`, collected in `out/<name>.pvd`.
    pub fn new(out: &Path, name: &str, mesh: &M) -> Result<Self, OutputError> {
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
    pub fn write(&mut self, s: &M::Snapshot) -> Result<PathBuf, OutputError> {
        let file = format!("{}_{:05}.vtu", self.name, self.entries.len());
        let path = self.dir.join(&file);
        write_vtu(&path, &self.mesh, s)?;
        self.entries.push((s.time(), format!("vtu/{file}")));
        write_pvd(&self.pvd, &self.entries)?;
        Ok(path)
    }
}

/// Writes the `.pvd` collection `pvd` listing `entries` (time \[s\], file path relative to
/// the collection), through a temporary file and a rename so that ParaView never reads half
/// a file.
pub fn write_pvd(pvd: &Path, entries: &[(f64, String)]) -> Result<(), OutputError> {
    let mut text = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n",
    );
    for (t, f) in entries {
        text.push_str(&format!(
            "    <DataSet timestep=\"{t:e}\" group=\"\" part=\"0\" file=\"{f}\"/>\n"
        ));
    }
    text.push_str("  </Collection>\n</VTKFile>\n");
    let tmp = pvd.with_extension("pvd.tmp");
    std::fs::write(&tmp, text).map_err(|e| OutputError::write(&tmp, e))?;
    std::fs::rename(&tmp, pvd).map_err(|e| OutputError::write(pvd, e))
}
