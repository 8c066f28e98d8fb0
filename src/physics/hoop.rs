//! The material laws of MODEL.md §3 with a hoop stretch, for the axisymmetric model
//! (MODEL.md §10).
//!
//! In the meridian half-plane (r, y) the deformation gradient is block diagonal,
//! `F = F₂ ⊕ λ` with `F₂ = I + ∇u` (2 × 2, r and y) and the hoop stretch
//! `λ = F₃₃ = 1 + u_r/r`; the active strain has its fibres in the meridian plane, so
//! `F_a = F_a2 ⊕ 1` and `C_e = C_e2 ⊕ λ²`. With `c = C_e,33 = λ²` the invariants are
//!
//! `I₁ = tr C₂ + c`, `I₂ = det C₂ + c tr C₂`, `I₃ = c det C₂`
//!
//! (plane strain is `c = 1`), the stresses are block diagonal too and gain their 33 entry,
//! and `Ḟ = Ḟ₂ ⊕ λ̇` with `λ̇ = u̇_r/r`. The energy and the laws are the plane-strain ones
//! of [`super::plane_strain`] with that one entry free; plane strain keeps its own functions
//! (`λ = 1` fixed, no derivative with respect to it).
//!
//! Admissibility: every function assumes `det F₂ > 0` and `λ > 0` ([`admissible_hoop`]).

#![allow(non_snake_case)]

use nalgebra::{Matrix2, SMatrix};
use num_dual::DualSVec64;

use super::law::{Invariants, IsotropicSolid, StressScalars};
use super::plane_strain::{Sym, ViscousKinematics, elastic_right_cauchy_green};
use super::{Real, Viscosity, Yeoh};

/// A block-diagonal 3 × 3 tensor `A₂ ⊕ a₃₃`: its meridian (r, y) block and its hoop (θθ)
/// entry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockDiag<T> {
    /// The (r, y) block.
    pub plane: Matrix2<T>,
    /// The hoop entry.
    pub hoop: T,
}

impl<T: Real> BlockDiag<T> {
    /// `plane ⊕ hoop`.
    pub fn new(plane: Matrix2<T>, hoop: T) -> Self {
        Self { plane, hoop }
    }

    /// `det = hoop · det plane`.
    pub fn det(&self) -> T {
        let p = &self.plane;
        (p[(0, 0)] * p[(1, 1)] - p[(0, 1)] * p[(1, 0)]) * self.hoop
    }
}

/// `true` when `F` is finite with `det F₂ > 0` and `λ > 0` (so `J = λ det F₂ > 0`); the
/// functions of this module assume it.
pub fn admissible_hoop(F: &BlockDiag<f64>) -> bool {
    super::admissible(&F.plane) && F.hoop.is_finite() && F.hoop > 0.0
}

impl Yeoh {
    /// Strain energy `W(C_e)` per unit intermediate volume \[Pa\] from the in-plane block of
    /// the symmetric `C_e` and its hoop entry `c = λ_e²`.
    fn strain_energy_hoop_sym<T: Real>(&self, Ce: Sym<T>, c: T) -> T {
        let tr = Ce.tr();
        let d2 = Ce.det();
        self.energy_density(Invariants {
            i1: tr + c,
            i2: d2 + c * tr,
            i3: c * d2,
        })
    }

    /// Energy per unit reference volume `Ψ(F) = J_a W(C_e)` \[Pa\] for `F = F₂ ⊕ λ`,
    /// `F_a = F_a2 ⊕ 1`.
    pub fn energy_hoop<T: Real>(&self, F: &BlockDiag<T>, Fa: &Matrix2<f64>) -> T {
        let (Ce, _, Ja) = elastic_right_cauchy_green(&F.plane, Fa);
        self.strain_energy_hoop_sym(Ce, F.hoop * F.hoop) * Ja
    }

