//! Reference-element set-up: everything about an element that does not change during a
//! run, computed once from the mesh and the parameters — the geometry at the points of
//! the standard and the band rules, the consistent mass, the active-strain tensors and
//! the outward radial directions of the membrane — for the six-node triangles and the
//! ten-node tetrahedra alike.
//!
//! In the axisymmetric model every integral is per radian, `∫ f r dA`: the quadrature
//! weights of both rules are multiplied by the reference radius r of their points here,
//! once, so that the mass, gravity, drag, band forces and observables integrate with the
//! weight r without further change, and the solid kernels find `Nₐ/r` (the hoop row of
//! the strain) at the standard points in [`ElementOf::hoop`]. The points of both rules are
//! interior to the element, so r > 0 there.

use nalgebra::{SMatrix, SVector};

use super::kinematics::NodalOf;
use super::shape::{Shape, TabOf};
use super::{ModelError, ModelParams};
use crate::fem::{CellMesh, Domain, ElementTabulation, GeometryOf};
use crate::physics::{Fibre, Fibres, KinematicModel};

/// Degree of the standard (solid and mass) rule: the mass integrand Nₐ N_b is of degree 4
/// on a straight element.
pub const STANDARD_DEGREE: usize = 4;

/// Per-element data computed once on the reference configuration.
pub(crate) struct ElementOf<const D: usize, const N: usize> {
    pub(crate) nodes: [usize; N],
    pub(crate) domain: Domain,
    /// Index of the solid law and density (nucleus, cytoplasm, membrane).
    pub(crate) solid: usize,
    /// Whether the element carries μ_as unknowns (membrane element with adhesion).
    pub(crate) with_mu: bool,
    /// Geometry at the points of the standard rule.
    pub(crate) geo: GeometryOf<D, N>,
    /// `A_q` with `F_a = I − t_a A_q` at the standard points (empty: no active strain).
    pub(crate) active: Vec<SMatrix<f64, D, D>>,
    /// The fibre families at the standard points (MODEL.md §11; empty: no fibres, which
    /// is every element but the cytoplasm's when the case has fibres).
    pub(crate) fibres: Vec<[Fibre<D>; 2]>,
    /// Consistent mass ∫ρ Nₐ N_b (scalar per node pair).
    pub(crate) mass: [[f64; N]; N],
    /// ∫ Nₐ N_b (unit density, for the drag).
    pub(crate) mass1: [[f64; N]; N],
    /// Geometry at the band-rule points.
    pub(crate) cgeo: GeometryOf<D, N>,
    /// Outward radial reference direction (X − c)/|X − c| at the band points (membrane
    /// elements).
    pub(crate) radial: Vec<SVector<f64, D>>,
    /// Axisymmetric: `Nₐ/r` at the standard points (`∂λ_θ/∂u_(a,r)`, λ_θ = 1 + u_r/r);
    /// empty otherwise.
    pub(crate) hoop: Vec<[f64; N]>,
}

/// The reference elements of a mesh and the tabulation of the band rule they share.
pub(crate) struct ReferenceElements<T, const D: usize, const N: usize> {
    pub(crate) elements: Vec<ElementOf<D, N>>,
    /// Shape functions at the band-rule points.
    pub(crate) ctab: T,
}

