//! The cell as one DAE (MODEL.md §8, §10): P2 finite elements of the cell with a
//! compressible Yeoh solid, active strain and Kelvin–Voigt viscosity, gravity, penalty
//! contact, the adhesive spreading force and the μ_as field — one model for the half cell
//! (six-node triangles, plane strain or axisymmetric: [`CellModel`]) and the 3-D quarter
//! cell (ten-node tetrahedra: [`QuarterCell`]), generic over the [`Shape`] (dimension,
//! element, mesh, substrate) and, inside the element loops, the kinematic model's
//! `kernels::Formulation`.
//!
//! Unknowns y = (u, v, μ_as) with inertia, (u, μ_as) without ([`dofs::DofMapOf`]).
//! Residual:
//! - kinematics (inertia only): `u̇ − v = 0`;
//! - momentum: `M v̇ + f_int(u, v) + c_d M₁ v − f_ext(t, u, μ_as) = 0` (consistent mass M,
//!   unit-density mass M₁ for the medium drag), or without inertia
//!   `f_int(u, u̇) + c_d M₁ u̇ − f_ext = 0`;
//! - adhesion (membrane nodes): `Ȧ − a(x) = 0` for the exposure A (μ_as = Φ(A),
//!   [`history`]), collocated at the nodes.
//!
//! The iteration matrix `J = ∂F/∂y + cj ∂F/∂ẏ` is exact: material tangents from the
//! physics module, contact and adhesion derivatives by forward-mode dual numbers at each
//! quadrature point, assembled into a pattern fixed at construction by positions computed
//! once per element (refilling, never rebuilding).
//!
//! Layout: `element` sets up the reference elements (geometry, mass, active strain);
//! [`kinematics`] gives the quadrature-point kinematics (F, Ḟ, x, J); `kernels` gives
//! each term's residual contribution and tangent per element (solid, mass, contact and
//! adhesion band, μ_as rate), `axisym` the axisymmetric solid kernels; `plan` is the
//! assembly plan (pattern and positions, built once) that scatters them; [`shape`] what
//! the dimension changes; `switch` the changes of system during a run (inertia off, the
//! μ_as unknowns added, a case branched); [`observe`] what a scene reports, and
//! `quarter` what only the 3-D cell reports.
//!
//! Contact and adhesion act as body forces in thin bands near the substrate. They are
//! integrated with a separate high-degree (optionally subdivided) rule, and only on the
//! elements that can reach the band in the current configuration: an element is skipped
//! when every node lies further from the substrate than the band's reach plus the
//! element's current diameter (the integrand is then exactly zero everywhere in it), and
//! inside an element the points below the band.

mod axisym;
pub mod dofs;
mod element;
pub mod events;
pub mod history;
pub(crate) mod kernels;
pub mod kinematics;
pub mod observables;
pub mod observe;
pub(crate) mod plan;
mod quarter;
mod self_contact;
pub mod shape;
mod switch;

use nalgebra::SVector;

use crate::dae::{Dae, DaeError, FirstOrderBlocks, Inadmissible, Pattern};
use crate::fem::{CellMesh, Domain, ElementGeometryError};
use crate::physics::{
    ActiveStrain, Adhesion, Condition, Contact, Fibres, KinematicModel, Lattice, Phases, Substrate,
    Surface, Viscosity, Yeoh,
};
use dofs::{DofMapOf, NONE};
pub use element::STANDARD_DEGREE;
use element::{ElementOf, ElementState, ReferenceElements};
use history::AdhesionHistoryOf;
use kernels::{Formulation, Switches};
use kinematics::NodalOf;
pub(crate) use kinematics::deformation;
use plan::{PlanOf, TangentOf};
use shape::TabOf;
pub use shape::{Constraints, Evaluation, HalfPlane, Quarter, Shape, State};
pub use switch::Restart;

