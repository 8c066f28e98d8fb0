//! Element kernels: each term of the momentum balance gives, on one element, its residual
//! contribution and its tangent from one computation of the quadrature-point kinematics.
//!
//! With the element force `f_e = ∫ Pᵀ∇N + M v̇ + c_d M₁ v − ∫ N b` (node-major,
//! `f_e[a][i]`), the tangents are split by what they multiply in `J = ∂F/∂y + cj ∂F/∂ẏ`:
//!
//! - `K = ∂f_e/∂u` (stiffness of the solid, contact and adhesion),
//! - `C = ∂f_e/∂v` (viscous damping, drag and, with inertia, `cj M` from `M v̇`), where v
//!   is the velocity unknown with inertia and u̇ without,
//! - `B = ∂f_e/∂μ_as` (adhesion, membrane elements).
//!
//! Kernels add into an [`ElementVector`] / [`ElementTangent`] in a fixed order (solid,
//! mass, band), the order in which the sums are formed. Per quadrature point:
//!
//! - [`solid_residual`] / [`solid_tangent`]: `f_aᵢ += w P_iJ ∂Nₐ/∂X_J`,
//!   `K_(ai)(bk) += w ∂Nₐ/∂X_J ∂P_iJ/∂F_kL ∂N_b/∂X_L`, and `C` the same with `∂P/∂Ḟ`, at
//!   the [`SolidPoint`] (F, Ḟ, F_a);
//! - [`mass_residual`] / [`mass_tangent`]: gravity `−g s_g t_g Σ_b M_ab e_y`, inertia
//!   `M v̇` and drag `c_d M₁ v`;
//! - [`band_residual`] / [`band_tangent`]: the body forces of the thin bands near the
//!   substrate at the [`BandPoint`] (F, x, μ_as), `f_aᵢ −= w Nₐ bᵢ` with
//!   `b = b_ct(x, J) + b_as(x, F, μ_as)` ([`band_force`]: contact, plus adhesion on
//!   membrane elements), derivatives by forward-mode dual numbers in (x, F, μ_as);
//! - [`mu_rate_residual`] / [`mu_rate_tangent`]: the nodal adhesion rows
//!   `Ȧ − μ_as0 H_ε(d(x) + e_f)` of the exposure A (μ_as = Φ(A), [`super::history`]).
//!
//! What the kinematic model changes is a [`Formulation`]: the solid kernels and `F₃₃` at
//! the band points. Plane strain's are below ([`PlaneStrain`]: `F₃₃ = 1`, stresses and
//! tangents of the in-plane block only); the axisymmetric ones are in
//! [`super::axisym`]. The r weight of the axisymmetric integrals is in the elements'
//! quadrature weights ([`super::element`]), so the mass kernels serve both.
//!
//! The element loops are instantiated once per kinematic model, so the helpers they share
//! (these kernels, the loads, the substrate's depth, the scatter) have two callers each,
//! and the compiler stopped inlining several of them into plane strain's loop: 3 % more
//! instructions on `cases/fast/push-pull-short.ron` (callgrind), for the same arithmetic.
//! The hot ones are marked `#[inline(always)]` for that reason.

use nalgebra::{Const, SVector};
use num_dual::DualSVec64;

use super::ModelParams;
use super::element::{EDOF, Element, ElementState, NODES, Nodal};
use super::kinematics::{
    DIM, Kin, Kinematics, PlaneStrain, Tensor, Vector, contract, current_position, deformation,
    rate,
};
use crate::dae::DaeError;
use crate::fem::p2::P2Tabulation;
use crate::physics::{
    Real, Viscosity, Yeoh, adhesion_force, adhesion_hoop_factor, adhesion_rate, contact_force,
    material_point, piola_total,
};

/// Element force vector, node-major: `f[a][i]`.
pub(crate) type ElementVector = Nodal;

/// The element tangents `K`, `C` and `B` of the six-node triangle.
pub(crate) type ElementTangent = super::plan::TangentOf<EDOF, NODES>;

/// The time-dependent switches of MODEL.md §5 at one time.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Switches {
    /// Gravity ramp t_g.
    pub(crate) t_g: f64,
    /// Adhesion ramp t_as.
    pub(crate) t_as: f64,
    /// Active-strain ramp t_a.
    pub(crate) t_a: f64,
    /// Gravity sign s_g.
    pub(crate) s_g: f64,
}

