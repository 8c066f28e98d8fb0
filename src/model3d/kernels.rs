//! Element kernels of the 3-D quarter cell: each term of the momentum balance gives, on one
//! ten-node tetrahedron, its residual contribution and its tangent — the same terms, in the
//! same order, as the half-plane kernels (`crate::model::kernels`, whose documentation
//! gives the split of `J` into `K`, `C`, `B`), with 3 × 3 tensors and the 3-D laws of
//! [`crate::physics::solid3`]:
//!
//! - [`solid_residual`] / [`solid_tangent`]: `f_aᵢ += w P_iJ ∂Nₐ/∂X_J`,
//!   `K_(ai)(bk) += w ∂Nₐ/∂X_J ∂P_iJ/∂F_kL ∂N_b/∂X_L`, `C` the same with `∂P/∂Ḟ`;
//! - [`mass_residual`] / [`mass_tangent`]: gravity, inertia `M v̇` and drag `c_d M₁ v`;
//! - [`band_residual`] / [`band_tangent`]: contact `b_ct(x, J)` and, on membrane elements
//!   while adhesion acts, `b_as(x, F, μ_as)`, with derivatives by forward-mode dual numbers
//!   in (x, F, μ_as): 13 directions;
//! - [`mu_rate_residual`] / [`mu_rate_tangent`]: the nodal rows `Ȧ − μ_as0 H_ε(d + e_f)`
//!   of the exposure unknowns.

#![allow(non_snake_case)]

use nalgebra::{Const, Matrix3, SVector, Vector3};
use num_dual::DualSVec64;

use super::element::{EDOF, Element3, ElementState3, NODES, Nodal};
use crate::dae::DaeError;
use crate::fem::tet::TetTabulation;
use crate::model::ModelParams;
use crate::model::kinematics::{contract, current_position, deformation, rate};
use crate::model::plan::TangentOf;
use crate::physics::{
    Real, Substrate3, Viscosity, Yeoh, adhesion_force3, adhesion_rate3, contact_force3,
    material_point3, piola_total3,
};

/// Element force vector, node-major: `f[a][i]`.
pub(crate) type ElementVector3 = Nodal;

/// The element tangents `K`, `C` (30 × 30) and `B` (30 × 10).
pub(crate) type ElementTangent3 = TangentOf<EDOF, NODES>;

/// `F` of element `e` at point `q` is admissible: `J = det F > 0` and finite.
#[inline(always)]
fn check_admissible(e: usize, q: usize, f: &Matrix3<f64>) -> Result<(), DaeError> {
    let j = f.determinant();
    if j > 0.0 && j.is_finite() {
        Ok(())
    } else {
        Err(DaeError::Inadmissible(format!(
            "element {e}, quadrature point {q}: det F = {j:.3e}"
        )))
    }
}

/// The solid's internal force `f_aᵢ += Σ_q w_q P_iJ ∂Nₐ/∂X_J`, with `P` the total first
/// Piola–Kirchhoff stress (Yeoh with active strain, plus Kelvin–Voigt viscosity).
pub(crate) fn solid_residual(
    e: usize,
    el: &Element3,
    law: &Yeoh,
    visc: &Viscosity,
    st: &ElementState3,
    t_a: f64,
    fe: &mut ElementVector3,
) -> Result<(), DaeError> {
    for q in 0..el.geo.jxw.len() {
        let g = &el.geo.grads[q];
        let F = deformation(&st.u, g);
        check_admissible(e, q, &F)?;
        let p = piola_total3(law, visc, &F, &rate(&st.v, g), &el.active_fa(q, t_a));
        let w = el.geo.jxw[q];
        for a in 0..NODES {
            for i in 0..3 {
                fe[a][i] += w * contract::<3>(|l| p[(i, l)] * g[a][l]);
            }
        }
    }
    Ok(())
}

/// The solid's tangents `K_(ai)(bk) += w Σ_JL ∂Nₐ/∂X_J A_(iJ)(kL) ∂N_b/∂X_L` with
/// `A = ∂P/∂F`, and `C` the same with `∂P/∂Ḟ`.
pub(crate) fn solid_tangent(
    e: usize,
    el: &Element3,
    law: &Yeoh,
    visc: &Viscosity,
    st: &ElementState3,
    t_a: f64,
    tan: &mut ElementTangent3,
) -> Result<(), DaeError> {
    for q in 0..el.geo.jxw.len() {
        let g = &el.geo.grads[q];
        let F = deformation(&st.u, g);
        check_admissible(e, q, &F)?;
        let mp = material_point3(law, visc, &F, &rate(&st.v, g), &el.active_fa(q, t_a));
        let w = el.geo.jxw[q];
        for a in 0..NODES {
            for i in 0..3 {
                // ak_(kL) = w Σ_J ∂Nₐ/∂X_J A_(iJ)(kL), the same for C.
                let mut ak = [0.0; 9];
                let mut ck = [0.0; 9];
                for (col, (akc, ckc)) in ak.iter_mut().zip(ck.iter_mut()).enumerate() {
                    *akc = w * contract::<3>(|j| mp.dP_dF[(3 * i + j, col)] * g[a][j]);
                    *ckc = w * contract::<3>(|j| mp.dP_dFdot[(3 * i + j, col)] * g[a][j]);
                }
                let rr = 3 * a + i;
                for b in 0..NODES {
                    for k in 0..3 {
                        let cc = 3 * b + k;
                        tan.k[rr][cc] += contract::<3>(|l| ak[3 * k + l] * g[b][l]);
                        tan.c[rr][cc] += contract::<3>(|l| ck[3 * k + l] * g[b][l]);
                    }
                }
            }
        }
    }
    Ok(())
}

