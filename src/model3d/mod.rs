//! The 3-D quarter cell as one DAE (MODEL.md §10): ten-node tetrahedra of the quarter
//! x ≥ 0, z ≥ 0 of the three concentric balls, with the physics of MODEL.md §3–6 in 3-D
//! ([`crate::physics::solid3`], [`Substrate3`], the 3-D loads and active strain).
//!
//! The system is the half-plane models' (`crate::model`) with three displacement
//! components per node: unknowns y = (u, v, μ_as) with inertia, (u, μ_as) without
//! ([`DofMapOf`]), the same residual rows, the exact iteration matrix assembled by the
//! same plan ([`PlanOf`]) from the element tangents of [`kernels`], the same element loop
//! in blocks (in parallel or not, the same bits). Symmetry: u_x = 0 on the plane x = c_x
//! and u_z = 0 on z = c_z ([`Constraints::Quarter`]); the slab check of MODEL.md §10
//! fixes u_z on every node instead ([`Constraints::Slab`]), which reproduces plane strain
//! on a 2-D mesh extruded one layer thick.
//!
//! The μ_as unknowns are the exposures A (μ_as = Φ(A), `crate::model::history`); as in
//! the half-plane models they can be left out of the system until T_g0
//! ([`Cell3::deferring_adhesion`]), A integrated beside it along the accepted steps.

mod element;
mod kernels;
pub mod observe;
mod switch;

use nalgebra::Vector3;

use crate::dae::{Dae, DaeError, FirstOrderBlocks, Pattern};
use crate::fem::assembly::NONE;
use crate::fem::tet::TetTabulation;
use crate::fem::{Domain, Mesh3};
use crate::model::dofs::DofMapOf;
use crate::model::history::{self, AdhesionHistoryOf};
use crate::model::kernels::Switches;
use crate::model::plan::PlanOf;
use crate::model::{BLOCK, ModelParams, in_blocks};
use crate::physics::{Lattice, Substrate3};
use element::{EDOF, Element3, ElementState3, NODES, Nodal, ReferenceElements3};
pub use element::{ElementError, STANDARD_DEGREE};
use kernels::{ElementTangent3, ElementVector3};

/// The parameters of the 3-D cell: those of the half-plane models (the centre's (x, y),
/// the substrate's section z = 0, materials, loads, phases) and the pillar lattice in z.
#[derive(Debug, Clone)]
pub struct Params3 {
    /// Every parameter the 2-D model has; `center` is (c_x, c_y), with c_z = 0.
    pub plane: ModelParams,
    /// Where the pillar axes lie in z ([`Lattice`]).
    pub lattice: Lattice,
}

impl Params3 {
    /// The cell centre c = (c_x, c_y, 0).
    pub fn center(&self) -> Vector3<f64> {
        Vector3::new(self.plane.center[0], self.plane.center[1], 0.0)
    }

    /// The substrate in 3-D: the 2-D one's section with the lattice in z.
    pub fn substrate(&self) -> Substrate3 {
        Substrate3 {
            plane: self.plane.substrate,
            lattice: self.lattice,
        }
    }
}

/// Which displacement components the symmetry eliminates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Constraints {
    /// The quarter cell: u_x = 0 on the mesh's plane x = c_x, u_z = 0 on z = c_z.
    Quarter,
    /// The slab check: u_x = 0 on x = c_x and u_z = 0 on every node (plane strain).
    Slab,
}

