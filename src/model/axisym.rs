//! The solid kernels of the axisymmetric model (MODEL.md §10): the [`Formulation`] of
//! [`Axisymmetric`].
//!
//! In the meridian half-plane (r, y) the strain of node a's radial displacement has a hoop
//! row besides the in-plane gradient: `F = F₂ ⊕ λ`, `λ = 1 + Σₐ Nₐ u_(a,r)/r`, so
//! `∂λ/∂u_(a,r) = Nₐ/r` ([`Element::hoop`], tabulated once). With the block-diagonal
//! first Piola stress `P = P₂ ⊕ P₃₃` ([`piola_total_hoop`]) and the weight `w = r dA` (in
//! the element's quadrature weights), the internal force is
//!
//! `f_aᵢ = Σ_q w (P_iJ ∂Nₐ/∂X_J + δ_ir P₃₃ Nₐ/r)`,
//!
//! and the tangents `K = Σ_q w Bᵀ (∂P/∂F) B`, with `B` mapping node displacements to the
//! five entries (F₂, λ) of `F` (`C` the same with `∂P/∂Ḟ`, `λ̇ = Σₐ Nₐ u̇_(a,r)/r`).

#![allow(non_snake_case)]

use nalgebra::Vector2;

use super::element::ElementOf;
use super::kernels::{Formulation, Solid, check_admissible, inadmissible};
use super::kinematics::{Axisymmetric, NodalOf, contract, deformation, rate};
use super::plan::TangentOf;
use crate::dae::{DaeError, ElementPoint};
use crate::physics::hoop::{HOOP, HOOP_ENTRIES};
use crate::physics::{BlockDiag, Real, material_point_hoop, piola_total_hoop};

/// Nodes of the six-node triangle.
const NODES: usize = 6;
/// Its dimension.
const DIM: usize = 2;
/// The half-plane element, its nodal vectors and tangents.
type Element = ElementOf<DIM, NODES>;
type ElementVector = NodalOf<DIM, NODES>;
type ElementTangent = TangentOf<12, NODES>;

/// `u_r/r` (or `u̇_r/r`) at standard point `q`: `Σₐ Nₐ/r · w_(a,r)`.
#[inline]
fn over_r(el: &Element, q: usize, w: &ElementVector) -> f64 {
    let h = &el.hoop[q];
    let mut s = h[0] * w[0][0];
    for a in 1..NODES {
        s += h[a] * w[a][0];
    }
    s
}

/// Kinematics at a point of the standard rule with the hoop stretch.
struct HoopPoint {
    F: BlockDiag<f64>,
    Fdot: BlockDiag<f64>,
    Fa: nalgebra::Matrix2<f64>,
}

/// `F = F₂ ⊕ λ`, `Ḟ = Ḟ₂ ⊕ λ̇` and `F_a` at standard point `q`, checked admissible
/// (`det F₂ > 0`, `λ > 0`).
#[inline]
fn hoop_point(s: &Solid<DIM, NODES>, q: usize) -> Result<HoopPoint, DaeError> {
    let (el, st) = (s.el, s.st);
    let g = &el.geo.grads[q];
    let F2 = deformation(&st.u, g);
    check_admissible(s.e, q, &F2)?;
    let lambda = 1.0 + over_r(el, q, &st.u);
    if !(lambda > 0.0 && lambda.is_finite()) {
        let quantity = "hoop stretch 1 + u_r/r";
        return Err(inadmissible(
            s.e,
            ElementPoint::Quadrature(q),
            quantity,
            lambda,
        ));
    }
    let F = BlockDiag::new(F2, lambda);
    let Fdot = BlockDiag::new(rate(&st.v, g), over_r(el, q, &st.v));
    Ok(HoopPoint {
        F,
        Fdot,
        Fa: el.active_fa(q, s.t_a),
    })
}

impl Formulation<DIM, NODES, 12> for Axisymmetric {
    /// `f_aᵢ += w (P_iJ ∂Nₐ/∂X_J + δ_ir P₃₃ Nₐ/r)`.
    fn solid_residual(s: &Solid<DIM, NODES>, fe: &mut ElementVector) -> Result<(), DaeError> {
        s.each_point(hoop_point, |q, g, w, pt| {
            let h = &s.el.hoop[q];
            let mut p = piola_total_hoop(s.law, s.visc, &pt.F, &pt.Fdot, &pt.Fa);
            s.el.add_fibres::<1>(s.fibres, q, &pt.F.plane, &pt.Fa, &mut p.plane, None);
            for a in 0..NODES {
                for i in 0..DIM {
                    fe[a][i] += w * contract::<DIM>(|l| p.plane[(i, l)] * g[a][l]);
                }
                fe[a][0] += w * p.hoop * h[a];
            }
        })
    }

    /// `K_(ai)(bk) += w Σ_αβ B_(ai)α (∂P_α/∂F_β) B_(bk)β` over the five entries α, β of
    /// (F₂, λ): `B_(ai)(iJ) = ∂Nₐ/∂X_J`, `B_(a,r)λ = Nₐ/r`; `C` the same with `∂P/∂Ḟ`.
    fn solid_tangent(s: &Solid<DIM, NODES>, tan: &mut ElementTangent) -> Result<(), DaeError> {
        s.each_point(hoop_point, |q, g, w, pt| {
            let h = &s.el.hoop[q];
            let mut mp = material_point_hoop(s.law, s.visc, &pt.F, &pt.Fdot, &pt.Fa);
            let plane = &mut mp.P.plane;
            s.el.add_fibres(s.fibres, q, &pt.F.plane, &pt.Fa, plane, Some(&mut mp.dP_dF));
            for a in 0..NODES {
                for i in 0..DIM {
                    // ak_β = w Σ_α B_(ai)α A_αβ, the same for C.
                    let mut ak = [0.0; HOOP_ENTRIES];
                    let mut ck = [0.0; HOOP_ENTRIES];
                    for (col, (akc, ckc)) in ak.iter_mut().zip(ck.iter_mut()).enumerate() {
                        let mut sa = contract::<DIM>(|j| mp.dP_dF[(DIM * i + j, col)] * g[a][j]);
                        let mut sc = contract::<DIM>(|j| mp.dP_dFdot[(DIM * i + j, col)] * g[a][j]);
                        if i == 0 {
                            sa += mp.dP_dF[(HOOP, col)] * h[a];
                            sc += mp.dP_dFdot[(HOOP, col)] * h[a];
                        }
                        *akc = w * sa;
                        *ckc = w * sc;
                    }
                    let rr = DIM * a + i;
                    for b in 0..NODES {
                        for k in 0..DIM {
                            let cc = DIM * b + k;
                            let mut kk = contract::<DIM>(|l| ak[DIM * k + l] * g[b][l]);
                            let mut kc = contract::<DIM>(|l| ck[DIM * k + l] * g[b][l]);
                            if k == 0 {
                                kk += ak[HOOP] * h[b];
                                kc += ck[HOOP] * h[b];
                            }
                            tan.k[rr][cc] += kk;
                            tan.c[rr][cc] += kc;
                        }
                    }
                }
            }
        })
    }

    /// `λ = x_r/X_r`: the current over the reference radius (`1 + u_r/r`).
    #[inline(always)]
    fn hoop<T: Real>(x: &Vector2<T>, x_ref: &[f64; DIM]) -> Option<T> {
        Some(x[0] * (1.0 / x_ref[0]))
    }
}