impl Switches {
    /// The switches of `params` at time `t`.
    pub(crate) fn at(params: &ModelParams, t: f64) -> Self {
        let ph = &params.phases;
        Self {
            t_g: ph.t_g(t),
            t_as: ph.t_as(t),
            t_a: ph.t_a(t),
            s_g: ph.gravity_sign(t),
        }
    }
}

/// What a kinematic model changes in the element kernels (MODEL.md §3, §10): the solid's
/// internal force and tangents at the standard points, and `F₃₃` at the band points. The
/// element loops are generic over it, so the choice is made once per loop and each model
/// runs its own code ([`PlaneStrain`] keeps `F₃₃ = 1` fixed, with no work for it).
pub(crate) trait Formulation {
    /// The solid's internal force of element `e` ([`solid_residual`] in plane strain).
    fn solid_residual(
        e: usize,
        el: &Element,
        law: &Yeoh,
        visc: &Viscosity,
        st: &ElementState,
        t_a: f64,
        fe: &mut ElementVector,
    ) -> Result<(), DaeError>;

    /// The solid's tangents `K`, `C` of element `e` ([`solid_tangent`] in plane strain).
    fn solid_tangent(
        e: usize,
        el: &Element,
        law: &Yeoh,
        visc: &Viscosity,
        st: &ElementState,
        t_a: f64,
        tan: &mut ElementTangent,
    ) -> Result<(), DaeError>;

    /// `F₃₃` at a band point with current position `x` and reference position `x_ref`:
    /// `None` where it is 1 (plane strain).
    fn hoop<T: Real>(x: &Vector<T>, x_ref: &[f64; DIM]) -> Option<T>;
}

impl Formulation for PlaneStrain {
    #[inline(always)]
    fn solid_residual(
        e: usize,
        el: &Element,
        law: &Yeoh,
        visc: &Viscosity,
        st: &ElementState,
        t_a: f64,
        fe: &mut ElementVector,
    ) -> Result<(), DaeError> {
        solid_residual(e, el, law, visc, st, t_a, fe)
    }

    #[inline(always)]
    fn solid_tangent(
        e: usize,
        el: &Element,
        law: &Yeoh,
        visc: &Viscosity,
        st: &ElementState,
        t_a: f64,
        tan: &mut ElementTangent,
    ) -> Result<(), DaeError> {
        solid_tangent(e, el, law, visc, st, t_a, tan)
    }

    #[inline(always)]
    fn hoop<T: Real>(_x: &Vector<T>, _x_ref: &[f64; DIM]) -> Option<T> {
        None
    }
}

/// Kinematics at a point of the standard rule: `F` (checked admissible), `Ḟ`, `F_a`.
#[allow(non_snake_case)]
pub(crate) struct SolidPoint {
    pub(crate) F: Tensor<f64>,
    pub(crate) Fdot: Tensor<f64>,
    pub(crate) Fa: Tensor<f64>,
}

/// `F` of element `e` at point `q` is admissible: `J = det F > 0` and finite.
#[inline(always)]
pub(crate) fn check_admissible(e: usize, q: usize, f: &Tensor<f64>) -> Result<(), DaeError> {
    let j = Kin::det::<f64>(f);
    if j > 0.0 && j.is_finite() {
        Ok(())
    } else {
        Err(DaeError::Inadmissible(format!(
            "element {e}, quadrature point {q}: det F = {j:.3e}"
        )))
    }
}

impl SolidPoint {
    /// At standard point `q` of element `e` in state `st`, active ramp `t_a`.
    #[allow(non_snake_case)]
    #[inline]
    pub(crate) fn at(
        e: usize,
        el: &Element,
        q: usize,
        st: &ElementState,
        t_a: f64,
    ) -> Result<Self, DaeError> {
        let g = &el.geo.grads[q];
        let F = deformation(&st.u, g);
        check_admissible(e, q, &F)?;
        Ok(Self {
            F,
            Fdot: rate(&st.v, g),
            Fa: el.active_fa(q, t_a),
        })
    }
}

