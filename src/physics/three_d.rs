//! The material laws of MODEL.md §3 with a full 3 × 3 deformation gradient, for the 3-D
//! quarter cell (MODEL.md §10).
//!
//! The same compressible Yeoh solid with active strain `F = F_e F_a` and the same
//! Kelvin–Voigt viscosity as [`super::plane_strain`] and [`super::hoop`]
//! (hoop stretch), with `F`, `Ḟ` and `F_a` general 3 × 3 tensors. Those two keep their own
//! functions; nothing here is called by them.
//!
//! **Solid.** `C_e = F_a⁻ᵀ FᵀF F_a⁻¹` has the invariants `I₁ = tr C_e`,
//! `I₂ = ½(I₁² − tr C_e²)` (the sum of the principal 2 × 2 minors), `I₃ = det C_e`, and
//!
//! `S_e = 2∂W/∂C_e = a I + k C_e⁻¹ + c C_e`, `a = 2(A + βI₁)`,
//! `k = λ_Y ln J_e − 2A I₃^{1/3} − 4β I₃^{2/3}`, `c = −2β`, `A = α₁ + 2α₂X + 3α₃X²`,
//!
//! evaluated as `a I + (k/I₃) adj(C_e) + c C_e` (no division but the one by `I₃`). The
//! reference stress is `S_s = J_a F_a⁻¹ S_e F_a⁻ᵀ`, `P_s = F S_s`; `F_a⁻¹` is skipped when
//! `F_a = I` exactly (everywhere but in the active regions). Symmetric tensors are kept as
//! their six entries (`Sym3`), which halves the dual-number work of the products.
//!
//! **Viscosity.** `S_f = (Jλ_f/2) tr(C⁻¹Ċ) C⁻¹ + Jμ_f C⁻¹ĊC⁻¹` with `Ċ = ḞᵀF + FᵀḞ`. With
//! `H = F⁻¹` and `L = ḞH`, `C⁻¹Ċ = 2H d F` (`d = sym L`), so `tr(C⁻¹Ċ) = 2 tr L` and
//! `C⁻¹ĊC⁻¹ = 2H d Hᵀ`, and
//!
//! `P_f = F S_f = J σ F⁻ᵀ = σ cof F`, `σ = λ_f tr(d) I + 2μ_f d`, `cof F = J F⁻ᵀ = adj(F)ᵀ`:
//!
//! the same stress as the `C` form of the 2-D code, with about 60 % of its products
//! (`adj F`, `ḞF⁻¹`, one product with `cof F`; no `C`, `C⁻¹` or `C⁻¹ĊC⁻¹`), which counts
//! twice for dual numbers. A test checks it against MODEL.md's `S_f` literally.
//!
//! **Tangent.** [`material_point_full`] returns `∂P/∂F` in closed form, not by dual
//! numbers. With `M = F_a⁻¹F_a⁻ᵀ` (`I` without active strain) the push-forward through
//! `F_a⁻¹` maps `I ↦ M`, `C_e⁻¹ ↦ C⁻¹`, `C_e ↦ MCM`, so `S_s = J_a(a M + k C⁻¹ + c MCM)`
//! and
//!
//! `∂S_s/∂C = J_a[(2A′ + 2β) M⊗M − 2A′s (M⊗C⁻¹ + C⁻¹⊗M) + κ C⁻¹⊗C⁻¹ − k C⁻¹⊙C⁻¹ + c M⊙M]`,
//!
//! `s = I₃^{1/3}`, `A′ = 2α₂ + 6α₃X`, `κ = λ_Y/2 + 2A′s² − (2/3)As − (8/3)βs²`,
//! `(A⊙B)_IJKL = ½(A_IK B_JL + A_IL B_JK)`. With `∂C_MN/∂F_kL = δ_ML F_kN + F_kM δ_NL`,
//! `U = FM`, `V = FC⁻¹ = F⁻ᵀ` and `B = FMFᵀ` (the elastic left Cauchy–Green tensor),
//!
//! `∂P_iJ/∂F_kL = δ_ik S_LJ + J_a[c₁ U_iJ U_kL + c₂(U_iJ V_kL + V_iJ U_kL) + c₃ V_iJ V_kL
//!   − k(V_iL V_kJ + δ_ik C⁻¹_JL) + c(U_iL U_kJ + B_ik M_JL)]`,
//!
//! `c₁ = 4(A′ + β)`, `c₂ = −4A′s`, `c₃ = 2κ`. The viscous part, from `P_f = Jσ Hᵀ` with
//! `∂J = J H_Lk`, `∂H_ab = −H_ak H_Lb`, `∂L_ab = −L_ak H_Lb`:
//!
//! `∂P_f,iJ/∂F_kL = H_Lk P_f,iJ − P_f,iL H_Jk − Jλ_f (HL)_Lk H_Ji − Jμ_f(L_ik C⁻¹_LJ + H_Li (HL)_Jk)`,
//!
//! `∂P_f,iJ/∂Ḟ_kL = Jλ_f H_Lk H_Ji + Jμ_f(δ_ik C⁻¹_LJ + H_Li H_Jk)`: as `P_f` is linear in
//! `Ḟ`, its column `3k + L` is `P_f(F, E_kL)` (`E_kL` the unit matrix), the columns
//! plane strain's `material_point` evaluates one by one; here they come in closed form.
//!
//! The tests check both against finite differences and against one `DualSVec64<9>` pass
//! over `F` ([`super::dual_material_point`], kept as the independent reference in the tests).
//!
//! Admissibility: every function assumes `det F > 0` and `det F_a > 0` (check with
//! [`admissible_full`]); it does not check, for speed.

