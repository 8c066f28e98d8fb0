//! Element kernels: each term of the momentum balance gives, on one element, its residual
//! contribution and its tangent from one computation of the quadrature-point kinematics,
//! written once for the triangles and the tetrahedra (`D`, `N`, `E = D·N` as parameters).
//!
//! With the element force `f_e = ∫ Pᵀ∇N + M v̇ + c_d M₁ v − ∫ N b` (node-major,
//! `f_e[a][i]`), the tangents are split by what they multiply in `J = ∂F/∂y + cj ∂F/∂ẏ`:
//!
//! - `K = ∂f_e/∂u` (stiffness of the solid, contact and adhesion),
//! - `C = ∂f_e/∂v` (viscous damping, drag and, with inertia, `cj M` from `M v̇`), where v
//!   is the velocity unknown with inertia and u̇ without,
//! - `B = ∂f_e/∂μ_as` (adhesion, membrane elements).
//!
//! Kernels add into an element vector / [`TangentOf`] in a fixed order (solid, mass,
//! band), the order in which the sums are formed. Per quadrature point:
//!
//! - [`Formulation::solid_residual`] / [`Formulation::solid_tangent`]: `f_aᵢ += w P_iJ
//!   ∂Nₐ/∂X_J`, `K_(ai)(bk) += w ∂Nₐ/∂X_J ∂P_iJ/∂F_kL ∂N_b/∂X_L`, and `C` the same with
//!   `∂P/∂Ḟ`, at (F, Ḟ, F_a) — the kinematic model's part: [`PlaneStrain`] and [`ThreeD`]
//!   here (`solid_residual`, `solid_tangent` over their stress and material point), the
//!   axisymmetric hoop row in [`super::axisym`];
//! - [`mass_residual`] / [`mass_tangent`]: gravity `−g s_g t_g Σ_b M_ab e_y`, inertia
//!   `M v̇` and drag `c_d M₁ v`;
//! - [`band_residual`] / [`band_tangent`]: the body forces of the thin bands near the
//!   substrate at the [`BandPoint`] (F, x, μ_as), `f_aᵢ −= w Nₐ bᵢ` with
//!   `b = b_ct(x, J) + b_as(x, F, μ_as)` ([`band_force`]: contact, plus adhesion on
//!   membrane elements), derivatives by forward-mode dual numbers in (x, F, μ_as);
//! - [`mu_rate_residual`] / [`mu_rate_tangent`]: the nodal adhesion rows
//!   `Ȧ − μ_as0 H_ε(d(x) + e_f)` of the exposure A (μ_as = Φ(A), [`super::history`]).
//!
//! The r weight of the axisymmetric integrals is in the elements' quadrature weights
//! ([`super::element`]), so the mass and band kernels serve it too. The element loops are
//! instantiated once per kinematic model; the hot helpers are `#[inline(always)]` so that
//! each instance inlines them (3 % more instructions on `cases/fast/push-pull-short.ron`
//! when they were not, callgrind).

use nalgebra::{SMatrix, SVector};

use super::ModelParams;
use super::element::{ElementOf, ElementState};
use super::kinematics::{
    NodalOf, PlaneStrain, ThreeD, contract, current_position, deformation, det, rate,
};
use super::plan::TangentOf;
use super::shape::{Seeded, Shape, TabOf};
use crate::dae::{DaeError, ElementPoint, Inadmissible};
use crate::fem::ElementTabulation;
use crate::physics::{
    Fibres, MaterialPointOf, Real, Surface, Viscosity, Yeoh, adhesion_force, adhesion_hoop_factor,
    adhesion_rate, contact_force, cst, material_point, material_point_full, piola_total,
    piola_total_full, re,
};

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

/// The solid's inputs on element `e`: the element, its law and the viscosity, its state
/// and the active-strain ramp `t_a`.
pub(crate) struct Solid<'a, const D: usize, const N: usize> {
    pub(crate) e: usize,
    pub(crate) el: &'a ElementOf<D, N>,
    pub(crate) law: &'a Yeoh,
    pub(crate) visc: &'a Viscosity,
    pub(crate) st: &'a ElementState<D, N>,
    pub(crate) t_a: f64,
    /// The fibre law (MODEL.md §11), where the case has fibres.
    pub(crate) fibres: Option<&'a Fibres>,
}