/// Physical parameters of a scene in solver units (µm, s, pN).
#[derive(Debug, Clone)]
pub struct ModelParams {
    /// Plane strain (the paper's 2-D half cell, per unit thickness), axisymmetric (the
    /// (x, y) half-plane is the meridian (r, y) of a 3-D cell, every integral per radian)
    /// or 3-D (the quarter cell, [`QuarterCell`]).
    pub kinematics: KinematicModel,
    /// Cell centre c \[µm\] in the plane z = 0 (the 3-D cell's is (c_x, c_y, 0)).
    pub center: [f64; 2],
    /// Solid law of the nucleus, cytoplasm and membrane.
    pub solids: [Yeoh; 3],
    /// Mass densities of nucleus, cytoplasm, membrane [pN·s²/µm⁴].
    pub densities: [f64; 3],
    /// Kelvin–Voigt viscosity (whole cell).
    pub viscosity: Viscosity,
    /// Gravity g \[µm/s²\].
    pub gravity: f64,
    /// Phase switches and the optional gravity flip.
    pub phases: Phases,
    /// The substrate (in 3-D its section z = 0, the pillars on [`Self::lattice`]).
    pub substrate: Substrate,
    /// 3-D: where the pillar axes lie in z (unused by the half-plane models).
    pub lattice: Lattice,
    /// Penalty contact.
    pub contact: Contact,
    /// Adhesion (absent: no μ_as unknowns).
    pub adhesion: Option<Adhesion>,
    /// Active strain (absent or without regions: no active terms).
    pub active: Option<ActiveStrain>,
    /// Fibres in the cytoplasm's active regions (MODEL.md §11; absent: the paper's
    /// isotropic cell). They lie in the regions of [`Self::active`].
    pub fibres: Option<Fibres>,
    /// Model inertia (v unknowns and the mass matrix).
    pub inertia: bool,
    /// Medium drag c_d [pN·s/µm⁴] per unit reference volume (MODEL.md §8).
    pub drag: f64,
    /// Polynomial degree of the contact/adhesion quadrature rule.
    pub contact_degree: usize,
    /// Subdivision levels of that rule (4^levels sub-triangles, 8^levels sub-tetrahedra).
    pub contact_subdivisions: u32,
    /// Extra breakpoints (e.g. the scene's end time).
    pub extra_breakpoints: Vec<f64>,
    /// The conditions whose root functions the integrators watch (MODEL.md §11: the
    /// phases the cell starts itself, not yet started), two functions each
    /// ([`events`]). Empty: no root functions.
    pub events: Vec<Condition>,
}

impl ModelParams {
    /// Whether the outline's self-contact is in the model (half-plane models with
    /// `contact.self_contact`): only where the outline can fold, on pillars and once
    /// adhesion acts (`adhesion_unknowns`: the μ_as unknowns are in the system; from the
    /// start without adhesion). A fold forms where adhesion holds the membrane on a
    /// pillar's wall and the cell sinks past it; on a flat substrate and during the fall no
    /// face of the outline comes near another, and the pairs would only fill the
    /// Jacobian's pattern (docs/benchmarks.md, "Self-contact only where a fold can form").
    pub(crate) fn may_fold(&self, adhesion_unknowns: bool) -> bool {
        self.contact.self_contact
            && matches!(self.substrate, Substrate::Pillars(_))
            && (adhesion_unknowns || self.adhesion.is_none())
    }

    pub(crate) fn domain_index(d: Domain) -> usize {
        match d {
            Domain::Nucleus => 0,
            Domain::Cytoplasm => 1,
            Domain::Membrane => 2,
        }
    }
}

/// Why a model cannot be built.
#[derive(Debug, Clone, thiserror::Error)]
pub enum ModelError {
    /// The kinematic model does not go with the mesh (the 3-D model on the half-plane
    /// mesh, a half-plane model on the 3-D mesh).
    #[error("the {model:?} model cannot be built on the {elements} mesh")]
    Kinematics {
        /// The parameters' kinematic model.
        model: KinematicModel,
        /// The mesh's elements.
        elements: &'static str,
    },
    /// An element's reference geometry is invalid (inverted or degenerate).
    #[error("element {element}: {source}")]
    Geometry {
        /// Index of the element in the mesh.
        element: usize,
        /// What is wrong with it.
        source: ElementGeometryError,
    },
    /// A system rebuilt during a run could not be made consistent with the old state.
    #[error("{what} at t = {t}: {source}")]
    Restart {
        /// The change of system (e.g. "switching inertia off").
        what: &'static str,
        /// Time of the change \[s\].
        t: f64,
        /// The consistent-initialisation failure.
        source: Box<crate::dae::IntegratorError>,
    },
}

/// The cell model as a [`Dae`], on the shape `S` (dimension `D`, `N` nodes and `E = D·N`
/// unknowns per element).
pub struct CellOf<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> {
    /// Parameters.
    pub params: ModelParams,
    /// The substrate (from the parameters).
    pub substrate: S::Substrate,
    /// The mesh.
    pub mesh: S::Mesh,
    /// Unknown numbering.
    pub dofs: DofMapOf<D>,
    /// The symmetry conditions.
    pub constraints: Constraints,
    elements: Vec<ElementOf<D, N>>,
    ctab: TabOf<S, D, N, E>,
    plan: PlanOf<D, N, E>,
    /// Initial state (t₀, y₀, ẏ₀) when not the rest state at t = 0 (restarts).
    initial_state: Option<(f64, Vec<f64>, Vec<f64>)>,
    /// The exposure integrated beside the system while adhesion is modelled but cannot
    /// act yet (before T_g0): its unknowns are then left out ([`history`]).
    history: Option<AdhesionHistoryOf<D, S::Substrate>>,
    /// Whether the element loops run on rayon's threads ([`Self::set_parallel`]).
    parallel: bool,
    scratch: Scratch<D, N, E>,
    /// The element the last evaluation found inadmissible, with the centroid of its nodes
    /// in that state; `None` after an evaluation that succeeded ([`Self::last_inadmissible`]).
    inadmissible: Option<(Inadmissible, Domain, [f64; D])>,
    /// The outline's self-contact (half-plane models with `contact.self_contact`).
    self_contact: Option<self_contact::SelfContact>,
}

