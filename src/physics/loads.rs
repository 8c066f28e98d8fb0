//! Body forces per unit reference volume (MODEL.md §5): contact, adhesion and gravity, and
//! the rate of the adhesion coefficient. Forces in pN/µm³, positions in µm.
//!
//! Functions of the unknowns (`x`, `F`, `J`, `μ_as`) are generic over [`Real`] for exact
//! tangents, and over the dimension `D` and its substrate ([`Surface`]: the 2-D section
//! [`super::Substrate`], the 3-D [`super::LatticeSubstrate`]); the dimension enters only
//! the cofactor and the determinant. Gravity depends on time only and is `f64`:
//! `−ρ₀ g s_g t_g e_y` in every dimension.

#![allow(non_snake_case)]

use super::smooth::{heaviside, smooth_step};
use super::substrate::Surface;
use super::{PhysicsError, Real, check, cst, re, sqrt};
use crate::tensor::cofactor;
use nalgebra::{SMatrix, SVector, Vector2};
use serde::{Deserialize, Serialize};

/// Penalty contact with the substrate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// Penalty coefficient `μ_ct` [pN/µm³] (MODEL.md: 2e9 N/m³ = 2e3 pN/µm³).
    pub mu_ct: f64,
    /// Half-width `ε_ct` of the contact band \[µm\] (MODEL.md: 0.1).
    pub eps: f64,
    /// Stiffening `κ` beyond the band: for `d > ε` the force is `J μ_ct (1 + κ ξ³) n`,
    /// `ξ = (d − ε)/ε`, C² at `d = ε` (MODEL.md: 0, the paper's force that stays at
    /// `J μ_ct` however deep material sinks).
    pub stiffening: f64,
    /// Whether the cell's outer surface is kept from passing through itself
    /// ([`self_contact_force`]; half-plane models).
    pub self_contact: bool,
}

impl Contact {
    /// Checks `μ_ct ≥ 0`, `ε > 0`, finite.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.mu_ct.is_finite() && self.mu_ct >= 0.0,
            "contact.mu_ct",
            self.mu_ct,
            "must be finite and >= 0",
        )?;
        check(
            self.eps.is_finite() && self.eps > 0.0,
            "contact.eps",
            self.eps,
            "must be finite and > 0",
        )?;
        check(
            self.stiffening.is_finite() && self.stiffening >= 0.0,
            "contact.stiffening",
            self.stiffening,
            "must be finite and >= 0",
        )
    }
}

/// Direction of the adhesive spreading force (the paper's Eq. (26)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum AdhesionDirection {
    /// `cof(F) N` as Eq. (26) writes it (MODEL.md's reading): by Nanson's formula the
    /// current normal of the surface whose reference normal is `N`, scaled by its area
    /// stretch `da/dA`.
    Cofactor,
    /// Its unit vector `cof(F) N / |cof(F) N|`: the current normal alone.
    Unit,
}

/// Adhesive spreading in the fibronectin layer and the maturation of the adhesion
/// coefficient `μ_as`, with the readings of the paper that MODEL.md leaves open
/// (`direction`, `jacobian_factor`, `exclude_substrate`; MODEL.md's defaults are
/// `Cofactor`, `false`, `None`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Adhesion {
    /// Thickness `e_f` of the fibronectin layer over the substrate \[µm\] (MODEL.md: 1.5).
    pub e_f: f64,
    /// Half-width of the layer's Heaviside \[µm\] (MODEL.md does not say; default 0.1,
    /// the contact band's `ε_ct`).
    pub eps: f64,
    /// Maturation rate `μ_as0` [pN/(µm³·s)] (MODEL.md: 1e6 N/(m³·s) = 1 pN/(µm³·s)).
    pub mu_as0: f64,
    /// Cap `μ_as,max` [pN/µm³] (MODEL.md: 1.4e9 N/m³ = 1.4e3 pN/µm³).
    pub mu_as_max: f64,
    /// Direction of the force: `cof(F) N` or its unit vector (Eq. (26); MODEL.md:
    /// `Cofactor`).
    pub direction: AdhesionDirection,
    /// Multiply the force by `J = det F`, the paper's "J f_as" of Eq. (37) (MODEL.md:
    /// no, `b_as` is the force per unit reference volume as Eq. (26) gives it).
    pub jacobian_factor: bool,
    /// `Some(ε)`: the layer indicator excludes the substrate itself, `H_ε_f(d + e_f) −
    /// H_ε(d)`, the paper's "layer obtained by subtracting g_flat" (Sect. 2.2.1, used in
    /// Eqs. (26) and (28)), with `ε` the half-width of the substrate's own indicator (the
    /// contact band's `ε_ct`). `None` (MODEL.md): `H_ε_f(d + e_f)`, substrate included.
    pub exclude_substrate: Option<f64>,
    /// Whether the force lets go of membrane turned over onto the cell, facing away from
    /// the substrate ([`ADHESION_TURN`]): `true` (docs/MODEL.md §5) or the paper's force
    /// on all membrane in the layer, however far it has turned (`false`).
    pub fold_release: bool,
}

/// Which membrane the spreading force pulls, by how far it has turned and which way it
/// faces: the force is multiplied by `1 − (1 − S(c; c₀, c₁)) S(s; s₀, s₁)` with
/// `c = â·N` the cosine between the membrane's current outward normal `â = a/|a|`
/// (`a = cof(F) N`, Nanson) and its reference one `N`, and `s = â·n_sub` the cosine between
/// that normal and the substrate's outward normal at the point ([`ADHESION_AWAY`]).
/// Released: membrane turned by more than 127° (`c ≤ −0.6`) whose normal points away
/// from the substrate (`s ≥ 0.3`); whole: membrane turned by less than 107° (`c ≥ −0.3`),
/// or turned over but facing the substrate (`s ≤ 0`). The paper's force pulls the membrane
/// in the layer outward along its current normal; where the membrane has turned over and
/// faces away from the wall — the inner face of a fold beside a pillar wall, late in the
/// active phase — that normal points into the cell, and the pull drives the fold into the
/// cytoplasm as deep as the layer reaches, deeper the finer the mesh (docs/MODEL.md §5).
/// Membrane that rolls over a narrow pillar's top and down its far face turns as far, but
/// faces the pillar, and keeps the pull that holds it there. Spreading turns no adhered
/// membrane that far: in the paper's scenes `c ≥ −0.17` wherever the force acts.
pub const ADHESION_TURN: [f64; 2] = [-0.6, -0.3];

/// Which turned-over membrane the spreading force lets go of, by the cosine `s` between its
/// outward normal and the substrate's ([`ADHESION_TURN`]): none that faces the substrate
/// (`s ≤ 0`), all that points away from it (`s ≥ 0.3`).
pub const ADHESION_AWAY: [f64; 2] = [0.0, 0.3];