    /// `S_e = 2∂W/∂C_e` \[Pa\], in-plane block and hoop entry, from `C_e = C_e2 ⊕ c`:
    /// `S_e = a I + k C_e⁻¹ − 2β C_e` with `a = 2(A + βI₁)`,
    /// `k = λ_Y ln J_e − 2A I₃^{1/3} − 4β I₃^{2/3}`, `A = α₁ + 2α₂X + 3α₃X²`; in-plane
    /// `C_e⁻¹ = adj(C_e2)/det C_e2`, hoop `1/c`.
    fn pk2_elastic_hoop_sym<T: Real>(&self, Ce: Sym<T>, c: T) -> (Sym<T>, T) {
        let d2 = Ce.det();
        let StressScalars { a, k, c: cc } = self.stress_scalars(Ce.tr() + c, c * d2);
        // In-plane: a I + (k/det C₂) adj(C₂) − 2β C₂, adj(C) = (yy, −xy, xx).
        let b = k / d2;
        let plane = Sym {
            xx: a + b * Ce.yy + Ce.xx * cc,
            xy: (-b + cc) * Ce.xy,
            yy: a + b * Ce.xx + Ce.yy * cc,
        };
        (plane, a + c * cc + k / c)
    }

    /// Solid second Piola–Kirchhoff stress `S_s = J_a F_a⁻¹ S_e F_a⁻ᵀ`, in-plane and hoop
    /// (`F_a,33 = 1`, so the hoop entry is `J_a S_e,33`).
    fn pk2_solid_hoop_sym<T: Real>(&self, F: &BlockDiag<T>, Fa: &Matrix2<f64>) -> (Sym<T>, T) {
        let (Ce, Fa_inv, Ja) = elastic_right_cauchy_green(&F.plane, Fa);
        let (Se, s33) = self.pk2_elastic_hoop_sym(Ce, F.hoop * F.hoop);
        match Fa_inv {
            None => (Se, s33),
            Some(G) => (Se.push(&(G * Ja.sqrt())), s33 * Ja),
        }
    }

    /// First Piola–Kirchhoff stress of the solid phase `P_s = F S_s` \[Pa\], block diagonal
    /// (`P₃₃ = λ S₃₃`); it equals `∂Ψ/∂F` (in-plane entries and `∂Ψ/∂λ`).
    pub fn piola_solid_hoop<T: Real>(&self, F: &BlockDiag<T>, Fa: &Matrix2<f64>) -> BlockDiag<T> {
        let (S, s33) = self.pk2_solid_hoop_sym(F, Fa);
        BlockDiag::new(S.left_mul(&F.plane), F.hoop * s33)
    }
}

impl Viscosity {
    /// Viscous `S_f` (MODEL.md §3) for `F = F₂ ⊕ λ`, `Ḟ = Ḟ₂ ⊕ λ̇`: `J = λ det F₂`,
    /// `C₃₃ = λ²`, `Ċ₃₃ = 2λλ̇`, so `tr(C⁻¹Ċ)` gains `2λ̇/λ` and the hoop entry is
    /// `(Jλ_f/2) tr(C⁻¹Ċ)/λ² + Jμ_f 2λ̇/λ³`.
    fn pk2_viscous_hoop_sym<T: Real>(&self, F: &BlockDiag<T>, Fdot: &BlockDiag<T>) -> (Sym<T>, T) {
        let v = ViscousKinematics::of(&F.plane, &Fdot.plane);
        let (l, ld) = (F.hoop, Fdot.hoop);
        let J = v.J * l;
        let rate = ld / l;
        let tr = v.Ci.dot(v.Cd) + rate * 2.0;
        let vol = J * tr * (0.5 * self.lambda_f);
        let c33_inv = (l * l).recip();
        let plane = v.Ci.scale(vol).add(v.K.scale(J * self.mu_f));
        (plane, c33_inv * vol + rate * c33_inv * 2.0 * J * self.mu_f)
    }

    /// Viscous first Piola–Kirchhoff stress `P_f = F S_f` \[Pa\] with the hoop stretch;
    /// linear in `Ḟ`.
    pub fn piola_viscous_hoop<T: Real>(
        &self,
        F: &BlockDiag<T>,
        Fdot: &BlockDiag<T>,
    ) -> BlockDiag<T> {
        let (S, s33) = self.pk2_viscous_hoop_sym(F, Fdot);
        BlockDiag::new(S.left_mul(&F.plane), F.hoop * s33)
    }
}