/// The half-plane models (plane strain, axisymmetric) on six-node triangles.
pub type CellModel = CellOf<HalfPlane, 2, 6, 12>;

/// The 3-D quarter cell on ten-node tetrahedra.
pub type QuarterCell = CellOf<Quarter, 3, 10, 30>;

/// Elements per block of the element loops: each block's element vectors or tangents
/// are computed (in parallel, or not) into a buffer, then scattered in element order.
pub(crate) const BLOCK: usize = 64;

/// The per-block buffers of the element loops, kept between calls.
struct Scratch<const D: usize, const N: usize, const E: usize> {
    vectors: Vec<(NodalOf<D, N>, Result<(), DaeError>)>,
    tangents: Vec<(Box<TangentOf<E, N>>, Result<(), DaeError>)>,
    /// Φ(A), dΦ/dA per μ_as unknown ([`CellOf::fill_caps`]).
    caps: Vec<(f64, f64)>,
}

impl<const D: usize, const N: usize, const E: usize> Default for Scratch<D, N, E> {
    fn default() -> Self {
        Self {
            vectors: Vec::new(),
            tangents: Vec::new(),
            caps: Vec::new(),
        }
    }
}

impl<const D: usize, const N: usize, const E: usize> Scratch<D, N, E> {
    fn take_vectors(&mut self) -> Vec<(NodalOf<D, N>, Result<(), DaeError>)> {
        let mut b = std::mem::take(&mut self.vectors);
        b.resize_with(BLOCK, || ([[0.0; D]; N], Ok(())));
        b
    }

    fn take_tangents(&mut self) -> Vec<(Box<TangentOf<E, N>>, Result<(), DaeError>)> {
        let mut b = std::mem::take(&mut self.tangents);
        b.resize_with(BLOCK, || (Box::new(TangentOf::zeros()), Ok(())));
        b
    }
}

/// `Ok` when every value of `v` is finite, else `what` is not.
fn all_finite(v: &[f64], what: &'static str) -> Result<(), DaeError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(DaeError::Inadmissible(Inadmissible::NonFinite(what)))
    }
}

/// `e` with the time `t` of the residual or Jacobian that met it.
fn at_time(e: DaeError, t: f64) -> DaeError {
    match e {
        DaeError::Inadmissible(i) => DaeError::Inadmissible(i.at(t)),
        other => other,
    }
}

/// The element loop of a residual or a Jacobian over `ne` elements: for each block of
/// [`BLOCK`] elements, `compute(e, out)` for every element of the block into `buf` (on
/// rayon's threads when `parallel`), then `scatter(e, out)` in element order. Stops at the
/// first element (in order) whose `compute` failed. The results are the same bits in
/// parallel or not: each element is computed on its own and added in order.
pub(crate) fn in_blocks<T: Send>(
    ne: usize,
    parallel: bool,
    buf: &mut [(T, Result<(), DaeError>)],
    compute: impl Fn(usize, &mut T) -> Result<(), DaeError> + Sync,
    mut scatter: impl FnMut(usize, &T),
) -> Result<(), DaeError> {
    use rayon::prelude::*;
    for start in (0..ne).step_by(BLOCK) {
        let n = BLOCK.min(ne - start);
        let block = &mut buf[..n];
        let run = |(k, (out, res)): (usize, &mut (T, Result<(), DaeError>))| {
            *res = compute(start + k, out);
        };
        if parallel {
            block.par_iter_mut().enumerate().for_each(run);
        } else {
            block.iter_mut().enumerate().for_each(run);
        }
        for (k, (out, res)) in block.iter_mut().enumerate() {
            std::mem::replace(res, Ok(()))?;
            scatter(start + k, out);
        }
    }
    Ok(())
}

impl<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> CellOf<S, D, N, E> {
    /// Builds the model on `mesh` (the quarter cell's symmetry for 3-D): unknown
    /// numbering, the reference elements (geometry, mass, active strain) and the assembly
    /// plan (the pattern of the iteration matrix and the positions to refill it).
    pub fn new(params: ModelParams, mesh: S::Mesh) -> Result<Self, ModelError> {
        Self::with_constraints(params, mesh, Constraints::Quarter)
    }

    /// As [`Self::new`] with the symmetry conditions `constraints` (the 3-D slab check).
    pub fn with_constraints(
        params: ModelParams,
        mesh: S::Mesh,
        constraints: Constraints,
    ) -> Result<Self, ModelError> {
        let adhesion = params.adhesion.is_some();
        Self::build(params, mesh, constraints, adhesion)
    }

