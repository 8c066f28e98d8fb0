//! Fibres in the cytoplasm (MODEL.md §11): the anisotropic term of Nolan et al. (2014) on
//! the full fourth invariant, added to the solid's energy in the active regions,
//!
//! `W_fib = χ (k₁/(2k₂)) [exp(k₂ ⟨I₄ − 1⟩²) − 1]`, `I₄ = a·C_e a`,
//!
//! with `a` the region's unit reference fibre direction (`T` in the PAC, `N` in the bottom
//! region), `χ` its smooth indicator and `⟨x⟩ = x S(x; −δ, δ)` a C² ramp: the fibres resist
//! stretch, not shortening, and stress and tangent are continuous.
//!
//! **Written once for every kinematics.** With `F_a` the active strain, `C_e = F_a⁻ᵀ C F_a⁻¹`
//! and `b = F_a⁻¹ a`, `I₄ = b·C b = |F b|²`. The energy per unit reference volume is
//! `Ψ = J_a W_fib`, so with `ψ(x) = (k₁/(2k₂))[exp(k₂⟨x⟩²) − 1]` and `x = |Fb|² − 1`
//! (`∂x/∂F_kL = 2 (Fb)_k b_L`):
//!
//! `P_iJ = 2 J_a χ ψ′ (Fb)_i b_J`,
//! `∂P_iJ/∂F_kL = 2 J_a χ [ψ′ δ_ik b_J b_L + 2ψ″ (Fb)_i b_J (Fb)_k b_L]`,
//!
//! `ψ′ = k₁ r r′ e^{k₂r²}`, `ψ″ = k₁ e^{k₂r²} (r′² + r r″ + 2k₂ r² r′²)`, `r = ⟨x⟩`. These
//! hold for any `D × D` gradient whose fibre lies in it: the plane-strain block, the meridian
//! block of the axisymmetric model (`T` and `N` lie in the meridian plane, so the hoop entry
//! gains nothing) and the 3-D gradient. The fibre term does not depend on `Ḟ`.
//!
//! In the small-strain limit under stretch along `a` (`x > δ`) the tangent gains
//! `2ψ′ + 4ψ″ → 4k₁` in its `(a, a, a, a)` component; under shortening (`x ≤ −δ`) nothing.

#![allow(non_snake_case)]

use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

use super::smooth::smooth_step_d;
use super::{PhysicsError, check};

/// The fibre law's parameters (MODEL.md §11).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Fibres {
    /// Stiffness `k₁` \[Pa\].
    pub k1: f64,
    /// Exponential stiffening `k₂` (dimensionless).
    pub k2: f64,
    /// Half-width `δ` of the ramp `⟨x⟩ = x S(x; −δ, δ)` (MODEL.md: 1e-3).
    pub delta: f64,
}

/// One fibre family at a material point: its unit reference direction `a` and the region's
/// indicator `χ` there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fibre<const D: usize> {
    /// Unit reference direction `a`.
    pub a: SVector<f64, D>,
    /// Indicator `χ` ∈ [0, 1].
    pub chi: f64,
}

/// A fibre family in the current active strain: `b = F_a⁻¹ a` and the weight `J_a χ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ActiveFibre<const D: usize> {
    /// `b = F_a⁻¹ a`, so `I₄ = |F b|²`.
    pub b: SVector<f64, D>,
    /// `J_a χ`: the energy is per unit intermediate volume.
    pub weight: f64,
}

impl<const D: usize> Fibre<D> {
    /// No fibres here (`χ = 0`; the direction is any unit vector).
    pub fn absent() -> Self {
        let mut a = SVector::zeros();
        a[0] = 1.0;
        Fibre { a, chi: 0.0 }
    }

    /// The family under the active strain `F_a` (`det F_a > 0`).
    #[inline]
    pub fn under(&self, Fa: &SMatrix<f64, D, D>) -> ActiveFibre<D> {
        if *Fa == SMatrix::<f64, D, D>::identity() {
            return ActiveFibre {
                b: self.a,
                weight: self.chi,
            };
        }
        let (ja, b) = det_and_solve(Fa, &self.a);
        ActiveFibre {
            b,
            weight: ja * self.chi,
        }
    }
}