/// The solid's internal force `f_aᵢ += Σ_q w_q P_iJ ∂Nₐ/∂X_J`, with `P` the total first
/// Piola–Kirchhoff stress (Yeoh with active strain, plus Kelvin–Voigt viscosity).
#[inline(always)]
pub(crate) fn solid_residual(
    e: usize,
    el: &Element,
    law: &Yeoh,
    visc: &Viscosity,
    st: &ElementState,
    t_a: f64,
    fe: &mut ElementVector,
) -> Result<(), DaeError> {
    for q in 0..el.geo.jxw.len() {
        let g = &el.geo.grads[q];
        let pt = SolidPoint::at(e, el, q, st, t_a)?;
        let p = piola_total(law, visc, &pt.F, &pt.Fdot, &pt.Fa);
        let w = el.geo.jxw[q];
        for a in 0..NODES {
            for i in 0..DIM {
                fe[a][i] += w * contract::<DIM>(|l| p[(i, l)] * g[a][l]);
            }
        }
    }
    Ok(())
}

/// The solid's tangents `K_(ai)(bk) += w Σ_JL ∂Nₐ/∂X_J A_(iJ)(kL) ∂N_b/∂X_L` with
/// `A = ∂P/∂F`, and `C` the same with `∂P/∂Ḟ`.
#[allow(non_snake_case)]
#[inline(always)]
pub(crate) fn solid_tangent(
    e: usize,
    el: &Element,
    law: &Yeoh,
    visc: &Viscosity,
    st: &ElementState,
    t_a: f64,
    tan: &mut ElementTangent,
) -> Result<(), DaeError> {
    for q in 0..el.geo.jxw.len() {
        let g = &el.geo.grads[q];
        let pt = SolidPoint::at(e, el, q, st, t_a)?;
        let mp = material_point(law, visc, &pt.F, &pt.Fdot, &pt.Fa);
        let w = el.geo.jxw[q];
        for a in 0..NODES {
            for i in 0..DIM {
                // ak_(kL) = w Σ_J ∂Nₐ/∂X_J A_(iJ)(kL), the same for C.
                let mut ak = [0.0; DIM * DIM];
                let mut ck = [0.0; DIM * DIM];
                for (col, (akc, ckc)) in ak.iter_mut().zip(ck.iter_mut()).enumerate() {
                    *akc = w * contract::<DIM>(|j| mp.dP_dF[(DIM * i + j, col)] * g[a][j]);
                    *ckc = w * contract::<DIM>(|j| mp.dP_dFdot[(DIM * i + j, col)] * g[a][j]);
                }
                let rr = DIM * a + i;
                for b in 0..NODES {
                    for k in 0..DIM {
                        let cc = DIM * b + k;
                        tan.k[rr][cc] += contract::<DIM>(|l| ak[DIM * k + l] * g[b][l]);
                        tan.c[rr][cc] += contract::<DIM>(|l| ck[DIM * k + l] * g[b][l]);
                    }
                }
            }
        }
    }
    Ok(())
}

/// Gravity, inertia and drag: `f_a,y += g_now Σ_b M_ab` (body force `−ρ g s_g t_g e_y`
/// integrated, `g_now = g s_g t_g`), `f_aᵢ += Σ_b M_ab v̇_bᵢ` (inertia) and
/// `+= c_d Σ_b M₁_ab v_bᵢ` (drag, `c_d > 0`).
#[inline(always)]
pub(crate) fn mass_residual(
    el: &Element,
    g_now: f64,
    inertia: bool,
    drag: f64,
    st: &ElementState,
    fe: &mut ElementVector,
) {
    for a in 0..NODES {
        let ma: f64 = el.mass[a].iter().sum();
        fe[a][DIM - 1] += ma * g_now;
        for b in 0..NODES {
            for i in 0..DIM {
                if inertia {
                    fe[a][i] += el.mass[a][b] * st.a[b][i];
                }
                if drag > 0.0 {
                    fe[a][i] += drag * el.mass1[a][b] * st.v[b][i];
                }
            }
        }
    }
}

/// Inertia and drag tangents: `C_(ai)(bi) += cj M_ab + c_d M₁_ab` (with inertia, `M v̇`
/// gives `cj M` in the v columns; without, the drag acts on u̇).
#[inline(always)]
pub(crate) fn mass_tangent(
    el: &Element,
    cj: f64,
    inertia: bool,
    drag: f64,
    tan: &mut ElementTangent,
) {
    for a in 0..NODES {
        for b in 0..NODES {
            let m = if inertia { cj * el.mass[a][b] } else { 0.0 } + drag * el.mass1[a][b];
            for i in 0..DIM {
                tan.c[DIM * a + i][DIM * b + i] += m;
            }
        }
    }
}