impl Adhesion {
    /// Checks `e_f ≥ 0`, `ε > 0`, `μ_as0 ≥ 0`, `μ_as,max > 0`, finite; when the layer
    /// excludes the substrate, its `ε_s > 0` and `e_f ≥ ε + ε_s`.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.e_f.is_finite() && self.e_f >= 0.0,
            "adhesion.e_f",
            self.e_f,
            "must be finite and >= 0",
        )?;
        check(
            self.eps.is_finite() && self.eps > 0.0,
            "adhesion.eps",
            self.eps,
            "must be finite and > 0",
        )?;
        check(
            self.mu_as0.is_finite() && self.mu_as0 >= 0.0,
            "adhesion.mu_as0",
            self.mu_as0,
            "must be finite and >= 0",
        )?;
        check(
            self.mu_as_max.is_finite() && self.mu_as_max > 0.0,
            "adhesion.mu_as_max",
            self.mu_as_max,
            "must be finite and > 0",
        )?;
        if let Some(eps_s) = self.exclude_substrate {
            check(
                eps_s.is_finite() && eps_s > 0.0,
                "adhesion.exclude_substrate",
                eps_s,
                "must be finite and > 0",
            )?;
            // Where the substrate's indicator is not 0 (d > −ε_s) the layer's must be 1
            // (d + e_f ≥ ε_f), so that the difference lies in [0, 1].
            check(
                self.e_f >= self.eps + eps_s,
                "adhesion.e_f",
                self.e_f,
                "must be >= the layer's and the substrate's half-widths summed when the \
                 layer excludes the substrate (so that the layer indicator stays in [0, 1])",
            )?;
        }
        Ok(())
    }
}

/// Contact force per unit reference volume [pN/µm³] at a current position `x` with
/// `J = det F`: `b_ct = J μ_ct H_ε(d(x)) n(x)`, from the substrate's `(d(x), n(x))`
/// ([`Surface::eval`], evaluated once per point by the caller and shared with the layer).
#[inline(always)]
pub fn contact_force<T: Real, const D: usize>(
    c: &Contact,
    (d, n): (T, SVector<T, D>),
    J: T,
) -> SVector<T, D> {
    let mut h = heaviside(d, c.eps);
    if c.stiffening > 0.0 && re(d) > c.eps {
        let xi = (d - c.eps) / c.eps;
        h += xi * xi * xi * c.stiffening;
    }
    n * (J * h * c.mu_ct)
}

/// How far a point may sit behind a face before the self-contact lets go of it: from
/// `1.5 ε` on the pressure is switched off, fully at `2.5 ε` (0.15 and 0.25 µm with
/// MODEL.md's ε = 0.1 µm). A fold's two faces are pushed apart from `d = −ε` on and never
/// meet that deep; the other side of the cell's outer layer (two membranes and the
/// cytoplasm between, 0.5 µm and more) is never that shallow.
pub const SELF_CONTACT_RELEASE: [f64; 2] = [1.5, 2.5];

/// Which faces may press on a point: those whose outward normal `n` opposes the point's
/// own, `c = −n_p·n` from 0.2 (no pressure) to 0.5 (all of it) — faces turned more than
/// about 100° from the point's, as the two faces of a closing fold are (`c → 1`), where the
/// neighbours round a convex corner of the outline are not (`c ≤ 0` up to a 90° corner).
pub const SELF_CONTACT_FACING: [f64; 2] = [0.2, 0.5];

/// Where along a face its pressure acts: the face's parameter `s` of the point's
/// projection, the weight rising over `[−τ, τ]` and falling over `[1 − τ, 1 + τ]`, so that
/// two faces meeting at a node share a point passing it (`½ + ½`).
pub const SELF_CONTACT_TAPER: f64 = 0.05;

/// The self-contact of the outline of a half-plane cell: the force [pN/µm, per unit
/// thickness in plane strain, per radian with `radius`] on an outline node at `x_p`
/// (its neighbours along the outline `x_prev`, `x_next`) from the straight face
/// `x_a → x_b` of the outline (traversed with the cell on its left, so that its outward
/// normal is `n = (e_y, −e_x)/|e|`, `e = x_b − x_a`), and the reactions on the face's ends.
///
/// With `d = −(x_p − x_a)·n` the depth behind the face and `s = (x_p − x_a)·e/|e|²` the
/// projection's parameter, the pressure is the substrate contact's `μ_ct` integrated over
/// the depth, `p = μ_ct H_ε(d) (d + ε)/2` (C², increasing, `μ_ct ε` at `d = ε`), times the
/// taper in `s` ([`SELF_CONTACT_TAPER`]), the facing switch on `c = −n_p·n` with `n_p` the
/// node's outward normal from its neighbours ([`SELF_CONTACT_FACING`]) and the release in
/// depth ([`SELF_CONTACT_RELEASE`]). The node takes `p ℓ n` with `ℓ = |e|/2` (times its
/// current radius `x_p,0` in the axisymmetric model, work per radian), the face's ends
/// `−(1 − s)` and `−s` of it: the three forces sum to zero. Returns `None` where the
/// pressure is zero (the caller skips the pair), else the forces on
/// `[x_prev, x_p, x_next, x_a, x_b]`.
#[inline]
pub fn self_contact_force<T: Real>(
    c: &Contact,
    [x_prev, x_p, x_next, x_a, x_b]: [Vector2<T>; 5],
    axisymmetric: bool,
) -> Option<[Vector2<T>; 5]> {
    let e = x_b - x_a;
    let l2 = e.norm_squared();
    let rel = x_p - x_a;
    let s = rel.dot(&e) / l2;
    let tau = SELF_CONTACT_TAPER;
    if re(s) <= -tau || re(s) >= 1.0 + tau {
        return None;
    }
    let len = sqrt(l2);
    let n = Vector2::new(e[1], -e[0]) / len;
    let d = -rel.dot(&n);
    let eps = c.eps;
    let [r0, r1] = SELF_CONTACT_RELEASE;
    if re(d) <= -eps || re(d) >= r1 * eps {
        return None;
    }
    let t = x_next - x_prev;
    let np = Vector2::new(t[1], -t[0]) / t.norm();
    let facing = -np.dot(&n);
    let [f0, f1] = SELF_CONTACT_FACING;
    if re(facing) <= f0 {
        return None;
    }
    let taper = smooth_step(s, -tau, tau) * (-smooth_step(s, 1.0 - tau, 1.0 + tau) + 1.0);
    let release = -smooth_step(d, r0 * eps, r1 * eps) + 1.0;
    let pressure = heaviside(d, eps) * (d + eps) * (0.5 * c.mu_ct);
    let mut scale = pressure * taper * smooth_step(facing, f0, f1) * release * len * 0.5;
    if axisymmetric {
        scale *= x_p[0];
    }
    let f = n * scale;
    let zero = Vector2::zeros();
    Some([zero, f, zero, f * (s - 1.0), -(f * s)])
}

