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

fn vtk_err(path: &Path, e: impl std::fmt::Display) -> OutputError {
    OutputError::Vtk {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// The VTK model of one output time (see the module documentation for its arrays).
pub fn vtk_model(mesh: &MeshFile, s: &Snapshot) -> Result<Vtk, String> {
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
    let points: Vec<f64> = mesh.nodes.iter().flat_map(|p| [p[0], p[1], 0.0]).collect();
    let connectivity: Vec<u64> = mesh
        .elements
        .iter()
        .flat_map(|el| el.iter().map(|&i| i as u64))
        .collect();
    let offsets: Vec<u64> = (1..=ne as u64).map(|k| 6 * k).collect();
    let vec3 = |v: &[[f64; 2]]| -> Vec<f64> { v.iter().flat_map(|a| [a[0], a[1], 0.0]).collect() };
    let mu: Vec<f64> = s.mu_as.iter().map(|m| m.unwrap_or(0.0)).collect();
    let domains: Vec<i32> = mesh.domains.iter().map(|&d| domain_code(d)).collect();
    let piece = UnstructuredGridPiece {
        points: points.into(),
        cells: Cells {
            cell_verts: VertexNumbers::XML {
                connectivity,
                offsets,
            },
            types: vec![CellType::QuadraticTriangle; ne],
        },
        data: Attributes {
            point: vec![
                Attribute::generic("displacement", 3).with_data(vec3(&s.u)),
                Attribute::generic("velocity", 3).with_data(vec3(&s.v)),
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
        title: format!("cellsim t = {} s", s.t),
        byte_order: ByteOrder::LittleEndian,
        data: DataSet::inline(piece),
        file_path: None,
    })
}

/// Writes the `.vtu` of one output time at `path`.
pub fn write_vtu(path: &Path, mesh: &MeshFile, s: &Snapshot) -> Result<(), OutputError> {
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

/// Reads a `.vtu` back through vtkio and summarises it.
pub fn read_vtu(path: &Path) -> Result<VtuSummary, OutputError> {
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
    let name = |a: &Attribute| a.name().to_string();
    let displacement = piece.data.point.iter().find_map(|a| match a {
        Attribute::DataArray(d) if d.name == "displacement" => d.data.clone().cast_into::<f64>(),
        _ => None,
    });
    Ok(VtuSummary {
        points: piece.num_points(),
        cells: piece.cells.types.len(),
        cell_types: piece.cells.types.iter().map(|t| *t as u8).collect(),
        point_arrays: piece.data.point.iter().map(name).collect(),
        cell_arrays: piece.data.cell.iter().map(name).collect(),
        displacement,
    })
}

/// The `.vtu` files of one run and their `.pvd` collection.
pub struct VtuSeries {
    mesh: MeshFile,
    dir: PathBuf,
    pvd: PathBuf,
    name: String,
    entries: Vec<(f64, String)>,
}

impl VtuSeries {
    /// A series written into `out/vtu/<name>_NNNNN.vtu`, collected in `out/<name>.pvd`.
    pub fn new(out: &Path, name: &str, mesh: &MeshFile) -> Result<Self, OutputError> {
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
    pub fn write(&mut self, s: &Snapshot) -> Result<PathBuf, OutputError> {
        let file = format!("{}_{:05}.vtu", self.name, self.entries.len());
        let path = self.dir.join(&file);
        write_vtu(&path, &self.mesh, s)?;
        self.entries.push((s.t, format!("vtu/{file}")));
        self.write_pvd()?;
        Ok(path)
    }

    fn write_pvd(&self) -> Result<(), OutputError> {
        write_pvd(&self.pvd, &self.entries)
    }
}

/// Writes the `.pvd` collection `pvd` listing `entries` (time [s], file path relative to
/// the collection), through a temporary file and a rename so that ParaView never reads half
/// a file. Shared by the 2-D and the 3-D series ([`super::vtu3::VtuSeries3`]).
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
