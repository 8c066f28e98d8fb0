//! The constitutive laws of MODEL.md §3, whatever the kinematics: the compressible Yeoh
//! solid with a Mooney term and active strain ([`IsotropicSolid`], written in the
//! invariants of `C_e`), the Kelvin–Voigt Newtonian viscosity, and the material point
//! (stress and tangents) the element kernels take. Each kinematics evaluates them from its
//! own storage of the tensors: plane strain ([`super::plane_strain`]), the hoop stretch
//! of the axisymmetric model ([`super::hoop`]) and 3-D ([`super::three_d`]).

#![allow(non_snake_case)]

use super::{PhysicsError, Real, cbrt, check, cst, ln};
use nalgebra::{Const, SMatrix, U1};
use num_dual::DualSVec64;
use serde::{Deserialize, Serialize};

/// Compressible Yeoh solid with a Mooney term (MODEL.md §3):
///
/// `W(C_e) = α₁X + α₂X² + α₃X³ + β(I₂ − 3I₃^{2/3}) + (λ_Y/2)(ln J_e)²`,
/// `X = I₁ − 3I₃^{1/3}`, invariants of `C_e`; `W` is per unit intermediate (relaxed) volume.
///
/// Units: all coefficients in Pa = pN/µm².
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Yeoh {
    /// `α₁ = μ_e/2 − β` \[Pa\].
    pub alpha1: f64,
    /// `α₂ = −γα₁` \[Pa\].
    pub alpha2: f64,
    /// `α₃ = γα₁` \[Pa\].
    pub alpha3: f64,
    /// Mooney coefficient `β = f_β μ_e/2` (`f_β = 0.2` in MODEL.md) \[Pa\].
    pub beta: f64,
    /// Volumetric coefficient `λ_Y = λ_e + (2/3)μ_e` (the bulk modulus) \[Pa\].
    pub lambda_y: f64,
}

/// The invariants of a symmetric 3 × 3 right Cauchy–Green tensor `C` (of `C_e` for the
/// solid): `I₁ = tr C`, `I₂ = ½((tr C)² − tr C²)`, `I₃ = det C`, however the kinematics
/// stores `C` (2 × 2 plus `C₃₃ = 1`, plus a hoop entry, or 3 × 3).
#[derive(Debug, Clone, Copy)]
pub struct Invariants<T> {
    /// `I₁`.
    pub i1: T,
    /// `I₂`.
    pub i2: T,
    /// `I₃`.
    pub i3: T,
}

/// The second Piola–Kirchhoff stress of an isotropic law in the form
/// `S = 2∂W/∂C = a I + k C⁻¹ + c C`.
#[derive(Debug, Clone, Copy)]
pub struct StressScalars<T> {
    /// Coefficient of `I`.
    pub a: T,
    /// Coefficient of `C⁻¹`.
    pub k: T,
    /// Coefficient of `C`.
    pub c: T,
}

/// What [`IsotropicSolid::tangent_scalars`] gives the closed-form tangent of the 3-D
/// kinematics (module notes of [`super::three_d`]): with `s = I₃^{1/3} = J^{2/3}`,
/// `∂S/∂C = (2A′ + 2β) M⊗M − 2A′s (M⊗C⁻¹ + C⁻¹⊗M) + κ C⁻¹⊗C⁻¹ − k C⁻¹⊙C⁻¹ + c M⊙M`.
#[derive(Debug, Clone, Copy)]
pub struct TangentScalars {
    /// `s = J^{2/3}`.
    pub s: f64,
    /// The stress's `a`, `k`, `c` ([`StressScalars`]).
    pub a: f64,
    /// `k`.
    pub k: f64,
    /// `c`.
    pub c: f64,
    /// `A′ + β`, a quarter of the `M⊗M` coefficient.
    pub ap_beta: f64,
    /// `−4A′s`, the `M⊗C⁻¹` coefficient times 2.
    pub m4_ap_s: f64,
    /// `κ`, half the `C⁻¹⊗C⁻¹` coefficient.
    pub kappa: f64,
}

/// An isotropic solid law `W(I₁, I₂, I₃)` per unit intermediate volume, written once in
/// terms of the invariants of `C_e` and evaluated by every kinematics (plane strain
/// [`super::plane_strain`], the hoop stretch [`super::hoop`], 3-D [`super::three_d`]), which
/// form the invariants from their own storage of `C_e` and the tensors from these
/// scalars.
pub trait IsotropicSolid {
    /// `W` \[Pa\].
    fn energy_density<T: Real>(&self, inv: Invariants<T>) -> T;
    /// `S_e = 2∂W/∂C_e = a I + k C_e⁻¹ + c C_e`, from `I₁` and `I₃` (the law's `∂W/∂I₂`
    /// is constant, so `I₂` does not enter).
    fn stress_scalars<T: Real>(&self, i1: T, i3: T) -> StressScalars<T>;
    /// The scalars of the closed-form tangent from `I₁` and `J_e` (`I₃ = J_e²`).
    fn tangent_scalars(&self, i1: f64, je: f64) -> TangentScalars;
}