/// Fibronectin-layer indicator at a current position `x` \[µm\], from the substrate's
/// penetration depth `d = d(x)`: `H_ε(d + e_f)` ∈ [0, 1], 1 within `e_f − ε` of the
/// substrate and inside it; or, when the layer excludes the substrate
/// (`exclude_substrate = Some(ε_s)`), `H_ε(d + e_f) − H_ε_s(d)`, 0 again inside the
/// substrate.
#[inline(always)]
pub fn layer<T: Real>(ad: &Adhesion, d: T) -> T {
    let h = heaviside(d + ad.e_f, ad.eps);
    match ad.exclude_substrate {
        None => h,
        Some(eps_s) => h - heaviside(d, eps_s),
    }
}

/// Adhesive spreading force per unit reference volume [pN/µm³] (membrane only — the caller
/// applies it there): `b_as = t_as μ_as g_l(x) a(F)`, with `g_l` the [`layer`] indicator
/// from the substrate's penetration depth `d = d(x)` (with `n_sub`, [`Surface::eval`]), `N` the outward radial reference
/// direction `(p − c)/|p − c|`, `μ_as` [pN/µm³] the local adhesion coefficient, `t_as` the
/// adhesion switch and `a(F)` by the readings of `ad`: `cof(F) N` (MODEL.md) or
/// `cof(F) N/|cof(F) N|` ([`AdhesionDirection`]), times `J = det F` when `jacobian_factor`,
/// and with `fold_release` times the release [`ADHESION_TURN`] of membrane turned over and
/// facing away from the substrate, whose outward normal at the point is `n_sub`.
#[inline(always)]
pub fn adhesion_force<T: Real, const D: usize>(
    ad: &Adhesion,
    (d, n_sub): (T, SVector<T, D>),
    F: &SMatrix<T, D, D>,
    N_ref: &SVector<f64, D>,
    mu_as: T,
    t_as: f64,
) -> SVector<T, D> {
    let h = layer(ad, d);
    let N: SVector<T, D> = N_ref.map(cst::<T>);
    let cof = cofactor(F);
    let mut a = cof * N;
    let unit = ad.direction == AdhesionDirection::Unit;
    // |cof(F) N| = J |F⁻ᵀ N| > 0 for an admissible F.
    let len = (ad.fold_release || unit).then(|| {
        let mut len2 = a[0] * a[0];
        for k in 1..D {
            len2 += a[k] * a[k];
        }
        sqrt(len2)
    });
    let mut turn = T::one();
    if let (true, Some(len)) = (ad.fold_release, len) {
        let [c0, c1] = ADHESION_TURN;
        let c = a.dot(&N) / len;
        // Turned less than 107° (nearly all membrane): the whole force, nothing more to
        // evaluate. Turned over and facing away from the substrate: released; turned over
        // and facing it (membrane wrapped over a pillar's far face): kept.
        if re(c) < c1 {
            let away = a.dot(&n_sub) / len;
            let [s0, s1] = ADHESION_AWAY;
            if re(c) <= c0 && re(away) >= s1 {
                return SVector::zeros();
            }
            turn = T::one() - (T::one() - smooth_step(c, c0, c1)) * smooth_step(away, s0, s1);
        }
    }
    if let (true, Some(len)) = (unit, len) {
        a /= len;
    }
    if ad.jacobian_factor {
        a *= if D == 2 {
            F[(0, 0)] * F[(1, 1)] - F[(1, 0)] * F[(0, 1)]
        } else {
            // det F = Σ_j F_0j cof_0j
            F[(0, 0)] * cof[(0, 0)] + F[(0, 1)] * cof[(0, 1)] + F[(0, 2)] * cof[(0, 2)]
        };
    }
    a * (h * turn * mu_as * t_as)
}

/// The factor by which a hoop stretch `λ = F₃₃` (axisymmetric model, MODEL.md §10)
/// multiplies the [`adhesion_force`] computed from the in-plane `F₂`: for
/// `F = F₂ ⊕ λ` and a reference direction `N` in the meridian plane,
/// `cof(F) N = λ cof(F₂) N` (`Cofactor`), while its unit vector is unchanged (`Unit`);
/// `J = λ det F₂` adds another λ with `jacobian_factor`.
pub fn adhesion_hoop_factor<T: Real>(ad: &Adhesion, hoop: T) -> T {
    let from_direction = match ad.direction {
        AdhesionDirection::Cofactor => hoop,
        AdhesionDirection::Unit => T::one(),
    };
    if ad.jacobian_factor {
        from_direction * hoop
    } else {
        from_direction
    }
}