#![allow(non_snake_case)]

use nalgebra::{Matrix3, SMatrix};

use super::law::{Invariants, IsotropicSolid, StressScalars, TangentScalars};
use super::{Real, Viscosity, Yeoh};

/// Number of entries of a 3 × 3 tensor, the size of the flattened tangents.
pub const FULL_ENTRIES: usize = 9;

/// A symmetric 3 × 3 tensor by its six entries; the stress computations use it to skip
/// the redundant half of every product (this matters for dual numbers).
#[derive(Debug, Clone, Copy)]
pub(super) struct Sym3<T> {
    pub(super) xx: T,
    pub(super) xy: T,
    pub(super) xz: T,
    pub(super) yy: T,
    pub(super) yz: T,
    pub(super) zz: T,
}

impl<T: Real> Sym3<T> {
    /// From the diagonal and the upper off-diagonal entries of `M` (assumed symmetric).
    #[cfg(test)]
    pub(super) fn from_upper(M: &Matrix3<T>) -> Self {
        Self {
            xx: M[(0, 0)],
            xy: M[(0, 1)],
            xz: M[(0, 2)],
            yy: M[(1, 1)],
            yz: M[(1, 2)],
            zz: M[(2, 2)],
        }
    }

    #[inline(always)]
    pub(super) fn tr(self) -> T {
        self.xx + self.yy + self.zz
    }

    /// The adjugate `adj(S) = det(S) S⁻¹` (symmetric for a symmetric `S`).
    #[inline(always)]
    pub(super) fn adj(self) -> Self {
        Self {
            xx: self.yy * self.zz - self.yz * self.yz,
            xy: self.xz * self.yz - self.xy * self.zz,
            xz: self.xy * self.yz - self.xz * self.yy,
            yy: self.xx * self.zz - self.xz * self.xz,
            yz: self.xy * self.xz - self.xx * self.yz,
            zz: self.xx * self.yy - self.xy * self.xy,
        }
    }

    /// `det S` from `S` and its adjugate (first row of `S` times first column of `adj S`).
    #[inline(always)]
    pub(super) fn det_with(self, adj: Self) -> T {
        self.xx * adj.xx + self.xy * adj.xy + self.xz * adj.xz
    }

    /// The sum of the principal 2 × 2 minors, `½((tr S)² − tr S²)` (= `tr adj S`).
    #[inline(always)]
    pub(super) fn minors(self) -> T {
        self.xx * self.yy + self.xx * self.zz + self.yy * self.zz
            - self.xy * self.xy
            - self.xz * self.xz
            - self.yz * self.yz
    }

    /// `Gᵀ S G` for a constant `G`.
    #[inline(always)]
    pub(super) fn congruence(self, G: &Matrix3<f64>) -> Self {
        let s = [
            [self.xx, self.xy, self.xz],
            [self.xy, self.yy, self.yz],
            [self.xz, self.yz, self.zz],
        ];
        // (SG)_kj = Σ_l S_kl G_lj
        let sg =
            |k: usize, j: usize| s[k][0] * G[(0, j)] + s[k][1] * G[(1, j)] + s[k][2] * G[(2, j)];
        let sg: [[T; 3]; 3] = std::array::from_fn(|k| std::array::from_fn(|j| sg(k, j)));
        // (Gᵀ SG)_ij = Σ_k G_ki (SG)_kj
        let r =
            |i: usize, j: usize| sg[0][j] * G[(0, i)] + sg[1][j] * G[(1, i)] + sg[2][j] * G[(2, i)];
        Self {
            xx: r(0, 0),
            xy: r(0, 1),
            xz: r(0, 2),
            yy: r(1, 1),
            yz: r(1, 2),
            zz: r(2, 2),
        }
    }

    /// `F S`.
    #[inline(always)]
    pub(super) fn left_mul(self, F: &Matrix3<T>) -> Matrix3<T> {
        let s = [
            [self.xx, self.xy, self.xz],
            [self.xy, self.yy, self.yz],
            [self.xz, self.yz, self.zz],
        ];
        Matrix3::from_fn(|i, j| F[(i, 0)] * s[0][j] + F[(i, 1)] * s[1][j] + F[(i, 2)] * s[2][j])
    }

    /// `FᵀF`.
    #[inline(always)]
    pub(super) fn gram(F: &Matrix3<T>) -> Self {
        let g = |i: usize, j: usize| {
            F[(0, i)] * F[(0, j)] + F[(1, i)] * F[(1, j)] + F[(2, i)] * F[(2, j)]
        };
        Self {
            xx: g(0, 0),
            xy: g(0, 1),
            xz: g(0, 2),
            yy: g(1, 1),
            yz: g(1, 2),
            zz: g(2, 2),
        }
    }
}

/// The adjugate `adj(M) = det(M) M⁻¹ = cof(M)ᵀ` of a 3 × 3 matrix, polynomial in `M`.
#[inline(always)]
pub(super) fn adjugate<T: Real>(M: &Matrix3<T>) -> Matrix3<T> {
    // adj_ij = cof_ji, cof_ji = M_{j+1,i+1} M_{j+2,i+2} − M_{j+1,i+2} M_{j+2,i+1} (cyclic)
    Matrix3::from_fn(|i, j| {
        let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
        let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
        M[(j1, i1)] * M[(j2, i2)] - M[(j1, i2)] * M[(j2, i1)]
    })
}

