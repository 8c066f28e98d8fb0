//! The cell as one DAE (MODEL.md §8): P2 finite elements of the half cell with a
//! compressible Yeoh solid, active strain and Kelvin–Voigt viscosity, gravity, penalty
//! contact, the adhesive spreading force and the μ_as field.
//!
//! Unknowns y = (u, v, μ_as) with inertia, (u, μ_as) without ([`dofs::DofMap`]). Residual:
//! - kinematics (inertia only): `u̇ − v = 0`;
//! - momentum: `M v̇ + f_int(u, v) + c_d M₁ v − f_ext(t, u, μ_as) = 0` (consistent mass M,
//!   unit-density mass M₁ for the medium drag), or without inertia
//!   `f_int(u, u̇) + c_d M₁ u̇ − f_ext = 0`;
//! - adhesion (membrane nodes): `μ̇_as − r(x, μ_as) = 0`, collocated at the nodes.
//!
//! The iteration matrix `J = ∂F/∂y + cj ∂F/∂ẏ` is exact: material tangents from the
//! physics module, contact and adhesion derivatives by forward-mode dual numbers at each
//! quadrature point, assembled into a pattern fixed at construction by positions computed
//! once per element (refilling, never rebuilding).
//!
//! Contact and adhesion act as body forces in thin bands near the substrate. They are
//! integrated with a separate high-degree (optionally subdivided) rule, and only on the
//! elements that can reach the band in the current configuration: an element is skipped
//! when every node lies further from the substrate than the band's reach plus the
//! element's current diameter (the integrand is then exactly zero everywhere in it).

pub mod dofs;
pub mod observe;

use nalgebra::{Matrix2, Vector2};
use num_dual::DualSVec64;

use crate::fem::assembly::{pattern_from_entries, position};
use crate::dae::{Dae, DaeError, FirstOrderBlocks, Pattern};
use crate::fem::p2::{ElementGeometry, P2Tabulation};
use crate::fem::quadrature::TriangleRule;
use crate::fem::{Domain, Mesh};
use crate::physics::{
    ActiveStrain, Adhesion, Contact, Phases, Substrate, Viscosity, Yeoh, adhesion_force,
    adhesion_rate, contact_force, material_point, piola_total,
};
use dofs::{DofMap, NONE};

/// Physical parameters of a scene in solver units (µm, s, pN).
#[derive(Debug, Clone)]
pub struct ModelParams {
    /// Cell centre c [µm].
    pub center: [f64; 2],
    /// Solid law of the nucleus, cytoplasm and membrane.
    pub solids: [Yeoh; 3],
    /// Mass densities of nucleus, cytoplasm, membrane [pN·s²/µm⁴].
    pub densities: [f64; 3],
    /// Kelvin–Voigt viscosity (whole cell).
    pub viscosity: Viscosity,
    /// Gravity g [µm/s²].
    pub gravity: f64,
    /// Phase switches and the optional gravity flip.
    pub phases: Phases,
    /// The substrate.
    pub substrate: Substrate,
    /// Penalty contact.
    pub contact: Contact,
    /// Adhesion (absent: no μ_as unknowns).
    pub adhesion: Option<Adhesion>,
    /// Active strain (absent or without fibres: no active terms).
    pub active: Option<ActiveStrain>,
    /// Model inertia (v unknowns and the mass matrix).
    pub inertia: bool,
    /// Medium drag c_d [pN·s/µm⁴] per unit reference volume (MODEL.md §8).
    pub drag: f64,
    /// Polynomial degree of the contact/adhesion quadrature rule.
    pub contact_degree: usize,
    /// Subdivision levels of that rule (4^levels sub-triangles).
    pub contact_subdivisions: u32,
    /// Extra breakpoints (e.g. the scene's end time).
    pub extra_breakpoints: Vec<f64>,
}

