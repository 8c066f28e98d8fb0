//! The derivative checks of the material laws, written once and run for every law ×
//! kinematics: the solid law ([`Yeoh`], an [`super::IsotropicSolid`]) and the
//! Kelvin–Voigt viscosity ([`Viscosity`]) in plane strain (`F₂ ⊕ 1`), with the hoop
//! stretch (`F₂ ⊕ λ`) and in 3-D (3 × 3).
//!
//! - the solid stress against central differences of its energy `Ψ(F) = J_a W(C_e)`;
//! - the tangents `∂P/∂F` (solid and viscous) and `∂P/∂Ḟ` against central differences of
//!   the total stress, with the model's viscosity (`λ_f ≫ μ_f`) and one where the shear
//!   part matters;
//! - the solid's tangent alone symmetric (`∂²Ψ/∂F∂F`: a hyperelastic law).
//!
//! A kinematics under test ([`Kinematics`]) gives its random inputs, flattens `F` to its
//! independent entries (4, 5 or 9) and evaluates the laws as the element kernels do.

#![allow(non_snake_case)]

use nalgebra::{Matrix2, Matrix3};

use super::hoop::{BlockDiag, HOOP, material_point_hoop, piola_total_hoop};
use super::plane_strain::tests::{Rng, cytoplasm};
use super::three_d::tests::cases as cases3;
use super::{Viscosity, Yeoh, material_point, material_point_full, piola_total, piola_total_full};

/// A kinematics under test: its `F`, `F_a`, and the laws evaluated on them.
trait Kinematics {
    /// Name in messages.
    const NAME: &'static str;
    /// Central-difference step of the energy check (near `F = I` the stress is small
    /// beside the moduli: a smaller step keeps the truncation error below it).
    const H_ENERGY: f64;
    /// The deformation gradient (and its rate).
    type F: Clone;
    /// The active strain.
    type Fa;
    /// `n` random admissible `(F, F_a)`, with and without active strain.
    fn cases(rng: &mut Rng, n: usize) -> Vec<(Self::F, Self::Fa)>;
    /// A random rate `Ḟ`.
    fn rate(rng: &mut Rng) -> Self::F;
    /// The independent entries of `F`, in the order of the tangents' columns.
    fn entries(f: &Self::F) -> Vec<f64>;
    /// `F` from its entries.
    fn from_entries(e: &[f64]) -> Self::F;
    /// `Ψ(F) = J_a W(C_e)`.
    fn energy(law: &Yeoh, f: &Self::F, fa: &Self::Fa) -> f64;
    /// The solid's `P_s`, flattened.
    fn piola_solid(law: &Yeoh, f: &Self::F, fa: &Self::Fa) -> Vec<f64>;
    /// The total `P`, flattened.
    fn piola(law: &Yeoh, visc: &Viscosity, f: &Self::F, fdot: &Self::F, fa: &Self::Fa) -> Vec<f64>;
    /// The kernels' `(P, ∂P/∂F, ∂P/∂Ḟ)`, the tangents row-major.
    fn point(
        law: &Yeoh,
        visc: &Viscosity,
        f: &Self::F,
        fdot: &Self::F,
        fa: &Self::Fa,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>);
}

fn m2(m: &Matrix2<f64>) -> Vec<f64> {
    vec![m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]]
}

fn block(p: &BlockDiag<f64>) -> Vec<f64> {
    let mut v = m2(&p.plane);
    v.push(p.hoop);
    v
}

struct PlaneStrain;
struct Hoop;
struct ThreeD;

impl Kinematics for PlaneStrain {
    const NAME: &'static str = "plane strain";
    const H_ENERGY: f64 = 1e-5;
    type F = Matrix2<f64>;
    type Fa = Matrix2<f64>;
    fn cases(rng: &mut Rng, n: usize) -> Vec<(Matrix2<f64>, Matrix2<f64>)> {
        (0..n)
            .map(|c| (rng.deformation(0.5), rng.active_strain(c % 2 == 1)))
            .collect()
    }
    fn rate(rng: &mut Rng) -> Matrix2<f64> {
        Matrix2::from_fn(|_, _| rng.uniform(-1.0, 1.0))
    }
    fn entries(f: &Matrix2<f64>) -> Vec<f64> {
        m2(f)
    }
    fn from_entries(e: &[f64]) -> Matrix2<f64> {
        Matrix2::new(e[0], e[1], e[2], e[3])
    }
    fn energy(law: &Yeoh, f: &Matrix2<f64>, fa: &Matrix2<f64>) -> f64 {
        law.energy(f, fa)
    }
    fn piola_solid(law: &Yeoh, f: &Matrix2<f64>, fa: &Matrix2<f64>) -> Vec<f64> {
        m2(&law.piola_solid(f, fa))
    }
    fn piola(
        law: &Yeoh,
        visc: &Viscosity,
        f: &Matrix2<f64>,
        fdot: &Matrix2<f64>,
        fa: &Matrix2<f64>,
    ) -> Vec<f64> {
        m2(&piola_total(law, visc, f, fdot, fa))
    }
    fn point(
        law: &Yeoh,
        visc: &Viscosity,
        f: &Matrix2<f64>,
        fdot: &Matrix2<f64>,
        fa: &Matrix2<f64>,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let mp = material_point(law, visc, f, fdot, fa);
        let rows = |m: &nalgebra::Matrix4<f64>| m.transpose().iter().copied().collect();
        (m2(&mp.P), rows(&mp.dP_dF), rows(&mp.dP_dFdot))
    }
}