/// Why a 3-D model cannot be built.
#[derive(Debug, Clone, thiserror::Error)]
pub enum Model3Error {
    /// An element's reference geometry is invalid.
    #[error(transparent)]
    Element(#[from] ElementError),
    /// A system rebuilt during a run could not be made consistent with the old state.
    #[error("{what} at t = {t}: {source}")]
    Restart {
        /// The change of system.
        what: &'static str,
        /// Time of the change [s].
        t: f64,
        /// The consistent-initialisation failure.
        source: Box<crate::dae::IntegratorError>,
    },
}

/// The per-block buffers of the element loops, kept between calls.
#[derive(Default)]
struct Scratch3 {
    vectors: Vec<(ElementVector3, Result<(), DaeError>)>,
    tangents: Vec<(Box<ElementTangent3>, Result<(), DaeError>)>,
    caps: Vec<(f64, f64)>,
}

/// The 3-D quarter cell as a [`Dae`].
pub struct Cell3 {
    /// Parameters.
    pub params: Params3,
    /// The substrate in 3-D (from the parameters).
    pub substrate: Substrate3,
    /// The mesh.
    pub mesh: Mesh3,
    /// Unknown numbering.
    pub dofs: DofMapOf<3>,
    /// The symmetry conditions.
    pub constraints: Constraints,
    elements: Vec<Element3>,
    ctab: TetTabulation,
    plan: PlanOf<3, NODES, EDOF>,
    initial_state: Option<(f64, Vec<f64>, Vec<f64>)>,
    /// The exposures integrated beside the system while their unknowns are left out
    /// (before T_g0).
    history: Option<AdhesionHistoryOf<3, Substrate3>>,
    parallel: bool,
    scratch: Scratch3,
}

impl Cell3 {
    /// The quarter cell on `mesh` ([`Constraints::Quarter`]).
    pub fn new(params: Params3, mesh: Mesh3) -> Result<Self, Model3Error> {
        Self::with_constraints(params, mesh, Constraints::Quarter)
    }

    /// The cell on `mesh` with the symmetry conditions `constraints`: unknown numbering,
    /// reference elements and the assembly plan.
    pub fn with_constraints(
        params: Params3,
        mesh: Mesh3,
        constraints: Constraints,
    ) -> Result<Self, Model3Error> {
        let adhesion = params.plane.adhesion.is_some();
        Self::build(params, mesh, constraints, adhesion)
    }

    /// As [`Self::with_constraints`], but with adhesion modelled its exposure unknowns
    /// are left out until adhesion can act (T_g0): A is integrated beside the system along
    /// the accepted steps, and [`Self::with_adhesion_unknowns`] adds the unknowns (see
    /// `crate::model::CellModel::deferring_adhesion`). Starting at T_g0 or later, the
    /// unknowns are there from the start.
    pub fn deferring_adhesion(
        params: Params3,
        mesh: Mesh3,
        constraints: Constraints,
    ) -> Result<Self, Model3Error> {
        let Some(ad) = params.plane.adhesion else {
            return Self::with_constraints(params, mesh, constraints);
        };
        if params.plane.phases.t_g0 <= 0.0 {
            return Self::with_constraints(params, mesh, constraints);
        }
        let mut m = Self::build(params, mesh, constraints, false)?;
        let nodes = m.membrane_nodes();
        let x = nodes.iter().map(|&i| m.mesh.nodes[i]).collect();
        let xdot = vec![[0.0; 3]; nodes.len()];
        m.history = Some(AdhesionHistoryOf::new(
            ad,
            m.substrate,
            0.0,
            vec![0.0; nodes.len()],
            x,
            xdot,
        ));
        Ok(m)
    }

    /// The model on `mesh`, with the exposure unknowns when `adhesion_unknowns`.
    fn build(
        params: Params3,
        mesh: Mesh3,
        constraints: Constraints,
        adhesion_unknowns: bool,
    ) -> Result<Self, Model3Error> {
        let nn = mesh.nodes.len();
        let (mut on_x, mut on_z) = (vec![false; nn], vec![false; nn]);
        for &i in &mesh.symmetry_x {
            on_x[i] = true;
        }
        for &i in &mesh.symmetry_z {
            on_z[i] = true;
        }
        let slab = constraints == Constraints::Slab;
        let dofs = DofMapOf::<3>::numbered(
            nn,
            |i, c| (c == 0 && on_x[i]) || (c == 2 && (slab || on_z[i])),
            &nodes_of_domain(&mesh, Domain::Membrane),
            params.plane.inertia,
            adhesion_unknowns,
        );
        let ReferenceElements3 { elements, ctab } =
            ReferenceElements3::new(&params, &mesh, adhesion_unknowns)?;
        let plan_elements: Vec<_> = elements.iter().map(|el| (el.nodes, el.with_mu)).collect();
        let plan = PlanOf::new(&dofs, &plan_elements);
        Ok(Self {
            substrate: params.substrate(),
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
            scratch: Scratch3::default(),
        })
    }