impl<const D: usize, const N: usize> Solid<'_, D, N> {
    /// Calls `f(q, ∇N, w, point(q))` at each standard point `q` in turn, `point` the
    /// kinematics there (checked admissible).
    #[inline(always)]
    pub(crate) fn each_point<P>(
        &self,
        point: impl Fn(&Self, usize) -> Result<P, DaeError>,
        mut f: impl FnMut(usize, &NodalOf<D, N>, f64, P),
    ) -> Result<(), DaeError> {
        for q in 0..self.el.geo.jxw.len() {
            let pt = point(self, q)?;
            f(q, &self.el.geo.grads[q], self.el.geo.jxw[q], pt);
        }
        Ok(())
    }

    /// `F` (checked admissible), `Ḟ` and `F_a` at standard point `q`.
    #[inline(always)]
    #[allow(clippy::type_complexity)]
    fn point(&self, q: usize) -> Result<[SMatrix<f64, D, D>; 3], DaeError> {
        let g = &self.el.geo.grads[q];
        let f = deformation(&self.st.u, g);
        check_admissible(self.e, q, &f)?;
        Ok([f, rate(&self.st.v, g), self.el.active_fa(q, self.t_a)])
    }
}

/// What a kinematic model changes in the element kernels (MODEL.md §3, §10): the solid's
/// internal force and tangents at the standard points, and `F₃₃` at the band points. The
/// element loops are generic over it, so the choice is made once per loop and each model
/// runs its own code.
pub(crate) trait Formulation<const D: usize, const N: usize, const E: usize> {
    /// The solid's internal force.
    fn solid_residual(s: &Solid<D, N>, fe: &mut NodalOf<D, N>) -> Result<(), DaeError>;

    /// The solid's tangents `K`, `C`.
    fn solid_tangent(s: &Solid<D, N>, tan: &mut TangentOf<E, N>) -> Result<(), DaeError>;

    /// `F₃₃` at a band point with current position `x` and reference position `x_ref`:
    /// `None` where there is none beyond `F` (plane strain: 1; 3-D).
    fn hoop<T: Real>(x: &SVector<T, D>, x_ref: &[f64; D]) -> Option<T>;
}

/// The formulation of a kinematic model whose `F` is the element's `D × D` gradient, with
/// its total first Piola–Kirchhoff stress `$piola` and material point `$point`.
macro_rules! solid_formulation {
    ($kin:ty, $d:literal, $n:literal, $e:literal, $piola:ident, $point:ident) => {
        impl Formulation<$d, $n, $e> for $kin {
            #[inline(always)]
            fn solid_residual(s: &Solid<$d, $n>, fe: &mut NodalOf<$d, $n>) -> Result<(), DaeError> {
                solid_residual(s, fe, |[f, fdot, fa]| $piola(s.law, s.visc, &f, &fdot, &fa))
            }

            #[inline(always)]
            fn solid_tangent(
                s: &Solid<$d, $n>,
                tan: &mut TangentOf<$e, $n>,
            ) -> Result<(), DaeError> {
                solid_tangent(s, tan, |[f, fdot, fa]| {
                    $point(s.law, s.visc, &f, &fdot, &fa)
                })
            }

            #[inline(always)]
            fn hoop<T: Real>(_x: &SVector<T, $d>, _x_ref: &[f64; $d]) -> Option<T> {
                None
            }
        }
    };
}

solid_formulation!(PlaneStrain, 2, 6, 12, piola_total, material_point);
solid_formulation!(ThreeD, 3, 10, 30, piola_total_full, material_point_full);

/// The error of a quantity `quantity` = `value` out of its admissible range at `point`
/// of element `e`.
pub(crate) fn inadmissible(
    e: usize,
    point: ElementPoint,
    quantity: &'static str,
    value: f64,
) -> DaeError {
    DaeError::Inadmissible(Inadmissible::Element {
        t: f64::NAN,
        element: e,
        point,
        quantity,
        value,
    })
}

/// `F` of element `e` at point `q` is admissible: `J = det F > 0` and finite.
#[inline(always)]
pub(crate) fn check_admissible<const D: usize>(
    e: usize,
    q: usize,
    f: &SMatrix<f64, D, D>,
) -> Result<(), DaeError> {
    let j = det(f);
    if j > 0.0 && j.is_finite() {
        Ok(())
    } else {
        Err(inadmissible(e, ElementPoint::Quadrature(q), "det F", j))
    }
}