/// Kinematics at a point of the band rule: `F`, the current position `x` and, where
/// adhesion acts, the interpolated `μ_as = Σₐ Nₐ μₐ`.
#[allow(non_snake_case)]
pub(crate) struct BandPoint {
    pub(crate) F: Tensor<f64>,
    pub(crate) x: Vector<f64>,
    pub(crate) mu: Option<f64>,
}

impl BandPoint {
    /// At band point `q` of `el` in state `st`; `mue`: nodal μ_as where adhesion acts.
    #[allow(non_snake_case)]
    #[inline]
    pub(crate) fn at(
        el: &Element,
        ctab: &P2Tabulation,
        q: usize,
        st: &ElementState,
        mue: Option<&[f64; NODES]>,
    ) -> Self {
        let nv = &ctab.values[q];
        let F = deformation(&st.u, &el.cgeo.grads[q]);
        let x = current_position(&el.cgeo.x[q], nv, &st.u);
        let mu = mue.map(|m| (0..NODES).map(|a| nv[a] * m[a]).sum::<f64>());
        Self { F, x, mu }
    }
}

/// Body force of the bands at a point: contact `b_ct(x, J)` plus, with `mu` (membrane
/// elements while adhesion acts), adhesion `b_as(x, F, μ_as)` along the outward radial
/// reference direction `radial`, ramped by `t_as`. `J` is `det F₂`; with a hoop stretch
/// `hoop = F₃₃` (axisymmetric) the contact takes `J = F₃₃ det F₂` and the adhesion its
/// factor [`adhesion_hoop_factor`].
#[allow(non_snake_case, clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn band_force<T: Real>(
    p: &ModelParams,
    x: &Vector<T>,
    F: &Tensor<T>,
    J: T,
    hoop: Option<T>,
    radial: Option<&Vector<f64>>,
    mu: Option<T>,
    t_as: f64,
) -> Vector<T> {
    let J = match hoop {
        Some(l) => J * l,
        None => J,
    };
    let mut b = contact_force(&p.substrate, &p.contact, x, J);
    if let (Some(ad), Some(mu), Some(n)) = (&p.adhesion, mu, radial) {
        let f = adhesion_force(&p.substrate, ad, x, F, n, mu, t_as);
        b += match hoop {
            Some(l) => f * adhesion_hoop_factor(ad, l),
            None => f,
        };
    }
    b
}

/// Whether adhesion acts on `el` at `t_as`.
#[inline]
pub(crate) fn adhesion_acts(p: &ModelParams, el: &Element, t_as: f64) -> bool {
    el.with_mu && t_as > 0.0 && p.adhesion.is_some()
}

/// The band forces `f_aᵢ −= Σ_q w_q Nₐ bᵢ` ([`band_force`]); `mue`: the nodal μ_as when
/// adhesion acts on the element.
#[allow(non_snake_case, clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn band_residual<K: Formulation>(
    e: usize,
    el: &Element,
    ctab: &P2Tabulation,
    p: &ModelParams,
    st: &ElementState,
    mue: Option<&[f64; NODES]>,
    t_as: f64,
    fe: &mut ElementVector,
) -> Result<(), DaeError> {
    for q in 0..el.cgeo.jxw.len() {
        let nv = &ctab.values[q];
        let pt = BandPoint::at(el, ctab, q, st, mue);
        let J = Kin::det::<f64>(&pt.F);
        let hoop = K::hoop(&pt.x, &el.cgeo.x[q]);
        let J3 = hoop.map_or(J, |l| J * l);
        if !(J > 0.0 && J3 > 0.0) {
            return Err(DaeError::Inadmissible(format!(
                "element {e}, contact point {q}: det F = {J3:.3e}"
            )));
        }
        let b = band_force(p, &pt.x, &pt.F, J, hoop, el.radial.get(q), pt.mu, t_as);
        let w = el.cgeo.jxw[q];
        for a in 0..NODES {
            for i in 0..DIM {
                fe[a][i] -= w * nv[a] * b[i];
            }
        }
    }
    Ok(())
}