/// Total first Piola–Kirchhoff stress `P = F(S_s + S_f)` \[Pa\] with the hoop stretch,
/// block diagonal.
pub fn piola_total_hoop<T: Real>(
    yeoh: &Yeoh,
    visc: &Viscosity,
    F: &BlockDiag<T>,
    Fdot: &BlockDiag<T>,
    Fa: &Matrix2<f64>,
) -> BlockDiag<T> {
    let (Ss, s33) = yeoh.pk2_solid_hoop_sym(F, Fa);
    let (Sf, f33) = visc.pk2_viscous_hoop_sym(F, Fdot);
    BlockDiag::new(Ss.add(Sf).left_mul(&F.plane), F.hoop * (s33 + f33))
}

/// Number of independent entries of a block-diagonal `F`: the four of the block and the
/// hoop entry.
pub const HOOP_ENTRIES: usize = 5;

/// Index of the hoop entry in the flattening of [`MaterialPointHoop`].
pub const HOOP: usize = 4;

/// Stress and exact tangents at one material point with the hoop stretch.
///
/// Flattening: `2i + J` for the block entry (i, J), [`HOOP`] = 4 for the hoop entry; rows
/// for `P`, columns for `F` (or `Ḟ`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialPointHoop {
    /// Total first Piola–Kirchhoff stress `P` \[Pa\].
    pub P: BlockDiag<f64>,
    /// `∂P_α/∂F_β` \[Pa\].
    pub dP_dF: SMatrix<f64, HOOP_ENTRIES, HOOP_ENTRIES>,
    /// `∂P_α/∂Ḟ_β` \[Pa·s\] (viscous part only).
    pub dP_dFdot: SMatrix<f64, HOOP_ENTRIES, HOOP_ENTRIES>,
}