impl Kinematics for Hoop {
    const NAME: &'static str = "hoop stretch";
    const H_ENERGY: f64 = 1e-5;
    type F = BlockDiag<f64>;
    type Fa = Matrix2<f64>;
    fn cases(rng: &mut Rng, n: usize) -> Vec<(BlockDiag<f64>, Matrix2<f64>)> {
        (0..n)
            .map(|c| {
                let f = BlockDiag::new(rng.deformation(0.5), rng.uniform(0.6, 1.6));
                (f, rng.active_strain(c % 2 == 1))
            })
            .collect()
    }
    fn rate(rng: &mut Rng) -> BlockDiag<f64> {
        BlockDiag::new(
            Matrix2::from_fn(|_, _| rng.uniform(-1.0, 1.0)),
            rng.uniform(-1.0, 1.0),
        )
    }
    fn entries(f: &BlockDiag<f64>) -> Vec<f64> {
        block(f)
    }
    fn from_entries(e: &[f64]) -> BlockDiag<f64> {
        BlockDiag::new(Matrix2::new(e[0], e[1], e[2], e[3]), e[HOOP])
    }
    fn energy(law: &Yeoh, f: &BlockDiag<f64>, fa: &Matrix2<f64>) -> f64 {
        law.energy_hoop(f, fa)
    }
    fn piola_solid(law: &Yeoh, f: &BlockDiag<f64>, fa: &Matrix2<f64>) -> Vec<f64> {
        block(&law.piola_solid_hoop(f, fa))
    }
    fn piola(
        law: &Yeoh,
        visc: &Viscosity,
        f: &BlockDiag<f64>,
        fdot: &BlockDiag<f64>,
        fa: &Matrix2<f64>,
    ) -> Vec<f64> {
        block(&piola_total_hoop(law, visc, f, fdot, fa))
    }
    fn point(
        law: &Yeoh,
        visc: &Viscosity,
        f: &BlockDiag<f64>,
        fdot: &BlockDiag<f64>,
        fa: &Matrix2<f64>,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let mp = material_point_hoop(law, visc, f, fdot, fa);
        let rows = |m: &nalgebra::SMatrix<f64, 5, 5>| m.transpose().iter().copied().collect();
        (block(&mp.P), rows(&mp.dP_dF), rows(&mp.dP_dFdot))
    }
}

impl Kinematics for ThreeD {
    const NAME: &'static str = "3-D";
    const H_ENERGY: f64 = 1e-6;
    type F = Matrix3<f64>;
    type Fa = Matrix3<f64>;
    fn cases(rng: &mut Rng, n: usize) -> Vec<(Matrix3<f64>, Matrix3<f64>)> {
        cases3(rng, n)
    }
    fn rate(rng: &mut Rng) -> Matrix3<f64> {
        Matrix3::from_fn(|_, _| rng.uniform(-1.0, 1.0))
    }
    fn entries(f: &Matrix3<f64>) -> Vec<f64> {
        f.transpose().iter().copied().collect()
    }
    fn from_entries(e: &[f64]) -> Matrix3<f64> {
        Matrix3::from_row_slice(e)
    }
    fn energy(law: &Yeoh, f: &Matrix3<f64>, fa: &Matrix3<f64>) -> f64 {
        law.energy_full(f, fa)
    }
    fn piola_solid(law: &Yeoh, f: &Matrix3<f64>, fa: &Matrix3<f64>) -> Vec<f64> {
        Self::entries(&law.piola_solid_full(f, fa))
    }
    fn piola(
        law: &Yeoh,
        visc: &Viscosity,
        f: &Matrix3<f64>,
        fdot: &Matrix3<f64>,
        fa: &Matrix3<f64>,
    ) -> Vec<f64> {
        Self::entries(&piola_total_full(law, visc, f, fdot, fa))
    }
    fn point(
        law: &Yeoh,
        visc: &Viscosity,
        f: &Matrix3<f64>,
        fdot: &Matrix3<f64>,
        fa: &Matrix3<f64>,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let mp = material_point_full(law, visc, f, fdot, fa);
        let rows = |m: &nalgebra::SMatrix<f64, 9, 9>| m.transpose().iter().copied().collect();
        (Self::entries(&mp.P), rows(&mp.dP_dF), rows(&mp.dP_dFdot))
    }
}