    /// As [`Self::new`], but with adhesion modelled its μ_as unknowns are left out until
    /// adhesion can act (T_g0): the exposure is integrated beside the system along the
    /// accepted steps ([`history`]), and [`Self::with_adhesion_unknowns`] adds the
    /// unknowns. Starting at T_g0 or later, the unknowns are there from the start.
    pub fn deferring_adhesion(params: ModelParams, mesh: S::Mesh) -> Result<Self, ModelError> {
        let Some(ad) = params.adhesion else {
            return Self::new(params, mesh);
        };
        if params
            .phases
            .adhesion
            .is_some_and(|[start, _]| start <= 0.0)
        {
            return Self::new(params, mesh);
        }
        let mut m = Self::build(params, mesh, Constraints::Quarter, false)?;
        let nodes = m.membrane_nodes();
        let x = nodes.iter().map(|&i| m.mesh.nodes()[i]).collect();
        let xdot = vec![[0.0; D]; nodes.len()];
        let mu = vec![0.0; nodes.len()];
        m.history = Some(AdhesionHistoryOf::new(ad, m.substrate, 0.0, mu, x, xdot));
        Ok(m)
    }

    /// The model on `mesh`, with the μ_as unknowns when `adhesion_unknowns`.
    fn build(
        params: ModelParams,
        mesh: S::Mesh,
        constraints: Constraints,
        adhesion_unknowns: bool,
    ) -> Result<Self, ModelError> {
        if (params.kinematics == KinematicModel::ThreeD) != (D == 3) {
            return Err(ModelError::Kinematics {
                model: params.kinematics,
                elements: <S::Mesh as CellMesh<D, N>>::ELEMENTS,
            });
        }
        let eliminated = S::eliminated(&mesh, constraints);
        let mut tied = vec![false; mesh.nodes().len()];
        for &i in S::tied(&mesh) {
            tied[i] = true;
        }
        let dofs = DofMapOf::<D>::numbered(
            mesh.nodes().len(),
            |i, c| eliminated[i][c],
            |i, c| (tied[i] && c == D - 1).then_some(0),
            &mesh.nodes_of_domain(Domain::Membrane),
            params.inertia,
            adhesion_unknowns,
        );
        let ReferenceElements { elements, ctab } =
            ReferenceElements::new::<S, E>(&params, &mesh, adhesion_unknowns)?;
        let plan_elements: Vec<_> = elements.iter().map(|el| (el.nodes, el.with_mu)).collect();
        let outline = if D == 2 && params.may_fold(adhesion_unknowns) {
            S::outline(&mesh)
        } else {
            Vec::new()
        };
        let mut self_contact = (!outline.is_empty()).then(|| {
            let nodes = mesh.nodes();
            self_contact::SelfContact::new(
                outline,
                |i| [nodes[i][0], nodes[i][1]],
                params.kinematics == KinematicModel::Axisymmetric,
            )
        });
        let extra: Vec<[usize; 5]> = self_contact.iter().flat_map(|sc| sc.node_sets()).collect();
        let plan = PlanOf::new(&dofs, &plan_elements, &extra);
        if let Some(sc) = &mut self_contact {
            let two = |m: [usize; D]| [m[0], m[1]];
            sc.locate(
                &plan.pattern,
                |i| two(dofs.momentum_rows(i)),
                |i| two(dofs.u[i]),
            );
        }
        Ok(Self {
            substrate: S::substrate(&params),
            params,
            mesh,
            dofs,
            constraints,
            elements,
            ctab,
            plan,
            initial_state: None,
            history: None,
            parallel: false,
            scratch: Scratch::default(),
            inadmissible: None,
            self_contact,
        })
    }

