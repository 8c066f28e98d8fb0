//! ParaView output: one `.vtu` (VTK XML unstructured grid) per output time and a `.pvd`
//! collection that lists them with their times, written through vtkio.
//!
//! Each file holds the **reference** mesh — points (X, Y, 0) in µm, the six-node P2
//! triangles as VTK quadratic triangles (cell type 22, whose node order — three corners
//! counter-clockwise, then the mid-sides of edges 0–1, 1–2, 2–0 — is ours) — with
//! - point data `displacement` (u_x, u_y, 0) [µm] (ParaView: *Warp By Vector* on it shows
//!   the deformed cell), `velocity` (v_x, v_y, 0) [µm/s] (the v unknowns with inertia, u̇
//!   without), `mu_as` [pN/µm³] (0 off the membrane, where it is not an unknown);
//! - cell data `domain` (0 nucleus, 1 cytoplasm, 2 membrane), `mean_E_norm` (the element's
//!   reference-area mean of ‖E‖_F) and `det_F` (its mean det F).
//!
//! The `.pvd` is rewritten after each file, so it lists every file written even when the
//! run stops early.

use std::path::{Path, PathBuf};

use vtkio::model::{
    Attribute, Attributes, ByteOrder, CellType, Cells, DataSet, UnstructuredGridPiece, Version,
    VertexNumbers, Vtk,
};

use super::OutputError;
use crate::fem::Domain;
use crate::record::MeshFile;
use crate::record::Snapshot;

/// The VTK cell type of a six-node triangle.
pub const QUADRATIC_TRIANGLE: u8 = 22;

/// Integer code of a domain in the `domain` cell array.
pub fn domain_code(d: Domain) -> i32 {
    match d {
        Domain::Nucleus => 0,
        Domain::Cytoplasm => 1,
        Domain::Membrane => 2,
    }
}

/// A [`OutputError::Vtk`] for `path` (shared by [`super::vtu3`]).
pub(crate) fn vtk_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Vtk {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Checks that a snapshot's per-node arrays (the lengths of `u`, `v` and `mu_as`) have
/// one entry per node of the mesh (`nodes`) and its per-element arrays (the lengths of
/// `element_strain` and `element_jacobian`) one per element (`elements`). Shared by both
/// models ([`super::vtu3::check_snapshot3`]).
pub(crate) fn check_lengths(
    nodes: usize,
    elements: usize,
    per_node: [usize; 3],
    per_element: [usize; 2],
) -> Result<(), String> {
    if per_node.iter().any(|&n| n != nodes) {
        return Err(format!(
            "snapshot has per-node arrays of the wrong length ({nodes} nodes)"
        ));
    }
    if per_element.iter().any(|&n| n != elements) {
        return Err(format!(
            "snapshot has per-element arrays of the wrong length ({elements} elements)"
        ));
    }
    Ok(())
}

/// One output time of either model as the `.vtu` holds it: a mesh whose points have `D`
/// coordinates and whose elements have `N` nodes, and a snapshot on it (arrays already
/// checked against the mesh). What [`vtk_model`] and [`super::vtu3::vtk_model3`] share.
pub(crate) struct GridData<'a, const D: usize, const N: usize> {
    /// Reference node coordinates [µm] (z = 0 when `D` is 2).
    pub nodes: &'a [[f64; D]],
    /// The elements' nodes, in the mesh's local order.
    pub elements: &'a [[usize; N]],
    /// VTK's local node `a` of a cell is the element's local node `vtk_order[a]`.
    pub vtk_order: [usize; N],
    /// The VTK type of every cell.
    pub cell_type: CellType,
    /// Domain of each element.
    pub domains: &'a [Domain],
    /// Displacement of every node [µm].
    pub u: &'a [[f64; D]],
    /// Velocity of every node [µm/s].
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

/// The VTK model of one output time (see the module documentation for its arrays).
pub fn vtk_model(mesh: &MeshFile, s: &Snapshot) -> Result<Vtk, String> {
    check_lengths(
        mesh.nodes.len(),
        mesh.elements.len(),
        [s.u.len(), s.v.len(), s.mu_as.len()],
        [s.element_strain.len(), s.element_jacobian.len()],
    )?;
    Ok(GridData {
        nodes: &mesh.nodes,
        elements: &mesh.elements,
        // Our node order is VTK's (see the module documentation).
        vtk_order: [0, 1, 2, 3, 4, 5],
        cell_type: CellType::QuadraticTriangle,
        domains: &mesh.domains,
        u: &s.u,
        v: &s.v,
        mu_as: &s.mu_as,
        element_strain: &s.element_strain,
        element_jacobian: &s.element_jacobian,
        title: format!("cellsim t = {} s", s.t),
    }
    .into_vtk())
}

/// A mesh whose output times are written as `.vtu` files: the 2-D [`MeshFile`] with its
/// [`Snapshot`]s, the 3-D [`Mesh3File`](crate::record::Mesh3File) with its
/// [`Snapshot3`](crate::record::Snapshot3)s ([`super::vtu3`]).
pub trait VtuMesh: Clone {
    /// The state of one output time on this mesh.
    type Snapshot;
    /// The time of `s` [s].
    fn time(s: &Self::Snapshot) -> f64;
    /// The VTK model of `s` ([`vtk_model`], [`super::vtu3::vtk_model3`]); an error if its
    /// arrays do not fit the mesh.
    fn vtk_model(&self, s: &Self::Snapshot) -> Result<Vtk, String>;
}

impl VtuMesh for MeshFile {
    type Snapshot = Snapshot;
    fn time(s: &Snapshot) -> f64 {
        s.t
    }
    fn vtk_model(&self, s: &Snapshot) -> Result<Vtk, String> {
        vtk_model(self, s)
    }
}

/// Writes the `.vtu` of one output time at `path` (of either model: [`VtuMesh`]).
pub fn write_vtu<M: VtuMesh>(path: &Path, mesh: &M, s: &M::Snapshot) -> Result<(), OutputError> {
    let vtk = mesh.vtk_model(s).map_err(|m| vtk_err(path, m))?;
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
/// (shared by [`super::vtu3::read_vtu_grid`]).
pub(crate) fn load_piece(path: &Path) -> Result<UnstructuredGridPiece, OutputError> {
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
pub(crate) fn summarise(piece: &UnstructuredGridPiece) -> VtuSummary {
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
        self.entries.push((M::time(s), format!("vtu/{file}")));
        write_pvd(&self.pvd, &self.entries)?;
        Ok(path)
    }
}

/// Writes the `.pvd` collection `pvd` listing `entries` (time [s], file path relative to
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