impl IsotropicSolid for Yeoh {
    /// `W = α₁X + α₂X² + α₃X³ + β(I₂ − 3I₃^{2/3}) + (λ_Y/2)(ln J_e)²`, `X = I₁ − 3I₃^{1/3}`.
    #[inline(always)]
    fn energy_density<T: Real>(&self, inv: Invariants<T>) -> T {
        let Invariants { i1, i2, i3 } = inv;
        let I3_13 = cbrt(i3);
        let X = i1 - I3_13 * 3.0;
        let lnJ = ln(i3) * 0.5;
        X * (X * (X * self.alpha3 + self.alpha2) + self.alpha1)
            + (i2 - I3_13 * I3_13 * 3.0) * self.beta
            + lnJ * lnJ * (0.5 * self.lambda_y)
    }

    /// `a = 2(A + βI₁)`, `k = λ_Y ln J_e − 2A I₃^{1/3} − 4β I₃^{2/3}`, `c = −2β`, with
    /// `A = ∂W/∂X = α₁ + 2α₂X + 3α₃X²`.
    #[inline(always)]
    fn stress_scalars<T: Real>(&self, i1: T, i3: T) -> StressScalars<T> {
        let I3_13 = cbrt(i3);
        let X = i1 - I3_13 * 3.0;
        let A = X * (X * (self.alpha3 * 3.0) + self.alpha2 * 2.0) + self.alpha1;
        let lnJ = ln(i3) * 0.5;
        StressScalars {
            a: (A + i1 * self.beta) * 2.0,
            k: lnJ * self.lambda_y - A * I3_13 * 2.0 - I3_13 * I3_13 * (4.0 * self.beta),
            c: cst(-2.0 * self.beta),
        }
    }

    /// `A′ = ∂A/∂X = 2α₂ + 6α₃X` and `κ = λ_Y/2 + 2A′s² − (2/3)As − (8/3)βs²`.
    #[inline(always)]
    fn tangent_scalars(&self, i1: f64, je: f64) -> TangentScalars {
        let s = (je * je).cbrt();
        let ln_j = je.ln();
        let X = i1 - 3.0 * s;
        let A = self.alpha1 + X * (2.0 * self.alpha2 + 3.0 * self.alpha3 * X);
        let Ap = 2.0 * self.alpha2 + 6.0 * self.alpha3 * X;
        let beta = self.beta;
        TangentScalars {
            s,
            a: 2.0 * (A + beta * i1),
            k: self.lambda_y * ln_j - 2.0 * A * s - 4.0 * beta * s * s,
            c: -2.0 * beta,
            ap_beta: Ap + beta,
            m4_ap_s: -4.0 * Ap * s,
            kappa: 0.5 * self.lambda_y + 2.0 * Ap * s * s
                - (2.0 / 3.0) * A * s
                - (8.0 / 3.0) * beta * s * s,
        }
    }
}

impl Yeoh {
    /// Coefficients from Young's modulus `e` \[Pa\], Poisson's ratio `nu`, the stiffening
    /// ratio `gamma` and the Mooney fraction `beta_fraction` (MODEL.md: 0.2):
    ///
    /// `μ_e = E/(2(1+ν))`, `λ_e = Eν/((1+ν)(1−2ν))`, `β = f_β μ_e/2`, `α₁ = μ_e/2 − β`,
    /// `α₂ = −γα₁`, `α₃ = γα₁`, `λ_Y = λ_e + (2/3)μ_e`.
    ///
    /// The small-strain limit is then linear elasticity with `(E, ν)`.
    /// Rejects `E ≤ 0`, `ν ∉ (−1, ½)`, `γ ∉ [0, 3)` (`dW/dX = α₁(1 − 2γX + 3γX²) > 0`
    /// for all `X` needs `0 ≤ γ < 3`), `f_β ∉ [0, 1)` (`α₁ > 0`), and non-finite values.
    pub fn from_engineering(
        e: f64,
        nu: f64,
        gamma: f64,
        beta_fraction: f64,
    ) -> Result<Self, PhysicsError> {
        check(e.is_finite() && e > 0.0, "E", e, "must be finite and > 0")?;
        check(
            nu.is_finite() && nu > -1.0 && nu < 0.5,
            "nu",
            nu,
            "must lie in (-1, 0.5)",
        )?;
        check(
            gamma.is_finite() && (0.0..3.0).contains(&gamma),
            "gamma",
            gamma,
            "must lie in [0, 3) for a monotone stiffening",
        )?;
        check(
            beta_fraction.is_finite() && (0.0..1.0).contains(&beta_fraction),
            "beta_fraction",
            beta_fraction,
            "must lie in [0, 1) so that alpha1 > 0",
        )?;
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let beta = beta_fraction * mu / 2.0;
        let alpha1 = mu / 2.0 - beta;
        Ok(Self {
            alpha1,
            alpha2: -gamma * alpha1,
            alpha3: gamma * alpha1,
            beta,
            lambda_y: lambda + 2.0 / 3.0 * mu,
        })
    }
}