    /// Runs the element loops (residual and Jacobian) on rayon's thread pool. The results
    /// are the same bits either way: each element's contribution is computed on its own
    /// and the contributions are added in element order (`solver.parallel_elements`, on
    /// in the 3-D scenes: 0.83× the wall time of the coarse eighth push-pull with GMRES,
    /// docs/benchmarks.md). Off in the 2-D runs: on 2 cores
    /// it made the flat gravity phase 1.17× slower at refine 1 and 2 and push-pull 1.22×
    /// (paired runs against `RAYON_NUM_THREADS=1`, medians of 3–7, quiet machine,
    /// 2026-12-02; perf put a fifth of the samples in the pool's `sched_yield` and futex
    /// calls).
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel;
    }

    /// Whether the element loops run in parallel.
    pub fn parallel(&self) -> bool {
        self.parallel
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elements.len()
    }

    /// The nodes of the membrane elements, in the order of the μ_as unknowns.
    fn membrane_nodes(&self) -> Vec<usize> {
        let on = self.mesh.nodes_of_domain(Domain::Membrane);
        (0..on.len()).filter(|&i| on[i]).collect()
    }

    /// Whether the μ_as unknowns are left out until adhesion can act (then
    /// [`Self::with_adhesion_unknowns`] is due at T_g0).
    pub fn adhesion_deferred(&self) -> bool {
        self.history.is_some()
    }

    /// Number of μ_as values (unknowns, or integrated beside the system while deferred).
    pub fn n_mu_as(&self) -> usize {
        self.history.as_ref().map_or(self.dofs.n_mu(), |h| h.len())
    }

    /// μ_as per mesh node at time `t` with state `y` (`None` off the membrane or without
    /// adhesion): the unknowns, or while deferred the history's values (`t` within the
    /// integrator's last step).
    pub fn nodal_mu_as(
        &self,
        t: f64,
        y: &[f64],
    ) -> Result<Vec<Option<f64>>, history::OutsideHistory> {
        let n = self.mesh.nodes().len();
        let Some(ad) = &self.params.adhesion else {
            return Ok(vec![None; n]);
        };
        let mu = |a: f64| history::cap(a, ad.mu_as_max).0;
        match &self.history {
            None => Ok((0..n)
                .map(|i| (self.dofs.mu[i] != NONE).then(|| mu(y[self.dofs.mu[i]])))
                .collect()),
            Some(h) => {
                let a = h.at(t)?;
                let mut out = vec![None; n];
                for (k, i) in self.membrane_nodes().into_iter().enumerate() {
                    out[i] = Some(mu(a[k]));
                }
                Ok(out)
            }
        }
    }

    /// Positions and velocities of the membrane nodes from (y, ẏ) (velocity u̇).
    fn membrane_motion(&self, y: &[f64], yp: &[f64]) -> (Vec<[f64; D]>, Vec<[f64; D]>) {
        let nodes = self.membrane_nodes();
        let x = nodes
            .iter()
            .map(|&i| {
                let u = self.dofs.node_u(y, i);
                std::array::from_fn(|k| self.mesh.nodes()[i][k] + u[k])
            })
            .collect();
        let xdot = nodes.iter().map(|&i| self.dofs.node_u(yp, i)).collect();
        (x, xdot)
    }

    /// Starts the integration from (t₀, y₀, ẏ₀) instead of the rest state at t = 0.
    pub fn set_initial(&mut self, t0: f64, y0: Vec<f64>, yp0: Vec<f64>) {
        self.initial_state = Some((t0, y0, yp0));
    }

    /// The time the integration starts from: 0, or that of [`Self::set_initial`].
    pub fn initial_time(&self) -> f64 {
        self.initial_state.as_ref().map_or(0.0, |s| s.0)
    }

    /// Per-component absolute tolerances: `atol` \[µm\] on displacements, `atol`/s on
    /// velocities, `atol` · μ_as,max/µm on the exposures (so each block is measured
    /// against its own scale).
    pub fn atol_vector(&self, atol: f64) -> Vec<f64> {
        let (nu, nv, nm) = self.block_sizes();
        let mu_scale = self.params.adhesion.map(|a| a.mu_as_max).unwrap_or(1.0);
        let mut v = vec![atol; nu + nv];
        v.extend(std::iter::repeat_n(atol * mu_scale, nm));
        v
    }

    /// Number of unknowns by block: (u, v, μ_as).
    pub fn block_sizes(&self) -> (usize, usize, usize) {
        let nv = if self.dofs.inertia { self.dofs.n_u } else { 0 };
        (self.dofs.n_u, nv, self.dofs.n_mu())
    }

    /// Element displacements u, velocities v (v with inertia, u̇ without) and
    /// accelerations v̇ (inertia only) gathered from (y, ẏ).
    fn gather(&self, el: &ElementOf<D, N>, y: &[f64], yp: &[f64]) -> ElementState<D, N> {
        let mut st = ElementState {
            u: [[0.0; D]; N],
            v: [[0.0; D]; N],
            a: [[0.0; D]; N],
        };
        for a in 0..N {
            let i = el.nodes[a];
            for k in 0..D {
                let du = self.dofs.u[i][k];
                if du == NONE {
                    continue;
                }
                st.u[a][k] = y[du];
                if self.dofs.inertia {
                    let dv = self.dofs.v[i][k];
                    st.v[a][k] = y[dv];
                    st.a[a][k] = yp[dv];
                } else {
                    st.v[a][k] = yp[du];
                }
            }
        }
        st
    }

    /// The element loop of a residual or a Jacobian at time `t` in state `y` with the
    /// switches `sw`: the caps of `y` ([`Self::fill_caps`], in the scratch vector), then
    /// [`in_blocks`] on the buffers `buf` with `compute(cell, caps, e, out)` and
    /// `scatter(plan, e, out)`. Errors carry the time `t`.
    fn element_loop<T: Send>(
        &mut self,
        t: f64,
        y: &[f64],
        sw: &Switches,
        buf: &mut [(T, Result<(), DaeError>)],
        compute: impl Fn(&Self, &[(f64, f64)], usize, &mut T) -> Result<(), DaeError> + Sync,
        mut scatter: impl FnMut(&PlanOf<D, N, E>, usize, &T),
    ) -> Result<(), DaeError> {
        let mut caps = std::mem::take(&mut self.scratch.caps);
        self.fill_caps(y, sw.t_as, &mut caps);
        let cell = &*self;
        let result = in_blocks(
            cell.elements.len(),
            cell.parallel,
            buf,
            |e, out| compute(cell, &caps, e, out),
            |e, out| scatter(&cell.plan, e, out),
        );
        self.scratch.caps = caps;
        result.map_err(|e| at_time(e, t))
    }

    /// The solid's inputs on element `e` in state `st` at the active-strain ramp `t_a`.
    #[inline(always)]
    fn solid<'a>(
        &'a self,
        e: usize,
        st: &'a ElementState<D, N>,
        t_a: f64,
    ) -> kernels::Solid<'a, D, N> {
        let el = &self.elements[e];
        kernels::Solid {
            e,
            el,
            law: &self.params.solids[el.solid],
            visc: &self.params.viscosity,
            st,
            t_a,
            fibres: self.params.fibres.as_ref(),
        }
    }

    /// The band forces' inputs on `el` in state `st` ([`kernels::Band`]).
    #[inline(always)]
    fn band<'a>(
        &'a self,
        el: &'a ElementOf<D, N>,
        st: &'a ElementState<D, N>,
        mue: Option<&'a [f64; N]>,
        t_as: f64,
    ) -> kernels::Band<'a, S, D, N, E> {
        kernels::Band {
            el,
            ctab: &self.ctab,
            p: &self.params,
            sub: &self.substrate,
            st,
            mue,
            t_as,
        }
    }

    /// Φ(A) and dΦ/dA of every μ_as unknown, in their order, into `out` (emptied when
    /// adhesion cannot act at `t_as`): computed once per residual or Jacobian, not once
    /// per element that shares the node.
    fn fill_caps(&self, y: &[f64], t_as: f64, out: &mut Vec<(f64, f64)>) {
        out.clear();
        let Some(ad) = &self.params.adhesion else {
            return;
        };
        if t_as > 0.0 {
            let off = self.dofs.mu_offset();
            out.extend((0..self.dofs.n_mu()).map(|k| history::cap(y[off + k], ad.mu_as_max)));
        }
    }

    /// The nodal μ_as = Φ(A) of `el` and dμ_as/dA when adhesion acts on it at `t_as`,
    /// from the values of [`Self::fill_caps`].
    #[inline]
    #[allow(clippy::type_complexity)]
    fn gather_mu(
        &self,
        el: &ElementOf<D, N>,
        caps: &[(f64, f64)],
        t_as: f64,
    ) -> Option<([f64; N], [f64; N])> {
        if !kernels::adhesion_acts(&self.params, el, t_as) {
            return None;
        }
        let off = self.dofs.mu_offset();
        let c = el.nodes.map(|i| caps[self.dofs.mu[i] - off]);
        Some((c.map(|v| v.0), c.map(|v| v.1)))
    }

    /// The element the last residual or Jacobian found inadmissible (an inverted or
    /// flattened element), its domain and the centroid of its nodes in that state; `None`
    /// when the last evaluation succeeded. What a run that gives up reports as its place.
    pub fn last_inadmissible(&self) -> Option<&(Inadmissible, Domain, [f64; D])> {
        self.inadmissible.as_ref()
    }

    /// The centroid of element `e`'s nodes in state `y` \[µm\] (where a stop at an
    /// element is reported).
    pub(crate) fn element_centroid(&self, y: &[f64], e: usize) -> [f64; D] {
        let nodes = &self.mesh.elements()[e];
        let mut x = [0.0; D];
        for &i in nodes {
            let p = self.position(y, i);
            for (k, xk) in x.iter_mut().enumerate() {
                *xk += p[k] / N as f64;
            }
        }
        x
    }

    /// Records the outcome of an evaluation at `y` for [`Self::last_inadmissible`], and
    /// passes it on.
    fn note_admissibility(
        &mut self,
        result: Result<(), DaeError>,
        y: &[f64],
    ) -> Result<(), DaeError> {
        self.inadmissible = match &result {
            Err(DaeError::Inadmissible(why @ Inadmissible::Element { element, .. })) => Some((
                why.clone(),
                self.mesh.domains()[*element],
                self.element_centroid(y, *element),
            )),
            _ => None,
        };
        result
    }

    /// Current position of node `i` in state `y`.
    #[inline]
    pub fn position(&self, y: &[f64], i: usize) -> SVector<f64, D> {
        let u = self.dofs.node_u(y, i);
        let xn = self.mesh.nodes()[i];
        SVector::<f64, D>::from_fn(|k, _| xn[k] + u[k])
    }

    /// The first two components of node `i`'s current position (the half-plane models').
    fn position2(&self, y: &[f64], i: usize) -> [f64; 2] {
        let p = self.position(y, i);
        [p[0], p[1]]
    }

    /// The first two of node `i`'s momentum rows (the half-plane models').
    fn rows2(&self, i: usize) -> [usize; 2] {
        let m = self.dofs.momentum_rows(i);
        [m[0], m[1]]
    }

    /// Whether an element can reach the contact or adhesion band in the configuration `ue`:
    /// some node lies within the band's reach plus 1.5 × the element's current diameter
    /// of the substrate (every point of the element is within one diameter of a node, and
    /// the depth d is 1-Lipschitz up to the first-order distance's corner factor).
    fn in_reach(&self, el: &ElementOf<D, N>, ue: &NodalOf<D, N>) -> bool {
        let p = &self.params;
        let band = match &p.adhesion {
            Some(ad) if el.domain == Domain::Membrane => (ad.e_f + ad.eps).max(p.contact.eps),
            _ => p.contact.eps,
        };
        let xs: [SVector<f64, D>; N] = std::array::from_fn(|a| {
            let xn = self.mesh.nodes()[el.nodes[a]];
            SVector::<f64, D>::from_fn(|k, _| xn[k] + ue[a][k])
        });
        let mut diam2: f64 = 0.0;
        for a in 0..N {
            for b in a + 1..N {
                diam2 = diam2.max((xs[a] - xs[b]).norm_squared());
            }
        }
        let reach = band + 1.5 * diam2.sqrt();
        xs.iter().any(|x| self.substrate.eval(x).0 > -reach)
    }

    /// The residual or the iteration matrix with the kernels of the kinematic model `K`.
    pub(crate) fn evaluate_with<K: Formulation<D, N, E>>(
        &mut self,
        what: Evaluation,
    ) -> Result<(), DaeError> {
        match what {
            Evaluation::Residual(at, r) => self.residual_of::<K>(at, r),
            Evaluation::Jacobian(at, cj, v) => self.jacobian_of::<K>(at, cj, v),
        }
    }

    /// The residual with the kernels of the kinematic model `K` ([`Dae::residual`]).
    fn residual_of<K: Formulation<D, N, E>>(
        &mut self,
        at: State,
        r: &mut [f64],
    ) -> Result<(), DaeError> {
        let State { t, y, yp } = at;
        let sw = Switches::at(&self.params, t);
        r.fill(0.0);
        if self.dofs.inertia {
            let n_u = self.dofs.n_u;
            for k in 0..n_u {
                r[k] = yp[k] - y[n_u + k];
            }
        }
        let g_now = self.params.gravity * sw.s_g * sw.t_g;
        let element = |cell: &Self, caps: &[(f64, f64)], e: usize, fe: &mut NodalOf<D, N>| {
            let (el, p) = (&cell.elements[e], &cell.params);
            let st = cell.gather(el, y, yp);
            *fe = [[0.0f64; D]; N];
            K::solid_residual(&cell.solid(e, &st, sw.t_a), fe)?;
            kernels::mass_residual(el, g_now, cell.dofs.inertia, p.drag, &st, fe);
            if cell.in_reach(el, &st.u) {
                let mue = cell.gather_mu(el, caps, sw.t_as).map(|m| m.0);
                let band = cell.band(el, &st, mue.as_ref(), sw.t_as);
                kernels::band_residual::<S, K, D, N, E>(e, &band, fe)?;
            }
            Ok(())
        };
        let mut buf = self.scratch.take_vectors();
        let result = self.element_loop(t, y, &sw, &mut buf, element, |plan, e, fe| {
            plan.scatter_residual(e, fe, r)
        });
        self.scratch.vectors = buf;
        result?;
        if let Some(sc) = &self.self_contact {
            sc.residual(
                &self.params.contact,
                |i| self.position2(y, i),
                |i| self.rows2(i),
                r,
            );
        }
        let mu_off = self.dofs.mu_offset();
        for (k, &i) in self.dofs.mu_nodes.iter().enumerate() {
            let row = mu_off + k;
            let x = self.position(y, i);
            r[row] =
                kernels::mu_rate_residual::<S, D, N, E>(&self.params, &self.substrate, &x, yp[row]);
        }
        all_finite(r, "residual")
    }

    /// The iteration matrix with the kernels of the kinematic model `K` ([`Dae::jacobian`]).
    fn jacobian_of<K: Formulation<D, N, E>>(
        &mut self,
        at: State,
        cj: f64,
        v: &mut [f64],
    ) -> Result<(), DaeError> {
        let State { t, y, yp } = at;
        let sw = Switches::at(&self.params, t);
        v.fill(0.0);
        self.plan.add_kinematic(cj, v);
        let element =
            |cell: &Self, caps: &[(f64, f64)], e: usize, tan: &mut Box<TangentOf<E, N>>| {
                let (el, p) = (&cell.elements[e], &cell.params);
                let st = cell.gather(el, y, yp);
                tan.reset(el.with_mu);
                K::solid_tangent(&cell.solid(e, &st, sw.t_a), tan)?;
                kernels::mass_tangent(el, cj, cell.dofs.inertia, p.drag, tan);
                if cell.in_reach(el, &st.u) {
                    let mue = cell.gather_mu(el, caps, sw.t_as);
                    let mu = mue.map(|m| m.0);
                    let band = cell.band(el, &st, mu.as_ref(), sw.t_as);
                    kernels::band_tangent::<S, K, D, N, E>(&band, tan);
                    // The unknown is the exposure A: ∂f/∂A_b = ∂f/∂μ_b dμ_b/dA_b.
                    if let Some((_, g)) = mue {
                        for row in tan.b.iter_mut() {
                            for (b, gb) in row.iter_mut().zip(g) {
                                *b *= gb;
                            }
                        }
                    }
                }
                Ok(())
            };
        let mut buf = self.scratch.take_tangents();
        let result = self.element_loop(t, y, &sw, &mut buf, element, |plan, e, tan| {
            plan.scatter_tangent(e, tan, cj, v)
        });
        self.scratch.tangents = buf;
        result?;
        if let Some(sc) = &self.self_contact {
            sc.tangent(&self.params.contact, |i| self.position2(y, i), v);
        }
        if self.params.adhesion.is_some() {
            for (k, &i) in self.dofs.mu_nodes.iter().enumerate() {
                let x = self.position(y, i);
                let (dx, da) =
                    kernels::mu_rate_tangent::<S, D, N, E>(&self.params, &self.substrate, &x);
                let (own, on_u) = &self.plan.mu_rate[k];
                v[*own] += cj - da;
                for c in 0..D {
                    if on_u[c] != NONE {
                        v[on_u[c]] -= dx[c];
                    }
                }
            }
        }
        all_finite(v, "Jacobian")
    }
}