/// `det M` from `M` and its adjugate (first row of `M` times first column of `adj M`).
#[inline(always)]
fn det_with<T: Real>(M: &Matrix3<T>, adj: &Matrix3<T>) -> T {
    M[(0, 0)] * adj[(0, 0)] + M[(0, 1)] * adj[(1, 0)] + M[(0, 2)] * adj[(2, 0)]
}

/// `(F_a⁻¹, J_a)` of an active strain with `det F_a > 0`, or `None` when `F_a = I`
/// exactly (the common case, skipped for speed).
#[inline(always)]
fn active_inverse(Fa: &Matrix3<f64>) -> Option<(Matrix3<f64>, f64)> {
    if *Fa == Matrix3::identity() {
        return None;
    }
    let adj = adjugate(Fa);
    let Ja = det_with(Fa, &adj);
    Some((adj / Ja, Ja))
}

/// `(C_e, F_a⁻¹, J_a)` with `C_e = F_a⁻ᵀ FᵀF F_a⁻¹`; `F_a⁻¹` is `None` when `F_a = I`.
#[inline(always)]
fn elastic_right_cauchy_green_full<T: Real>(
    F: &Matrix3<T>,
    Fa: &Matrix3<f64>,
) -> (Sym3<T>, Option<Matrix3<f64>>, f64) {
    let C = Sym3::gram(F);
    match active_inverse(Fa) {
        None => (C, None, 1.0),
        Some((G, Ja)) => (C.congruence(&G), Some(G), Ja),
    }
}

impl Yeoh {
    /// Strain energy `W(C_e)` per unit intermediate volume \[Pa\] from a symmetric 3 × 3
    /// `C_e`: `I₁ = tr C_e`, `I₂ = ½(I₁² − tr C_e²)`, `I₃ = det C_e`, `W` as in [`Yeoh`].
    fn strain_energy_full_sym<T: Real>(&self, Ce: Sym3<T>) -> T {
        self.energy_density(Invariants {
            i1: Ce.tr(),
            i2: Ce.minors(),
            i3: Ce.det_with(Ce.adj()),
        })
    }

    /// Energy per unit reference volume `Ψ(F) = J_a W(C_e)`, `C_e = F_a⁻ᵀ FᵀF F_a⁻¹`
    /// \[Pa\], with a full 3 × 3 `F` and `F_a`.
    pub fn energy_full<T: Real>(&self, F: &Matrix3<T>, Fa: &Matrix3<f64>) -> T {
        let (Ce, _, Ja) = elastic_right_cauchy_green_full(F, Fa);
        self.strain_energy_full_sym(Ce) * Ja
    }

    /// `S_e = 2∂W/∂C_e = a I + (k/I₃) adj(C_e) + c C_e` (module notes).
    #[inline(always)]
    fn pk2_elastic_full_sym<T: Real>(&self, Ce: Sym3<T>) -> Sym3<T> {
        let adj = Ce.adj();
        let I3 = Ce.det_with(adj);
        let StressScalars { a, k, c } = self.stress_scalars(Ce.tr(), I3);
        let b = k / I3;
        Sym3 {
            xx: a + b * adj.xx + Ce.xx * c,
            xy: b * adj.xy + Ce.xy * c,
            xz: b * adj.xz + Ce.xz * c,
            yy: a + b * adj.yy + Ce.yy * c,
            yz: b * adj.yz + Ce.yz * c,
            zz: a + b * adj.zz + Ce.zz * c,
        }
    }

    /// Solid second Piola–Kirchhoff stress `S_s = J_a F_a⁻¹ S_e F_a⁻ᵀ`, symmetric.
    #[inline(always)]
    fn pk2_solid_full_sym<T: Real>(&self, F: &Matrix3<T>, Fa: &Matrix3<f64>) -> Sym3<T> {
        let (Ce, Fa_inv, Ja) = elastic_right_cauchy_green_full(F, Fa);
        let Se = self.pk2_elastic_full_sym(Ce);
        match Fa_inv {
            None => Se,
            // G S Gᵀ = (Gᵀ)ᵀ S Gᵀ, with √J_a on each side.
            Some(G) => Se.congruence(&(G.transpose() * Ja.sqrt())),
        }
    }

    /// First Piola–Kirchhoff stress of the solid phase, `P_s = F J_a F_a⁻¹ S_e F_a⁻ᵀ` \[Pa\],
    /// 3 × 3; it equals `∂Ψ/∂F` ([`Self::energy_full`]).
    pub fn piola_solid_full<T: Real>(&self, F: &Matrix3<T>, Fa: &Matrix3<f64>) -> Matrix3<T> {
        self.pk2_solid_full_sym(F, Fa).left_mul(F)
    }
}

impl Viscosity {
    /// Viscous first Piola–Kirchhoff stress `P_f = F S_f` \[Pa\] with a full 3 × 3 `F`, `Ḟ`:
    /// `S_f = (Jλ_f/2) tr(C⁻¹Ċ) C⁻¹ + Jμ_f C⁻¹ĊC⁻¹`, evaluated as
    /// `P_f = σ cof F`, `σ = λ_f tr(d) I + 2μ_f d`, `d = sym(ḞF⁻¹)` (the same tensor;
    /// module notes). Linear in `Ḟ`, zero for rigid rates `Ḟ = WF`, `W` skew.
    pub fn piola_viscous_full<T: Real>(&self, F: &Matrix3<T>, Fdot: &Matrix3<T>) -> Matrix3<T> {
        let adj = adjugate(F);
        let J = det_with(F, &adj);
        // Lh = Ḟ adj(F) = J L, L = ḞF⁻¹.
        let Lh = Fdot * adj;
        let inv_J = J.recip();
        let vol = (Lh[(0, 0)] + Lh[(1, 1)] + Lh[(2, 2)]) * inv_J * self.lambda_f;
        let mu = inv_J * self.mu_f;
        // σ = vol I + μ_f (L + Lᵀ), symmetric.
        let sigma = Sym3 {
            xx: vol + Lh[(0, 0)] * mu * 2.0,
            xy: (Lh[(0, 1)] + Lh[(1, 0)]) * mu,
            xz: (Lh[(0, 2)] + Lh[(2, 0)]) * mu,
            yy: vol + Lh[(1, 1)] * mu * 2.0,
            yz: (Lh[(1, 2)] + Lh[(2, 1)]) * mu,
            zz: vol + Lh[(2, 2)] * mu * 2.0,
        };
        // σ cof F = σ adj(F)ᵀ = (adj(F) σ)ᵀ
        sigma.left_mul(&adj).transpose()
    }
}