/// The solid's internal force `f_aᵢ += Σ_q w_q P_iJ ∂Nₐ/∂X_J`, with `P = piola(F, Ḟ, F_a)`
/// the total first Piola–Kirchhoff stress (Yeoh with active strain, plus Kelvin–Voigt
/// viscosity).
#[inline(always)]
fn solid_residual<const D: usize, const N: usize>(
    s: &Solid<D, N>,
    fe: &mut NodalOf<D, N>,
    piola: impl Fn([SMatrix<f64, D, D>; 3]) -> SMatrix<f64, D, D>,
) -> Result<(), DaeError> {
    s.each_point(Solid::point, |q, g, w, pt| {
        let mut p = piola(pt);
        s.el.add_fibres::<1>(s.fibres, q, &pt[0], &pt[2], &mut p, None);
        for a in 0..N {
            for i in 0..D {
                fe[a][i] += w * contract::<D>(|l| p[(i, l)] * g[a][l]);
            }
        }
    })
}

/// The solid's tangents `K_(ai)(bk) += w Σ_JL ∂Nₐ/∂X_J A_(iJ)(kL) ∂N_b/∂X_L` with
/// `A = ∂P/∂F`, and `C` the same with `∂P/∂Ḟ`, from the material point `point(F, Ḟ, F_a)`.
#[inline(always)]
fn solid_tangent<const D: usize, const N: usize, const E: usize, const DD: usize>(
    s: &Solid<D, N>,
    tan: &mut TangentOf<E, N>,
    point: impl Fn([SMatrix<f64, D, D>; 3]) -> MaterialPointOf<D, DD>,
) -> Result<(), DaeError> {
    s.each_point(Solid::point, |q, g, w, pt| {
        let mut mp = point(pt);
        s.el.add_fibres(s.fibres, q, &pt[0], &pt[2], &mut mp.P, Some(&mut mp.dP_dF));
        for a in 0..N {
            for i in 0..D {
                // ak_(kL) = w Σ_J ∂Nₐ/∂X_J A_(iJ)(kL), the same for C (D² of 9 used).
                let mut ak = [0.0; 9];
                let mut ck = [0.0; 9];
                for (col, (akc, ckc)) in ak[..D * D]
                    .iter_mut()
                    .zip(ck[..D * D].iter_mut())
                    .enumerate()
                {
                    *akc = w * contract::<D>(|j| mp.dP_dF[(D * i + j, col)] * g[a][j]);
                    *ckc = w * contract::<D>(|j| mp.dP_dFdot[(D * i + j, col)] * g[a][j]);
                }
                let rr = D * a + i;
                for b in 0..N {
                    for k in 0..D {
                        let cc = D * b + k;
                        tan.k[rr][cc] += contract::<D>(|l| ak[D * k + l] * g[b][l]);
                        tan.c[rr][cc] += contract::<D>(|l| ck[D * k + l] * g[b][l]);
                    }
                }
            }
        }
    })
}