/// `P` and its exact tangents with the hoop stretch, as [`super::material_point`] does
/// in plane strain: `∂P/∂F` by one `DualSVec64<5>` pass over (F₂, λ), `∂P/∂Ḟ` column by
/// column from the linearity of `P_f` in `Ḟ`.
///
/// Assumes [`admissible_hoop`]`(F)` and `det F_a > 0`.
pub fn material_point_hoop(
    yeoh: &Yeoh,
    visc: &Viscosity,
    F: &BlockDiag<f64>,
    Fdot: &BlockDiag<f64>,
    Fa: &Matrix2<f64>,
) -> MaterialPointHoop {
    type D5 = DualSVec64<HOOP_ENTRIES>;
    let Fd = BlockDiag::new(
        Matrix2::from_fn(|k, l| D5::from_re(F.plane[(k, l)]).derivative(2 * k + l)),
        D5::from_re(F.hoop).derivative(HOOP),
    );
    let Gd = BlockDiag::new(Fdot.plane.map(D5::from_re), D5::from_re(Fdot.hoop));
    let P1 = piola_total_hoop(yeoh, visc, &Fd, &Gd, Fa);
    let entries = |P: &BlockDiag<D5>| -> [D5; HOOP_ENTRIES] {
        [
            P.plane[(0, 0)],
            P.plane[(0, 1)],
            P.plane[(1, 0)],
            P.plane[(1, 1)],
            P.hoop,
        ]
    };
    let mut dP_dF = SMatrix::zeros();
    for (row, p) in entries(&P1).iter().enumerate() {
        let g = p
            .eps
            .unwrap_generic(nalgebra::Const::<HOOP_ENTRIES>, nalgebra::U1);
        for c in 0..HOOP_ENTRIES {
            dP_dF[(row, c)] = g[c];
        }
    }
    let P = BlockDiag::new(P1.plane.map(|v| v.re), P1.hoop.re);
    // P_f is linear in Ḟ: column β of ∂P/∂Ḟ is P_f(F, E_β), E_β the unit entry β.
    let mut dP_dFdot = SMatrix::zeros();
    for col in 0..HOOP_ENTRIES {
        let mut E = BlockDiag::new(Matrix2::zeros(), 0.0);
        if col == HOOP {
            E.hoop = 1.0;
        } else {
            E.plane[(col / 2, col % 2)] = 1.0;
        }
        let Pf = visc.piola_viscous_hoop(F, &E);
        let v = [
            Pf.plane[(0, 0)],
            Pf.plane[(0, 1)],
            Pf.plane[(1, 0)],
            Pf.plane[(1, 1)],
            Pf.hoop,
        ];
        for (row, x) in v.into_iter().enumerate() {
            dP_dFdot[(row, col)] = x;
        }
    }
    MaterialPointHoop { P, dP_dF, dP_dFdot }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::physics::piola_total;
    use crate::physics::plane_strain::tests::{Rng, active, cytoplasm};

    /// A random admissible `F₂ ⊕ λ`: `F₂` as the plane-strain tests draw it, λ ∈ [0.6, 1.6).
    fn deformation(rng: &mut Rng, s: f64) -> BlockDiag<f64> {
        let plane = rng.deformation(s);
        BlockDiag::new(plane, rng.uniform(0.6, 1.6))
    }

    #[test]
    fn with_unit_hoop_stretch_the_laws_are_the_plane_strain_ones() {
        let mut rng = Rng::new(23);
        let mat = cytoplasm();
        let visc = Viscosity {
            lambda_f: 3.0,
            mu_f: 2.0,
        };
        for case in 0..10 {
            let F = rng.deformation(0.5);
            let Fdot = Matrix2::from_fn(|_, _| rng.uniform(-1.0, 1.0));
            let Fa = rng.active_strain(case % 2 == 1);
            let P2 = piola_total(&mat, &visc, &F, &Fdot, &Fa);
            let P3 = piola_total_hoop(
                &mat,
                &visc,
                &BlockDiag::new(F, 1.0),
                &BlockDiag::new(Fdot, 0.0),
                &Fa,
            );
            assert!((P3.plane - P2).norm() < 1e-13 * P2.norm(), "case {case}");
            let e2 = mat.energy(&F, &Fa);
            let e3 = mat.energy_hoop(&BlockDiag::new(F, 1.0), &Fa);
            assert!((e2 - e3).abs() < 1e-13 * e2.abs().max(1.0));
        }
    }

    #[test]
    fn the_hoop_entry_is_an_in_plane_entry_of_the_isotropic_law() {
        // W is isotropic: for principal stretches (a, b, c) along (r, y, θ) the stress along
        // θ is the one along r with a and c swapped, P₃₃(a, b, c) = P₁₁(c, b, a), and the
        // energy is the same. The viscous law likewise with the rates swapped. This ties the
        // hoop entry to the plane-strain formulas, independently of the derivatives.
        let mat = Yeoh::from_engineering(500.0, 0.485, 0.5, 0.2).unwrap();
        let visc = Viscosity {
            lambda_f: 3.0,
            mu_f: 2.0,
        };
        let I = Matrix2::<f64>::identity();
        for (a, b, c) in [
            (1.2f64, 0.9, 0.7),
            (0.8, 1.1, 1.4),
            (1.0, 1.0, 1.3),
            (1.5, 0.6, 1.0),
        ] {
            let (ad, bd, cd) = (0.3f64, -0.2, 0.5);
            let F = BlockDiag::new(Matrix2::new(a, 0.0, 0.0, b), c);
            let Fs = BlockDiag::new(Matrix2::new(c, 0.0, 0.0, b), a);
            let G = BlockDiag::new(Matrix2::new(ad, 0.0, 0.0, bd), cd);
            let Gs = BlockDiag::new(Matrix2::new(cd, 0.0, 0.0, bd), ad);
            let P = piola_total_hoop(&mat, &visc, &F, &G, &I);
            let Ps = piola_total_hoop(&mat, &visc, &Fs, &Gs, &I);
            let scale = P.plane.norm() + P.hoop.abs();
            assert!(
                (P.hoop - Ps.plane[(0, 0)]).abs() < 1e-12 * scale,
                "{a} {b} {c}"
            );
            assert!((Ps.hoop - P.plane[(0, 0)]).abs() < 1e-12 * scale);
            assert!((P.plane[(1, 1)] - Ps.plane[(1, 1)]).abs() < 1e-12 * scale);
            let (e, es) = (mat.energy_hoop(&F, &I), mat.energy_hoop(&Fs, &I));
            assert!((e - es).abs() < 1e-12 * e.abs().max(1.0));
        }
    }

    #[test]
    fn reference_state_is_stress_free_and_small_strains_are_linear_elasticity_in_3d() {
        let (e, nu) = (100.0, 0.485);
        let mat = Yeoh::from_engineering(e, nu, 0.1, 0.2).unwrap();
        let I = Matrix2::identity();
        let P0 = mat.piola_solid_hoop(&BlockDiag::new(I, 1.0), &I);
        assert!(P0.plane.norm() < 1e-13 && P0.hoop.abs() < 1e-13);
        // F = F_a ⊕ 1: no elastic stress.
        let Fa = active(0.4, 0.3, 2.0);
        let P = mat.piola_solid_hoop(&BlockDiag::new(Fa, 1.0), &Fa);
        assert!(P.plane.norm() < 1e-12 && P.hoop.abs() < 1e-12);
        // P(I + εH)/ε → λ tr H I + μ(H + Hᵀ) with the hoop strain H₃₃ in tr H.
        let mu = e / (2.0 * (1.0 + nu));
        let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let H = Matrix2::new(0.3, -0.7, 0.2, -0.1);
        let h33 = 0.6;
        let eps = 1e-6;
        let P = mat.piola_solid_hoop(&BlockDiag::new(I + H * eps, 1.0 + h33 * eps), &I);
        let tr = H.trace() + h33;
        let lin = I * (lam * tr) + (H + H.transpose()) * mu;
        let lin33 = lam * tr + 2.0 * mu * h33;
        assert!((P.plane / eps - lin).norm() < 1e-5 * lin.norm());
        assert!((P.hoop / eps - lin33).abs() < 1e-5 * lin33.abs());
    }

    #[test]
    fn viscous_hoop_stress_is_newtonian_and_vanishes_for_rigid_rates() {
        let visc = Viscosity {
            lambda_f: 3.0,
            mu_f: 2.0,
        };
        // At F = I: P = σ = λ_f tr(d) I + 2μ_f d, d = sym(Ḟ₂) ⊕ λ̇.
        let G = Matrix2::new(0.3, -0.7, 0.2, -0.1);
        let ld = 0.4f64;
        let P = visc.piola_viscous_hoop(
            &BlockDiag::new(Matrix2::identity(), 1.0),
            &BlockDiag::new(G, ld),
        );
        let d = (G + G.transpose()) * 0.5;
        let tr = d.trace() + ld;
        assert!((P.plane - (Matrix2::identity() * (3.0 * tr) + d * 4.0)).norm() < 1e-14);
        assert!((P.hoop - (3.0 * tr + 4.0 * ld)).abs() < 1e-14);
        // A rotation rate in the meridian plane with the hoop stretch fixed: no stress.
        let mut rng = Rng::new(37);
        for _ in 0..10 {
            let F = deformation(&mut rng, 0.5);
            let w = rng.uniform(-2.0, 2.0);
            let W = Matrix2::new(0.0, -w, w, 0.0);
            let P = visc.piola_viscous_hoop(&F, &BlockDiag::new(W * F.plane, 0.0));
            assert!(P.plane.norm() + P.hoop.abs() < 1e-13 * (5.0 * (W * F.plane).norm()));
        }
    }

    #[test]
    fn admissibility_with_hoop_stretch() {
        let I = Matrix2::identity();
        assert!(admissible_hoop(&BlockDiag::new(I, 1.0)));
        assert!(!admissible_hoop(&BlockDiag::new(I, 0.0)));
        assert!(!admissible_hoop(&BlockDiag::new(I, -0.5)));
        assert!(!admissible_hoop(&BlockDiag::new(I, f64::NAN)));
        assert!(!admissible_hoop(&BlockDiag::new(
            Matrix2::new(1.0, 0.0, 0.0, -0.1),
            1.0
        )));
    }
}