/// Total first Piola–Kirchhoff stress `P = F(S_s + S_f)` \[Pa\] with a full 3 × 3 `F`, `Ḟ`,
/// `F_a` (solid with active strain plus viscosity). Generic: `f64` for residuals.
pub fn piola_total_full<T: Real>(
    yeoh: &Yeoh,
    visc: &Viscosity,
    F: &Matrix3<T>,
    Fdot: &Matrix3<T>,
    Fa: &Matrix3<f64>,
) -> Matrix3<T> {
    yeoh.piola_solid_full(F, Fa) + visc.piola_viscous_full(F, Fdot)
}

/// `true` when `F` is finite with `det F > 0` (then `det F_e = det F / det F_a > 0` for
/// any admissible active strain, `det F_a > 0`). The stress functions assume it.
#[inline]
pub fn admissible_full(F: &Matrix3<f64>) -> bool {
    F.iter().all(|v| v.is_finite()) && F.determinant() > 0.0
}

/// The material point of the 3-D model (the flattening `3i + J`, `3k + L`).
pub type MaterialPointFull = super::law::MaterialPointOf<3, FULL_ENTRIES>;

/// `P` and its exact tangents `∂P/∂F`, `∂P/∂Ḟ` at one material point of the 3-D model, in
/// closed form (module notes): the solid's through `∂S_s/∂C` written with `M = F_a⁻¹F_a⁻ᵀ`
/// and `C⁻¹` (no push-forward of a fourth-order tensor), the viscous ones from
/// `P_f = Jσ F⁻ᵀ`.
///
/// Measured with `benches/kernels3.rs` (criterion, release, 256 inputs, half with active
/// strain; a shared 2-core machine, so ratios, over three runs): 0.24–0.26 µs per call,
/// 3.3–3.5 × the residual-only [`piola_total_full`] in `f64` and 1.6–1.9 × plane strain's
/// [`super::material_point`]; one `DualSVec64<9>` pass ([`super::dual_material_point`]) costs
/// 7–10 × as much (1.9–2.4 µs) instantiated in the calling crate as here, and 3.5–4.8 ×
/// (1.2–1.3 µs) when it was compiled in this crate. `P` agrees with [`piola_total_full`] to
/// round-off (the same stress summed in another order).
///
/// Assumes [`admissible_full`]`(F)` and `det F_a > 0`.
#[inline]
pub fn material_point_full(
    yeoh: &Yeoh,
    visc: &Viscosity,
    F: &Matrix3<f64>,
    Fdot: &Matrix3<f64>,
    Fa: &Matrix3<f64>,
) -> MaterialPointFull {
    let adj = adjugate(F);
    let J = det_with(F, &adj);
    let H = adj / J; // F⁻¹
    let V = H.transpose(); // F C⁻¹ = F⁻ᵀ
    let Ci = H * V; // C⁻¹ = F⁻¹F⁻ᵀ
    let (M, U, Ja) = match active_inverse(Fa) {
        None => (Matrix3::identity(), *F, 1.0),
        Some((G, Ja)) => {
            let M = G * G.transpose();
            (M, F * M, Ja)
        }
    };
    let B = U * F.transpose(); // F M Fᵀ
    // Invariants of C_e: I₁ = C : M = F : FM, J_e = J/J_a, s = I₃^{1/3} = J_e^{2/3}.
    let I1 = F.dot(&U);
    let TangentScalars {
        a,
        k,
        c,
        ap_beta,
        m4_ap_s,
        kappa,
        ..
    } = yeoh.tangent_scalars(I1, J / Ja);
    // S_s = J_a(a M + k C⁻¹ + c MCM), MCM = UᵀU; P_s = F S_s = J_a(a U + k V + c B U).
    let S = (M * a + Ci * k + U.transpose() * U * c) * Ja;
    let Ps = (U * a + V * k + B * U * c) * Ja;

    // Viscous: L = ḞF⁻¹, σ = λ_f tr(L) I + μ_f(L + Lᵀ), P_f = Jσ F⁻ᵀ.
    let L = Fdot * H;
    let trL = L.trace();
    let sigma = Matrix3::identity() * (visc.lambda_f * trL) + (L + L.transpose()) * visc.mu_f;
    let Pf = sigma * V * J;
    let HL = H * L;
    let (jl, jm) = (J * visc.lambda_f, J * visc.mu_f);

    // The terms of ∂P/∂F (module notes) grouped by the shape of their index pattern:
    //   X_iJ Y_kL (rank one), X_iL Y_kJ (swapped), X_ik Y_JL (paired), δ_ik X_LJ:
    //   rank one: (c₁U + c₂V) ⊗ U + (c₂U + c₃V + P_f) ⊗ V − Jλ_f V ⊗ (HL)ᵀ,
    //   swapped: c U_iL U_kJ + V_iL (−k V − Jμ_f (HL)ᵀ)_kJ − P_f,iL V_kJ,
    //   paired: c B_ik M_JL − Jμ_f L_ik C⁻¹_LJ,
    //   δ_ik (S_LJ − k C⁻¹_JL),
    // with c, k, c₁, c₂, c₃ times J_a; and ∂P/∂Ḟ = Jλ_f V ⊗ V + Jμ_f V_iL V_kJ
    //   + δ_ik Jμ_f C⁻¹_LJ.
    let (c1, c2, c3) = (Ja * 4.0 * ap_beta, Ja * m4_ap_s, Ja * 2.0 * kappa);
    let (kj, cj) = (Ja * k, Ja * c);
    let HLt = HL.transpose();
    let rows = |m: &Matrix3<f64>| -> [[f64; 3]; 3] {
        std::array::from_fn(|i| std::array::from_fn(|j| m[(i, j)]))
    };
    let r1 = rows(&(U * c1 + V * c2));
    let r2 = rows(&(U * c2 + V * c3 + Pf));
    let y = rows(&(HLt * -jl));
    let z = rows(&(V * -kj - HLt * jm));
    let bc = rows(&(B * cj));
    let lm = rows(&(L * jm));
    let dk = rows(&(S - Ci * kj));
    let cim = rows(&(Ci * jm));
    let (u, v, pf, m, ci) = (rows(&U), rows(&V), rows(&Pf), rows(&M), rows(&Ci));
    let (vl, vm) = (rows(&(V * jl)), rows(&(V * jm)));

    let mut dP_dF = SMatrix::<f64, FULL_ENTRIES, FULL_ENTRIES>::zeros();
    let mut dP_dFdot = SMatrix::<f64, FULL_ENTRIES, FULL_ENTRIES>::zeros();
    for kk in 0..3 {
        for l in 0..3 {
            let col = 3 * kk + l;
            for i in 0..3 {
                for j in 0..3 {
                    let row = 3 * i + j;
                    let mut val = r1[i][j] * u[kk][l]
                        + r2[i][j] * v[kk][l]
                        + v[i][j] * y[kk][l]
                        + cj * u[i][l] * u[kk][j]
                        + v[i][l] * z[kk][j]
                        - pf[i][l] * v[kk][j]
                        + bc[i][kk] * m[j][l]
                        - lm[i][kk] * ci[l][j];
                    let mut rate = vl[i][j] * v[kk][l] + vm[i][l] * v[kk][j];
                    if i == kk {
                        val += dk[l][j];
                        rate += cim[l][j];
                    }
                    dP_dF[(row, col)] = val;
                    dP_dFdot[(row, col)] = rate;
                }
            }
        }
    }
    MaterialPointFull {
        P: Ps + Pf,
        dP_dF,
        dP_dFdot,
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::physics::dual_material_point;

    /// [`material_point_full`] by forward-mode dual numbers ([`dual_material_point`]: one
    /// `DualSVec64<9>` pass of [`piola_total_full`] over `F`, `∂P/∂Ḟ` from the linearity of
    /// `P_f` in `Ḟ`), as [`super::super::material_point`] does in plane strain: the
    /// independent reference for the closed form.
    fn by_duals(m: (&Yeoh, &Viscosity), [F, Fdot, Fa]: [&Matrix3<f64>; 3]) -> MaterialPointFull {
        let piola = |Fd: &_, Gd: &_| piola_total_full(m.0, m.1, Fd, Gd, Fa);
        dual_material_point(F, Fdot, piola, |E| m.1.piola_viscous_full(F, E))
    }
    use crate::physics::hoop::{BlockDiag, HOOP, material_point_hoop, piola_total_hoop};
    use crate::physics::plane_strain::tests::{Rng, active, cytoplasm};
    use crate::physics::{material_point, piola_total, reference};
    use nalgebra::{Matrix2, Rotation3, SVector, Vector3};

    type V9 = SVector<f64, FULL_ENTRIES>;

    /// The entries of a 3 × 3 tensor, row-major (index 3k + l), the layout of the tangents.
    pub(in crate::physics) fn flat9(m: &Matrix3<f64>) -> V9 {
        V9::from_iterator((0..FULL_ENTRIES).map(|c| m[(c / 3, c % 3)]))
    }

    /// `A₂ ⊕ a₃₃`.
    pub(in crate::physics) fn embed(A: &Matrix2<f64>, a33: f64) -> Matrix3<f64> {
        Matrix3::new(
            A[(0, 0)],
            A[(0, 1)],
            0.0,
            A[(1, 0)],
            A[(1, 1)],
            0.0,
            0.0,
            0.0,
            a33,
        )
    }

    /// The 3-D tangent `big` (on the flattened 3 × 3 entries) restricted to the rows and
    /// columns `idx` equals the lower-dimensional tangent `small`, to 1e-12 of its norm.
    fn assert_sub_tangent<const M: usize>(
        big: &SMatrix<f64, FULL_ENTRIES, FULL_ENTRIES>,
        small: &SMatrix<f64, M, M>,
        idx: &[usize; M],
        what: &str,
    ) {
        for (r, &rb) in idx.iter().enumerate() {
            for (c, &cb) in idx.iter().enumerate() {
                let (a, b) = (big[(rb, cb)], small[(r, c)]);
                assert!(
                    (a - b).abs() < 1e-12 * small.norm(),
                    "{what} ({r},{c}) {a} vs {b}"
                );
            }
        }
    }

    /// A random rotation (axis-angle with the angle up to π).
    pub(in crate::physics) fn rotation(rng: &mut Rng) -> Matrix3<f64> {
        let v = Vector3::new(
            rng.uniform(-1.8, 1.8),
            rng.uniform(-1.8, 1.8),
            rng.uniform(-1.8, 1.8),
        );
        Rotation3::from_scaled_axis(v).into_inner()
    }

    /// A random F with entries I + U(−s, s), det F ≥ 0.3.
    fn deformation(rng: &mut Rng, s: f64) -> Matrix3<f64> {
        loop {
            let F = Matrix3::identity() + Matrix3::from_fn(|_, _| rng.uniform(-s, s));
            if F.determinant() >= 0.3 {
                return F;
            }
        }
    }

    /// A large strain: `R₁ diag(λ) R₂` with principal stretches λ ∈ [0.5, 2).
    fn large_strain(rng: &mut Rng) -> Matrix3<f64> {
        let l = Matrix3::from_diagonal(&Vector3::new(
            rng.uniform(0.5, 2.0),
            rng.uniform(0.5, 2.0),
            rng.uniform(0.5, 2.0),
        ));
        rotation(rng) * l * rotation(rng)
    }

    /// A symmetric active strain `I − a T⊗T − b N⊗N` like the model's, with orthonormal
    /// `N`, `T` in a random orientation; I when not `on`.
    fn active_strain(rng: &mut Rng, on: bool) -> Matrix3<f64> {
        if !on {
            return Matrix3::identity();
        }
        let (a, b) = (rng.uniform(0.0, 0.7), rng.uniform(0.0, 0.7));
        let R = rotation(rng);
        let (n, t) = (R.column(0).into_owned(), R.column(1).into_owned());
        Matrix3::identity() - t * t.transpose() * a - n * n.transpose() * b
    }

    /// The inputs of the random tests: F near I, moderate and large, with and without
    /// active strain.
    pub(in crate::physics) fn cases(rng: &mut Rng, n: usize) -> Vec<(Matrix3<f64>, Matrix3<f64>)> {
        (0..n)
            .map(|case| {
                let F = match case % 3 {
                    0 => deformation(rng, 0.05),
                    1 => deformation(rng, 0.5),
                    _ => large_strain(rng),
                };
                (F, active_strain(rng, (case / 3) % 2 == 1))
            })
            .collect()
    }

    fn rel(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
        (a - b).norm() / b.norm()
    }

    fn shear_viscosity() -> Viscosity {
        Viscosity {
            lambda_f: 3.0,
            mu_f: 2.0,
        }
    }

    #[test]
    fn energy_uses_the_invariants_of_model_md() {
        // W from I₂ = ½(I₁² − tr C²) and I₃ = det C computed by nalgebra, against
        // strain_energy_full_sym (principal minors and the adjugate).
        let mut rng = Rng::new(41);
        let m = Yeoh::from_engineering(500.0, 0.3, 1.5, 0.2).unwrap();
        for _ in 0..10 {
            let F = deformation(&mut rng, 0.5);
            let C = F.transpose() * F;
            let I1 = C.trace();
            let I2 = 0.5 * (I1 * I1 - (C * C).trace());
            let I3 = C.determinant();
            let X = I1 - 3.0 * I3.cbrt();
            let W = m.alpha1 * X
                + m.alpha2 * X * X
                + m.alpha3 * X * X * X
                + m.beta * (I2 - 3.0 * I3.powf(2.0 / 3.0))
                + 0.5 * m.lambda_y * (0.5 * I3.ln()).powi(2);
            let w = m.strain_energy_full_sym(Sym3::from_upper(&C));
            assert!((w - W).abs() < 1e-12 * W.abs().max(1.0), "{w} vs {W}");
            assert_eq!(m.energy_full(&F, &Matrix3::identity()), w);
        }
    }

    #[test]
    fn closed_form_tangent_equals_the_dual_pass() {
        let mut rng = Rng::new(53);
        for visc in [reference::viscosity(), shear_viscosity()] {
            for mat in [
                cytoplasm(),
                Yeoh::from_engineering(500.0, 0.3, 1.5, 0.2).unwrap(),
            ] {
                for (case, (F, Fa)) in cases(&mut rng, 12).into_iter().enumerate() {
                    let Fdot = Matrix3::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                    let a = material_point_full(&mat, &visc, &F, &Fdot, &Fa);
                    let d = by_duals((&mat, &visc), [&F, &Fdot, &Fa]);
                    // dual arithmetic rounds differently from f64 in the last bits
                    let P = piola_total_full(&mat, &visc, &F, &Fdot, &Fa);
                    assert!(rel(&d.P, &P) < 1e-14, "case {case}");
                    let eF = (a.dP_dF - d.dP_dF).norm() / d.dP_dF.norm();
                    let eV = (a.dP_dFdot - d.dP_dFdot).norm() / d.dP_dFdot.norm();
                    assert!(eF < 1e-12, "case {case}: dP/dF {eF:e}");
                    assert!(eV < 1e-13, "case {case}: dP/dFdot {eV:e}");
                }
            }
        }
    }

    #[test]
    fn stress3_is_frame_indifferent() {
        // P(QF) = Q P(F) for the solid (with and without F_a) and P_f(QF, QḞ) = Q P_f(F, Ḟ)
        // for the viscous stress (Q constant).
        let mat = cytoplasm();
        let visc = shear_viscosity();
        let mut rng = Rng::new(59);
        for (case, (F, Fa)) in cases(&mut rng, 12).into_iter().enumerate() {
            let Q = rotation(&mut rng);
            let P = mat.piola_solid_full(&F, &Fa);
            assert!(
                rel(&mat.piola_solid_full(&(Q * F), &Fa), &(Q * P)) < 1e-12,
                "case {case}"
            );
            let G = Matrix3::from_fn(|_, _| rng.uniform(-1.0, 1.0));
            let Pf = visc.piola_viscous_full(&F, &G);
            assert!(rel(&visc.piola_viscous_full(&(Q * F), &(Q * G)), &(Q * Pf)) < 1e-12);
        }
    }

    #[test]
    fn reference_and_pure_active_states_are_stress_free() {
        let mat = cytoplasm();
        let visc = reference::viscosity();
        let I = Matrix3::identity();
        let P = piola_total_full(&mat, &visc, &I, &Matrix3::zeros(), &I);
        assert!(P.norm() < 1e-13, "P(I) = {P}");
        assert!(
            material_point_full(&mat, &visc, &I, &Matrix3::zeros(), &I)
                .P
                .norm()
                < 1e-13
        );
        assert!(mat.energy_full(&I, &I).abs() < 1e-13);
        // F = F_a and F = R F_a: F_e is a rotation, no elastic stress (to the round-off of
        // the terms of size λ_Y that cancel: measured ≈ 1e-15 λ_Y).
        let tol = 1e-14 * mat.lambda_y;
        let mut rng = Rng::new(61);
        for _ in 0..5 {
            let Fa = active_strain(&mut rng, true);
            assert!(mat.piola_solid_full(&Fa, &Fa).norm() < tol);
            let R = rotation(&mut rng);
            assert!(mat.piola_solid_full(&(R * Fa), &Fa).norm() < tol);
            let mp = material_point_full(&mat, &visc, &(R * Fa), &Matrix3::zeros(), &Fa);
            assert!(mp.P.norm() < tol);
        }
        // F = I with a non-trivial F_a is stressed.
        assert!(
            mat.piola_solid_full(&I, &active_strain(&mut rng, true))
                .norm()
                > 1.0
        );
    }

    #[test]
    fn small_strain_limit_is_linear_elasticity() {
        // P(I + εH)/ε → λ tr(H) I + μ(H + Hᵀ), error O(ε).
        let (e, nu) = (100.0, 0.485);
        let mat = Yeoh::from_engineering(e, nu, 0.1, 0.2).unwrap();
        let mu = e / (2.0 * (1.0 + nu));
        let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mut rng = Rng::new(67);
        let I = Matrix3::identity();
        for _ in 0..5 {
            let H = Matrix3::from_fn(|_, _| rng.uniform(-1.0, 1.0));
            let lin = I * (lam * H.trace()) + (H + H.transpose()) * mu;
            let err = |eps: f64| rel(&(mat.piola_solid_full(&(I + H * eps), &I) / eps), &lin);
            let (e5, e6) = (err(1e-5), err(1e-6));
            assert!(e6 < 1e-5, "error at ε = 1e-6: {e6:e}");
            let ratio = e5 / e6;
            assert!((5.0..20.0).contains(&ratio), "ratio {ratio}");
        }
        // and the tangent at I is the isotropic elasticity tensor
        let mp = material_point_full(
            &mat,
            &Viscosity {
                lambda_f: 0.0,
                mu_f: 0.0,
            },
            &I,
            &I,
            &I,
        );
        for c in 0..FULL_ENTRIES {
            let mut E = Matrix3::zeros();
            E[(c / 3, c % 3)] = 1.0;
            let col = I * (lam * E.trace()) + (E + E.transpose()) * mu;
            assert!((mp.dP_dF.column(c) - flat9(&col)).norm() < 1e-11 * lam);
        }
    }

    #[test]
    fn viscous_stress3_is_the_model_md_formula_newtonian_and_objective() {
        let mut rng = Rng::new(71);
        for visc in [reference::viscosity(), shear_viscosity()] {
            for _ in 0..10 {
                let F = deformation(&mut rng, 0.5);
                let G = Matrix3::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                // MODEL.md §3 literally: S_f = (Jλ_f/2) tr(C⁻¹Ċ) C⁻¹ + Jμ_f C⁻¹ĊC⁻¹.
                let J = F.determinant();
                let C = F.transpose() * F;
                let Ci = C.try_inverse().unwrap();
                let Cd = G.transpose() * F + F.transpose() * G;
                let Sf = Ci * (0.5 * J * visc.lambda_f * (Ci * Cd).trace())
                    + Ci * Cd * Ci * (J * visc.mu_f);
                let P = visc.piola_viscous_full(&F, &G);
                let scale = (visc.lambda_f + visc.mu_f) * G.norm();
                assert!((P - F * Sf).norm() < 1e-13 * scale);
                // a rigid rate Ḟ = WF is not resisted, a stretching rate of that size is
                let w = Vector3::new(rng.uniform(-2.0, 2.0), rng.uniform(-2.0, 2.0), 0.3);
                let W = w.cross_matrix();
                let scale = (visc.lambda_f + visc.mu_f) * (W * F).norm();
                assert!(visc.piola_viscous_full(&F, &(W * F)).norm() < 1e-13 * scale);
                let D = Matrix3::from_diagonal(&w) * F;
                assert!(visc.piola_viscous_full(&F, &D).norm() > 1e-3 * visc.mu_f * D.norm());
            }
        }
        // at F = I: P = σ = λ_f tr(d) I + 2μ_f d
        let visc = shear_viscosity();
        let G = Matrix3::new(0.3, -0.7, 0.2, -0.1, 0.5, 0.4, 0.9, -0.2, 0.1);
        let d = (G + G.transpose()) * 0.5;
        let sigma = Matrix3::identity() * (3.0 * d.trace()) + d * 4.0;
        assert!(rel(&visc.piola_viscous_full(&Matrix3::identity(), &G), &sigma) < 1e-15);
    }

    #[test]
    fn with_f33_one_the_laws_and_tangents_are_the_plane_strain_ones() {
        // F = F₂ ⊕ 1, Ḟ = Ḟ₂ ⊕ 0, F_a = F_a2 ⊕ 1: in-plane blocks of P, ∂P/∂F and ∂P/∂Ḟ
        // equal plane strain's; the out-of-plane shear entries vanish.
        let mut rng = Rng::new(73);
        let mat = cytoplasm();
        let inplane = [0, 1, 3, 4]; // 3i + J for i, J ∈ {0, 1}
        for visc in [reference::viscosity(), shear_viscosity()] {
            for case in 0..20 {
                let F2 = rng.deformation(0.5);
                let G2 = Matrix2::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                let Fa2 = rng.active_strain(case % 2 == 1);
                let (F, G, Fa) = (embed(&F2, 1.0), embed(&G2, 0.0), embed(&Fa2, 1.0));
                let P2 = piola_total(&mat, &visc, &F2, &G2, &Fa2);
                let scale = P2.norm() + mat.lambda_y;
                let mp2 = material_point(&mat, &visc, &F2, &G2, &Fa2);
                for (name, mp) in [
                    ("closed form", material_point_full(&mat, &visc, &F, &G, &Fa)),
                    ("dual", by_duals((&mat, &visc), [&F, &G, &Fa])),
                ] {
                    let P3 = piola_total_full(&mat, &visc, &F, &G, &Fa);
                    for P in [P3, mp.P] {
                        let block = P.fixed_view::<2, 2>(0, 0);
                        assert!((block - P2).norm() < 1e-13 * scale, "{name} case {case}");
                        for (i, j) in [(0, 2), (1, 2), (2, 0), (2, 1)] {
                            assert!(P[(i, j)].abs() < 1e-13 * scale);
                        }
                    }
                    let what = format!("{name} case {case}");
                    assert_sub_tangent(&mp.dP_dF, &mp2.dP_dF, &inplane, &format!("{what}: dP/dF"));
                    assert_sub_tangent(&mp.dP_dFdot, &mp2.dP_dFdot, &inplane, &what);
                }
            }
        }
    }

    #[test]
    fn with_a_hoop_stretch_the_laws_and_tangents_are_the_axisymmetric_ones() {
        // F = F₂ ⊕ λ, Ḟ = Ḟ₂ ⊕ λ̇, F_a = F_a2 ⊕ 1: the in-plane blocks and the 33 entries
        // equal the hoop model's (P, and the 5 × 5 tangents on (F₂, λ)).
        let mut rng = Rng::new(79);
        let mat = cytoplasm();
        let idx = [0, 1, 3, 4, 8]; // the hoop flattening in the 3-D one (HOOP = 4 ↦ 8)
        assert_eq!(idx[HOOP], 8);
        for visc in [reference::viscosity(), shear_viscosity()] {
            for case in 0..20 {
                let F2 = rng.deformation(0.5);
                let G2 = Matrix2::from_fn(|_, _| rng.uniform(-1.0, 1.0));
                let (l, ld) = (rng.uniform(0.6, 1.6), rng.uniform(-1.0, 1.0));
                let Fa2 = if case % 2 == 1 {
                    active(0.5, 0.3, rng.uniform(-3.0, 3.0))
                } else {
                    Matrix2::identity()
                };
                let Fh = BlockDiag::new(F2, l);
                let Gh = BlockDiag::new(G2, ld);
                let Ph = piola_total_hoop(&mat, &visc, &Fh, &Gh, &Fa2);
                let mph = material_point_hoop(&mat, &visc, &Fh, &Gh, &Fa2);
                let (F, G, Fa) = (embed(&F2, l), embed(&G2, ld), embed(&Fa2, 1.0));
                let scale = Ph.plane.norm() + Ph.hoop.abs() + mat.lambda_y;
                let mp = material_point_full(&mat, &visc, &F, &G, &Fa);
                for P in [piola_total_full(&mat, &visc, &F, &G, &Fa), mp.P] {
                    assert!((P.fixed_view::<2, 2>(0, 0) - Ph.plane).norm() < 1e-13 * scale);
                    assert!((P[(2, 2)] - Ph.hoop).abs() < 1e-13 * scale, "case {case}");
                }
                let what = format!("case {case}");
                assert_sub_tangent(&mp.dP_dF, &mph.dP_dF, &idx, &format!("{what}: dP/dF"));
                assert_sub_tangent(&mp.dP_dFdot, &mph.dP_dFdot, &idx, &what);
            }
        }
    }

    #[test]
    fn admissibility() {
        assert!(admissible_full(&Matrix3::identity()));
        assert!(!admissible_full(&Matrix3::from_diagonal(&Vector3::new(
            1.0, 1.0, -0.1
        ))));
        assert!(!admissible_full(&Matrix3::from_diagonal(&Vector3::new(
            1.0, 1.0, 0.0
        ))));
        let mut F = Matrix3::identity();
        F[(0, 2)] = f64::NAN;
        assert!(!admissible_full(&F));
    }
}