impl<T: ElementTabulation<D, N>, const D: usize, const N: usize> ReferenceElements<T, D, N> {
    /// Geometry, mass and active strain of every element of `mesh` under `params`: the
    /// standard rule of degree [`STANDARD_DEGREE`] (solid and mass), the band rule of
    /// `params.contact_degree` subdivided `params.contact_subdivisions` times.
    /// `adhesion_unknowns`: whether the membrane elements carry μ_as unknowns (adhesion
    /// modelled and not deferred).
    pub(crate) fn new<S: Shape<D, N, E, Mesh: CellMesh<D, N, Tab = T>>, const E: usize>(
        params: &ModelParams,
        mesh: &S::Mesh,
        adhesion_unknowns: bool,
    ) -> Result<Self, ModelError> {
        let std_tab = T::on_rule(STANDARD_DEGREE, 0);
        let ctab = T::on_rule(params.contact_degree, params.contact_subdivisions);
        let elements = (0..mesh.elements().len())
            .map(|e| {
                ElementOf::reference::<S, E>(params, mesh, e, &std_tab, &ctab)
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

impl<const D: usize, const N: usize> ElementOf<D, N> {
    /// Element `e` of `mesh` on the reference configuration.
    fn reference<S: Shape<D, N, E>, const E: usize>(
        params: &ModelParams,
        mesh: &S::Mesh,
        e: usize,
        std_tab: &TabOf<S, D, N, E>,
        ctab: &TabOf<S, D, N, E>,
    ) -> Result<Self, crate::fem::ElementGeometryError> {
        let nodes = mesh.elements()[e];
        let x = mesh.element_coords(e);
        let domain = mesh.domains()[e];
        let mut geo = std_tab.element_geometry(&x)?;
        let mut cgeo = ctab.element_geometry(&x)?;
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
                .zip(std_tab.values())
                .map(|(p, n)| n.map(|v| v / p[0]))
                .collect();
        }
        let solid = ModelParams::domain_index(domain);
        let rho = params.densities[solid];
        // M₁_ab = ∫ Nₐ N_b on the standard rule; M = ρ M₁.
        let mut mass1 = [[0.0; N]; N];
        for (q, n) in std_tab.values().iter().enumerate() {
            for a in 0..N {
                for b in 0..N {
                    mass1[a][b] += geo.jxw[q] * n[a] * n[b];
                }
            }
        }
        let mass = mass1.map(|row| row.map(|m| m * rho));
        let c = S::center(params);
        let active = match params
            .active
            .filter(|a| a.pac.is_some() || a.bottom.is_some())
        {
            Some(act) => {
                let a: Vec<SMatrix<f64, D, D>> = geo
                    .x
                    .iter()
                    .map(|p| SMatrix::identity() - S::active_tensor(&act, p, &c, domain))
                    .collect();
                if a.iter().all(|m| m.abs().max() == 0.0) {
                    Vec::new()
                } else {
                    a
                }
            }
            None => Vec::new(),
        };
        let fibres = match (params.fibres, params.active) {
            (Some(_), Some(act)) if domain == Domain::Cytoplasm => {
                let f: Vec<[Fibre<D>; 2]> = geo.x.iter().map(|p| S::fibres(&act, p, &c)).collect();
                if f.iter().flatten().all(|fib| fib.chi == 0.0) {
                    Vec::new()
                } else {
                    f
                }
            }
            _ => Vec::new(),
        };
        let radial = if domain == Domain::Membrane {
            cgeo.x
                .iter()
                .map(|p| (SVector::from(*p) - c).normalize())
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
            fibres,
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
    pub(crate) fn active_fa(&self, q: usize, t_a: f64) -> SMatrix<f64, D, D> {
        if self.active.is_empty() {
            SMatrix::identity()
        } else {
            SMatrix::identity() - self.active[q] * t_a
        }
    }

    /// Adds the fibres' stress at standard point `q` (`F` there, the active strain `fa`)
    /// to the first Piola–Kirchhoff stress `p`, and with `tangent` their `∂P/∂F` to it
    /// (MODEL.md §11; nothing where the element has no fibres).
    #[inline]
    pub(crate) fn add_fibres<const M: usize>(
        &self,
        law: Option<&Fibres>,
        q: usize,
        f: &SMatrix<f64, D, D>,
        fa: &SMatrix<f64, D, D>,
        p: &mut SMatrix<f64, D, D>,
        tangent: Option<&mut SMatrix<f64, M, M>>,
    ) {
        let (Some(law), Some(families)) = (law, self.fibres.get(q)) else {
            return;
        };
        let mut tangent = tangent;
        for fib in families.iter().filter(|fib| fib.chi > 0.0) {
            let af = fib.under(fa);
            law.add_piola(f, &af, p);
            if let Some(t) = tangent.as_deref_mut() {
                law.add_tangent(f, &af, t);
            }
        }
    }
}

/// The nodal fields of an element gathered from (y, ẏ): displacements u, velocities v
/// (v with inertia, u̇ without) and accelerations v̇ (inertia only; else zero).
pub(crate) struct ElementState<const D: usize, const N: usize> {
    pub(crate) u: NodalOf<D, N>,
    pub(crate) v: NodalOf<D, N>,
    pub(crate) a: NodalOf<D, N>,
}