impl ModelParams {
    /// MODEL.md's defaults: the paper's materials, flat substrate at y = −2 µm, adhesion,
    /// no active strain, inertia on, no drag, contact rule of degree 10.
    pub fn defaults() -> Self {
        let yeoh = |e: f64| {
            Yeoh::from_engineering(e, 0.485, 0.1, 0.2).expect("MODEL.md defaults are valid")
        };
        Self {
            center: [0.0, 8.5],
            solids: [yeoh(500.0), yeoh(100.0), yeoh(100.0)],
            densities: [1.4e-9, 1.0e-9, 1.0e-9],
            viscosity: Viscosity::default(),
            gravity: 9.81e6,
            phases: Phases::default(),
            substrate: Substrate::Flat { y_s: -2.0 },
            contact: Contact::default(),
            adhesion: Some(Adhesion::default()),
            active: None,
            inertia: true,
            drag: 0.0,
            contact_degree: 10,
            contact_subdivisions: 0,
            extra_breakpoints: Vec::new(),
        }
    }

    fn domain_index(d: Domain) -> usize {
        match d {
            Domain::Nucleus => 0,
            Domain::Cytoplasm => 1,
            Domain::Membrane => 2,
        }
    }
}

/// Per-element data computed once on the reference configuration.
struct Element {
    nodes: [usize; 6],
    domain: Domain,
    solid: usize,
    /// Geometry at the points of the standard rule.
    geo: ElementGeometry,
    /// `A_q` with `F_a = I − t_a A_q` at the standard points (empty: no active strain).
    active: Vec<Matrix2<f64>>,
    /// Consistent mass ∫ρ Nₐ N_b (scalar per node pair).
    mass: [[f64; 6]; 6],
    /// ∫ Nₐ N_b (unit density, for the drag).
    mass1: [[f64; 6]; 6],
    /// Geometry at the contact-rule points.
    cgeo: ElementGeometry,
    /// Outward radial reference direction at the contact points (membrane elements).
    radial: Vec<Vector2<f64>>,
    /// Momentum rows of the element's 12 displacement components (NONE where eliminated).
    mrows: [usize; 12],
    /// Positions of (mrows, u cols) in the value array, row-major 12 × 12.
    pos_mu: Vec<usize>,
    /// Positions of (mrows, v cols), 12 × 12 (inertia only; else empty).
    pos_mv: Vec<usize>,
    /// Positions of (mrows, μ cols), 12 × 6 (membrane elements with adhesion; else empty).
    pos_mm: Vec<usize>,
}

/// The cell model as a [`Dae`].
pub struct CellModel {
    /// Parameters.
    pub params: ModelParams,
    /// The mesh.
    pub mesh: Mesh,
    /// Unknown numbering.
    pub dofs: DofMap,
    elements: Vec<Element>,
    ctab: P2Tabulation,
    pattern: Pattern,
    /// Kinematic rows (inertia): positions of (u_k, u_k) and (u_k, v_k).
    pos_kin: Vec<[usize; 2]>,
    /// Adhesion rows: positions of (μ_k, μ_k), (μ_k, u_x), (μ_k, u_y) of its node.
    pos_ads: Vec<[usize; 3]>,
    /// Initial state (t₀, y₀, ẏ₀) when not the rest state at t = 0 (restarts).
    initial_state: Option<(f64, Vec<f64>, Vec<f64>)>,
}

type D7 = DualSVec64<7>;

/// A vector per node of an element.
type Nodal = [[f64; 2]; 6];

/// Deformation gradient F = I + Σ uₐ ⊗ ∇Nₐ.
#[inline]
fn deformation(ue: &[[f64; 2]; 6], grads: &[[f64; 2]; 6]) -> Matrix2<f64> {
    let mut f = Matrix2::identity();
    for a in 0..6 {
        for i in 0..2 {
            f[(i, 0)] += ue[a][i] * grads[a][0];
            f[(i, 1)] += ue[a][i] * grads[a][1];
        }
    }
    f
}

/// Ḟ = Σ vₐ ⊗ ∇Nₐ.
#[inline]
fn rate(ve: &[[f64; 2]; 6], grads: &[[f64; 2]; 6]) -> Matrix2<f64> {
    let mut f = Matrix2::zeros();
    for a in 0..6 {
        for i in 0..2 {
            f[(i, 0)] += ve[a][i] * grads[a][0];
            f[(i, 1)] += ve[a][i] * grads[a][1];
        }
    }
    f
}