/// `(det A, A⁻¹ v)` of a 2 × 2 or 3 × 3 `A` by its adjugate (`det A ≠ 0`).
#[inline]
fn det_and_solve<const D: usize>(
    A: &SMatrix<f64, D, D>,
    v: &SVector<f64, D>,
) -> (f64, SVector<f64, D>) {
    let mut x = SVector::<f64, D>::zeros();
    let det;
    if D == 2 {
        det = A[(0, 0)] * A[(1, 1)] - A[(0, 1)] * A[(1, 0)];
        x[0] = (A[(1, 1)] * v[0] - A[(0, 1)] * v[1]) / det;
        x[1] = (A[(0, 0)] * v[1] - A[(1, 0)] * v[0]) / det;
    } else {
        assert_eq!(D, 3, "fibres live in 2 or 3 dimensions");
        let a = |i: usize, j: usize| A[(i, j)];
        // adj(A)_ij = cofactor of A_ji
        let adj = [
            [
                a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1),
                a(0, 2) * a(2, 1) - a(0, 1) * a(2, 2),
                a(0, 1) * a(1, 2) - a(0, 2) * a(1, 1),
            ],
            [
                a(1, 2) * a(2, 0) - a(1, 0) * a(2, 2),
                a(0, 0) * a(2, 2) - a(0, 2) * a(2, 0),
                a(0, 2) * a(1, 0) - a(0, 0) * a(1, 2),
            ],
            [
                a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0),
                a(0, 1) * a(2, 0) - a(0, 0) * a(2, 1),
                a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0),
            ],
        ];
        det = a(0, 0) * adj[0][0] + a(0, 1) * adj[1][0] + a(0, 2) * adj[2][0];
        for i in 0..3 {
            x[i] = (adj[i][0] * v[0] + adj[i][1] * v[1] + adj[i][2] * v[2]) / det;
        }
    }
    (det, x)
}

impl Fibres {
    /// MODEL.md's ramp width δ = 1e-3.
    pub const DELTA: f64 = 1e-3;

