//! Body forces per unit reference volume (MODEL.md §5): contact, adhesion and gravity, and
//! the rate of the adhesion coefficient. Forces in pN/µm³, positions in µm.
//!
//! Functions of the unknowns (`x`, `F`, `J`, `μ_as`) are generic over [`Real`] for exact
//! tangents; gravity depends on time only and is `f64`.

#![allow(non_snake_case)]

use super::smooth::{heaviside, smooth_step};
use super::substrate::Substrate;
use super::{PhysicsError, Real, check, cst, sqrt};
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

/// Penalty contact with the substrate.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    /// Penalty coefficient `μ_ct` [pN/µm³] (MODEL.md: 2e9 N/m³ = 2e3 pN/µm³).
    pub mu_ct: f64,
    /// Half-width `ε_ct` of the contact band [µm] (MODEL.md: 0.1).
    pub eps: f64,
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
    /// Thickness `e_f` of the fibronectin layer over the substrate [µm] (MODEL.md: 1.5).
    pub e_f: f64,
    /// Half-width of the layer's Heaviside [µm] (MODEL.md does not say; default 0.1,
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
}

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

/// Contact force per unit reference volume [pN/µm³] at current position `x` with
/// `J = det F`: `b_ct = J μ_ct H_ε(d(x)) n(x)`.
#[inline(always)]
pub fn contact_force<T: Real>(sub: &Substrate, c: &Contact, x: &Vector2<T>, J: T) -> Vector2<T> {
    let (d, n) = sub.eval(x);
    let h = heaviside(d, c.eps);
    n * (J * h * c.mu_ct)
}

/// Fibronectin-layer indicator at current position `x` [µm]: `H_ε(d(x) + e_f)` ∈ [0, 1],
/// 1 within `e_f − ε` of the substrate and inside it; or, when the layer excludes the
/// substrate (`exclude_substrate = Some(ε_s)`), `H_ε(d + e_f) − H_ε_s(d)`, 0 again inside
/// the substrate.
#[inline(always)]
pub fn layer<T: Real>(sub: &Substrate, ad: &Adhesion, x: &Vector2<T>) -> T {
    let (d, _) = sub.eval(x);
    let h = heaviside(d + ad.e_f, ad.eps);
    match ad.exclude_substrate {
        None => h,
        Some(eps_s) => h - heaviside(d, eps_s),
    }
}

/// Cofactor `cof(F) = J F⁻ᵀ`; in 2-D `[[F₁₁, −F₁₀], [−F₀₁, F₀₀]]`, polynomial in `F`.
pub fn cofactor<T: Real>(F: &Matrix2<T>) -> Matrix2<T> {
    Matrix2::new(F[(1, 1)], -F[(1, 0)], -F[(0, 1)], F[(0, 0)])
}