/// Gravity, inertia and drag: `f_a,y += g_now Σ_b M_ab` (body force `−ρ g s_g t_g e_y`
/// integrated, `g_now = g s_g t_g`), `f_aᵢ += Σ_b M_ab v̇_bᵢ` (inertia) and
/// `+= c_d Σ_b M₁_ab v_bᵢ` (drag, `c_d > 0`).
#[inline(always)]
pub(crate) fn mass_residual<const D: usize, const N: usize>(
    el: &ElementOf<D, N>,
    g_now: f64,
    inertia: bool,
    drag: f64,
    st: &ElementState<D, N>,
    fe: &mut NodalOf<D, N>,
) {
    for a in 0..N {
        let ma: f64 = el.mass[a].iter().sum();
        fe[a][1] += ma * g_now;
        for b in 0..N {
            for i in 0..D {
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
pub(crate) fn mass_tangent<const D: usize, const N: usize, const E: usize>(
    el: &ElementOf<D, N>,
    cj: f64,
    inertia: bool,
    drag: f64,
    tan: &mut TangentOf<E, N>,
) {
    for a in 0..N {
        for b in 0..N {
            let m = if inertia { cj * el.mass[a][b] } else { 0.0 } + drag * el.mass1[a][b];
            for i in 0..D {
                tan.c[D * a + i][D * b + i] += m;
            }
        }
    }
}

/// Kinematics at a point of the band rule: `F`, the current position `x` and, where
/// adhesion acts, the interpolated `μ_as = Σₐ Nₐ μₐ`.
pub(crate) struct BandPoint<const D: usize> {
    pub(crate) f: SMatrix<f64, D, D>,
    pub(crate) x: SVector<f64, D>,
    pub(crate) mu: Option<f64>,
}

impl<const D: usize> BandPoint<D> {
    /// At band point `q` of `el` in state `st`; `nv`: the shape functions there; `mue`:
    /// nodal μ_as where adhesion acts.
    #[inline]
    pub(crate) fn at<const N: usize>(
        el: &ElementOf<D, N>,
        nv: &[f64; N],
        q: usize,
        st: &ElementState<D, N>,
        mue: Option<&[f64; N]>,
    ) -> Self {
        let f = deformation(&st.u, &el.cgeo.grads[q]);
        let x = current_position(&el.cgeo.x[q], nv, &st.u);
        let mu = mue.map(|m| (0..N).map(|a| nv[a] * m[a]).sum::<f64>());
        Self { f, x, mu }
    }
}

/// Body force of the bands at a point where the substrate gives `surf = (d(x), n(x))` for
/// the current position `x` ([`Surface::eval`], once per point): contact `b_ct(x, J)` plus,
/// with `mu` (membrane elements while adhesion acts), adhesion `b_as(x, F, μ_as)` along the
/// outward radial reference direction `radial`, ramped by `t_as`. `J` is `det F`; with a
/// hoop stretch `hoop = F₃₃` (axisymmetric) the contact takes `J = F₃₃ det F₂` and the
/// adhesion its factor [`adhesion_hoop_factor`].
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(crate) fn band_force<T: Real, const D: usize>(
    p: &ModelParams,
    surf: (T, SVector<T, D>),
    f: &SMatrix<T, D, D>,
    j: T,
    hoop: Option<T>,
    radial: Option<&SVector<f64, D>>,
    mu: Option<T>,
    t_as: f64,
) -> SVector<T, D> {
    // J₊ = max(J, 0): none where the element's map degenerates between the solid rule's
    // points ([`band_residual`]).
    let j = if re(j) > 0.0 { j } else { cst(0.0) };
    let j = match hoop {
        Some(l) => j * l,
        None => j,
    };
    let mut b = contact_force(&p.contact, surf, j);
    if let (Some(ad), Some(mu), Some(n)) = (&p.adhesion, mu, radial) {
        let fa = adhesion_force(ad, surf, f, n, mu, t_as);
        b += match hoop {
            Some(l) => fa * adhesion_hoop_factor(ad, l),
            None => fa,
        };
    }
    b
}

/// Whether adhesion acts on `el` at `t_as`.
#[inline]
pub(crate) fn adhesion_acts<const D: usize, const N: usize>(
    p: &ModelParams,
    el: &ElementOf<D, N>,
    t_as: f64,
) -> bool {
    el.with_mu && t_as > 0.0 && p.adhesion.is_some()
}

/// Whether the band force is exactly zero where the substrate's penetration depth is `d`,
/// with its derivatives: below the contact band (`d ≤ −ε_ct`, where `H_ε` and its
/// derivatives vanish) and, where adhesion acts (`adhesion`), below the fibronectin layer
/// too (`d + e_f ≤ −ε`). The band rule's points there are skipped (a thick element reaching
/// into the band has most of its points far above it).
#[inline]
fn band_is_zero(p: &ModelParams, d: f64, adhesion: bool) -> bool {
    let below_contact = d <= -p.contact.eps;
    match (&p.adhesion, adhesion) {
        (Some(ad), true) => below_contact && d + ad.e_f <= -ad.eps,
        _ => below_contact,
    }
}

/// The band forces' inputs on element `el`: the tabulation of the band rule, the
/// parameters, the substrate, the element's state, its nodal μ_as `mue` when adhesion acts
/// on it, and the adhesion ramp `t_as`.
pub(crate) struct Band<'a, S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> {
    pub(crate) el: &'a ElementOf<D, N>,
    pub(crate) ctab: &'a TabOf<S, D, N, E>,
    pub(crate) p: &'a ModelParams,
    pub(crate) sub: &'a S::Substrate,
    pub(crate) st: &'a ElementState<D, N>,
    pub(crate) mue: Option<&'a [f64; N]>,
    pub(crate) t_as: f64,
}

impl<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> Band<'_, S, D, N, E> {
    /// [`band_force`] at band point `q`, where the substrate gives `surf`.
    #[inline(always)]
    fn force<T: Real>(
        &self,
        q: usize,
        surf: (T, SVector<T, D>),
        f: &SMatrix<T, D, D>,
        j: T,
        hoop: Option<T>,
        mu: Option<T>,
    ) -> SVector<T, D> {
        let radial = self.el.radial.get(q);
        band_force(self.p, surf, f, j, hoop, radial, mu, self.t_as)
    }
}

/// The band forces `f_aᵢ −= Σ_q w_q Nₐ bᵢ` ([`band_force`]).
#[inline(always)]
pub(crate) fn band_residual<
    S: Shape<D, N, E>,
    K: Formulation<D, N, E>,
    const D: usize,
    const N: usize,
    const E: usize,
>(
    e: usize,
    band: &Band<S, D, N, E>,
    fe: &mut NodalOf<D, N>,
) -> Result<(), DaeError> {
    let (el, p, sub, st, mue) = (band.el, band.p, band.sub, band.st, band.mue);
    let values = band.ctab.values();
    for q in 0..el.cgeo.jxw.len() {
        let nv = &values[q];
        // The substrate at the point, evaluated once (the position is that of `pt` below).
        let mut surf = None;
        if !S::CHECK_EVERY_BAND_POINT {
            let x = current_position(&el.cgeo.x[q], nv, &st.u);
            let s = sub.eval(&x);
            if band_is_zero(p, s.0, mue.is_some()) {
                continue;
            }
            surf = Some(s);
        }
        let pt = BandPoint::at(el, nv, q, st, mue);
        let j = det(&pt.f);
        let hoop = K::hoop(&pt.x, &el.cgeo.x[q]);
        // The solid rule's points keep each element's material admissible (the law has a
        // barrier at J = 0 there, [`check_admissible`]). The band rule's denser points can
        // find a P2 element's map degenerate between them, at the tip of a crease of the
        // membrane: there the contact force, J μ_ct H_ε n per reference volume, is taken
        // at J = 0 ([`band_force`]), where it tends as J does. A point across the axis
        // (hoop stretch ≤ 0) is no such crease: refused.
        if !(j.is_finite() && hoop.is_none_or(|l| l > 0.0)) {
            let j3 = hoop.map_or(j, |l| j * l);
            return Err(inadmissible(e, ElementPoint::Contact(q), "det F", j3));
        }
        let surf = match surf {
            Some(s) => s,
            None => {
                let s = sub.eval(&pt.x);
                if band_is_zero(p, s.0, mue.is_some()) {
                    continue;
                }
                s
            }
        };
        let b = band.force(q, surf, &pt.f, j, hoop, pt.mu);
        let w = el.cgeo.jxw[q];
        for a in 0..N {
            for i in 0..D {
                fe[a][i] -= w * nv[a] * b[i];
            }
        }
    }
    Ok(())
}

/// The band tangents: with `∂b/∂(x, F, μ_as)` by dual numbers at each point (directions:
/// x_k → k, F_kL → D + D k + L, μ_as → D + D²),
/// `K_(ai)(bk) −= w Nₐ (∂bᵢ/∂x_k N_b + Σ_L ∂bᵢ/∂F_kL ∂N_b/∂X_L)` and
/// `B_(ai)b −= w Nₐ ∂bᵢ/∂μ_as N_b` (membrane elements with adhesion).
#[inline(always)]
pub(crate) fn band_tangent<
    S: Shape<D, N, E>,
    K: Formulation<D, N, E>,
    const D: usize,
    const N: usize,
    const E: usize,
>(
    band: &Band<S, D, N, E>,
    tan: &mut TangentOf<E, N>,
) {
    let (el, p, sub, st, mue) = (band.el, band.p, band.sub, band.st, band.mue);
    let with_mu = el.with_mu;
    let values = band.ctab.values();
    let f_dir = |k: usize, l: usize| D + D * k + l;
    let mu_dir = D + D * D;
    for q in 0..el.cgeo.jxw.len() {
        let g = &el.cgeo.grads[q];
        let nv = &values[q];
        let x = current_position(&el.cgeo.x[q], nv, &st.u);
        if band_is_zero(p, sub.eval(&x).0, mue.is_some()) {
            continue;
        }
        let pt = BandPoint::at(el, nv, q, st, mue);
        let xd: SVector<S::BandDual, D> = SVector::from_fn(|k, _| S::BandDual::seeded(pt.x[k], k));
        let fd: SMatrix<S::BandDual, D, D> =
            SMatrix::from_fn(|k, l| S::BandDual::seeded(pt.f[(k, l)], f_dir(k, l)));
        let j = det(&fd);
        let mud = pt.mu.map(|mu| S::BandDual::seeded(mu, mu_dir));
        // F₃₃ = x_r/X_r (axisymmetric) is a function of x: no dual direction of its own.
        let hoop = K::hoop(&xd, &el.cgeo.x[q]);
        let b = band.force(q, sub.eval(&xd), &fd, j, hoop, mud);
        let w = el.cgeo.jxw[q];
        for i in 0..D {
            let db = b[i].gradient();
            for a in 0..N {
                let wa = w * nv[a];
                if wa == 0.0 {
                    continue;
                }
                for bb in 0..N {
                    for k in 0..D {
                        // ∂bᵢ/∂u_(bb,k) = ∂bᵢ/∂x_k N_bb + Σ_L ∂bᵢ/∂F_kL ∂N_bb/∂X_L
                        let mut d = db[k] * nv[bb];
                        for l in 0..D {
                            d += db[f_dir(k, l)] * g[bb][l];
                        }
                        tan.k[D * a + i][D * bb + k] -= wa * d;
                    }
                    if with_mu {
                        tan.b[D * a + i][bb] -= wa * db[mu_dir] * nv[bb];
                    }
                }
            }
        }
    }
}

/// The adhesion row of a membrane node: `Ȧ − a(x)` with the drive `a = r(x, μ_as = 0)`
/// at its current position `x` (the rate of μ_as before the cap).
pub(crate) fn mu_rate_residual<
    S: Shape<D, N, E>,
    const D: usize,
    const N: usize,
    const E: usize,
>(
    p: &ModelParams,
    sub: &S::Substrate,
    x: &SVector<f64, D>,
    a_dot: f64,
) -> f64 {
    match &p.adhesion {
        Some(ad) => a_dot - adhesion_rate(sub, ad, x, 0.0),
        None => 0.0,
    }
}

/// `∂a/∂x` of the drive at a node, by dual numbers, and `∂a/∂A` (0: the drive does not
/// depend on the exposure); the row's entries are `cj − ∂a/∂A` and `−∂a/∂x_k`.
pub(crate) fn mu_rate_tangent<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize>(
    p: &ModelParams,
    sub: &S::Substrate,
    x: &SVector<f64, D>,
) -> ([f64; D], f64) {
    let Some(ad) = &p.adhesion else {
        return ([0.0; D], 0.0);
    };
    let xd: SVector<S::RateDual, D> = SVector::from_fn(|k, _| S::RateDual::seeded(x[k], k));
    let rate = adhesion_rate(sub, ad, &xd, S::RateDual::constant(0.0));
    let d = rate.gradient();
    (std::array::from_fn(|k| d[k]), d[D])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The contact force per reference volume is J μ_ct H_ε n: it tends to zero with J,
    /// and where an element's map degenerates between the solid rule's points (J ≤ 0 at a
    /// band point) it is that limit, zero; the adhesion force does not depend on J.
    #[test]
    fn the_band_force_takes_the_contact_at_j_plus() {
        let p = crate::scene::reference_params();
        let n = SVector::<f64, 2>::new(0.0, 1.0);
        let surf = (0.0, n);
        let f = SMatrix::<f64, 2, 2>::identity();
        let b = |j: f64| band_force::<f64, 2>(&p, surf, &f, j, None, None, None, 0.0);
        let full = contact_force(&p.contact, surf, 1.0);
        assert!(full.y > 0.0);
        assert!((b(1.0) - full).norm() <= 1e-12 * full.norm());
        assert!((b(0.25) - full * 0.25).norm() <= 1e-12 * full.norm());
        assert!((b(1e-9) - full * 1e-9).norm() <= 1e-12 * full.norm());
        for j in [0.0, -1e-12, -0.3] {
            assert_eq!(b(j), SVector::<f64, 2>::zeros(), "J = {j}");
        }
        // With adhesion (μ_as > 0, ramped in) the adhesion part stays.
        let r = SVector::<f64, 2>::new(0.0, -1.0);
        let ba = |j: f64| band_force(&p, surf, &f, j, None, Some(&r), Some(1.0), 1.0);
        let adhesion_only = ba(-0.3);
        assert!(adhesion_only.norm() > 0.0);
        assert!((ba(0.5) - b(0.5) - adhesion_only).norm() <= 1e-9 * adhesion_only.norm());
    }
}