    /// The nodes of the membrane elements, in the order of the exposure unknowns.
    fn membrane_nodes(&self) -> Vec<usize> {
        let on = nodes_of_domain(&self.mesh, Domain::Membrane);
        (0..on.len()).filter(|&i| on[i]).collect()
    }

    /// Whether the exposure unknowns are left out until adhesion can act.
    pub fn adhesion_deferred(&self) -> bool {
        self.history.is_some()
    }

    /// Number of μ_as values (unknowns, or integrated beside the system while deferred).
    pub fn n_mu_as(&self) -> usize {
        self.history.as_ref().map_or(self.dofs.n_mu(), |h| h.len())
    }

    /// Positions and velocities of the membrane nodes from (y, ẏ) (velocity u̇).
    fn membrane_motion(&self, y: &[f64], yp: &[f64]) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let nodes = self.membrane_nodes();
        let x = nodes
            .iter()
            .map(|&i| {
                let u = self.dofs.node_u(y, i);
                std::array::from_fn(|k| self.mesh.nodes[i][k] + u[k])
            })
            .collect();
        let xdot = nodes.iter().map(|&i| self.dofs.node_u(yp, i)).collect();
        (x, xdot)
    }

    /// Runs the element loops on rayon's thread pool (the same bits either way).
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel;
    }

    /// Starts the integration from (t₀, y₀, ẏ₀) instead of the rest state at t = 0.
    pub fn set_initial(&mut self, t0: f64, y0: Vec<f64>, yp0: Vec<f64>) {
        self.initial_state = Some((t0, y0, yp0));
    }

    /// Per-component absolute tolerances: `atol` [µm] on displacements, `atol`/s on
    /// velocities, `atol` · μ_as,max/µm on the exposures (as the half-plane models').
    pub fn atol_vector(&self, atol: f64) -> Vec<f64> {
        let nv = if self.dofs.inertia { self.dofs.n_u } else { 0 };
        let mu_scale = self.params.plane.adhesion.map_or(1.0, |a| a.mu_as_max);
        let mut v = vec![atol; self.dofs.n_u + nv];
        v.extend(std::iter::repeat_n(atol * mu_scale, self.dofs.n_mu()));
        v
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elements.len()
    }

    /// Current position of node `i`.
    #[inline]
    pub fn position(&self, y: &[f64], i: usize) -> Vector3<f64> {
        let u = self.dofs.node_u(y, i);
        let x = self.mesh.nodes[i];
        Vector3::new(x[0] + u[0], x[1] + u[1], x[2] + u[2])
    }

    fn gather(&self, el: &Element3, y: &[f64], yp: &[f64]) -> ElementState3 {
        let mut st = ElementState3 {
            u: [[0.0; 3]; NODES],
            v: [[0.0; 3]; NODES],
            a: [[0.0; 3]; NODES],
        };
        for a in 0..NODES {
            let i = el.nodes[a];
            for k in 0..3 {
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

    /// Φ(A) and dΦ/dA of every μ_as unknown into `out` (empty while adhesion cannot act).
    fn fill_caps(&self, y: &[f64], t_as: f64, out: &mut Vec<(f64, f64)>) {
        out.clear();
        let Some(ad) = &self.params.plane.adhesion else {
            return;
        };
        if t_as > 0.0 {
            let off = self.dofs.mu_offset();
            out.extend((0..self.dofs.n_mu()).map(|k| history::cap(y[off + k], ad.mu_as_max)));
        }
    }

    fn gather_mu(
        &self,
        el: &Element3,
        caps: &[(f64, f64)],
        t_as: f64,
    ) -> Option<([f64; NODES], [f64; NODES])> {
        if !kernels::adhesion_acts(&self.params.plane, el, t_as) {
            return None;
        }
        let off = self.dofs.mu_offset();
        let c = el.nodes.map(|i| caps[self.dofs.mu[i] - off]);
        Some((c.map(|v| v.0), c.map(|v| v.1)))
    }

    /// Whether an element can reach the contact or adhesion band in the configuration
    /// `ue` (as in the half-plane models: some node within the band's reach plus 1.5 × the
    /// element's current diameter of the substrate).
    fn in_reach(&self, el: &Element3, ue: &Nodal) -> bool {
        let p = &self.params.plane;
        let band = match &p.adhesion {
            Some(ad) if el.domain == Domain::Membrane => (ad.e_f + ad.eps).max(p.contact.eps),
            _ => p.contact.eps,
        };
        let xs: [Vector3<f64>; NODES] = std::array::from_fn(|a| {
            let xn = self.mesh.nodes[el.nodes[a]];
            Vector3::new(xn[0] + ue[a][0], xn[1] + ue[a][1], xn[2] + ue[a][2])
        });
        let mut diam2: f64 = 0.0;
        for a in 0..NODES {
            for b in a + 1..NODES {
                diam2 = diam2.max((xs[a] - xs[b]).norm_squared());
            }
        }
        let reach = band + 1.5 * diam2.sqrt();
        xs.iter().any(|x| self.substrate.eval(x).0 > -reach)
    }

    fn take_vectors(&mut self) -> Vec<(ElementVector3, Result<(), DaeError>)> {
        let mut b = std::mem::take(&mut self.scratch.vectors);
        b.resize_with(BLOCK, || ([[0.0; 3]; NODES], Ok(())));
        b
    }

    fn take_tangents(&mut self) -> Vec<(Box<ElementTangent3>, Result<(), DaeError>)> {
        let mut b = std::mem::take(&mut self.scratch.tangents);
        b.resize_with(BLOCK, || (Box::new(ElementTangent3::zeros()), Ok(())));
        b
    }
}

/// Whether each node of `mesh` belongs to an element of domain `d`.
pub(crate) fn nodes_of_domain(mesh: &Mesh3, d: Domain) -> Vec<bool> {
    let mut on = vec![false; mesh.nodes.len()];
    for (el, &dom) in mesh.elements.iter().zip(&mesh.domains) {
        if dom == d {
            for &i in el {
                on[i] = true;
            }
        }
    }
    on
}

impl Dae for Cell3 {
    fn size(&self) -> usize {
        self.dofs.n
    }

    /// `F(t, y, ẏ)`: kinematic rows, then per element the solid, mass and band kernels
    /// scattered into the momentum rows, then the adhesion rows.
    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> Result<(), DaeError> {
        let mut buf = self.take_vectors();
        let mut caps = std::mem::take(&mut self.scratch.caps);
        r.fill(0.0);
        let p = &self.params.plane;
        let sw = Switches::at(p, t);
        self.fill_caps(y, sw.t_as, &mut caps);
        let inertia = self.dofs.inertia;
        if inertia {
            let n_u = self.dofs.n_u;
            for k in 0..n_u {
                r[k] = yp[k] - y[n_u + k];
            }
        }
        let g_now = p.gravity * sw.s_g * sw.t_g;
        let element = |e: usize, fe: &mut ElementVector3| -> Result<(), DaeError> {
            let el = &self.elements[e];
            let st = self.gather(el, y, yp);
            *fe = [[0.0f64; 3]; NODES];
            let law = &p.solids[el.solid];
            kernels::solid_residual(e, el, law, &p.viscosity, &st, sw.t_a, fe)?;
            kernels::mass_residual(el, g_now, inertia, p.drag, &st, fe);
            if self.in_reach(el, &st.u) {
                let mue = self.gather_mu(el, &caps, sw.t_as).map(|m| m.0);
                kernels::band_residual(
                    e,
                    el,
                    &self.ctab,
                    p,
                    &self.substrate,
                    &st,
                    mue.as_ref(),
                    sw.t_as,
                    fe,
                )?;
            }
            Ok(())
        };
        let result = in_blocks(
            self.elements.len(),
            self.parallel,
            &mut buf,
            element,
            |e, fe| self.plan.scatter_residual(e, fe, r),
        );
        self.scratch.vectors = buf;
        self.scratch.caps = caps;
        result?;
        let mu_off = self.dofs.mu_offset();
        for (k, &i) in self.dofs.mu_nodes.iter().enumerate() {
            let row = mu_off + k;
            let x = self.position(y, i);
            r[row] = kernels::mu_rate_residual(p, &self.substrate, &x, yp[row]);
        }
        if r.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(DaeError::Inadmissible("non-finite residual".into()))
        }
    }

    fn pattern(&self) -> &Pattern {
        &self.plan.pattern
    }

    /// `J = ∂F/∂y + cj ∂F/∂ẏ`: the same kernels' tangents, scattered by the plan.
    fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        cj: f64,
        v: &mut [f64],
    ) -> Result<(), DaeError> {
        let mut buf = self.take_tangents();
        let mut caps = std::mem::take(&mut self.scratch.caps);
        v.fill(0.0);
        let p = &self.params.plane;
        let sw = Switches::at(p, t);
        self.fill_caps(y, sw.t_as, &mut caps);
        let inertia = self.dofs.inertia;
        self.plan.add_kinematic(cj, v);
        let element = |e: usize, tan: &mut Box<ElementTangent3>| -> Result<(), DaeError> {
            let el = &self.elements[e];
            let st = self.gather(el, y, yp);
            tan.reset(el.with_mu);
            let law = &p.solids[el.solid];
            kernels::solid_tangent(e, el, law, &p.viscosity, &st, sw.t_a, tan)?;
            kernels::mass_tangent(el, cj, inertia, p.drag, tan);
            if self.in_reach(el, &st.u) {
                let mue = self.gather_mu(el, &caps, sw.t_as);
                kernels::band_tangent(
                    el,
                    &self.ctab,
                    p,
                    &self.substrate,
                    &st,
                    mue.map(|m| m.0).as_ref(),
                    sw.t_as,
                    tan,
                );
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
        let result = in_blocks(
            self.elements.len(),
            self.parallel,
            &mut buf,
            element,
            |e, tan| self.plan.scatter_tangent(e, tan, cj, v),
        );
        self.scratch.tangents = buf;
        self.scratch.caps = caps;
        result?;
        if p.adhesion.is_some() {
            for (k, &i) in self.dofs.mu_nodes.iter().enumerate() {
                let x = self.position(y, i);
                let d = kernels::mu_rate_tangent(p, &self.substrate, &x);
                let (own, on_u) = &self.plan.mu_rate[k];
                v[*own] += cj;
                for c in 0..3 {
                    if on_u[c] != NONE {
                        v[on_u[c]] -= d[c];
                    }
                }
            }
        }
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(DaeError::Inadmissible("non-finite Jacobian".into()))
        }
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

    /// With inertia, the pairs (u_k, v_k), as in the half-plane models.
    fn first_order_blocks(&self) -> Option<FirstOrderBlocks> {
        self.dofs.inertia.then(|| {
            let n_u = self.dofs.n_u;
            FirstOrderBlocks::contiguous(0, n_u, n_u)
        })
    }

    /// Advances the exposure history (while deferred) over the accepted step.
    fn accepted_step(&mut self, t: f64, y: &[f64], yp: &[f64]) {
        if self.history.is_some() {
            let (x, xdot) = self.membrane_motion(y, yp);
            if let Some(h) = &mut self.history {
                h.advance(t, x, xdot);
            }
        }
    }

    fn breakpoints(&self) -> Vec<f64> {
        let p = &self.params.plane;
        let mut b = p.phases.breakpoints();
        b.extend(p.extra_breakpoints.iter().copied());
        b.retain(|t| *t > 0.0);
        b.sort_by(f64::total_cmp);
        b.dedup();
        b
    }
}
