//! Reference-element set-up: everything about an element that does not change during a
//! run, computed once from the mesh and the parameters — the geometry at the points of
//! the standard and the band rules, the consistent mass, the active-strain tensors and
//! the outward radial directions of the membrane.
//!
//! In the axisymmetric model every integral is per radian, `∫ f r dA`: the quadrature
//! weights of both rules are multiplied by the reference radius r of their points here,
//! once, so that the mass, gravity, drag, band forces and observables integrate with the
//! weight r without further change, and the solid kernels find `Nₐ/r` (the hoop row of
//! the strain) at the standard points in [`Element::hoop`]. The points of both rules are
//! interior to the element, so r > 0 there.

use nalgebra::Vector2;

use super::kinematics::{DIM, NodalOf, Tensor, Vector};
use super::{ModelError, ModelParams};
use crate::fem::p2::{ElementGeometry, P2Tabulation};
use crate::fem::quadrature::TriangleRule;
use crate::fem::{Domain, Mesh};
use crate::physics::{ActiveStrain, KinematicModel};

/// Nodes of the element (six-node P2 triangle).
pub const NODES: usize = 6;

/// Displacement components of an element, node-major (`DIM · a + i`).
pub const EDOF: usize = DIM * NODES;

/// A vector per node of an element.
pub type Nodal = NodalOf<DIM, NODES>;

/// Per-element data computed once on the reference configuration.
pub(crate) struct Element {
    pub(crate) nodes: [usize; NODES],
    pub(crate) domain: Domain,
    /// Index of the solid law and density (nucleus, cytoplasm, membrane).
    pub(crate) solid: usize,
    /// Whether the element carries μ_as unknowns (membrane element with adhesion).
    pub(crate) with_mu: bool,
    /// Geometry at the points of the standard rule.
    pub(crate) geo: ElementGeometry,
    /// `A_q` with `F_a = I − t_a A_q` at the standard points (empty: no active strain).
    pub(crate) active: Vec<Tensor<f64>>,
    /// Consistent mass ∫ρ Nₐ N_b (scalar per node pair).
    pub(crate) mass: [[f64; NODES]; NODES],
    /// ∫ Nₐ N_b (unit density, for the drag).
    pub(crate) mass1: [[f64; NODES]; NODES],
    /// Geometry at the band-rule points.
    pub(crate) cgeo: ElementGeometry,
    /// Outward radial reference direction at the band points (membrane elements).
    pub(crate) radial: Vec<Vector<f64>>,
    /// Axisymmetric: `Nₐ/r` at the standard points (`∂λ_θ/∂u_(a,r)`, λ_θ = 1 + u_r/r);
    /// empty in plane strain.
    pub(crate) hoop: Vec<[f64; NODES]>,
}

/// The reference elements of a mesh and the tabulation of the band rule they share.
pub(crate) struct ReferenceElements {
    pub(crate) elements: Vec<Element>,
    /// P2 shape functions at the band-rule points.
    pub(crate) ctab: P2Tabulation,
}

impl ReferenceElements {
    /// Geometry, mass and active strain of every element of `mesh` under `params`:
    /// the standard rule of degree 4 (solid and mass), the band rule of
    /// `params.contact_degree` subdivided `params.contact_subdivisions` times.
    /// `adhesion_unknowns`: whether the membrane elements carry μ_as unknowns (adhesion
    /// modelled and not deferred).
    pub(crate) fn new(
        params: &ModelParams,
        mesh: &Mesh,
        adhesion_unknowns: bool,
    ) -> Result<Self, ModelError> {
        let std_tab = P2Tabulation::new(&TriangleRule::degree(4));
        let crule =
            TriangleRule::degree(params.contact_degree).subdivided(params.contact_subdivisions);
        let ctab = P2Tabulation::new(&crule);
        let active = params
            .active
            .filter(|a| a.pac.is_some() || a.bottom.is_some());
        let c = Vector2::new(params.center[0], params.center[1]);
        let elements = mesh
            .elements
            .iter()
            .enumerate()
            .map(|(e, &nodes)| {
                Element::reference(params, mesh, e, nodes, &std_tab, &ctab, active.as_ref(), &c)
                    .map(|mut el| {
                        el.with_mu &= adhesion_unknowns;
                        el
                    })
                    .map_err(|source| ModelError::Geometry { element: e, source })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self { elements, ctab })
    }
}

impl Element {
    /// Element `e` with `nodes` on the reference configuration.
    #[allow(clippy::too_many_arguments)]
    fn reference(
        params: &ModelParams,
        mesh: &Mesh,
        e: usize,
        nodes: [usize; NODES],
        std_tab: &P2Tabulation,
        ctab: &P2Tabulation,
        active: Option<&ActiveStrain>,
        c: &Vector2<f64>,
    ) -> Result<Self, crate::fem::P2Error> {
        let x = mesh.element_coords(e);
        let domain = mesh.domains[e];
        let mut geo = std_tab.geometry(&x)?;
        let mut cgeo = ctab.geometry(&x)?;
        let mut hoop = Vec::new();
        if params.kinematics == KinematicModel::Axisymmetric {
            // Work per radian: dV = r dA. The rules' points are interior, so r > 0.
            for g in [&mut geo, &mut cgeo] {
                for (w, p) in g.jxw.iter_mut().zip(&g.x) {
                    *w *= p[0];
                }
            }
            hoop = geo
                .x
                .iter()
                .zip(&std_tab.values)
                .map(|(p, n)| n.map(|v| v / p[0]))
                .collect();
        }
        let solid = ModelParams::domain_index(domain);
        let rho = params.densities[solid];
        // M₁_ab = ∫ Nₐ N_b on the standard rule; M = ρ M₁.
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
        let active_q: Vec<Tensor<f64>> = match active {
            Some(act) => {
                let a: Vec<Tensor<f64>> = geo
                    .x
                    .iter()
                    .map(|p| {
                        Tensor::<f64>::identity() - act.fa(&Vector2::new(p[0], p[1]), domain, 1.0)
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
                .map(|p| (Vector2::new(p[0], p[1]) - c).normalize())
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
            active: active_q,
            mass,
            mass1,
            cgeo,
            radial,
            hoop,
        })
    }

    /// The active-strain tensor `F_a = I − t_a A_q` at standard point `q` (`I` without
    /// active strain).
    #[inline]
    pub(crate) fn active_fa(&self, q: usize, t_a: f64) -> Tensor<f64> {
        if self.active.is_empty() {
            Tensor::<f64>::identity()
        } else {
            Tensor::<f64>::identity() - self.active[q] * t_a
        }
    }
}

/// The nodal fields of an element gathered from (y, ẏ): displacements u, velocities v
/// (v with inertia, u̇ without) and accelerations v̇ (inertia only; else zero).
pub(crate) struct ElementState {
    pub(crate) u: Nodal,
    pub(crate) v: Nodal,
    pub(crate) a: Nodal,
}
