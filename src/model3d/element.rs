//! Reference-element set-up of the 3-D quarter cell: everything about a ten-node
//! tetrahedron that does not change during a run, computed once from the mesh and the
//! parameters — the geometry at the points of the standard and the band rules, the
//! consistent mass, the active-strain tensors and the outward radial directions of the
//! membrane. The same set-up as the half-plane models' (`crate::model::element`) with 3-D
//! arrays.

use nalgebra::{Matrix3, Vector3};

use super::Params3;
use crate::fem::quadrature::TetRule;
use crate::fem::tet::{TetGeometry, TetTabulation};
use crate::fem::{Domain, Mesh3};
use crate::model::ModelParams;
use crate::model::kinematics::NodalOf;

/// Nodes of the element (ten-node P2 tetrahedron).
pub const NODES: usize = 10;

/// Displacement components of an element, node-major (`3 · a + i`).
pub const EDOF: usize = 3 * NODES;

/// A vector per node of an element.
pub type Nodal = NodalOf<3, NODES>;

/// Degree of the standard (solid and mass) rule: the mass integrand N_a N_b is of degree
/// 4 on a straight tetrahedron.
pub const STANDARD_DEGREE: usize = 4;

/// Per-element data computed once on the reference configuration.
pub(crate) struct Element3 {
    pub(crate) nodes: [usize; NODES],
    pub(crate) domain: Domain,
    /// Index of the solid law and density (nucleus, cytoplasm, membrane).
    pub(crate) solid: usize,
    /// Whether the element carries μ_as unknowns (membrane element with adhesion).
    pub(crate) with_mu: bool,
    /// Geometry at the points of the standard rule.
    pub(crate) geo: TetGeometry,
    /// `A_q` with `F_a = I − t_a A_q` at the standard points (empty: no active strain).
    pub(crate) active: Vec<Matrix3<f64>>,
    /// Consistent mass ∫ρ Nₐ N_b (scalar per node pair).
    pub(crate) mass: [[f64; NODES]; NODES],
    /// ∫ Nₐ N_b (unit density, for the drag).
    pub(crate) mass1: [[f64; NODES]; NODES],
    /// Geometry at the band-rule points.
    pub(crate) cgeo: TetGeometry,
    /// Outward radial reference direction (X − c)/|X − c| at the band points (membrane
    /// elements).
    pub(crate) radial: Vec<Vector3<f64>>,
}

/// The reference elements of a mesh and the tabulation of the band rule they share.
pub(crate) struct ReferenceElements3 {
    pub(crate) elements: Vec<Element3>,
    /// P2 shape functions at the band-rule points.
    pub(crate) ctab: TetTabulation,
}

/// Why an element cannot be set up.
#[derive(Debug, Clone, thiserror::Error)]
#[error("element {element}: {message}")]
pub struct ElementError {
    /// Index of the element in the mesh.
    pub element: usize,
    /// What is wrong with it.
    pub message: String,
}

impl ReferenceElements3 {
    /// Geometry, mass and active strain of every element of `mesh` under `params`: the
    /// standard rule of degree [`STANDARD_DEGREE`] (solid and mass), the band rule of
    /// `params.contact_degree` subdivided `params.contact_subdivisions` times (8 sub-tets
    /// per level). `adhesion_unknowns`: whether the membrane elements carry μ_as unknowns.
    pub(crate) fn new(
        p3: &Params3,
        mesh: &Mesh3,
        adhesion_unknowns: bool,
    ) -> Result<Self, ElementError> {
        let params = &p3.plane;
        let std_tab = TetTabulation::new(&TetRule::degree(STANDARD_DEGREE));
        let crule = TetRule::degree(params.contact_degree).subdivided(params.contact_subdivisions);
        let ctab = TetTabulation::new(&crule);
        let c = p3.center();
        let elements = mesh
            .elements
            .iter()
            .enumerate()
            .map(|(e, &nodes)| {
                Element3::reference(p3, mesh, e, nodes, &std_tab, &ctab, &c).map(|mut el| {
                    el.with_mu &= adhesion_unknowns;
                    el
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { elements, ctab })
    }
}

impl Element3 {
    /// Element `e` with `nodes` on the reference configuration.
    fn reference(
        p3: &Params3,
        mesh: &Mesh3,
        e: usize,
        nodes: [usize; NODES],
        std_tab: &TetTabulation,
        ctab: &TetTabulation,
        c: &Vector3<f64>,
    ) -> Result<Self, ElementError> {
        let params: &ModelParams = &p3.plane;
        let x: [[f64; 3]; NODES] = nodes.map(|i| mesh.nodes[i]);
        let domain = mesh.domains[e];
        let err = |message: String| ElementError {
            element: e,
            message,
        };
        let geo = std_tab.geometry(&x).map_err(|s| err(s.to_string()))?;
        let cgeo = ctab.geometry(&x).map_err(|s| err(s.to_string()))?;
        let solid = ModelParams::domain_index(domain);
        let rho = params.densities[solid];
        let mut mass1 = [[0.0; NODES]; NODES];
        for q in 0..std_tab.len() {
            let n = &std_tab.values[q];
            for a in 0..NODES {
                for b in 0..NODES {
                    mass1[a][b] += geo.jxw[q] * n[a] * n[b];
                }
            }
        }
        let mass = mass1.map(|row| row.map(|m| m * rho));
        let active = match params
            .active
            .filter(|a| a.pac.is_some() || a.bottom.is_some())
        {
            Some(act) => {
                let a: Vec<Matrix3<f64>> = geo
                    .x
                    .iter()
                    .map(|p| {
                        Matrix3::identity()
                            - act.fa3(&Vector3::new(p[0], p[1], p[2]), c.z, domain, 1.0)
                    })
                    .collect();
                if a.iter().all(|m| m.abs().max() == 0.0) {
                    Vec::new()
                } else {
                    a
                }
            }
            None => Vec::new(),
        };
        let radial = if domain == Domain::Membrane {
            cgeo.x
                .iter()
                .map(|p| (Vector3::new(p[0], p[1], p[2]) - c).normalize())
                .collect()
        } else {
            Vec::new()
        };
        Ok(Self {
            nodes,
            domain,
            solid,
            with_mu: params.adhesion.is_some() && domain == Domain::Membrane,
            geo,
            active,
            mass,
            mass1,
            cgeo,
            radial,
        })
    }

    /// The active-strain tensor `F_a = I − t_a A_q` at standard point `q` (`I` without
    /// active strain).
    #[inline]
    pub(crate) fn active_fa(&self, q: usize, t_a: f64) -> Matrix3<f64> {
        if self.active.is_empty() {
            Matrix3::identity()
        } else {
            Matrix3::identity() - self.active[q] * t_a
        }
    }
}

/// The nodal fields of an element gathered from (y, ẏ): displacements u, velocities v
/// (v with inertia, u̇ without) and accelerations v̇ (inertia only; else zero).
pub(crate) struct ElementState3 {
    pub(crate) u: Nodal,
    pub(crate) v: Nodal,
    pub(crate) a: Nodal,
}