impl CellModel {
    /// Builds the model on `mesh`: unknown numbering, reference geometry, the pattern of
    /// the iteration matrix and the positions to refill it.
    pub fn new(params: ModelParams, mesh: Mesh) -> Result<Self, String> {
        let adhesion = params.adhesion.is_some();
        let dofs = DofMap::new(&mesh, params.inertia, adhesion);
        let std_tab = P2Tabulation::new(&TriangleRule::degree(4));
        let crule =
            TriangleRule::degree(params.contact_degree).subdivided(params.contact_subdivisions);
        let ctab = P2Tabulation::new(&crule);
        let mass_tab = std_tab.clone();
        let active = params
            .active
            .filter(|a| a.pac.is_some() || a.bottom.is_some());
        let c = Vector2::new(params.center[0], params.center[1]);

        let mut elements = Vec::with_capacity(mesh.elements.len());
        let mut entries: Vec<(usize, usize)> = Vec::new();
        for (e, &nodes) in mesh.elements.iter().enumerate() {
            let x = mesh.element_coords(e);
            let domain = mesh.domains[e];
            let geo = std_tab
                .geometry(&x)
                .map_err(|err| format!("element {e}: {err}"))?;
            let cgeo = ctab
                .geometry(&x)
                .map_err(|err| format!("element {e}: {err}"))?;
            let solid = ModelParams::domain_index(domain);
            let rho = params.densities[solid];
            let mut mass1 = [[0.0; 6]; 6];
            let mgeo = mass_tab
                .geometry(&x)
                .map_err(|err| format!("element {e}: {err}"))?;
            for q in 0..mass_tab.len() {
                let n = &mass_tab.values[q];
                for a in 0..6 {
                    for b in 0..6 {
                        mass1[a][b] += mgeo.jxw[q] * n[a] * n[b];
                    }
                }
            }
            let mass = mass1.map(|row| row.map(|m| m * rho));
            let active_q: Vec<Matrix2<f64>> = match &active {
                Some(act) => {
                    let a: Vec<Matrix2<f64>> = geo
                        .x
                        .iter()
                        .map(|p| {
                            Matrix2::identity() - act.fa(&Vector2::new(p[0], p[1]), domain, 1.0)
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
            let mut mrows = [NONE; 12];
            let mut ucols = [NONE; 12];
            let mut vcols = [NONE; 12];
            for a in 0..6 {
                let m = dofs.momentum_rows(nodes[a]);
                for i in 0..2 {
                    mrows[2 * a + i] = m[i];
                    ucols[2 * a + i] = dofs.u[nodes[a]][i];
                    vcols[2 * a + i] = dofs.v[nodes[a]][i];
                }
            }
            let mucols: [usize; 6] = nodes.map(|i| dofs.mu[i]);
            let with_mu = adhesion && domain == Domain::Membrane;
            for &r in mrows.iter().filter(|&&r| r != NONE) {
                for &cc in ucols.iter().filter(|&&c| c != NONE) {
                    entries.push((r, cc));
                }
                if params.inertia {
                    for &cc in vcols.iter().filter(|&&c| c != NONE) {
                        entries.push((r, cc));
                    }
                }
                if with_mu {
                    for &cc in mucols.iter().filter(|&&c| c != NONE) {
                        entries.push((r, cc));
                    }
                }
            }
            elements.push((
                Element {
                    nodes,
                    domain,
                    solid,
                    geo,
                    active: active_q,
                    mass,
                    mass1,
                    cgeo,
                    radial,
                    mrows,
                    pos_mu: Vec::new(),
                    pos_mv: Vec::new(),
                    pos_mm: Vec::new(),
                },
                ucols,
                vcols,
                mucols,
                with_mu,
            ));
        }
        // Kinematic rows u̇ − v.
        if params.inertia {
            for i in 0..mesh.nodes.len() {
                for k in 0..2 {
                    let (uk, vk) = (dofs.u[i][k], dofs.v[i][k]);
                    if uk != NONE {
                        entries.push((uk, uk));
                        entries.push((uk, vk));
                    }
                }
            }
        }
        // Adhesion rows.
        for (k, &i) in dofs.mu_nodes.iter().enumerate() {
            let row = dofs.mu_offset() + k;
            entries.push((row, row));
            for &cc in dofs.u[i].iter().filter(|&&c| c != NONE) {
                entries.push((row, cc));
            }
        }
        let pattern = pattern_from_entries(dofs.n, &entries);
        drop(entries);
        let pos = |r: usize, c: usize| -> usize {
            if r == NONE || c == NONE {
                NONE
            } else {
                position(&pattern, r, c).unwrap_or(NONE)
            }
        };
        let mut built = Vec::with_capacity(elements.len());
        for (mut el, ucols, vcols, mucols, with_mu) in elements {
            el.pos_mu = (0..144)
                .map(|k| pos(el.mrows[k / 12], ucols[k % 12]))
                .collect();
            if params.inertia {
                el.pos_mv = (0..144)
                    .map(|k| pos(el.mrows[k / 12], vcols[k % 12]))
                    .collect();
            }
            if with_mu {
                el.pos_mm = (0..72)
                    .map(|k| pos(el.mrows[k / 6], mucols[k % 6]))
                    .collect();
            }
            built.push(el);
        }
        let mut pos_kin = Vec::new();
        if params.inertia {
            for i in 0..mesh.nodes.len() {
                for k in 0..2 {
                    let (uk, vk) = (dofs.u[i][k], dofs.v[i][k]);
                    if uk != NONE {
                        pos_kin.push([pos(uk, uk), pos(uk, vk)]);
                    }
                }
            }
        }
        let pos_ads = dofs
            .mu_nodes
            .iter()
            .enumerate()
            .map(|(k, &i)| {
                let row = dofs.mu_offset() + k;
                [
                    pos(row, row),
                    pos(row, dofs.u[i][0]),
                    pos(row, dofs.u[i][1]),
                ]
            })
            .collect();
        Ok(Self {
            params,
            mesh,
            dofs,
            elements: built,
            ctab,
            pattern,
            pos_kin,
            pos_ads,
            initial_state: None,
        })
    }

    /// Starts the integration from (t₀, y₀, ẏ₀) instead of the rest state at t = 0.
    pub fn set_initial(&mut self, t0: f64, y0: Vec<f64>, yp0: Vec<f64>) {
        self.initial_state = Some((t0, y0, yp0));
    }

    /// The state of this model (with inertia) mapped to the same model without inertia:
    /// u and μ_as carried over, u̇ = v, μ̇_as kept. Returns (y, ẏ) of the smaller system.
    pub fn drop_inertia_state(&self, y: &[f64], yp: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let n_u = self.dofs.n_u;
        let n_mu = self.dofs.n_mu();
        let off = self.dofs.mu_offset();
        let mut y2 = Vec::with_capacity(n_u + n_mu);
        let mut yp2 = Vec::with_capacity(n_u + n_mu);
        y2.extend_from_slice(&y[..n_u]);
        if self.dofs.inertia {
            yp2.extend_from_slice(&y[n_u..2 * n_u]);
        } else {
            yp2.extend_from_slice(&yp[..n_u]);
        }
        y2.extend_from_slice(&y[off..off + n_mu]);
        yp2.extend_from_slice(&yp[off..off + n_mu]);
        (y2, yp2)
    }

    /// Per-component absolute tolerances: `atol` [µm] on displacements, `atol`/s on
    /// velocities, `atol` · μ_as,max/µm on the adhesion coefficient (so each block is
    /// measured against its own scale).
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

    /// Element displacements and velocities gathered from (y, ẏ).
    fn gather(&self, el: &Element, y: &[f64], yp: &[f64]) -> (Nodal, Nodal, Nodal) {
        let mut ue = [[0.0; 2]; 6];
        let mut ve = [[0.0; 2]; 6];
        let mut ae = [[0.0; 2]; 6];
        for a in 0..6 {
            let i = el.nodes[a];
            for k in 0..2 {
                let du = self.dofs.u[i][k];
                if du == NONE {
                    continue;
                }
                ue[a][k] = y[du];
                if self.dofs.inertia {
                    let dv = self.dofs.v[i][k];
                    ve[a][k] = y[dv];
                    ae[a][k] = yp[dv];
                } else {
                    ve[a][k] = yp[du];
                }
            }
        }
        (ue, ve, ae)
    }

    /// Whether an element can reach the contact or adhesion band in the configuration `ue`:
    /// some node lies within the band's reach plus 1.5 × the element's current diameter
    /// of the substrate (every point of the element is within one diameter of a node, and
    /// the depth d is 1-Lipschitz up to the first-order distance's corner factor).
    fn in_reach(&self, el: &Element, ue: &[[f64; 2]; 6]) -> bool {
        let p = &self.params;
        let band = match &p.adhesion {
            Some(ad) if el.domain == Domain::Membrane => (ad.e_f + ad.eps).max(p.contact.eps),
            _ => p.contact.eps,
        };
        let xs: [Vector2<f64>; 6] = std::array::from_fn(|a| {
            let xn = self.mesh.nodes[el.nodes[a]];
            Vector2::new(xn[0] + ue[a][0], xn[1] + ue[a][1])
        });
        let mut diam2: f64 = 0.0;
        for a in 0..6 {
            for b in a + 1..6 {
                diam2 = diam2.max((xs[a] - xs[b]).norm_squared());
            }
        }
        let reach = band + 1.5 * diam2.sqrt();
        xs.iter().any(|x| p.substrate.eval(x).0 > -reach)
    }

    fn check_admissible(e: usize, q: usize, f: &Matrix2<f64>) -> Result<(), DaeError> {
        let j = f.determinant();
        if j > 0.0 && j.is_finite() {
            Ok(())
        } else {
            Err(DaeError::Inadmissible(format!(
                "element {e}, quadrature point {q}: det F = {j:.3e}"
            )))
        }
    }

    fn active_fa(el: &Element, q: usize, t_a: f64) -> Matrix2<f64> {
        if el.active.is_empty() {
            Matrix2::identity()
        } else {
            Matrix2::identity() - el.active[q] * t_a
        }
    }

    /// At solid quadrature point `q` of element `e`: F (checked admissible), Ḟ and F_a.
    #[allow(non_snake_case)]
    #[inline]
    fn solid_point(
        e: usize,
        el: &Element,
        q: usize,
        ue: &Nodal,
        ve: &Nodal,
        t_a: f64,
    ) -> Result<[Matrix2<f64>; 3], DaeError> {
        let g = &el.geo.grads[q];
        let F = deformation(ue, g);
        Self::check_admissible(e, q, &F)?;
        Ok([F, rate(ve, g), Self::active_fa(el, q, t_a)])
    }

    /// At contact quadrature point `q` of an element: F and the current position x.
    #[allow(non_snake_case)]
    #[inline]
    fn contact_point(&self, el: &Element, q: usize, ue: &Nodal) -> (Matrix2<f64>, Vector2<f64>) {
        let nv = &self.ctab.values[q];
        let F = deformation(ue, &el.cgeo.grads[q]);
        let mut x = Vector2::new(el.cgeo.x[q][0], el.cgeo.x[q][1]);
        for a in 0..6 {
            x.x += nv[a] * ue[a][0];
            x.y += nv[a] * ue[a][1];
        }
        (F, x)
    }

    /// μ_as interpolated at contact quadrature point `q` of a membrane element.
    #[inline]
    fn mu_at(&self, el: &Element, q: usize, y: &[f64]) -> f64 {
        let nv = &self.ctab.values[q];
        (0..6).map(|a| nv[a] * y[self.dofs.mu[el.nodes[a]]]).sum()
    }
}

impl Dae for CellModel {
    fn size(&self) -> usize {
        self.dofs.n
    }

    #[allow(non_snake_case)]
    fn residual(&mut self, t: f64, y: &[f64], yp: &[f64], r: &mut [f64]) -> Result<(), DaeError> {
        r.fill(0.0);
        let p = &self.params;
        let (t_g, t_as, t_a, s_g) = (
            p.phases.t_g(t),
            p.phases.t_as(t),
            p.phases.t_a(t),
            p.phases.gravity_sign(t),
        );
        let inertia = self.dofs.inertia;
        if inertia {
            let n_u = self.dofs.n_u;
            for k in 0..n_u {
                r[k] = yp[k] - y[n_u + k];
            }
        }
        let mu_off = self.dofs.mu_offset();
        for (e, el) in self.elements.iter().enumerate() {
            let (ue, ve, ae) = self.gather(el, y, yp);
            let mut fe = [[0.0f64; 2]; 6];
            let solid = &p.solids[el.solid];
            for q in 0..el.geo.jxw.len() {
                let g = &el.geo.grads[q];
                let [F, Fdot, Fa] = Self::solid_point(e, el, q, &ue, &ve, t_a)?;
                let P = piola_total(solid, &p.viscosity, &F, &Fdot, &Fa);
                let w = el.geo.jxw[q];
                for a in 0..6 {
                    for i in 0..2 {
                        fe[a][i] += w * (P[(i, 0)] * g[a][0] + P[(i, 1)] * g[a][1]);
                    }
                }
            }
            // Gravity b_g = −ρ g s_g t_g e_y: ∫ Nₐ b_g = −g s_g t_g Σ_b M_ab e_y. Inertia
            // M v̇ and medium drag c_d M₁ v (v = u̇ without inertia).
            let g_now = p.gravity * s_g * t_g;
            for a in 0..6 {
                let ma: f64 = el.mass[a].iter().sum();
                fe[a][1] += ma * g_now;
                for b in 0..6 {
                    for i in 0..2 {
                        if inertia {
                            fe[a][i] += el.mass[a][b] * ae[b][i];
                        }
                        if p.drag > 0.0 {
                            fe[a][i] += p.drag * el.mass1[a][b] * ve[b][i];
                        }
                    }
                }
            }
            if self.in_reach(el, &ue) {
                let with_mu = !el.pos_mm.is_empty();
                for q in 0..el.cgeo.jxw.len() {
                    let nv = &self.ctab.values[q];
                    let (F, x) = self.contact_point(el, q, &ue);
                    let J = F.determinant();
                    if !(J > 0.0) {
                        return Err(DaeError::Inadmissible(format!(
                            "element {e}, contact point {q}: det F = {J:.3e}"
                        )));
                    }
                    let mut b = contact_force(&p.substrate, &p.contact, &x, J);
                    if with_mu && t_as > 0.0 {
                        if let Some(ad) = &p.adhesion {
                            let mu = self.mu_at(el, q, y);
                            b += adhesion_force(&p.substrate, ad, &x, &F, &el.radial[q], mu, t_as);
                        }
                    }
                    let w = el.cgeo.jxw[q];
                    for a in 0..6 {
                        fe[a][0] -= w * nv[a] * b.x;
                        fe[a][1] -= w * nv[a] * b.y;
                    }
                }
            }
            for a in 0..6 {
                for i in 0..2 {
                    let row = el.mrows[2 * a + i];
                    if row != NONE {
                        r[row] += fe[a][i];
                    }
                }
            }
        }
        if let Some(ad) = &p.adhesion {
            for (k, &i) in self.dofs.mu_nodes.iter().enumerate() {
                let row = mu_off + k;
                let u = self.dofs.node_u(y, i);
                let x = Vector2::new(self.mesh.nodes[i][0] + u[0], self.mesh.nodes[i][1] + u[1]);
                r[row] = yp[row] - adhesion_rate(&p.substrate, ad, &x, y[row]);
            }
        }
        if r.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(DaeError::Inadmissible("non-finite residual".into()))
        }
    }

    fn pattern(&self) -> &Pattern {
        &self.pattern
    }

    #[allow(non_snake_case)]
    fn jacobian(
        &mut self,
        t: f64,
        y: &[f64],
        yp: &[f64],
        cj: f64,
        v: &mut [f64],
    ) -> Result<(), DaeError> {
        v.fill(0.0);
        let p = &self.params;
        let (t_as, t_a) = (p.phases.t_as(t), p.phases.t_a(t));
        let inertia = self.dofs.inertia;
        for &[puu, puv] in &self.pos_kin {
            v[puu] += cj;
            v[puv] -= 1.0;
        }
        let mut kmat = [[0.0f64; 12]; 12];
        let mut cmat = [[0.0f64; 12]; 12];
        let mut mmat = [[0.0f64; 6]; 12];
        for (e, el) in self.elements.iter().enumerate() {
            let (ue, ve, _) = self.gather(el, y, yp);
            for row in kmat.iter_mut() {
                row.fill(0.0);
            }
            for row in cmat.iter_mut() {
                row.fill(0.0);
            }
            let solid = &p.solids[el.solid];
            for q in 0..el.geo.jxw.len() {
                let g = &el.geo.grads[q];
                let [F, Fdot, Fa] = Self::solid_point(e, el, q, &ue, &ve, t_a)?;
                let mp = material_point(solid, &p.viscosity, &F, &Fdot, &Fa);
                let w = el.geo.jxw[q];
                // K_(a i)(b k) = w Σ_JL A_(iJ)(kL) ∇Nₐ_J ∇N_b_L, same for C with ∂P/∂Ḟ.
                for a in 0..6 {
                    for i in 0..2 {
                        let mut ak = [0.0; 4];
                        let mut ck = [0.0; 4];
                        for (col, (akc, ckc)) in ak.iter_mut().zip(ck.iter_mut()).enumerate() {
                            *akc = w
                                * (mp.dP_dF[(2 * i, col)] * g[a][0]
                                    + mp.dP_dF[(2 * i + 1, col)] * g[a][1]);
                            *ckc = w
                                * (mp.dP_dFdot[(2 * i, col)] * g[a][0]
                                    + mp.dP_dFdot[(2 * i + 1, col)] * g[a][1]);
                        }
                        let rr = 2 * a + i;
                        for b in 0..6 {
                            for k in 0..2 {
                                let cc = 2 * b + k;
                                kmat[rr][cc] += ak[2 * k] * g[b][0] + ak[2 * k + 1] * g[b][1];
                                cmat[rr][cc] += ck[2 * k] * g[b][0] + ck[2 * k + 1] * g[b][1];
                            }
                        }
                    }
                }
            }
            // Mass and drag: with inertia ∂/∂v̇ = M (× cj) and ∂/∂v = c_d M₁ in the v
            // columns; without, the drag acts on u̇: cj c_d M₁ in the u columns.
            for a in 0..6 {
                for b in 0..6 {
                    let m =
                        if inertia { cj * el.mass[a][b] } else { 0.0 } + p.drag * el.mass1[a][b];
                    for i in 0..2 {
                        cmat[2 * a + i][2 * b + i] += m;
                    }
                }
            }
            // Contact and adhesion (exact derivatives by dual numbers in (x, F, μ)).
            let with_mu = !el.pos_mm.is_empty();
            if with_mu {
                for row in mmat.iter_mut() {
                    row.fill(0.0);
                }
            }
            if self.in_reach(el, &ue) {
                for q in 0..el.cgeo.jxw.len() {
                    let g = &el.cgeo.grads[q];
                    let nv = &self.ctab.values[q];
                    let (F, x) = self.contact_point(el, q, &ue);
                    let xd = Vector2::new(
                        D7::from_re(x.x).derivative(0),
                        D7::from_re(x.y).derivative(1),
                    );
                    let Fd = Matrix2::new(
                        D7::from_re(F[(0, 0)]).derivative(2),
                        D7::from_re(F[(0, 1)]).derivative(3),
                        D7::from_re(F[(1, 0)]).derivative(4),
                        D7::from_re(F[(1, 1)]).derivative(5),
                    );
                    let J = Fd[(0, 0)] * Fd[(1, 1)] - Fd[(0, 1)] * Fd[(1, 0)];
                    let mut b = contact_force(&p.substrate, &p.contact, &xd, J);
                    if with_mu && t_as > 0.0 {
                        if let Some(ad) = &p.adhesion {
                            let mud = D7::from_re(self.mu_at(el, q, y)).derivative(6);
                            b += adhesion_force(
                                &p.substrate,
                                ad,
                                &xd,
                                &Fd,
                                &el.radial[q],
                                mud,
                                t_as,
                            );
                        }
                    }
                    let w = el.cgeo.jxw[q];
                    for i in 0..2 {
                        let db = b[i].eps.unwrap_generic(nalgebra::U7, nalgebra::U1);
                        for a in 0..6 {
                            let wa = w * nv[a];
                            if wa == 0.0 {
                                continue;
                            }
                            for bb in 0..6 {
                                for k in 0..2 {
                                    // ∂b_i/∂u_(bb,k) = ∂b_i/∂x_k N_bb + Σ_L ∂b_i/∂F_kL ∇N_bb_L
                                    let d = db[k] * nv[bb]
                                        + db[2 + 2 * k] * g[bb][0]
                                        + db[3 + 2 * k] * g[bb][1];
                                    kmat[2 * a + i][2 * bb + k] -= wa * d;
                                }
                                if with_mu {
                                    mmat[2 * a + i][bb] -= wa * db[6] * nv[bb];
                                }
                            }
                        }
                    }
                }
            }
            // Scatter.
            if inertia {
                for rr in 0..12 {
                    for cc in 0..12 {
                        let k = 12 * rr + cc;
                        let (pu, pv) = (el.pos_mu[k], el.pos_mv[k]);
                        if pu != NONE {
                            v[pu] += kmat[rr][cc];
                        }
                        if pv != NONE {
                            v[pv] += cmat[rr][cc];
                        }
                    }
                }
            } else {
                for rr in 0..12 {
                    for cc in 0..12 {
                        let pu = el.pos_mu[12 * rr + cc];
                        if pu != NONE {
                            v[pu] += kmat[rr][cc] + cj * cmat[rr][cc];
                        }
                    }
                }
            }
            if with_mu {
                for rr in 0..12 {
                    for cc in 0..6 {
                        let pm = el.pos_mm[6 * rr + cc];
                        if pm != NONE {
                            v[pm] += mmat[rr][cc];
                        }
                    }
                }
            }
        }
        if let Some(ad) = &p.adhesion {
            type D3 = DualSVec64<3>;
            let off = self.dofs.mu_offset();
            for (k, &i) in self.dofs.mu_nodes.iter().enumerate() {
                let row = off + k;
                let u = self.dofs.node_u(y, i);
                let xn = self.mesh.nodes[i];
                let x = Vector2::new(
                    D3::from_re(xn[0] + u[0]).derivative(0),
                    D3::from_re(xn[1] + u[1]).derivative(1),
                );
                let rate = adhesion_rate(&p.substrate, ad, &x, D3::from_re(y[row]).derivative(2));
                let d = rate.eps.unwrap_generic(nalgebra::U3, nalgebra::U1);
                let [pmm, pux, puy] = self.pos_ads[k];
                v[pmm] += cj - d[2];
                if pux != NONE {
                    v[pux] -= d[0];
                }
                if puy != NONE {
                    v[puy] -= d[1];
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

    /// With inertia, the pairs (u_k, v_k): rows [0, n_u) are the kinematic rows u̇ − v = 0
    /// and row n_u + k is the momentum balance of u_k's component.
    fn first_order_blocks(&self) -> Option<FirstOrderBlocks> {
        self.dofs.inertia.then(|| {
            let n_u = self.dofs.n_u;
            FirstOrderBlocks::contiguous(0, n_u, n_u)
        })
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