/// Central differences of `g` with respect to each entry of `F`, step `h`: row-major,
/// entry (r, c) = ∂g_r/∂F_c.
fn central_differences<K: Kinematics>(f: &K::F, h: f64, g: impl Fn(&K::F) -> Vec<f64>) -> Vec<f64> {
    let e = K::entries(f);
    let columns: Vec<Vec<f64>> = (0..e.len())
        .map(|c| {
            let (mut p, mut m) = (e.clone(), e.clone());
            p[c] += h;
            m[c] -= h;
            let (gp, gm) = (g(&K::from_entries(&p)), g(&K::from_entries(&m)));
            gp.iter()
                .zip(&gm)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        })
        .collect();
    let rows = columns[0].len();
    (0..rows * e.len())
        .map(|k| columns[k % e.len()][k / e.len()])
        .collect()
}

/// `|a − b| / |b|` in the Frobenius norm.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    let n: f64 = b.iter().map(|y| y * y).sum();
    (d / n).sqrt()
}

/// The two solid laws of the checks: the cytoplasm's and a stiffening one.
fn laws() -> [Yeoh; 2] {
    [
        cytoplasm(),
        Yeoh::from_engineering(500.0, 0.3, 1.5, 0.2).unwrap(),
    ]
}

/// The solid's `P_s` is `∂Ψ/∂F`, to 1e-8 relative.
fn stress_is_the_derivative_of_the_energy<K: Kinematics>(seed: u128) {
    let mut rng = Rng::new(seed);
    for law in laws() {
        for (case, (f, fa)) in K::cases(&mut rng, 24).into_iter().enumerate() {
            let p = K::piola_solid(&law, &f, &fa);
            let g = central_differences::<K>(&f, K::H_ENERGY, |f| vec![K::energy(&law, f, &fa)]);
            let e = rel(&g, &p);
            assert!(e < 1e-8, "{}, case {case}: rel. error {e:e}", K::NAME);
        }
    }
}

/// `∂P/∂F` and `∂P/∂Ḟ` of the kernels against central differences of the total stress,
/// with two viscosities; the solid's tangent alone against its stress and symmetric.
fn tangents_equal_finite_differences_of_the_stress<K: Kinematics>(seed: u128) {
    let mut rng = Rng::new(seed);
    let h = 1e-6;
    let shear = Viscosity {
        lambda_f: 3.0,
        mu_f: 2.0,
    };
    let none = Viscosity {
        lambda_f: 0.0,
        mu_f: 0.0,
    };
    for visc in [crate::physics::reference::viscosity(), shear] {
        let law = cytoplasm();
        for (case, (f, fa)) in K::cases(&mut rng, 24).into_iter().enumerate() {
            let fdot = K::rate(&mut rng);
            let (p, dp_df, dp_dfdot) = K::point(&law, &visc, &f, &fdot, &fa);
            let total = K::piola(&law, &visc, &f, &fdot, &fa);
            assert!(rel(&p, &total) < 1e-12, "{}, case {case}: P", K::NAME);
            let fd_f = central_differences::<K>(&f, h, |f| K::piola(&law, &visc, f, &fdot, &fa));
            // P is linear in Ḟ: a large step has no truncation error and less round-off.
            let fd_fdot =
                central_differences::<K>(&fdot, 1e-2, |g| K::piola(&law, &visc, &f, g, &fa));
            let (ef, ev) = (rel(&fd_f, &dp_df), rel(&fd_fdot, &dp_dfdot));
            assert!(ef < 1e-7, "{}, dP/dF case {case}: {ef:e}", K::NAME);
            assert!(ev < 1e-9, "{}, dP/dFdot case {case}: {ev:e}", K::NAME);
            // The solid alone (the viscous tangent dominates at λ_f = 1000): against its
            // stress, and symmetric.
            let (_, ds, _) = K::point(&law, &none, &f, &fdot, &fa);
            let fd_s = central_differences::<K>(&f, h, |f| K::piola_solid(&law, f, &fa));
            let es = rel(&fd_s, &ds);
            assert!(es < 1e-7, "{}, solid dP/dF case {case}: {es:e}", K::NAME);
            let n = K::entries(&f).len();
            let transposed: Vec<f64> = (0..n * n).map(|k| ds[(k % n) * n + k / n]).collect();
            let asym = rel(&transposed, &ds);
            assert!(asym < 1e-12, "{}, case {case}: asymmetry {asym:e}", K::NAME);
        }
    }
}

#[test]
fn the_solid_stress_is_the_derivative_of_its_energy_in_every_kinematics() {
    stress_is_the_derivative_of_the_energy::<PlaneStrain>(7);
    stress_is_the_derivative_of_the_energy::<Hoop>(29);
    stress_is_the_derivative_of_the_energy::<ThreeD>(43);
}

#[test]
fn the_tangents_are_the_derivatives_of_the_stress_in_every_kinematics() {
    tangents_equal_finite_differences_of_the_stress::<PlaneStrain>(11);
    tangents_equal_finite_differences_of_the_stress::<Hoop>(31);
    tangents_equal_finite_differences_of_the_stress::<ThreeD>(47);
}