/// Number of dual directions of the band tangent: x (DIM), F (DIM²), μ_as (1).
const NB: usize = DIM + DIM * DIM + 1;
/// Dual direction of `F_kL`.
const fn f_dir(k: usize, l: usize) -> usize {
    DIM + DIM * k + l
}
/// Dual direction of μ_as.
const MU_DIR: usize = DIM + DIM * DIM;
type DualB = DualSVec64<NB>;

/// The band tangents: with `∂b/∂(x, F, μ_as)` by dual numbers at each point,
/// `K_(ai)(bk) −= w Nₐ (∂bᵢ/∂x_k N_b + Σ_L ∂bᵢ/∂F_kL ∂N_b/∂X_L)` and
/// `B_(ai)b −= w Nₐ ∂bᵢ/∂μ_as N_b` (membrane elements with adhesion).
#[allow(non_snake_case, clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn band_tangent<K: Formulation>(
    el: &Element,
    ctab: &P2Tabulation,
    p: &ModelParams,
    st: &ElementState,
    mue: Option<&[f64; NODES]>,
    t_as: f64,
    tan: &mut ElementTangent,
) {
    let with_mu = el.with_mu;
    for q in 0..el.cgeo.jxw.len() {
        let g = &el.cgeo.grads[q];
        let nv = &ctab.values[q];
        let pt = BandPoint::at(el, ctab, q, st, mue);
        let xd: SVector<DualB, DIM> =
            SVector::from_fn(|k, _| DualB::from_re(pt.x[k]).derivative(k));
        let Fd: Tensor<DualB> =
            Tensor::<DualB>::from_fn(|k, l| DualB::from_re(pt.F[(k, l)]).derivative(f_dir(k, l)));
        let J = Kin::det::<DualB>(&Fd);
        let mud = pt.mu.map(|mu| DualB::from_re(mu).derivative(MU_DIR));
        // F₃₃ = x_r/X_r (axisymmetric) is a function of x: no dual direction of its own.
        let hoop = K::hoop(&xd, &el.cgeo.x[q]);
        let b = band_force(p, &xd, &Fd, J, hoop, el.radial.get(q), mud, t_as);
        let w = el.cgeo.jxw[q];
        for i in 0..DIM {
            let db = b[i].eps.unwrap_generic(Const::<NB>, Const::<1>);
            for a in 0..NODES {
                let wa = w * nv[a];
                if wa == 0.0 {
                    continue;
                }
                for bb in 0..NODES {
                    for k in 0..DIM {
                        // ∂bᵢ/∂u_(bb,k) = ∂bᵢ/∂x_k N_bb + Σ_L ∂bᵢ/∂F_kL ∂N_bb/∂X_L
                        let mut d = db[k] * nv[bb];
                        for l in 0..DIM {
                            d += db[f_dir(k, l)] * g[bb][l];
                        }
                        tan.k[DIM * a + i][DIM * bb + k] -= wa * d;
                    }
                    if with_mu {
                        tan.b[DIM * a + i][bb] -= wa * db[MU_DIR] * nv[bb];
                    }
                }
            }
        }
    }
}

/// The adhesion row of a membrane node: `Ȧ − a(x)` with the drive `a = r(x, μ_as = 0)`
/// at its current position `x` (the rate of μ_as before the cap).
pub(crate) fn mu_rate_residual(p: &ModelParams, x: &Vector<f64>, a_dot: f64) -> f64 {
    match &p.adhesion {
        Some(ad) => a_dot - adhesion_rate(&p.substrate, ad, x, 0.0),
        None => 0.0,
    }
}

/// `∂a/∂x` (DIM values) of the drive at a node, by dual numbers, and `∂a/∂A = 0`; the
/// row's entries are `cj` and `−∂a/∂x_k`.
pub(crate) fn mu_rate_tangent(p: &ModelParams, x: &Vector<f64>) -> [f64; DIM + 1] {
    type DualR = DualSVec64<{ DIM + 1 }>;
    let Some(ad) = &p.adhesion else {
        return [0.0; DIM + 1];
    };
    let xd: SVector<DualR, DIM> = SVector::from_fn(|k, _| DualR::from_re(x[k]).derivative(k));
    let rate = adhesion_rate(&p.substrate, ad, &xd, DualR::from_re(0.0));
    let d = rate.eps.unwrap_generic(Const::<{ DIM + 1 }>, Const::<1>);
    std::array::from_fn(|k| d[k])
}