    /// Checks `k₁ ≥ 0`, `k₂ > 0`, `0 < δ ≤ 0.1`, all finite (`k₂ ≤ 10`: `exp(k₂x²)`
    /// overflows near `x ≈ 8.4` for `k₂ = 10`, a stretch nobody asks of a cell).
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.k1.is_finite() && self.k1 >= 0.0,
            "k1",
            self.k1,
            "must be finite and >= 0",
        )?;
        check(
            self.k2.is_finite() && self.k2 > 0.0 && self.k2 <= 10.0,
            "k2",
            self.k2,
            "must lie in (0, 10]",
        )?;
        check(
            self.delta.is_finite() && self.delta > 0.0 && self.delta <= 0.1,
            "delta",
            self.delta,
            "must lie in (0, 0.1]",
        )
    }

    /// `(ψ, ψ′, ψ″)` at `x = I₄ − 1` (module notes).
    #[inline]
    pub fn scalars(&self, x: f64) -> (f64, f64, f64) {
        if x <= -self.delta {
            return (0.0, 0.0, 0.0);
        }
        let (s, s1, s2) = smooth_step_d(x, -self.delta, self.delta);
        let r = x * s;
        let r1 = s + x * s1;
        let r2 = 2.0 * s1 + x * s2;
        let q = self.k2 * r * r;
        let e = q.exp();
        // exp_m1: ψ ~ k₁r²/2 where r is small, without the cancellation of e − 1
        let psi = self.k1 / (2.0 * self.k2) * q.exp_m1();
        let d1 = self.k1 * r * r1 * e;
        let d2 = self.k1 * e * (r1 * r1 + r * r2 + 2.0 * self.k2 * r * r * r1 * r1);
        (psi, d1, d2)
    }

    /// Energy per unit reference volume `J_a χ ψ(|Fb|² − 1)` \[Pa\].
    pub fn energy<const D: usize>(&self, F: &SMatrix<f64, D, D>, f: &ActiveFibre<D>) -> f64 {
        let x = (F * f.b).norm_squared() - 1.0;
        f.weight * self.scalars(x).0
    }

    /// `P += 2 J_a χ ψ′ (Fb) ⊗ b`.
    #[inline]
    pub fn add_piola<const D: usize>(
        &self,
        F: &SMatrix<f64, D, D>,
        f: &ActiveFibre<D>,
        P: &mut SMatrix<f64, D, D>,
    ) {
        let fb = F * f.b;
        let (_, d1, _) = self.scalars(fb.norm_squared() - 1.0);
        if d1 != 0.0 {
            *P += fb * f.b.transpose() * (2.0 * f.weight * d1);
        }
    }

    /// `∂P_iJ/∂F_kL += 2 J_a χ [ψ′ δ_ik b_J b_L + 2ψ″ (Fb)_i b_J (Fb)_k b_L]`, in the
    /// flattening of [`super::MaterialPointOf`] (row `D i + J`, column `D k + L`) of an
    /// `M × M` tangent whose first `D²` entries are those of `F` (`M = D²`, or the
    /// axisymmetric model's five with the hoop entry last).
    #[inline]
    pub fn add_tangent<const D: usize, const M: usize>(
        &self,
        F: &SMatrix<f64, D, D>,
        f: &ActiveFibre<D>,
        dP: &mut SMatrix<f64, M, M>,
    ) {
        let fb = F * f.b;
        let (_, d1, d2) = self.scalars(fb.norm_squared() - 1.0);
        if d1 == 0.0 && d2 == 0.0 {
            return;
        }
        let c1 = 2.0 * f.weight * d1;
        let c2 = 4.0 * f.weight * d2;
        let b = &f.b;
        for i in 0..D {
            for J in 0..D {
                let gij = fb[i] * b[J];
                for k in 0..D {
                    for L in 0..D {
                        let mut v = c2 * gij * fb[k] * b[L];
                        if i == k {
                            v += c1 * b[J] * b[L];
                        }
                        dP[(D * i + J, D * k + L)] += v;
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};

    fn law(k1: f64, k2: f64) -> Fibres {
        Fibres {
            k1,
            k2,
            delta: Fibres::DELTA,
        }
    }

    /// A 2-D and a 3-D fibre, not along a coordinate axis.
    fn fibre2() -> Fibre<2> {
        let a = Vector2::new(0.6, 0.8);
        Fibre { a, chi: 0.7 }
    }

    fn fibre3() -> Fibre<3> {
        let a = Vector3::new(0.48, 0.6, 0.64);
        Fibre {
            a: a.normalize(),
            chi: 0.9,
        }
    }

    /// `F` near I (entries `I + s·h(seed)`), deterministic.
    fn deformation<const D: usize>(s: f64, seed: u64) -> SMatrix<f64, D, D> {
        let mut r = oorandom::Rand64::new(seed as u128);
        SMatrix::<f64, D, D>::identity()
            + SMatrix::<f64, D, D>::from_fn(|_, _| s * (2.0 * r.rand_float() - 1.0))
    }

    /// A symmetric active strain `I − α a⊗a − β n⊗n` like the model's (`n ⊥ a`).
    fn active2(f: &Fibre<2>, alpha: f64, beta: f64) -> Matrix2<f64> {
        let n = Vector2::new(-f.a.y, f.a.x);
        Matrix2::identity() - f.a * f.a.transpose() * alpha - n * n.transpose() * beta
    }

    fn active3(f: &Fibre<3>, alpha: f64) -> Matrix3<f64> {
        Matrix3::identity() - f.a * f.a.transpose() * alpha
    }

    /// A central-difference check: step `h`, tolerances relative to the stress's and the
    /// tangent's norms (each at least `floor`).
    struct Fd {
        h: f64,
        p_rel: f64,
        t_rel: f64,
        floor: f64,
    }

    /// Away from the ramp.
    const FD: Fd = Fd {
        h: 1e-6,
        p_rel: 1e-6,
        t_rel: 1e-6,
        floor: 1e-3,
    };

    /// Stress against central differences of the energy, tangent against central
    /// differences of the stress, at `F`.
    fn check_derivatives<const D: usize, const DD: usize>(
        m: &Fibres,
        F: &SMatrix<f64, D, D>,
        f: &ActiveFibre<D>,
        fd: &Fd,
    ) {
        let h = fd.h;
        let mut P = SMatrix::<f64, D, D>::zeros();
        m.add_piola(F, f, &mut P);
        let mut T = SMatrix::<f64, DD, DD>::zeros();
        m.add_tangent(F, f, &mut T);
        let scale_p = fd.p_rel * P.norm().max(fd.floor);
        let scale_t = fd.t_rel * T.norm().max(fd.floor);
        for k in 0..D {
            for l in 0..D {
                let mut Fp = *F;
                Fp[(k, l)] += h;
                let mut Fm = *F;
                Fm[(k, l)] -= h;
                let dw = (m.energy(&Fp, f) - m.energy(&Fm, f)) / (2.0 * h);
                assert!(
                    (dw - P[(k, l)]).abs() < scale_p,
                    "P[{k},{l}] = {} against dΨ/dF = {dw}",
                    P[(k, l)]
                );
                let (mut Pp, mut Pm) = (SMatrix::zeros(), SMatrix::zeros());
                m.add_piola(&Fp, f, &mut Pp);
                m.add_piola(&Fm, f, &mut Pm);
                let dP: SMatrix<f64, D, D> = (Pp - Pm) / (2.0 * h);
                for i in 0..D {
                    for j in 0..D {
                        let t = T[(D * i + j, D * k + l)];
                        assert!(
                            (dP[(i, j)] - t).abs() < scale_t,
                            "dP[{i}{j}]/dF[{k}{l}]: {t} against {}",
                            dP[(i, j)]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn stress_and_tangent_are_the_derivatives_of_the_energy_in_2d_and_3d() {
        let m = law(100.0, 1.0);
        for seed in 0..6 {
            // Stretched along the fibre (x well beyond δ), with and without active strain.
            let f2 = fibre2();
            let stretch2 = Matrix2::identity() + f2.a * f2.a.transpose() * 0.3;
            for Fa in [Matrix2::identity(), active2(&f2, 0.4, 0.2)] {
                let F = stretch2 * deformation::<2>(0.1, seed) * Fa;
                let af = f2.under(&Fa);
                assert!((F * af.b).norm_squared() - 1.0 > 0.05);
                check_derivatives::<2, 4>(&m, &F, &af, &FD);
            }
            let f3 = fibre3();
            let stretch3 = Matrix3::identity() + f3.a * f3.a.transpose() * 0.3;
            for Fa in [Matrix3::identity(), active3(&f3, 0.5)] {
                let F = stretch3 * deformation::<3>(0.1, seed) * Fa;
                let af = f3.under(&Fa);
                check_derivatives::<3, 9>(&m, &F, &af, &FD);
            }
        }
        // Inside the ramp |x| < δ, where ⟨x⟩ is the polynomial piece.
        let f = fibre2();
        for x in [-0.9e-3_f64, -0.3e-3, 0.2e-3, 0.8e-3] {
            let F = Matrix2::identity() + f.a * f.a.transpose() * ((1.0 + x).sqrt() - 1.0);
            let af = f.under(&Matrix2::identity());
            assert!(((F * af.b).norm_squared() - 1.0 - x).abs() < 1e-12);
            // A smaller step: the ramp's curvature is of order 1/δ².
            let ramp = Fd {
                h: 1e-9,
                p_rel: 1e-5,
                t_rel: 1e-4,
                floor: 1e-9,
            };
            check_derivatives::<2, 4>(&m, &F, &af, &ramp);
        }
    }

    #[test]
    fn the_ramp_is_c2_and_zero_in_shortening() {
        let m = law(1000.0, 1.0);
        // ψ, ψ', ψ'' continuous at ±δ (the ramp's ends)
        let d = Fibres::DELTA;
        for end in [-d, d] {
            let (a, b) = (m.scalars(end - 1e-12), m.scalars(end + 1e-12));
            assert!((a.0 - b.0).abs() < 1e-9);
            assert!((a.1 - b.1).abs() < 1e-7);
            assert!((a.2 - b.2).abs() < 1e-3 * (1.0 + a.2.abs()));
        }
        // Zero stress and tangent for I₄ ≤ 1 − δ, whatever the direction of shortening.
        let f = fibre3();
        let af = f.under(&Matrix3::identity());
        for s in [0.999, 0.9, 0.5] {
            let F = Matrix3::identity() + f.a * f.a.transpose() * (s - 1.0);
            let mut P = Matrix3::zeros();
            m.add_piola(&F, &af, &mut P);
            let mut T = SMatrix::<f64, 9, 9>::zeros();
            m.add_tangent(&F, &af, &mut T);
            assert_eq!(P, Matrix3::zeros());
            assert_eq!(T, SMatrix::<f64, 9, 9>::zeros());
            assert_eq!(m.energy(&F, &af), 0.0);
        }
        // A stretch across the fibre only (a ⊥ the stretch) gives x = 0: the ramp's middle,
        // ⟨0⟩ = 0 so no stress either.
        let n = Vector3::new(-f.a.y, f.a.x, 0.0).normalize();
        let F = Matrix3::identity() + n * n.transpose() * 0.5;
        let mut P = Matrix3::zeros();
        m.add_piola(&F, &af, &mut P);
        assert!(P.norm() < 1e-12);
    }

    #[test]
    fn small_strain_tangent_gains_4_k1_along_the_fibre_in_stretch_only() {
        let k1 = 100.0;
        let m = law(k1, 1.0);
        let f = fibre3();
        let af = Fibre { a: f.a, chi: 1.0 }.under(&Matrix3::identity());
        // Component (a, a, a, a): Σ a_i a_J a_k a_L ∂P_iJ/∂F_kL.
        let aaaa = |T: &SMatrix<f64, 9, 9>| {
            let mut s = 0.0;
            for i in 0..3 {
                for j in 0..3 {
                    for k in 0..3 {
                        for l in 0..3 {
                            s += f.a[i] * f.a[j] * f.a[k] * f.a[l] * T[(3 * i + j, 3 * k + l)];
                        }
                    }
                }
            }
            s
        };
        // Stretch by ε along a, beyond the ramp: tangent → 4k₁ as ε → 0 (error O(ε)).
        let mut prev = f64::INFINITY;
        for eps in [4e-2, 1e-2, 4e-3] {
            let F = Matrix3::identity() + f.a * f.a.transpose() * eps;
            let mut T = SMatrix::<f64, 9, 9>::zeros();
            m.add_tangent(&F, &af, &mut T);
            let err = (aaaa(&T) - 4.0 * k1).abs();
            assert!(
                err < 20.0 * eps * k1,
                "ε = {eps}: {} against {}",
                aaaa(&T),
                4.0 * k1
            );
            assert!(err < prev);
            prev = err;
        }
        // Shortening by ε: nothing.
        for eps in [4e-2, 1e-2, 4e-3] {
            let F = Matrix3::identity() - f.a * f.a.transpose() * eps;
            let mut T = SMatrix::<f64, 9, 9>::zeros();
            m.add_tangent(&F, &af, &mut T);
            assert_eq!(aaaa(&T), 0.0);
        }
    }

    #[test]
    fn the_fibre_under_an_active_strain_is_its_preimage() {
        let f = fibre3();
        let Fa = active3(&f, 0.4) + Matrix3::new(0.0, 0.1, 0.0, 0.05, 0.0, -0.1, 0.02, 0.0, 0.0);
        let af = f.under(&Fa);
        assert!((Fa * af.b - f.a).norm() < 1e-14);
        assert!((af.weight - Fa.determinant() * f.chi).abs() < 1e-14);
        let g = fibre2();
        let Ga = active2(&g, 0.3, 0.5) + Matrix2::new(0.0, 0.1, -0.2, 0.0);
        let ag = g.under(&Ga);
        assert!((Ga * ag.b - g.a).norm() < 1e-14);
        assert!((ag.weight - Ga.determinant() * g.chi).abs() < 1e-14);
    }

    #[test]
    fn a_2d_fibre_in_the_hoop_layout_leaves_the_hoop_entry_alone() {
        // The axisymmetric tangent has five entries, the meridian block's four then λ.
        let m = law(100.0, 1.0);
        let f = fibre2();
        let F = Matrix2::identity() + f.a * f.a.transpose() * 0.2;
        let af = f.under(&Matrix2::identity());
        let mut T4 = SMatrix::<f64, 4, 4>::zeros();
        m.add_tangent(&F, &af, &mut T4);
        let mut T5 = SMatrix::<f64, 5, 5>::zeros();
        m.add_tangent(&F, &af, &mut T5);
        assert_eq!(T5.fixed_view::<4, 4>(0, 0).into_owned(), T4);
        assert!(
            T5.row(4)
                .iter()
                .chain(T5.column(4).iter())
                .all(|&v| v == 0.0)
        );
        assert!(T4.norm() > 0.0);
    }

    #[test]
    fn frame_indifferent_and_the_active_strain_relaxes_the_fibre() {
        let m = law(100.0, 1.0);
        let f = fibre3();
        let F = Matrix3::identity() + f.a * f.a.transpose() * 0.3;
        let af = f.under(&Matrix3::identity());
        let R = nalgebra::Rotation3::from_euler_angles(0.3, -0.7, 1.1).into_inner();
        assert!((m.energy(&(R * F), &af) - m.energy(&F, &af)).abs() < 1e-12 * m.energy(&F, &af));
        let (mut P, mut PR) = (Matrix3::zeros(), Matrix3::zeros());
        m.add_piola(&F, &af, &mut P);
        m.add_piola(&(R * F), &af, &mut PR);
        assert!((PR - R * P).norm() < 1e-12 * P.norm());
        // F = F_a (the fibre shortened by the contraction, F_e = I): no fibre stress.
        let Fa = active3(&f, 0.3);
        let mut P = Matrix3::zeros();
        m.add_piola(&Fa, &f.under(&Fa), &mut P);
        assert!(P.norm() < 1e-12);
        // validation names the parameter
        assert!(law(-1.0, 1.0).validate().is_err());
        assert!(law(1.0, 0.0).validate().is_err());
        assert!(
            Fibres {
                delta: 0.0,
                ..law(1.0, 1.0)
            }
            .validate()
            .is_err()
        );
        assert!(law(1000.0, 1.0).validate().is_ok());
    }
}