/// Kelvin–Voigt Newtonian viscosity of the fluid phase (MODEL.md §3):
///
/// `S_f = (J λ_f/2) tr(C⁻¹Ċ) C⁻¹ + J μ_f C⁻¹ĊC⁻¹`, `Ċ = ḞᵀF + FᵀḞ`,
///
/// i.e. the Cauchy stress `σ = λ_f tr(d) I + 2μ_f d`, `d = sym(ḞF⁻¹)`, pulled back.
/// Units: Pa·s = pN·s/µm².
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Viscosity {
    /// Volumetric viscosity `λ_f` \[Pa·s\] (MODEL.md: 1000).
    pub lambda_f: f64,
    /// Shear viscosity `μ_f` \[Pa·s\] (MODEL.md: 2e-3).
    pub mu_f: f64,
}

impl Viscosity {
    /// Checks `λ_f ≥ 0`, `μ_f ≥ 0`, finite.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.lambda_f.is_finite() && self.lambda_f >= 0.0,
            "lambda_f",
            self.lambda_f,
            "must be finite and >= 0",
        )?;
        check(
            self.mu_f.is_finite() && self.mu_f >= 0.0,
            "mu_f",
            self.mu_f,
            "must be finite and >= 0",
        )
    }
}

/// Stress and exact tangents at one material point (MODEL.md §3) of a `D × D` gradient,
/// for assembly (`DD = D²`).
///
/// Flattening: row `D i + J` for `P_iJ`, column `D k + L` for `F_kL` (or `Ḟ_kL`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MaterialPointOf<const D: usize, const DD: usize> {
    /// Total first Piola–Kirchhoff stress `P` \[Pa\].
    pub P: SMatrix<f64, D, D>,
    /// `∂P_iJ/∂F_kL` \[Pa\].
    pub dP_dF: SMatrix<f64, DD, DD>,
    /// `∂P_iJ/∂Ḟ_kL` \[Pa·s\] (viscous part only).
    pub dP_dFdot: SMatrix<f64, DD, DD>,
}

/// A `D × D` matrix of dual numbers in `DD` directions.
pub type DualMatrix<const D: usize, const DD: usize> = SMatrix<DualSVec64<DD>, D, D>;

/// `P` and its exact tangents at one material point of a `D × D` kinematics by
/// forward-mode dual numbers: `∂P/∂F` by one `DualSVec64<DD>` pass of `piola(F, Ḟ)` over
/// `F` (entry (k, L) seeded along `D k + L`, `Ḟ` fixed); `∂P/∂Ḟ` needs no derivatives:
/// the solid does not depend on `Ḟ` and `P_f` is linear in it, so column `D k + L` is
/// `viscous(E_kL) = P_f(F, E_kL)` (`E_kL` the unit matrix), exactly.
#[inline(always)]
pub fn dual_material_point<const D: usize, const DD: usize>(
    F: &SMatrix<f64, D, D>,
    Fdot: &SMatrix<f64, D, D>,
    piola: impl Fn(&DualMatrix<D, DD>, &DualMatrix<D, DD>) -> DualMatrix<D, DD>,
    viscous: impl Fn(&SMatrix<f64, D, D>) -> SMatrix<f64, D, D>,
) -> MaterialPointOf<D, DD> {
    let Fd = SMatrix::from_fn(|k, l| DualSVec64::from_re(F[(k, l)]).derivative(D * k + l));
    let P1 = piola(&Fd, &Fdot.map(DualSVec64::from_re));
    let mut P = SMatrix::zeros();
    let mut dP_dF = SMatrix::zeros();
    for i in 0..D {
        for j in 0..D {
            P[(i, j)] = P1[(i, j)].re;
            let g = P1[(i, j)].eps.unwrap_generic(Const::<DD>, U1);
            for c in 0..DD {
                dP_dF[(D * i + j, c)] = g[c];
            }
        }
    }
    let mut dP_dFdot = SMatrix::zeros();
    for k in 0..D {
        for l in 0..D {
            let mut E = SMatrix::zeros();
            E[(k, l)] = 1.0;
            let col = viscous(&E);
            for i in 0..D {
                for j in 0..D {
                    dP_dFdot[(D * i + j, D * k + l)] = col[(i, j)];
                }
            }
        }
    }
    MaterialPointOf { P, dP_dF, dP_dFdot }
}