/// Adhesive spreading force per unit reference volume [pN/µm³] (membrane only — the
/// caller applies it there): `b_as = t_as μ_as g_l(x) a(F)`, with `g_l` the [`layer`]
/// indicator, `N` the outward radial reference direction, `μ_as` [pN/µm³] the local
/// adhesion coefficient, `t_as` the adhesion switch and `a(F)` by the readings of `ad`:
/// `cof(F) N` (MODEL.md) or `cof(F) N/|cof(F) N|` ([`AdhesionDirection`]), times
/// `J = det F` when `jacobian_factor`.
#[inline(always)]
pub fn adhesion_force<T: Real>(
    sub: &Substrate,
    ad: &Adhesion,
    x: &Vector2<T>,
    F: &Matrix2<T>,
    N_ref: &Vector2<f64>,
    mu_as: T,
    t_as: f64,
) -> Vector2<T> {
    let h = layer(sub, ad, x);
    let N: Vector2<T> = N_ref.map(cst::<T>);
    let mut a = cofactor(F) * N;
    if ad.direction == AdhesionDirection::Unit {
        // |cof(F) N| = J |F⁻ᵀ N| > 0 for an admissible F.
        let len = sqrt(a.x * a.x + a.y * a.y);
        a /= len;
    }
    if ad.jacobian_factor {
        a *= F.determinant();
    }
    a * (h * mu_as * t_as)
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
pub fn adhesion_rate<T: Real>(sub: &Substrate, ad: &Adhesion, x: &Vector2<T>, mu_as: T) -> T {
    let h = layer(sub, ad, x);
    let cap = smooth_step(mu_as, 0.98 * ad.mu_as_max, ad.mu_as_max);
    h * (-cap + 1.0) * ad.mu_as0
}

/// Gravity per unit reference volume [pN/µm³]: `b_g = −ρ₀ g s_g t_g e_y`, with `ρ₀`
/// [pN·s²/µm⁴] (1000 kg/m³ = 1e-9), `g` [µm/s²] (9.81e6), the gravity switch `t_g` and
/// sign `s_g`.
pub fn gravity_force(rho: f64, g: f64, t_g: f64, sign: f64) -> Vector2<f64> {
    Vector2::new(0.0, -rho * g * sign * t_g)
}

#[cfg(test)]
mod tests {
    use super::*;
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
            contact_force(&s, &c, &Vector2::new(0.0, -1.85), J),
            Vector2::zeros()
        );
        // deep inside (d > ε)
        let f = contact_force(&s, &c, &Vector2::new(0.0, -2.2), J);
        assert_eq!(f, Vector2::new(0.0, J * c.mu_ct));
        // on the surface: half
        let f = contact_force(&s, &c, &Vector2::new(0.0, -2.0), J);
        assert!((f.y - 0.5 * J * c.mu_ct).abs() < 1e-12);
        // pillars: on a side, deep inside → along the outward side normal
        let p = Substrate::Pillars(crate::physics::reference::pillars());
        let mid = crate::physics::reference::pillars().y_top - 4.0; // mid-height of the pillars
        let f = contact_force(&p, &c, &Vector2::new(11.7, mid), 1.0);
        assert!((f - Vector2::new(c.mu_ct, 0.0)).norm() < 1e-9, "f = {f}");
        let f = contact_force(&p, &c, &Vector2::new(12.2, mid), 1.0);
        assert_eq!(f, Vector2::zeros());
    }

    #[test]
    fn contact_force_derivatives_match_finite_differences() {
        type D = DualSVec64<3>;
        let c = crate::physics::reference::contact();
        let h = 1e-7;
        for s in substrates() {
            // points inside the contact band of the flat surface and of the pillars
            for (x, y, J) in [
                (0.0, -1.97, 1.1),
                (1.0, -2.04, 0.8),
                (5.0, -0.68, 1.0),
                (11.96, -3.0, 1.2),
                (8.0, -0.33, 0.9),
            ] {
                let xd = Vector2::new(D::from_re(x).derivative(0), D::from_re(y).derivative(1));
                let Jd = D::from_re(J).derivative(2);
                let f = contact_force(&s, &c, &xd, Jd);
                let base = [x, y, J];
                for k in 0..3 {
                    let mut p = base;
                    let mut m = base;
                    p[k] += h;
                    m[k] -= h;
                    let fp = contact_force(&s, &c, &Vector2::new(p[0], p[1]), p[2]);
                    let fm = contact_force(&s, &c, &Vector2::new(m[0], m[1]), m[2]);
                    let fd = (fp - fm) / (2.0 * h);
                    let scale = c.mu_ct / c.eps;
                    assert!(
                        (fd.x - eps(&f.x)[k]).abs() < 1e-6 * scale,
                        "{s:?} ({x},{y}) k={k}"
                    );
                    assert!(
                        (fd.y - eps(&f.y)[k]).abs() < 1e-6 * scale,
                        "{s:?} ({x},{y}) k={k}"
                    );
                }
            }
        }
    }

    /// MODEL.md's adhesion and each reading of the paper it leaves open, alone and all
    /// together.
    fn adhesion_readings() -> Vec<Adhesion> {
        let d = crate::physics::reference::adhesion();
        let eps_ct = crate::physics::reference::contact().eps;
        vec![
            d,
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
        type D = DualSVec64<7>;
        let h = 1e-6;
        let N = Vector2::new(0.6, -0.8);
        let F0 = Matrix2::new(1.1, 0.2, -0.3, 0.9);
        let y_top = crate::physics::reference::pillars().y_top;
        for (ad, s) in adhesion_readings()
            .into_iter()
            .flat_map(|ad| substrates().map(|s| (ad, s)))
        {
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
                let v = [x, y, F0[(0, 0)], F0[(0, 1)], F0[(1, 0)], F0[(1, 1)], mu];
                let dual = |i: usize| D::from_re(v[i]).derivative(i);
                let xd = Vector2::new(dual(0), dual(1));
                let Fd = Matrix2::new(dual(2), dual(3), dual(4), dual(5));
                let f = adhesion_force(&s, &ad, &xd, &Fd, &N, dual(6), 0.7);
                let r = adhesion_rate(&s, &ad, &xd, dual(6));
                let eval = |w: &[f64; 7]| {
                    let X = Vector2::new(w[0], w[1]);
                    let F = Matrix2::new(w[2], w[3], w[4], w[5]);
                    (
                        adhesion_force(&s, &ad, &X, &F, &N, w[6], 0.7),
                        adhesion_rate(&s, &ad, &X, w[6]),
                    )
                };
                for k in 0..7 {
                    let step = if k == 6 { 1e-3 } else { h };
                    let (mut p, mut m) = (v, v);
                    p[k] += step;
                    m[k] -= step;
                    let ((fp, rp), (fm, rm)) = (eval(&p), eval(&m));
                    let fd = (fp - fm) / (2.0 * step);
                    let rd = (rp - rm) / (2.0 * step);
                    let fscale = mu.max(1.0) / ad.eps;
                    assert!(
                        (fd.x - eps(&f.x)[k]).abs() < 1e-6 * fscale,
                        "{ad:?} {s:?} f_x k={k}"
                    );
                    assert!(
                        (fd.y - eps(&f.y)[k]).abs() < 1e-6 * fscale,
                        "{ad:?} {s:?} f_y k={k}"
                    );
                    let rscale = ad.mu_as0 / ad.eps.min(0.02 * ad.mu_as_max);
                    assert!(
                        (rd - eps(&r)[k]).abs() < 1e-6 * rscale,
                        "{ad:?} {s:?} rate k={k}: {rd} vs {}",
                        eps(&r)[k]
                    );
                }
            }
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
        let f = adhesion_force(&s, &ad, &X, &F, &N, 100.0, 0.5);
        let cof = F.try_inverse().unwrap().transpose() * F.determinant();
        assert!((f - cof * N * 50.0).norm() < 1e-12);
        // outside the layer: none
        let X = Vector2::new(0.0, -0.3);
        assert_eq!(
            adhesion_force(&s, &ad, &X, &F, &N, 100.0, 0.5),
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
        assert!((layer(&s, &ad, &Vector2::new(3.0_f64, -0.5)) - 0.5).abs() < 1e-12);
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
        let f0 = adhesion_force(&s, &d, &X, &F, &N, 100.0, 0.5);
        assert!((f0 - cof_n * 50.0).norm() < 1e-12);
        // Unit: the same direction, length t_as μ_as.
        let unit = Adhesion {
            direction: AdhesionDirection::Unit,
            ..d
        };
        let f = adhesion_force(&s, &unit, &X, &F, &N, 100.0, 0.5);
        assert!((f - cof_n / cof_n.norm() * 50.0).norm() < 1e-12);
        assert!((f.norm() - 50.0).abs() < 1e-12);
        // J f_as: J times the default.
        let with_j = Adhesion {
            jacobian_factor: true,
            ..d
        };
        let f = adhesion_force(&s, &with_j, &X, &F, &N, 100.0, 0.5);
        assert!((f - f0 * J).norm() < 1e-12);
        // Excluding the substrate: the same above its band, ½ less on its surface, nothing
        // inside it (where the default layer is 1).
        let excl = Adhesion {
            exclude_substrate: Some(eps_ct),
            ..d
        };
        assert_eq!(layer(&s, &excl, &X), layer(&s, &d, &X));
        let on = Vector2::new(0.0_f64, -2.0);
        assert_eq!(layer(&s, &d, &on), 1.0);
        assert!((layer(&s, &excl, &on) - 0.5).abs() < 1e-15);
        let inside = Vector2::new(0.0_f64, -2.5);
        assert_eq!(layer(&s, &d, &inside), 1.0);
        assert_eq!(layer(&s, &excl, &inside), 0.0);
        assert_eq!(adhesion_rate(&s, &excl, &inside, 0.0), 0.0);
        assert_eq!(adhesion_rate(&s, &d, &inside, 0.0), d.mu_as0);
        // The layer indicator stays in [0, 1] across both bands.
        for k in 0..=400 {
            let x = Vector2::new(0.0, -2.6 + 1.2 * k as f64 / 400.0);
            let g = layer(&s, &excl, &x);
            assert!((0.0..=1.0).contains(&g), "y = {}: {g}", x.y);
        }
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
        let F3 = nalgebra::Matrix3::new(
            F[(0, 0)],
            F[(0, 1)],
            0.0,
            F[(1, 0)],
            F[(1, 1)],
            0.0,
            0.0,
            0.0,
            lambda,
        );
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
                let f = adhesion_force(&s, &ad, &X, &F, &N, 100.0, 0.5)
                    * adhesion_hoop_factor(&ad, lambda);
                assert!(
                    (f - exact).norm() < 1e-12 * exact.norm(),
                    "{direction:?}, J {jacobian_factor}: {f} against {exact}"
                );
            }
        }
    }

    #[test]
    fn gravity() {
        let rho = 1.0e-9; // 1000 kg/m³
        let g = 9.81e6;
        let b = gravity_force(rho, g, 1.0, 1.0);
        assert!((b.y + 9.81e-3).abs() < 1e-15 && b.x == 0.0);
        assert!((gravity_force(rho, g, 0.5, -1.0).y - 0.5 * 9.81e-3).abs() < 1e-17);
    }

    #[test]
    fn parameter_validation() {
        assert!(crate::physics::reference::contact().validate().is_ok());
        assert!(crate::physics::reference::adhesion().validate().is_ok());
        assert!(
            Contact {
                eps: 0.0,
                ..crate::physics::reference::contact()
            }
            .validate()
            .is_err()
        );
        assert!(
            Adhesion {
                mu_as_max: 0.0,
                ..crate::physics::reference::adhesion()
            }
            .validate()
            .is_err()
        );
        assert!(
            Adhesion {
                e_f: f64::NAN,
                ..crate::physics::reference::adhesion()
            }
            .validate()
            .is_err()
        );
        // Excluding the substrate needs a positive half-width and a layer wider than
        // both bands.
        let excl = Adhesion {
            exclude_substrate: Some(0.1),
            ..crate::physics::reference::adhesion()
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
}