/// Gravity, inertia and drag: `f_a,y += g_now Σ_b M_ab` (the body force `−ρ g s_g t_g e_y`
/// integrated), `f_aᵢ += Σ_b M_ab v̇_bᵢ` (inertia) and `+= c_d Σ_b M₁_ab v_bᵢ` (drag).
pub(crate) fn mass_residual(
    el: &Element3,
    g_now: f64,
    inertia: bool,
    drag: f64,
    st: &ElementState3,
    fe: &mut ElementVector3,
) {
    for a in 0..NODES {
        let ma: f64 = el.mass[a].iter().sum();
        fe[a][1] += ma * g_now;
        for b in 0..NODES {
            for i in 0..3 {
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

/// Inertia and drag tangents: `C_(ai)(bi) += cj M_ab + c_d M₁_ab`.
pub(crate) fn mass_tangent(
    el: &Element3,
    cj: f64,
    inertia: bool,
    drag: f64,
    tan: &mut ElementTangent3,
) {
    for a in 0..NODES {
        for b in 0..NODES {
            let m = if inertia { cj * el.mass[a][b] } else { 0.0 } + drag * el.mass1[a][b];
            for i in 0..3 {
                tan.c[3 * a + i][3 * b + i] += m;
            }
        }
    }
}

/// Body force of the bands at a point: contact `b_ct(x, J)` plus, with `mu` (membrane
/// elements while adhesion acts), adhesion `b_as(x, F, μ_as)` along the outward radial
/// reference direction `radial`, ramped by `t_as`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn band_force<T: Real>(
    p: &ModelParams,
    sub: &Substrate3,
    x: &Vector3<T>,
    F: &Matrix3<T>,
    J: T,
    radial: Option<&Vector3<f64>>,
    mu: Option<T>,
    t_as: f64,
) -> Vector3<T> {
    let mut b = contact_force3(sub, &p.contact, x, J);
    if let (Some(ad), Some(mu), Some(n)) = (&p.adhesion, mu, radial) {
        b += adhesion_force3(sub, ad, x, F, n, mu, t_as);
    }
    b
}

/// Whether adhesion acts on `el` at `t_as`.
#[inline]
pub(crate) fn adhesion_acts(p: &ModelParams, el: &Element3, t_as: f64) -> bool {
    el.with_mu && t_as > 0.0 && p.adhesion.is_some()
}

/// Whether the band force is exactly zero at the current position `x`, with its
/// derivatives: below the contact band (`d ≤ −ε_ct`, where `H_ε` and its derivatives
/// vanish) and, where adhesion acts (`adhesion`), below the fibronectin layer too
/// (`d + e_f ≤ −ε`). The band rule's points there are skipped (a thick element reaching
/// into the band has most of its points far above it).
#[inline]
fn band_is_zero(p: &ModelParams, sub: &Substrate3, x: &Vector3<f64>, adhesion: bool) -> bool {
    let (d, _) = sub.eval(x);
    let below_contact = d <= -p.contact.eps;
    match (&p.adhesion, adhesion) {
        (Some(ad), true) => below_contact && d + ad.e_f <= -ad.eps,
        _ => below_contact,
    }
}

/// `F`, the current position `x` and, where adhesion acts, `μ_as = Σₐ Nₐ μₐ` at band
/// point `q`.
#[inline]
fn band_point(
    el: &Element3,
    ctab: &TetTabulation,
    q: usize,
    st: &ElementState3,
    mue: Option<&[f64; NODES]>,
) -> (Matrix3<f64>, Vector3<f64>, Option<f64>) {
    let nv = &ctab.values[q];
    let F = deformation(&st.u, &el.cgeo.grads[q]);
    let x = current_position(&el.cgeo.x[q], nv, &st.u);
    let mu = mue.map(|m| (0..NODES).map(|a| nv[a] * m[a]).sum::<f64>());
    (F, x, mu)
}

/// The band forces `f_aᵢ −= Σ_q w_q Nₐ bᵢ` ([`band_force`]); `mue`: the nodal μ_as when
/// adhesion acts on the element.
#[allow(clippy::too_many_arguments)]
pub(crate) fn band_residual(
    e: usize,
    el: &Element3,
    ctab: &TetTabulation,
    p: &ModelParams,
    sub: &Substrate3,
    st: &ElementState3,
    mue: Option<&[f64; NODES]>,
    t_as: f64,
    fe: &mut ElementVector3,
) -> Result<(), DaeError> {
    for q in 0..el.cgeo.jxw.len() {
        let nv = &ctab.values[q];
        if band_is_zero(
            p,
            sub,
            &current_position(&el.cgeo.x[q], nv, &st.u),
            mue.is_some(),
        ) {
            continue;
        }
        let (F, x, mu) = band_point(el, ctab, q, st, mue);
        let J = F.determinant();
        if !(J > 0.0) {
            return Err(DaeError::Inadmissible(format!(
                "element {e}, contact point {q}: det F = {J:.3e}"
            )));
        }
        let b = band_force(p, sub, &x, &F, J, el.radial.get(q), mu, t_as);
        let w = el.cgeo.jxw[q];
        for a in 0..NODES {
            for i in 0..3 {
                fe[a][i] -= w * nv[a] * b[i];
            }
        }
    }
    Ok(())
}

/// Number of dual directions of the band tangent: x (3), F (9), μ_as (1).
const NB: usize = 13;
/// Dual direction of `F_kL`.
const fn f_dir(k: usize, l: usize) -> usize {
    3 + 3 * k + l
}
/// Dual direction of μ_as.
const MU_DIR: usize = 12;
type DualB = DualSVec64<NB>;

/// The band tangents: with `∂b/∂(x, F, μ_as)` by dual numbers at each point,
/// `K_(ai)(bk) −= w Nₐ (∂bᵢ/∂x_k N_b + Σ_L ∂bᵢ/∂F_kL ∂N_b/∂X_L)` and
/// `B_(ai)b −= w Nₐ ∂bᵢ/∂μ_as N_b` (membrane elements with adhesion).
#[allow(clippy::too_many_arguments)]
pub(crate) fn band_tangent(
    el: &Element3,
    ctab: &TetTabulation,
    p: &ModelParams,
    sub: &Substrate3,
    st: &ElementState3,
    mue: Option<&[f64; NODES]>,
    t_as: f64,
    tan: &mut ElementTangent3,
) {
    let with_mu = el.with_mu;
    for q in 0..el.cgeo.jxw.len() {
        let g = &el.cgeo.grads[q];
        let nv = &ctab.values[q];
        if band_is_zero(
            p,
            sub,
            &current_position(&el.cgeo.x[q], nv, &st.u),
            mue.is_some(),
        ) {
            continue;
        }
        let (F, x, mu) = band_point(el, ctab, q, st, mue);
        let xd: Vector3<DualB> = SVector::from_fn(|k, _| DualB::from_re(x[k]).derivative(k));
        let Fd: Matrix3<DualB> =
            Matrix3::from_fn(|k, l| DualB::from_re(F[(k, l)]).derivative(f_dir(k, l)));
        let J = Fd.determinant();
        let mud = mu.map(|mu| DualB::from_re(mu).derivative(MU_DIR));
        let b = band_force(p, sub, &xd, &Fd, J, el.radial.get(q), mud, t_as);
        let w = el.cgeo.jxw[q];
        for i in 0..3 {
            let db = b[i].eps.unwrap_generic(Const::<NB>, Const::<1>);
            for a in 0..NODES {
                let wa = w * nv[a];
                if wa == 0.0 {
                    continue;
                }
                for bb in 0..NODES {
                    for k in 0..3 {
                        let mut d = db[k] * nv[bb];
                        for l in 0..3 {
                            d += db[f_dir(k, l)] * g[bb][l];
                        }
                        tan.k[3 * a + i][3 * bb + k] -= wa * d;
                    }
                    if with_mu {
                        tan.b[3 * a + i][bb] -= wa * db[MU_DIR] * nv[bb];
                    }
                }
            }
        }
    }
}

/// The adhesion row of a membrane node: `Ȧ − a(x)` with the drive `a = r(x, μ_as = 0)`
/// at its current position `x`.
pub(crate) fn mu_rate_residual(
    p: &ModelParams,
    sub: &Substrate3,
    x: &Vector3<f64>,
    a_dot: f64,
) -> f64 {
    match &p.adhesion {
        Some(ad) => a_dot - adhesion_rate3(sub, ad, x, 0.0),
        None => 0.0,
    }
}

/// `∂a/∂x` of the drive at a node, by dual numbers (the row's entries are `cj` on A and
/// `−∂a/∂x_k` on the node's u).
pub(crate) fn mu_rate_tangent(p: &ModelParams, sub: &Substrate3, x: &Vector3<f64>) -> [f64; 3] {
    type DualR = DualSVec64<3>;
    let Some(ad) = &p.adhesion else {
        return [0.0; 3];
    };
    let xd: Vector3<DualR> = SVector::from_fn(|k, _| DualR::from_re(x[k]).derivative(k));
    let rate = adhesion_rate3(sub, ad, &xd, DualR::from_re(0.0));
    let d = rate.eps.unwrap_generic(Const::<3>, Const::<1>);
    [d[0], d[1], d[2]]
}