impl<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> Dae for CellOf<S, D, N, E> {
    fn size(&self) -> usize {
        self.dofs.n
    }

    /// `F(t, y, ẏ)`: kinematic rows, then per element the solid, mass and band kernels
    /// scattered into the momentum rows, then the adhesion rows; the kernels of the case's
    /// kinematic model.
    fn residual(&mut self, at: State, r: &mut [f64]) -> Result<(), DaeError> {
        let result = S::evaluate(self, Evaluation::Residual(at, r));
        self.note_admissibility(result, at.y)
    }

    fn pattern(&self) -> &Pattern {
        &self.plan.pattern
    }

    /// `J = ∂F/∂y + cj ∂F/∂ẏ`: the same kernels' tangents, scattered by the plan.
    fn jacobian(&mut self, at: State, cj: f64, v: &mut [f64]) -> Result<(), DaeError> {
        let result = S::evaluate(self, Evaluation::Jacobian(at, cj, v));
        self.note_admissibility(result, at.y)
    }

    fn differential(&self) -> Vec<bool> {
        vec![true; self.dofs.n]
    }

    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        match &self.initial_state {
            Some(s) => s.clone(),
            None => (0.0, vec![0.0; self.dofs.n], vec![0.0; self.dofs.n]),
        }
    }

    /// With inertia, the pairs (u_k, v_k): rows [0, n_u) are the kinematic rows u̇ − v = 0
    /// and row n_u + k is the momentum balance of u_k's component.
    fn first_order_blocks(&self) -> Option<FirstOrderBlocks> {
        self.dofs.inertia.then(|| {
            let n_u = self.dofs.n_u;
            FirstOrderBlocks::contiguous(0, n_u, n_u)
        })
    }

    /// Advances the μ_as history (while deferred) over the accepted step.
    fn accepted_step(&mut self, t: f64, y: &[f64], yp: &[f64]) {
        if self.history.is_some() {
            let (x, xdot) = self.membrane_motion(y, yp);
            if let Some(h) = &mut self.history {
                h.advance(t, x, xdot);
            }
        }
    }

    /// Per watched condition: arming counted rising, firing counted falling.
    fn root_directions(&self) -> Vec<i32> {
        self.params.events.iter().flat_map(|_| [1, -1]).collect()
    }

    fn root_functions(&mut self, at: State, g: &mut [f64]) -> Result<(), DaeError> {
        self.condition_values(at, g);
        Ok(())
    }

    fn breakpoints(&self) -> Vec<f64> {
        let mut b = self.params.phases.breakpoints();
        b.extend(self.params.extra_breakpoints.iter().copied());
        b.retain(|t| *t > 0.0);
        b.sort_by(f64::total_cmp);
        b.dedup();
        b
    }
}