/// Rate of the adhesion coefficient [pN/(µm³·s)]:
/// `μ̇_as = μ_as0 g_l(x) (1 − S(μ_as; 0.98 μ_as,max, μ_as,max))`, `g_l` the [`layer`]
/// indicator (`H_ε(d(x) + e_f)` by default).
pub fn adhesion_rate<T: Real, S: Surface<D>, const D: usize>(
    sub: &S,
    ad: &Adhesion,
    x: &SVector<T, D>,
    mu_as: T,
) -> T {
    let h = layer(ad, sub.eval(x).0);
    let cap = smooth_step(mu_as, 0.98 * ad.mu_as_max, ad.mu_as_max);
    h * (-cap + 1.0) * ad.mu_as0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::{LatticeSubstrate, Substrate, reference};
    use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
    use num_dual::DualSVec64;

    fn substrates() -> [Substrate; 2] {
        [
            Substrate::Flat { y_s: -2.0 },
            Substrate::Pillars(crate::physics::reference::pillars()),
        ]
    }

    /// Gradient part of a dual number with N variables.
    fn eps<const N: usize>(v: &DualSVec64<N>) -> nalgebra::SVector<f64, N> {
        v.eps.unwrap_generic(nalgebra::Const::<N>, nalgebra::U1)
    }

    #[test]
    fn contact_is_zero_outside_and_full_inside() {
        let c = crate::physics::reference::contact();
        let s = Substrate::Flat { y_s: -2.0 };
        let J = 1.3;
        // above the band (d < −ε)
        assert_eq!(
            contact_force(&c, s.eval(&Vector2::new(0.0, -1.85)), J),
            Vector2::zeros()
        );
        // deep inside (d > ε)
        let f = contact_force(&c, s.eval(&Vector2::new(0.0, -2.2)), J);
        assert_eq!(f, Vector2::new(0.0, J * c.mu_ct));
        // on the surface: half
        let f = contact_force(&c, s.eval(&Vector2::new(0.0, -2.0)), J);
        assert!((f.y - 0.5 * J * c.mu_ct).abs() < 1e-12);
        // pillars: on a side, deep inside → along the outward side normal
        let p = Substrate::Pillars(crate::physics::reference::pillars());
        let mid = crate::physics::reference::pillars().y_top - 4.0; // mid-height of the pillars
        let f = contact_force(&c, p.eval(&Vector2::new(11.7, mid)), 1.0);
        assert!((f - Vector2::new(c.mu_ct, 0.0)).norm() < 1e-9, "f = {f}");
        let f = contact_force(&c, p.eval(&Vector2::new(12.2, mid)), 1.0);
        assert_eq!(f, Vector2::zeros());
    }

    #[test]
    fn stiffening_beyond_the_band_follows_its_cubic() {
        let c0 = crate::physics::reference::contact();
        let c = Contact {
            stiffening: 2.0,
            ..c0
        };
        let s = Substrate::Flat { y_s: -2.0 };
        // Within the band the paper's force, unchanged to the bit.
        for y in [-1.95, -2.0, -2.05, -2.1] {
            let at = s.eval(&Vector2::new(0.3, y));
            assert_eq!(contact_force(&c, at, 1.1), contact_force(&c0, at, 1.1));
        }
        // At depth 0.3 = ε + 2ε: ξ = 2, 1 + κ ξ³ = 17.
        let f = contact_force(&c, s.eval(&Vector2::new(0.3, -2.3)), 1.1);
        assert!(
            (f.y - 17.0 * 1.1 * c.mu_ct).abs() < 1e-9 * c.mu_ct,
            "f = {f}"
        );
    }

    #[test]
    fn contact_force_derivatives_match_finite_differences() {
        type D = DualSVec64<3>;
        let c0 = crate::physics::reference::contact();
        let h = 1e-7;
        let stiffened = Contact {
            stiffening: 2.0,
            ..c0
        };
        for (s, c) in substrates()
            .into_iter()
            .flat_map(|s| [(s, c0), (s, stiffened)])
        {
            // points inside the contact band of the flat surface and of the pillars, and
            // beyond it (depths 0.15 and 0.3 on the flat surface)
            for (x, y, J) in [
                (0.0, -1.97, 1.1),
                (1.0, -2.04, 0.8),
                (5.0, -0.68, 1.0),
                (11.96, -3.0, 1.2),
                (8.0, -0.33, 0.9),
                (0.0, -2.15, 1.0),
                (2.0, -2.3, 0.9),
            ] {
                let xd = Vector2::new(D::from_re(x).derivative(0), D::from_re(y).derivative(1));
                let Jd = D::from_re(J).derivative(2);
                let f = contact_force(&c, s.eval(&xd), Jd);
                let base = [x, y, J];
                for k in 0..3 {
                    let mut p = base;
                    let mut m = base;
                    p[k] += h;
                    m[k] -= h;
                    let fp = contact_force(&c, s.eval(&Vector2::new(p[0], p[1])), p[2]);
                    let fm = contact_force(&c, s.eval(&Vector2::new(m[0], m[1])), m[2]);
                    let fd = (fp - fm) / (2.0 * h);
                    // Relative to μ_ct/ε, or to the derivative itself where the stiffened
                    // force is many times μ_ct (deep points).
                    let tol = |d: f64| 1e-6 * (c.mu_ct / c.eps).max(d.abs());
                    let (dx, dy) = (eps(&f.x)[k], eps(&f.y)[k]);
                    assert!((fd.x - dx).abs() < tol(dx), "{s:?} ({x},{y}) k={k}");
                    assert!(
                        (fd.y - dy).abs() < tol(dy),
                        "{s:?} ({x},{y}) k={k}: fd {} dual {dy}",
                        fd.y
                    );
                }
            }
        }
    }

    /// MODEL.md's adhesion, the paper's force on turned-over membrane too, and each
    /// reading of the paper it leaves open, alone and all together.
    fn adhesion_readings() -> Vec<Adhesion> {
        let d = crate::physics::reference::adhesion();
        let eps_ct = crate::physics::reference::contact().eps;
        vec![
            d,
            Adhesion {
                fold_release: false,
                ..d
            },
            Adhesion {
                direction: AdhesionDirection::Unit,
                ..d
            },
            Adhesion {
                jacobian_factor: true,
                ..d
            },
            Adhesion {
                exclude_substrate: Some(eps_ct),
                ..d
            },
            Adhesion {
                direction: AdhesionDirection::Unit,
                jacobian_factor: true,
                exclude_substrate: Some(eps_ct),
                ..d
            },
        ]
    }

    #[test]
    fn adhesion_force_and_rate_derivatives_match_finite_differences() {
        // variables: x (2), F (4), μ_as (1)
        let h = 1e-6;
        let F0 = Matrix2::new(1.1, 0.2, -0.3, 0.9);
        let y_top = crate::physics::reference::pillars().y_top;
        // F0 turns the normal N by −20° (c = 0.94: the release's switch at 1); rotated by
        // 135° after it, by 115° (c = −0.42, inside the switch's transition)
        let N = Vector2::new(0.6, -0.8);
        let turned = nalgebra::Rotation2::new(135.0_f64.to_radians()).into_inner() * F0;
        // rotated by 244.5° after it, turned over (c = −0.72) and pointing away from a
        // floor or a pillar top by s = 0.15 (inside the facing switch's transition)
        let away = nalgebra::Rotation2::new(244.5_f64.to_radians()).into_inner() * F0;
        for (ad, s, F) in adhesion_readings().into_iter().flat_map(|ad| {
            substrates()
                .into_iter()
                .flat_map(move |s| [F0, turned, away].map(|F| (ad, s, F)))
        }) {
            // in the layer's transition (d + e_f ∈ (−ε, ε)), the cap's transition and
            // the substrate's own transition (d ∈ (−ε, ε), flat and pillar top)
            for (x, y, mu) in [
                (0.0, -0.45, 700.0),
                (2.0, -0.52, 1380.0),
                (8.3, 1.22, 1390.0),
                (13.5, -3.0, 10.0),
                (1.0, -1.96, 900.0),
                (3.0, -2.05, 400.0),
                (8.5, y_top + 0.03, 1200.0),
            ] {
                let v = [x, y, F[(0, 0)], F[(0, 1)], F[(1, 0)], F[(1, 1)], mu];
                check_adhesion_derivatives(&s, &ad, &N, v, h);
            }
        }
    }

    /// The adhesion force's and rate's dual derivatives along x, F and μ_as against central
    /// differences at `v` = (x, F row by row, μ_as) on `s` (`M = D + D² + 1`), t_as = 0.7.
    fn check_adhesion_derivatives<S, const D: usize, const M: usize>(
        s: &S,
        ad: &Adhesion,
        n: &SVector<f64, D>,
        v: [f64; M],
        h: f64,
    ) where
        S: Surface<D> + std::fmt::Debug,
    {
        let dual = |i: usize| DualSVec64::<M>::from_re(v[i]).derivative(i);
        let xd = SVector::from_fn(|i, _| dual(i));
        let fd = SMatrix::from_fn(|i, j| dual(D + D * i + j));
        let f = adhesion_force(ad, s.eval(&xd), &fd, n, dual(M - 1), 0.7);
        let r = adhesion_rate(s, ad, &xd, dual(M - 1));
        let eval = |w: &[f64; M]| {
            let x = SVector::from_fn(|i, _| w[i]);
            let F = SMatrix::from_fn(|i, j| w[D + D * i + j]);
            let force = adhesion_force(ad, s.eval(&x), &F, n, w[M - 1], 0.7);
            (force, adhesion_rate(s, ad, &x, w[M - 1]))
        };
        let fscale = v[M - 1].max(1.0) / ad.eps;
        let rscale = ad.mu_as0 / ad.eps.min(0.02 * ad.mu_as_max);
        for k in 0..M {
            let step = if k == M - 1 { 1e-3 } else { h };
            let (mut p, mut m) = (v, v);
            p[k] += step;
            m[k] -= step;
            let ((fp, rp), (fm, rm)) = (eval(&p), eval(&m));
            let (dfd, rd) = ((fp - fm) / (2.0 * step), (rp - rm) / (2.0 * step));
            for c in 0..D {
                let e = (dfd[c] - eps(&f[c])[k]).abs();
                assert!(e < 1e-6 * fscale, "{ad:?} {s:?} f_{c} k={k} at {v:?}");
            }
            let e = (rd - eps(&r)[k]).abs();
            assert!(e < 1e-6 * rscale, "{ad:?} {s:?} rate k={k} at {v:?}");
        }
    }

    #[test]
    fn adhesion_values() {
        let ad = crate::physics::reference::adhesion();
        let s = Substrate::Flat { y_s: -2.0 };
        let F = Matrix2::new(1.2, 0.1, 0.0, 0.8);
        let N = Vector2::new(0.0, -1.0);
        // inside the layer (d + e_f > ε): full force t_as μ cof(F) N; cof(F) = J F⁻ᵀ
        let X = Vector2::new(0.0, -1.0);
        let f = adhesion_force(&ad, s.eval(&X), &F, &N, 100.0, 0.5);
        let cof = F.try_inverse().unwrap().transpose() * F.determinant();
        assert!((f - cof * N * 50.0).norm() < 1e-12);
        // outside the layer: none
        let X = Vector2::new(0.0, -0.3);
        assert_eq!(
            adhesion_force(&ad, s.eval(&X), &F, &N, 100.0, 0.5),
            Vector2::zeros()
        );
        assert_eq!(adhesion_rate(&s, &ad, &X, 0.0), 0.0);
        // the rate is μ_as0 below the cap, 0 at the cap
        let X = Vector2::new(0.0, -1.0);
        assert_eq!(adhesion_rate(&s, &ad, &X, 0.0), ad.mu_as0);
        assert_eq!(adhesion_rate(&s, &ad, &X, 0.97 * ad.mu_as_max), ad.mu_as0);
        assert_eq!(adhesion_rate(&s, &ad, &X, ad.mu_as_max), 0.0);
        assert!((adhesion_rate(&s, &ad, &X, 0.99 * ad.mu_as_max) - 0.5 * ad.mu_as0).abs() < 1e-12);
        // layer indicator is ½ at distance e_f from the surface
        assert!((layer(&ad, s.eval(&Vector2::new(3.0_f64, -0.5)).0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn adhesion_readings_change_the_force_as_the_paper_reads() {
        let d = crate::physics::reference::adhesion();
        let eps_ct = crate::physics::reference::contact().eps;
        let s = Substrate::Flat { y_s: -2.0 };
        let F = Matrix2::new(1.2, 0.1, 0.0, 0.8);
        let J = F.determinant();
        let N = Vector2::new(0.6, -0.8);
        let X = Vector2::new(0.0_f64, -1.0); // inside the layer, above the substrate's band
        let cof_n = F.try_inverse().unwrap().transpose() * N * J;
        let f0 = adhesion_force(&d, s.eval(&X), &F, &N, 100.0, 0.5);
        assert!((f0 - cof_n * 50.0).norm() < 1e-12);
        // Unit: the same direction, length t_as μ_as.
        let unit = Adhesion {
            direction: AdhesionDirection::Unit,
            ..d
        };
        let f = adhesion_force(&unit, s.eval(&X), &F, &N, 100.0, 0.5);
        assert!((f - cof_n / cof_n.norm() * 50.0).norm() < 1e-12);
        assert!((f.norm() - 50.0).abs() < 1e-12);
        // J f_as: J times the default.
        let with_j = Adhesion {
            jacobian_factor: true,
            ..d
        };
        let f = adhesion_force(&with_j, s.eval(&X), &F, &N, 100.0, 0.5);
        assert!((f - f0 * J).norm() < 1e-12);
        // Excluding the substrate: the same above its band, ½ less on its surface, nothing
        // inside it (where the default layer is 1).
        let excl = Adhesion {
            exclude_substrate: Some(eps_ct),
            ..d
        };
        assert_eq!(layer(&excl, s.eval(&X).0), layer(&d, s.eval(&X).0));
        let on = Vector2::new(0.0_f64, -2.0);
        assert_eq!(layer(&d, s.eval(&on).0), 1.0);
        assert!((layer(&excl, s.eval(&on).0) - 0.5).abs() < 1e-15);
        let inside = Vector2::new(0.0_f64, -2.5);
        assert_eq!(layer(&d, s.eval(&inside).0), 1.0);
        assert_eq!(layer(&excl, s.eval(&inside).0), 0.0);
        assert_eq!(adhesion_rate(&s, &excl, &inside, 0.0), 0.0);
        assert_eq!(adhesion_rate(&s, &d, &inside, 0.0), d.mu_as0);
        // The layer indicator stays in [0, 1] across both bands.
        for k in 0..=400 {
            let x = Vector2::new(0.0, -2.6 + 1.2 * k as f64 / 400.0);
            let g = layer(&excl, s.eval(&x).0);
            assert!((0.0..=1.0).contains(&g), "y = {}: {g}", x.y);
        }
    }

    #[test]
    fn adhesion_lets_go_of_membrane_turned_over() {
        let d = crate::physics::reference::adhesion();
        assert!(d.fold_release, "MODEL.md's default");
        let paper = Adhesion {
            fold_release: false,
            ..d
        };
        let s = Substrate::Flat { y_s: -2.0 };
        let X = Vector2::new(0.0_f64, -1.0); // in the layer
        let N = Vector2::new(0.6, -0.8);
        // F a rotation by φ after a stretch along y (which turns the normal too)
        let force = |ad: &Adhesion, phi: f64, stretch: f64| {
            let r = nalgebra::Rotation2::new(phi.to_radians()).into_inner();
            let F = r * Matrix2::new(1.0, 0.0, 0.0, stretch);
            adhesion_force(ad, s.eval(&X), &F, &N, 100.0, 0.5)
        };
        // Turned up to 107° (c ≥ −0.3): the paper's force, to the bit.
        for phi in [0.0, 45.0, -90.0, 105.0] {
            assert_eq!(force(&d, phi, 1.0), force(&paper, phi, 1.0), "φ = {phi}°");
            assert!(force(&d, phi, 1.0).norm() > 0.0);
        }
        // Beyond 127° (c ≤ −0.6): none, where the paper's pulls the membrane back along
        // its turned normal.
        for phi in [130.0, 180.0, -150.0] {
            assert_eq!(force(&d, phi, 1.0), Vector2::zeros(), "φ = {phi}°");
            assert!(force(&paper, phi, 1.0).norm() > 0.0);
        }
        // In between, the C² switch S(c; −0.6, −0.3): ½ at c = −0.45 (φ = 116.7°).
        let phi = (-0.45_f64).acos().to_degrees();
        let ratio = force(&d, phi, 1.0).norm() / force(&paper, phi, 1.0).norm();
        assert!((ratio - 0.5).abs() < 1e-12, "{ratio}");
        // The cosine is the normal's, cof(F) N, not F N: stretched 3× along y, N turns by
        // 29° more than F's rotation, here 129° in all.
        assert_eq!(force(&d, 100.0, 3.0), Vector2::zeros());
        assert!(force(&paper, 100.0, 3.0).norm() > 0.0);
        // Turned over but facing the substrate (as membrane rolled down a pillar's far
        // face): the paper's force, to the bit. N points up and out; turned by 180° it
        // points down onto the floor (s = −0.8), by 150° down and out (s = −0.39).
        let up = Vector2::new(0.6, 0.8);
        let facing = |ad: &Adhesion, phi: f64| {
            let r = nalgebra::Rotation2::new(phi.to_radians()).into_inner();
            adhesion_force(ad, s.eval(&X), &r, &up, 100.0, 0.5)
        };
        for phi in [180.0, 150.0] {
            assert_eq!(facing(&d, phi), facing(&paper, phi), "φ = {phi}°");
            assert!(facing(&d, phi).norm() > 0.0);
        }
        // Turned over (c = −1) and pointing away from the floor by s = 0.15, in the middle
        // of S(s; 0, 0.3): N = (0.99, −0.15) turned by 180° points along (−0.99, 0.15),
        // and keeps half the force.
        let side = Vector2::new((1.0_f64 - 0.15 * 0.15).sqrt(), -0.15);
        let r = nalgebra::Rotation2::new(std::f64::consts::PI).into_inner();
        let half = adhesion_force(&d, s.eval(&X), &r, &side, 100.0, 0.5).norm()
            / adhesion_force(&paper, s.eval(&X), &r, &side, 100.0, 0.5).norm();
        assert!((half - 0.5).abs() < 1e-12, "{half}");
    }

    #[test]
    fn adhesion_hoop_factor_matches_the_3d_cofactor() {
        // For F = F₂ ⊕ λ (3 × 3) and N in the meridian plane, the 3-D reading of each
        // option, with cof(F) = det(F) F⁻ᵀ of the 3 × 3 matrix, against the 2-D force
        // times adhesion_hoop_factor.
        let base = crate::physics::reference::adhesion();
        let s = Substrate::Flat { y_s: -2.0 };
        let F = Matrix2::new(1.2, 0.1, -0.2, 0.8);
        let lambda = 1.35;
        let F3 = crate::physics::three_d::tests::embed(&F, lambda);
        let J3 = F3.determinant();
        let N = Vector2::new(0.6, -0.8);
        let N3 = nalgebra::Vector3::new(N.x, N.y, 0.0);
        let X = Vector2::new(0.0_f64, -1.0);
        let cof_n = F3.try_inverse().unwrap().transpose() * N3 * J3;
        assert_eq!(cof_n.z, 0.0);
        for direction in [AdhesionDirection::Cofactor, AdhesionDirection::Unit] {
            for jacobian_factor in [false, true] {
                let ad = Adhesion {
                    direction,
                    jacobian_factor,
                    ..base
                };
                let mut a = match direction {
                    AdhesionDirection::Cofactor => cof_n,
                    AdhesionDirection::Unit => cof_n / cof_n.norm(),
                };
                if jacobian_factor {
                    a *= J3;
                }
                let exact = Vector2::new(a.x, a.y) * (100.0 * 0.5);
                let f = adhesion_force(&ad, s.eval(&X), &F, &N, 100.0, 0.5)
                    * adhesion_hoop_factor(&ad, lambda);
                assert!(
                    (f - exact).norm() < 1e-12 * exact.norm(),
                    "{direction:?}, J {jacobian_factor}: {f} against {exact}"
                );
            }
        }
    }

    #[test]
    fn parameter_validation() {
        let (contact, adhesion) = (reference::contact(), reference::adhesion());
        assert!(contact.validate().is_ok() && adhesion.validate().is_ok());
        let eps = 0.0;
        assert!(Contact { eps, ..contact }.validate().is_err());
        let mu_as_max = 0.0;
        assert!(
            Adhesion {
                mu_as_max,
                ..adhesion
            }
            .validate()
            .is_err()
        );
        let e_f = f64::NAN;
        assert!(Adhesion { e_f, ..adhesion }.validate().is_err());
        // Excluding the substrate needs a positive half-width and a layer wider than
        // both bands.
        let excl = Adhesion {
            exclude_substrate: Some(0.1),
            ..adhesion
        };
        assert!(excl.validate().is_ok());
        for (e_f, eps_s) in [(1.5, 0.0), (1.5, f64::NAN), (0.15, 0.1)] {
            let bad = Adhesion {
                e_f,
                exclude_substrate: Some(eps_s),
                ..excl
            };
            assert!(bad.validate().is_err(), "e_f {e_f}, ε_s {eps_s}");
        }
    }

    // ---- 3-D twins --------------------------------------------------------------------

    /// The 3-D substrates paired with the 2-D one they reduce to on the plane `z = z₀`:
    /// flat; the pillars on the gap lattice at z₀ = 0 and on the four-pillar one at
    /// z₀ = P/2 (planes through a row of pillar axes).
    fn lattice_substrates() -> Vec<(LatticeSubstrate, Substrate, f64)> {
        use crate::physics::Lattice;
        let p = crate::physics::reference::pillars();
        let flat = Substrate::Flat { y_s: -2.0 };
        let pil = Substrate::Pillars(p);
        vec![
            (
                LatticeSubstrate {
                    plane: flat,
                    lattice: Lattice::FourPillars,
                },
                flat,
                0.0,
            ),
            (
                LatticeSubstrate {
                    plane: pil,
                    lattice: Lattice::Gap,
                },
                pil,
                0.0,
            ),
            (
                LatticeSubstrate {
                    plane: pil,
                    lattice: Lattice::FourPillars,
                },
                pil,
                0.5 * p.period(),
            ),
        ]
    }

    fn embed(F: &Matrix2<f64>) -> Matrix3<f64> {
        crate::physics::three_d::tests::embed(F, 1.0)
    }

    #[test]
    fn loads3_reduce_to_the_2d_ones_in_a_plane_through_the_axes() {
        // In the plane z = z₀ with F = F₂ ⊕ 1 and N in the plane: contact, layer,
        // adhesion force (every reading) and rate are the 2-D ones with a zero z entry.
        let c = crate::physics::reference::contact();
        let mut rng = crate::physics::plane_strain::tests::Rng::new(97);
        let y_top = crate::physics::reference::pillars().y_top;
        for (s3, s2, z0) in lattice_substrates() {
            for ad in adhesion_readings() {
                for _ in 0..100 {
                    // points across the contact and layer bands of the flat surface and
                    // the pillars
                    let x = rng.uniform(-20.0, 20.0);
                    let y = if rng.uniform(0.0, 1.0) < 0.5 {
                        rng.uniform(-2.6, 0.2)
                    } else {
                        y_top + rng.uniform(-5.0, 2.0)
                    };
                    let (X2, X3) = (Vector2::new(x, y), Vector3::new(x, y, z0));
                    let J = rng.uniform(0.7, 1.3);
                    let f2 = contact_force(&c, s2.eval(&X2), J);
                    let f3 = contact_force(&c, s3.eval(&X3), J);
                    assert_eq!(f3, Vector3::new(f2.x, f2.y, 0.0), "{s3:?} ({x}, {y})");
                    assert_eq!(layer(&ad, s3.eval(&X3).0), layer(&ad, s2.eval(&X2).0));
                    let F2 = crate::physics::plane_strain::tests::Rng::deformation(&mut rng, 0.4);
                    let phi = rng.uniform(-3.0, 3.0);
                    let N2 = Vector2::new(phi.cos(), phi.sin());
                    let N3 = Vector3::new(N2.x, N2.y, 0.0);
                    let mu = rng.uniform(0.0, 1400.0);
                    let a2 = adhesion_force(&ad, s2.eval(&X2), &F2, &N2, mu, 0.7);
                    let a3 = adhesion_force(&ad, s3.eval(&X3), &embed(&F2), &N3, mu, 0.7);
                    let scale = mu * (1.0 + F2.norm()).powi(2);
                    assert!(
                        (a3 - Vector3::new(a2.x, a2.y, 0.0)).norm() <= 1e-14 * scale,
                        "{ad:?} {s3:?}: {a3} vs {a2}"
                    );
                    assert_eq!(
                        adhesion_rate(&s3, &ad, &X3, mu),
                        adhesion_rate(&s2, &ad, &X2, mu)
                    );
                }
            }
        }
    }

    #[test]
    fn cofactor3_is_det_f_times_the_inverse_transpose() {
        let mut rng = crate::physics::plane_strain::tests::Rng::new(101);
        for _ in 0..20 {
            let F = Matrix3::identity() + Matrix3::from_fn(|_, _| rng.uniform(-0.8, 0.8));
            let J = F.determinant();
            if J.abs() < 1e-3 {
                continue;
            }
            let exact = F.try_inverse().unwrap().transpose() * J;
            assert!((cofactor(&F) - exact).norm() < 1e-14 * (1.0 + exact.norm()));
        }
        // its plane-strain block is the 2-D cofactor
        let F2 = Matrix2::new(1.2, 0.1, -0.3, 0.8);
        let c3 = cofactor(&embed(&F2));
        assert_eq!(c3.fixed_view::<2, 2>(0, 0), cofactor(&F2));
        assert_eq!(c3[(2, 2)], F2.determinant());
    }

    #[test]
    fn contact3_pushes_along_the_substrate_normal() {
        use crate::physics::Lattice;
        let c = crate::physics::reference::contact();
        let p = crate::physics::reference::pillars();
        let s = LatticeSubstrate {
            plane: Substrate::Pillars(p),
            lattice: Lattice::FourPillars,
        };
        let mid = p.y_top - 4.0;
        // inside the z side face of the pillar at (8, 8), deep in the band: μ_ct e_z
        let f = contact_force(&c, s.eval(&Vector3::new(8.0, mid, 11.7)), 1.0);
        assert!(
            (f - Vector3::new(0.0, 0.0, c.mu_ct)).norm() < 1e-9,
            "f = {f}"
        );
        // and nothing 0.2 µm outside it
        let f = contact_force(&c, s.eval(&Vector3::new(8.0, mid, 12.2)), 1.0);
        assert_eq!(f, Vector3::zeros());
    }

    #[test]
    fn loads3_derivatives_match_finite_differences() {
        use crate::physics::Lattice;
        // variables: x (3), F (9), μ_as (1); contact: x and J
        type D4 = DualSVec64<4>;
        let h = 1e-6;
        let c = crate::physics::reference::contact();
        let p = crate::physics::reference::pillars();
        let y_top = p.y_top;
        let F0 = Matrix3::new(1.1, 0.2, -0.1, -0.3, 0.9, 0.15, 0.05, -0.2, 1.05);
        let N = Vector3::new(0.6, -0.64, 0.48);
        let subs = [
            LatticeSubstrate {
                plane: Substrate::Flat { y_s: -2.0 },
                lattice: Lattice::FourPillars,
            },
            LatticeSubstrate {
                plane: Substrate::Pillars(p),
                lattice: Lattice::FourPillars,
            },
            LatticeSubstrate {
                plane: Substrate::Pillars(p),
                lattice: Lattice::Gap,
            },
        ];
        // in the contact band, the layer's transition and the cap's transition, over the
        // flat surface and the tops, edges and sides of a pillar of each lattice
        let pts = [
            (0.0, -1.97, 1.0, 700.0),
            (1.0, -2.04, -2.0, 1380.0),
            (2.0, -0.52, 3.0, 1390.0),
            (8.2, y_top + 0.03, 7.7, 1200.0),
            (8.3, 1.22, 8.4, 900.0),
            (11.96, y_top - 3.0, 8.5, 10.0),
            (8.4, y_top - 3.0, 11.93, 400.0),
            (5.0, y_top - 0.4, 0.5, 800.0),
            (11.5, y_top - 0.2, 11.2, 1000.0),
        ];
        for s in &subs {
            for ad in adhesion_readings() {
                for &(x, y, z, mu) in &pts {
                    let mut v = [0.0; 13];
                    v[..3].copy_from_slice(&[x, y, z]);
                    for k in 0..9 {
                        v[3 + k] = F0[(k / 3, k % 3)];
                    }
                    v[12] = mu;
                    check_adhesion_derivatives(s, &ad, &N, v, h);
                }
            }
            // contact: x and J
            for &(x, y, z, _) in &pts {
                let J = 1.1;
                let xd = Vector3::new(
                    D4::from_re(x).derivative(0),
                    D4::from_re(y).derivative(1),
                    D4::from_re(z).derivative(2),
                );
                let f = contact_force(&c, s.eval(&xd), D4::from_re(J).derivative(3));
                let base = [x, y, z, J];
                for k in 0..4 {
                    let (mut pp, mut mm) = (base, base);
                    pp[k] += 1e-7;
                    mm[k] -= 1e-7;
                    let fp = contact_force(&c, s.eval(&Vector3::new(pp[0], pp[1], pp[2])), pp[3]);
                    let fm = contact_force(&c, s.eval(&Vector3::new(mm[0], mm[1], mm[2])), mm[3]);
                    let fd = (fp - fm) / 2e-7;
                    let scale = c.mu_ct / c.eps;
                    for cpt in 0..3 {
                        assert!(
                            (fd[cpt] - eps(&f[cpt])[k]).abs() < 1e-6 * scale,
                            "{s:?} contact f_{cpt} k={k} at ({x}, {y}, {z})"
                        );
                    }
                }
            }
        }
    }

    /// Two faces of a fold: the face from (0.3, 0) to (−0.3, 0), whose outward normal is
    /// (0, 1), and the node at (`along`, −`depth`) with its neighbours 0.2 µm either side
    /// along the direction turned by `tilt` from +x, so that its own outward normal is
    /// (sin tilt, −cos tilt): opposite the face's for `tilt = 0`.
    fn fold(depth: f64, along: f64, tilt: f64) -> [Vector2<f64>; 5] {
        let (c, s) = (tilt.cos(), tilt.sin());
        let p = Vector2::new(along, -depth);
        let t = Vector2::new(0.2 * c, 0.2 * s);
        [
            p - t,
            p,
            p + t,
            Vector2::new(0.3, 0.0),
            Vector2::new(-0.3, 0.0),
        ]
    }

    #[test]
    fn self_contact_pushes_the_faces_of_a_fold_apart_and_balances() {
        let c = reference::contact();
        // At d = ε (taper, facing and release all 1): p = μ_ct ε, on ℓ = |e|/2 = 0.3 µm.
        let f = self_contact_force(&c, fold(c.eps, 0.1, 0.0), false).expect("in contact");
        let expect = c.mu_ct * c.eps * 0.3;
        assert!(
            (f[1] - Vector2::new(0.0, expect)).norm() < 1e-9 * expect,
            "{:?}",
            f[1]
        );
        // The node is pushed out along the face's normal; the face's ends take the
        // reaction in proportion to the projection (s = (0.3 − 0.1)/0.6 from x_a).
        let s = (0.3 - 0.1) / 0.6;
        assert!((f[3] + f[1] * (1.0 - s)).norm() < 1e-9 * expect);
        assert!((f[4] + f[1] * s).norm() < 1e-9 * expect);
        let sum: Vector2<f64> = f.iter().sum();
        assert!(sum.norm() < 1e-9 * expect, "forces sum to {sum}");
        // Axisymmetric: per radian, times the node's current radius.
        let mut at = fold(c.eps, 0.1, 0.0);
        for x in at.iter_mut() {
            x.x += 5.0;
        }
        let fa = self_contact_force(&c, at, true).unwrap();
        assert!((fa[1].y - 5.1 * expect).abs() < 1e-9 * expect);
        // Nothing where the node is in front of the face by ε or more, behind it beyond
        // the release, beyond the face's ends, or where the faces do not oppose (a convex
        // corner's neighbours: the node's normal turned by 90° or more from the face's).
        assert!(self_contact_force(&c, fold(-c.eps, 0.1, 0.0), false).is_none());
        assert!(self_contact_force(&c, fold(2.6 * c.eps, 0.1, 0.0), false).is_none());
        assert!(self_contact_force(&c, fold(0.05, 0.35, 0.0), false).is_none());
        assert!(self_contact_force(&c, fold(0.05, 0.1, 1.6), false).is_none());
        // And it grows with the depth.
        let depth = |d: f64| self_contact_force(&c, fold(d, 0.1, 0.0), false).unwrap()[1].y;
        assert!(depth(-0.05) < depth(0.0) && depth(0.0) < depth(0.05) && depth(0.05) < depth(0.1));
    }

    #[test]
    fn self_contact_force_derivatives_match_finite_differences() {
        type D = DualSVec64<10>;
        let c = reference::contact();
        let h = 1e-7;
        // Inside the band, the taper, the facing switch and the release, plane strain and
        // axisymmetric.
        for (depth, along, tilt, axisym) in [
            (0.03, 0.1, 0.2, false),
            (-0.05, 0.28, 0.9, false),
            (0.18, -0.31, 1.1, true),
            (0.07, 0.0, 0.0, true),
        ] {
            let mut x = fold(depth, along, tilt);
            if axisym {
                for p in x.iter_mut() {
                    p.x += 4.0;
                }
            }
            let xd: [Vector2<D>; 5] = std::array::from_fn(|a| {
                Vector2::new(
                    D::from_re(x[a].x).derivative(2 * a),
                    D::from_re(x[a].y).derivative(2 * a + 1),
                )
            });
            let fd = self_contact_force(&c, xd, axisym).expect("in contact");
            let scale = c.mu_ct * 0.3;
            for col in 0..10 {
                let shifted = |sign: f64| {
                    let mut y = x;
                    y[col / 2][col % 2] += sign * h;
                    self_contact_force(&c, y, axisym).expect("still in contact")
                };
                let (fp, fm) = (shifted(1.0), shifted(-1.0));
                for a in 0..5 {
                    for k in 0..2 {
                        let num = (fp[a][k] - fm[a][k]) / (2.0 * h);
                        let exact = fd[a][k]
                            .eps
                            .unwrap_generic(nalgebra::Const::<10>, nalgebra::Const::<1>)[col];
                        assert!(
                            (num - exact).abs() < 1e-6 * scale,
                            "depth {depth}, along {along}: ∂f[{a}][{k}]/∂x[{col}] {exact} against {num}"
                        );
                    }
                }
            }
        }
    }
}
