//! Active strain of the actin fibres (MODEL.md §6).
//!
//! `F_a = I − e_PAC t_a χ_PAC (T⊗T) − e_bot t_a χ_bot (N⊗N)`, with `N = (p − c)/|p − c|`
//! the radial and `T = (−N_y, N_x)` the tangential reference direction about the cell
//! centre `c`. PAC ("push", tangential fibres) acts in the cytoplasm only; bottom ("pull",
//! radial fibres) in the cytoplasm and the membrane. `χ` are products of regularised
//! Heavisides `H_ε` of signed distances to the bounding curves (in reference coordinates),
//! so `F_a` is smooth in `p`. Everything here is `f64`: it depends on the reference
//! position and time only.
//!
//! The PAC indicator has no switch of its own for MODEL.md's second reading of Table 1
//! (`active.pac.clip_to_cell`: semi-axes (10, 9) and (15, 14), ellipses leaving the cell):
//! the ellipses are used as given and the region is clipped by the cell because the PAC
//! acts in the cytoplasm only ([`ActiveStrain::fa`]'s domain restriction); the switch only
//! relaxes the case validation. The same holds in 3-D.
//!
//! **3-D** (MODEL.md §10; [`ActiveStrain::fa_revolved`],
//! [`ActiveStrain::chi_pac_revolved`], [`ActiveStrain::chi_bottom_revolved`]). With
//! `c = (c_x, c_y, c_z)` and `p = X − c`, the point's meridian coordinates are
//! `ρ = √(p_x² + p_z²)` (the horizontal distance from the vertical axis through `c`) and
//! `p_y`; the elevation is `θ = atan(p_y/ρ)`. The indicators are the 2-D ones evaluated at
//! `(ρ, p_y)`: the ellipses become ellipsoids of revolution about the axis (horizontal
//! semi-axis `a`, vertical `b`; the first-order distance of `l = 1 − (ρ/a)² − (p_y/b)²` in
//! 3-D is the 2-D one in `(ρ, p_y)`), the bounding rays become cones about the axis.
//! `N = p/|p|`, and `T = −N_y e_ρ + (ρ/|p|) e_y` is the unit tangent of the meridian
//! through `X` (`e_ρ = (p_x, 0, p_z)/ρ`): in the plane `z = c_z`, `x > c_x` it is the 2-D
//! `T`, so there `fa_revolved = fa ⊕ 1` bit for bit, and elsewhere
//! `fa_revolved(c + R p) = R fa_revolved(c + p) Rᵀ` for every rotation `R` about the
//! vertical axis.
//!
//! *On the axis* (`ρ = 0`) the meridian, hence `T`, is undefined: the meridian fibres of
//! the PAC converge there and `T⊗T → e_ρ⊗e_ρ` depends on the direction of approach. We take
//! its mean over the azimuth, `½(e_x⊗e_x + e_z⊗e_z)`, which keeps `F_a` axisymmetric and
//! `det F_a ∈ [(1 − e_PAC)(1 − e_bot), 1]`. With the default `θ_PAC = −18°` the PAC does
//! reach the axis: above the centre, between the ellipsoids (`p_y` ∈ (4.5, 7) µm) the cone
//! is far away and `χ_PAC = 1`, so the cap's fibres meet at its apex. Only the axis itself
//! (a line, on which no quadrature point of the quarter cell lies: it is an edge of the
//! domain) sees this choice; the 2-D half cell instead takes `T = (−1, 0)` on its symmetry
//! line, so `fa_revolved ≠ fa ⊕ 1` on the axis only. The bottom fibres (`N`) are defined on
//! the axis; `F_a = I` at `X = c`. The indicators are smooth across the axis wherever the
//! PAC or bottom region can act: `ρ` enters the ellipsoid distances through `ρ²`, and the
//! cone distances `cos θ₀ p_y − sin θ₀ ρ` (not smooth at the axis) are beyond `±ε_a` there
//! except within `ε_a/cos θ₀` of the centre, inside the nucleus.

#![allow(non_snake_case)]

use super::fibres::Fibre;
use super::smooth::heaviside;
use super::{PhysicsError, check};
use crate::fem::Domain;
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Perinuclear actin cap ("push"): tangential contraction in the cytoplasm between two
/// ellipses centred at `c`, for `θ ≥ θ_PAC`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pac {
    /// Contraction amplitude `e_PAC` (dimensionless, in [0, 1); target fibre stretch `1 − e`).
    pub e: f64,
    /// Bounding angle `θ_PAC` \[degrees\], measured from the +x axis; the PAC is `θ ≥ θ_PAC`.
    pub theta_deg: f64,
    /// Semi-axes (along x, along y) of the inner ellipse \[µm\].
    pub inner_axes: [f64; 2],
    /// Semi-axes (along x, along y) of the outer ellipse \[µm\].
    pub outer_axes: [f64; 2],
}

/// Bottom fibres ("pull"): radial contraction in the cytoplasm and membrane for
/// `θ ≤ θ_bot`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bottom {
    /// Contraction amplitude `e_bot` (dimensionless, in [0, 1)).
    pub e: f64,
    /// Bounding angle `θ_bot` \[degrees\]; the bottom region is `θ ≤ θ_bot`.
    pub theta_deg: f64,
}

/// The active-strain field: which fibre sets are active, the smoothing width and the
/// centre `c` the directions are taken about.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ActiveStrain {
    /// PAC fibres, if active in this scene.
    pub pac: Option<Pac>,
    /// Bottom fibres, if active in this scene.
    pub bottom: Option<Bottom>,
    /// Smoothing half-width `ε_a` of the indicator Heavisides \[µm\] (MODEL.md: 0.25).
    pub eps: f64,
    /// Cell centre `c` \[µm\] (MODEL.md: (0, 8.5)).
    pub center: [f64; 2],
}

/// Signed distance to the line through the origin at angle `theta` (radians) from the
/// +x axis, positive on the counter-clockwise side (larger polar angle for points with
/// `x > 0`): `d = cos θ · p_y − sin θ · p_x`.
fn side_of_ray(p: &Vector2<f64>, theta: f64) -> f64 {
    theta.cos() * p.y - theta.sin() * p.x
}

/// The unit tangent `T = −N_y e_ρ + (ρ/|p|) e_y` of the meridian through the offset `p`
/// from the centre (`ρ = √(p_x² + p_z²) > 0`, `r = |p|`; module notes).
#[inline]
fn meridian_tangent(p: &Vector3<f64>, rho: f64, r: f64) -> Vector3<f64> {
    let ny = p.y / r;
    Vector3::new(-ny * (p.x / rho), rho / r, -ny * (p.z / rho))
}

/// First-order signed distance to the ellipse `(x/a)² + (y/b)² = 1` centred at the origin,
/// positive inside: `l/|∇l|` with `l = 1 − (x/a)² − (y/b)²` (±∞ at the centre).
fn inside_ellipse(p: &Vector2<f64>, axes: [f64; 2]) -> f64 {
    let (a, b) = (axes[0], axes[1]);
    let l = 1.0 - (p.x / a).powi(2) - (p.y / b).powi(2);
    let g = (4.0 * (p.x / (a * a)).powi(2) + 4.0 * (p.y / (b * b)).powi(2)).sqrt();
    if g > 0.0 { l / g } else { f64::INFINITY }
}

impl ActiveStrain {
    /// Checks `ε_a > 0`, amplitudes in \[0, 1) (so `det F_a ≥ (1 − e_PAC)(1 − e_bot) > 0`),
    /// angles in (−90°, 90°\], positive semi-axes with the inner ellipse smaller than the
    /// outer one, all finite.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.eps.is_finite() && self.eps > 0.0,
            "active.eps",
            self.eps,
            "must be finite and > 0",
        )?;
        check(
            self.center.iter().all(|v| v.is_finite()),
            "active.center",
            self.center[0] + self.center[1],
            "must be finite",
        )?;
        // A region's amplitude and angle, with their names.
        let amplitude_and_angle = |[name_e, name_theta]: [&'static str; 2], e: f64, theta: f64| {
            check(
                e.is_finite() && (0.0..1.0).contains(&e),
                name_e,
                e,
                "must lie in [0, 1)",
            )?;
            check(
                theta.is_finite() && theta > -90.0 && theta <= 90.0,
                name_theta,
                theta,
                "must lie in (-90, 90]",
            )
        };
        if let Some(p) = self.pac {
            amplitude_and_angle(["pac.e", "pac.theta_deg"], p.e, p.theta_deg)?;
            for i in 0..2 {
                check(
                    p.inner_axes[i].is_finite() && p.inner_axes[i] > 0.0,
                    "pac.inner_axes",
                    p.inner_axes[i],
                    "must be finite and > 0",
                )?;
            }
            for i in 0..2 {
                check(
                    p.outer_axes[i].is_finite() && p.outer_axes[i] > p.inner_axes[i],
                    "pac.outer_axes",
                    p.outer_axes[i],
                    "must be finite and larger than the inner semi-axis",
                )?;
            }
        }
        if let Some(b) = self.bottom {
            amplitude_and_angle(["bottom.e", "bottom.theta_deg"], b.e, b.theta_deg)?;
        }
        Ok(())
    }

    fn offset(&self, X: &Vector2<f64>) -> Vector2<f64> {
        X - Vector2::new(self.center[0], self.center[1])
    }

    /// PAC indicator `χ_PAC(X) = H_ε(d_out) H_ε(d_in) H_ε(d_θ)` ∈ [0, 1] (0 if no PAC):
    /// `d_out = l_o/|∇l_o|`, `l_o = 1 − (x/a_o)² − (y/b_o)²` (inside the outer ellipse),
    /// `d_in = −l_i/|∇l_i|` (outside the inner ellipse), `d_θ = cos θ_PAC (X_y − c_y) −
    /// sin θ_PAC (X_x − c_x)`, the exact distance to the line of the bounding ray
    /// (`θ ≥ θ_PAC` on the half cell). Does not include the domain restriction (see [`Self::fa`]).
    pub fn chi_pac(&self, X: &Vector2<f64>) -> f64 {
        let Some(pac) = self.pac else { return 0.0 };
        let p = self.offset(X);
        let d_out = inside_ellipse(&p, pac.outer_axes);
        let d_in = -inside_ellipse(&p, pac.inner_axes);
        let d_th = side_of_ray(&p, pac.theta_deg.to_radians());
        heaviside(d_out, self.eps) * heaviside(d_in, self.eps) * heaviside(d_th, self.eps)
    }

    /// Bottom indicator `χ_bot(X) = H_ε(−(cos θ_bot (X_y − c_y) − sin θ_bot (X_x − c_x)))`
    /// ∈ [0, 1] (0 if no bottom fibres): the region `θ ≤ θ_bot` of the half cell, with the
    /// exact distance to the line of the bounding ray.
    pub fn chi_bottom(&self, X: &Vector2<f64>) -> f64 {
        let Some(bot) = self.bottom else { return 0.0 };
        let p = self.offset(X);
        heaviside(-side_of_ray(&p, bot.theta_deg.to_radians()), self.eps)
    }

    /// Active-strain tensor at reference point `X` of sub-domain `domain`, at active switch
    /// value `t_a` ∈ [0, 1]:
    ///
    /// `F_a = I − e_PAC t_a χ_PAC T⊗T − e_bot t_a χ_bot N⊗N`, `N = (X − c)/|X − c|`,
    /// `T = (−N_y, N_x)`; PAC only in the cytoplasm, bottom in cytoplasm and membrane,
    /// `F_a = I` in the nucleus (and at `X = c`, where `N` is undefined).
    pub fn fa(&self, X: &Vector2<f64>, domain: Domain, t_a: f64) -> Matrix2<f64> {
        let I = Matrix2::identity();
        if domain == Domain::Nucleus || t_a == 0.0 {
            return I;
        }
        // The contracting directions are the fibres' (χ = 0 at X = c, so F_a = I there).
        let [tangential, radial] = self.fibres(X);
        let mut Fa = I;
        if let (Some(pac), Domain::Cytoplasm) = (self.pac, domain) {
            let a = pac.e * t_a * tangential.chi;
            if a != 0.0 {
                Fa -= tangential.a * tangential.a.transpose() * a;
            }
        }
        if let Some(bot) = self.bottom {
            let b = bot.e * t_a * radial.chi;
            if b != 0.0 {
                Fa -= radial.a * radial.a.transpose() * b;
            }
        }
        Fa
    }

    /// The fibre families at reference point `X` (MODEL.md §11): the PAC's along `T` with
    /// `χ_PAC`, the bottom region's along `N` with `χ_bot` (a family with `χ = 0` where its
    /// region is absent, and both at `X = c`, where `N` is undefined). The fibres are a
    /// cytoplasm material: the caller restricts them to that domain.
    pub fn fibres(&self, X: &Vector2<f64>) -> [Fibre<2>; 2] {
        let p = self.offset(X);
        let r = p.norm();
        if r == 0.0 {
            return [Fibre::absent(); 2];
        }
        let N = p / r;
        let T = Vector2::new(-N.y, N.x);
        [
            Fibre {
                a: T,
                chi: self.chi_pac(X),
            },
            Fibre {
                a: N,
                chi: self.chi_bottom(X),
            },
        ]
    }

    // ---- 3-D (module notes) ---------------------------------------------------------------

    /// `(p, (ρ, p_y))` for `X` in 3-D: `p = X − c`, `c = (center[0], center[1], c_z)`, and
    /// its meridian coordinates.
    #[inline]
    fn meridian(&self, X: &Vector3<f64>, c_z: f64) -> (Vector3<f64>, Vector2<f64>) {
        let p = X - Vector3::new(self.center[0], self.center[1], c_z);
        let rho = (p.x * p.x + p.z * p.z).sqrt();
        (p, Vector2::new(rho, p.y))
    }

    /// The PAC indicator at the offset `q = (ρ, p_y)` from the centre.
    #[inline]
    fn chi_pac_offset(&self, pac: &Pac, q: &Vector2<f64>) -> f64 {
        let d_out = inside_ellipse(q, pac.outer_axes);
        let d_in = -inside_ellipse(q, pac.inner_axes);
        let d_th = side_of_ray(q, pac.theta_deg.to_radians());
        heaviside(d_out, self.eps) * heaviside(d_in, self.eps) * heaviside(d_th, self.eps)
    }

    /// The bottom indicator at the offset `q = (ρ, p_y)` from the centre.
    #[inline]
    fn chi_bottom_offset(&self, bot: &Bottom, q: &Vector2<f64>) -> f64 {
        heaviside(-side_of_ray(q, bot.theta_deg.to_radians()), self.eps)
    }

    /// PAC indicator in 3-D, `χ_PAC` ∈ [0, 1] (0 if no PAC): [`Self::chi_pac`] at the
    /// meridian coordinates `(ρ, X_y − c_y)` of `X` about the vertical axis through
    /// `c = (center[0], center[1], c_z)` — between two ellipsoids of revolution, above the
    /// cone `θ = θ_PAC`. Without the domain restriction (see [`Self::fa_revolved`]).
    #[inline]
    pub fn chi_pac_revolved(&self, X: &Vector3<f64>, c_z: f64) -> f64 {
        let Some(pac) = self.pac else { return 0.0 };
        let (_, q) = self.meridian(X, c_z);
        self.chi_pac_offset(&pac, &q)
    }

    /// Bottom indicator in 3-D, `χ_bot` ∈ [0, 1] (0 if no bottom fibres):
    /// [`Self::chi_bottom`] at the meridian coordinates of `X`, the region below the cone
    /// `θ = θ_bot` about the vertical axis through `c = (center[0], center[1], c_z)`.
    #[inline]
    pub fn chi_bottom_revolved(&self, X: &Vector3<f64>, c_z: f64) -> f64 {
        let Some(bot) = self.bottom else { return 0.0 };
        let (_, q) = self.meridian(X, c_z);
        self.chi_bottom_offset(&bot, &q)
    }

    /// Active-strain tensor of the 3-D model at reference point `X` of sub-domain `domain`,
    /// at active switch value `t_a` ∈ [0, 1], the cell centre `c = (center[0], center[1],
    /// c_z)`:
    ///
    /// `F_a = I − e_PAC t_a χ_PAC T⊗T − e_bot t_a χ_bot N⊗N`, `N = (X − c)/|X − c|`, `T` the
    /// unit tangent of the meridian through `X` (module notes; on the vertical axis through
    /// `c`, `T⊗T` is replaced by its azimuthal mean `½(e_x⊗e_x + e_z⊗e_z)`). PAC only in the
    /// cytoplasm, bottom in cytoplasm and membrane, `F_a = I` in the nucleus and at `X = c`.
    /// In the plane `z = c_z`, `x > c_x`, it is [`Self::fa`] `⊕ 1` exactly. Affine in `t_a`
    /// like [`Self::fa`]: `F_a(t_a) = I − t_a (I − F_a(1))`, axis included.
    #[inline]
    pub fn fa_revolved(
        &self,
        X: &Vector3<f64>,
        c_z: f64,
        domain: Domain,
        t_a: f64,
    ) -> Matrix3<f64> {
        let I = Matrix3::identity();
        if domain == Domain::Nucleus || t_a == 0.0 {
            return I;
        }
        let (p, q) = self.meridian(X, c_z);
        let r = p.norm();
        if r == 0.0 {
            return I;
        }
        let N = p / r;
        let mut Fa = I;
        if let (Some(pac), Domain::Cytoplasm) = (self.pac, domain) {
            let a = pac.e * t_a * self.chi_pac_offset(&pac, &q);
            if a != 0.0 {
                let rho = q.x;
                if rho > 0.0 {
                    let T = meridian_tangent(&p, rho, r);
                    Fa -= T * T.transpose() * a;
                } else {
                    Fa[(0, 0)] -= 0.5 * a;
                    Fa[(2, 2)] -= 0.5 * a;
                }
            }
        }
        if let Some(bot) = self.bottom {
            let b = bot.e * t_a * self.chi_bottom_offset(&bot, &q);
            if b != 0.0 {
                Fa -= N * N.transpose() * b;
            }
        }
        Fa
    }
}

impl ActiveStrain {
    /// The fibre families of the 3-D model at `X` ([`Self::fibres`] about the vertical axis
    /// through `c = (center[0], center[1], c_z)`): `T` the unit tangent of the meridian, `N`
    /// the radial direction. On the axis, where `T` is undefined, the PAC family has `χ = 0`
    /// (no quadrature point lies there: it is an edge of the quarter cell).
    #[inline]
    pub fn fibres_revolved(&self, X: &Vector3<f64>, c_z: f64) -> [Fibre<3>; 2] {
        let (p, q) = self.meridian(X, c_z);
        let r = p.norm();
        if r == 0.0 {
            return [Fibre::absent(); 2];
        }
        let N = p / r;
        let rho = q.x;
        let pac = match self.pac {
            Some(pac) if rho > 0.0 => Fibre {
                a: meridian_tangent(&p, rho, r),
                chi: self.chi_pac_offset(&pac, &q),
            },
            _ => Fibre::absent(),
        };
        let bottom = Fibre {
            a: N,
            chi: self.bottom.map_or(0.0, |b| self.chi_bottom_offset(&b, &q)),
        };
        [pac, bottom]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both regions at the case's defaults (the one source of MODEL.md's numbers).
    fn both() -> ActiveStrain {
        crate::scene::terms::active(&crate::case::Case::reference_active())
            .expect("the reference case has both regions")
    }

    fn at(r: f64, deg: f64) -> Vector2<f64> {
        let t = deg.to_radians();
        Vector2::new(r * t.cos(), 8.5 + r * t.sin())
    }

    #[test]
    fn the_fibres_are_the_directions_the_active_strain_contracts() {
        // F_a a = (1 − e χ) a for each family, in 2-D and 3-D, and in the plane z = c_z,
        // x > c_x the 3-D families are the 2-D ones (z component 0).
        let act = both();
        let e = [act.pac.unwrap().e, act.bottom.unwrap().e];
        for (r, deg) in [
            (6.2, 45.0),
            (8.0, -40.0),
            (7.0, -18.0),
            (6.0, -33.0),
            (9.9, -70.0),
        ] {
            let X = at(r, deg);
            let fa = act.fa(&X, Domain::Cytoplasm, 1.0);
            let fib = act.fibres(&X);
            for (k, f) in fib.iter().enumerate() {
                assert!((f.a.norm() - 1.0).abs() < 1e-14);
                assert!((fa * f.a - f.a * (1.0 - e[k] * f.chi)).norm() < 1e-14);
            }
            assert_eq!(fib[0].chi, act.chi_pac(&X));
            assert_eq!(fib[1].chi, act.chi_bottom(&X));
            let X3 = Vector3::new(X.x, X.y, 0.0);
            let fib3 = act.fibres_revolved(&X3, 0.0);
            for (f2, f3) in fib.iter().zip(&fib3) {
                assert!((f3.a - Vector3::new(f2.a.x, f2.a.y, 0.0)).norm() < 1e-14);
                assert!((f3.chi - f2.chi).abs() < 1e-14);
            }
            // and off that plane, a rotation about the vertical axis
            let (s, c) = 0.7f64.sin_cos();
            let R = Matrix3::new(c, 0.0, -s, 0.0, 1.0, 0.0, s, 0.0, c);
            let Xr = Vector3::new(act.center[0], act.center[1], 0.0)
                + R * (X3 - Vector3::new(act.center[0], act.center[1], 0.0));
            let fa_revolved = act.fa_revolved(&Xr, 0.0, Domain::Cytoplasm, 1.0);
            for (k, (f3, fr)) in fib3.iter().zip(&act.fibres_revolved(&Xr, 0.0)).enumerate() {
                assert!((fr.a - R * f3.a).norm() < 1e-12);
                assert!((fa_revolved * fr.a - fr.a * (1.0 - e[k] * fr.chi)).norm() < 1e-12);
            }
        }
    }

    #[test]
    fn identity_where_inactive() {
        let a = both();
        a.validate().unwrap();
        let I = Matrix2::identity();
        // nucleus, t_a = 0, no fibres
        assert_eq!(a.fa(&at(3.0, -60.0), Domain::Nucleus, 1.0), I);
        assert_eq!(a.fa(&at(6.2, 45.0), Domain::Cytoplasm, 0.0), I);
        assert_eq!(
            ActiveStrain {
                pac: None,
                bottom: None,
                ..both()
            }
            .fa(&at(6.2, 45.0), Domain::Cytoplasm, 1.0),
            I
        );
        // PAC does not act in the membrane
        assert_eq!(a.fa(&at(6.2, 45.0), Domain::Membrane, 1.0), I);
        // θ = 0, r = 9: outside the PAC's outer ellipse and far above the bottom ray
        assert_eq!(a.fa(&at(9.0, 0.0), Domain::Cytoplasm, 1.0), I);
    }

    #[test]
    fn pac_contracts_tangentially_and_bottom_radially() {
        let a = both();
        let t_a = 0.6;
        // deep inside the PAC: r = 6.2 at 45° (inner ellipse ≈ 4.73, outer ≈ 7.24 there)
        let X = at(6.2, 45.0);
        assert_eq!(a.chi_pac(&X), 1.0);
        assert_eq!(a.chi_bottom(&X), 0.0);
        let Fa = a.fa(&X, Domain::Cytoplasm, t_a);
        let t = 45f64.to_radians();
        let N = Vector2::new(t.cos(), t.sin());
        let T = Vector2::new(-N.y, N.x);
        assert!((Fa * T - T * (1.0 - 0.7 * t_a)).norm() < 1e-15);
        assert!((Fa * N - N).norm() < 1e-15);
        // deep in the bottom region: θ = −70°, membrane and cytoplasm alike
        for (r, dom) in [(9.9, Domain::Membrane), (8.0, Domain::Cytoplasm)] {
            let X = at(r, -70.0);
            assert_eq!(a.chi_bottom(&X), 1.0);
            let Fa = a.fa(&X, dom, t_a);
            let t = (-70f64).to_radians();
            let N = Vector2::new(t.cos(), t.sin());
            let T = Vector2::new(-N.y, N.x);
            assert!((Fa * N - N * (1.0 - 0.7 * t_a)).norm() < 1e-15);
            assert!((Fa * T - T).norm() < 1e-15);
        }
    }

    #[test]
    fn indicators_are_one_half_on_the_bounding_curves() {
        let a = both();
        // on the PAC ray (θ = −18°) between the ellipses: the angle factor is ½
        assert!((a.chi_pac(&at(6.2, -18.0)) - 0.5).abs() < 1e-12);
        // on the bottom ray
        assert!((a.chi_bottom(&at(8.0, -35.0)) - 0.5).abs() < 1e-12);
        // on the outer ellipse at 60°: x = 7.5 cos s, y = 7 sin s
        let s = 1.2_f64;
        let X = Vector2::new(7.5 * s.cos(), 8.5 + 7.0 * s.sin());
        assert!((a.chi_pac(&X) - 0.5).abs() < 1e-12);
        // on the inner ellipse
        let X = Vector2::new(5.0 * s.cos(), 8.5 + 4.5 * s.sin());
        assert!((a.chi_pac(&X) - 0.5).abs() < 1e-12);
        // half way across the smoothing band the distances are ±ε/2 from the ray: S(¼)
        let d = 0.125; // ε/2
        let n = Vector2::new(-(-18f64).to_radians().sin(), (-18f64).to_radians().cos());
        let X = at(6.2, -18.0) + n * d;
        let expect = crate::physics::smooth::smooth_step(0.75, 0.0, 1.0);
        assert!((a.chi_pac(&X) - expect).abs() < 1e-12);
    }

    #[test]
    fn fa_is_continuous_bounded_and_invertible() {
        let a = both();
        let h = 1e-4;
        // Lipschitz bound of H_ε over a 1-Lipschitz distance is 15/(8ε); the ellipse
        // distances are first-order, so allow a factor 2; three factors.
        let lip = 3.0 * 2.0 * 15.0 / (8.0 * a.eps);
        for i in 0..400 {
            let th = -89.0 + 178.0 * i as f64 / 399.0;
            for r in [5.1, 5.6, 6.3, 7.0, 7.4, 8.5, 9.5, 9.9] {
                let X = at(r, th);
                for dom in [Domain::Cytoplasm, Domain::Membrane] {
                    let Fa = a.fa(&X, dom, 1.0);
                    assert!(Fa.determinant() >= 0.3 * 0.3 - 1e-12);
                    let (cp, cb) = (a.chi_pac(&X), a.chi_bottom(&X));
                    assert!((0.0..=1.0).contains(&cp) && (0.0..=1.0).contains(&cb));
                    for dX in [Vector2::new(h, 0.0), Vector2::new(0.0, h)] {
                        let Fb = a.fa(&(X + dX), dom, 1.0);
                        assert!((Fb - Fa).norm() <= lip * h * 2.0, "jump at r={r}, θ={th}");
                    }
                }
            }
        }
    }

    #[test]
    fn validation() {
        assert!(both().validate().is_ok());
        let mut a = both();
        a.eps = 0.0;
        assert!(a.validate().is_err());
        let mut a = both();
        a.pac = Some(Pac {
            e: 1.0,
            ..both().pac.unwrap()
        });
        assert!(a.validate().is_err());
        let mut a = both();
        a.pac = Some(Pac {
            outer_axes: [4.0, 7.0],
            ..both().pac.unwrap()
        });
        assert!(a.validate().is_err());
        let mut a = both();
        a.bottom = Some(Bottom {
            theta_deg: -90.0,
            ..both().bottom.unwrap()
        });
        assert!(a.validate().is_err());
    }

    // ---- 3-D ----------------------------------------------------------------------------

    /// The active strains of the 3-D tests: the defaults, MODEL.md's clipped reading of
    /// Table 1 (semi-axes (10, 9), (15, 14)) and a centre off the origin.
    fn variants() -> Vec<(ActiveStrain, f64)> {
        let d = both();
        let clipped = ActiveStrain {
            pac: Some(Pac {
                inner_axes: [10.0, 9.0],
                outer_axes: [15.0, 14.0],
                ..d.pac.unwrap()
            }),
            ..d
        };
        let moved = ActiveStrain {
            center: [1.5, 7.0],
            ..d
        };
        vec![(d, 0.0), (clipped, 0.0), (moved, -2.5)]
    }

    const DOMAINS: [Domain; 3] = [Domain::Nucleus, Domain::Cytoplasm, Domain::Membrane];

    /// A random offset from the centre in [−10, 10]³, or on the axis.
    fn offset(rng: &mut crate::physics::plane_strain::tests::Rng, on_axis: bool) -> Vector3<f64> {
        if on_axis {
            Vector3::new(0.0, rng.uniform(-10.0, 10.0), 0.0)
        } else {
            Vector3::new(
                rng.uniform(-10.0, 10.0),
                rng.uniform(-10.0, 10.0),
                rng.uniform(-10.0, 10.0),
            )
        }
    }

    fn embed(A: &Matrix2<f64>) -> Matrix3<f64> {
        crate::physics::three_d::tests::embed(A, 1.0)
    }

    #[test]
    fn in_the_plane_through_the_centre_fa_revolved_is_fa_plus_one_exactly() {
        // z = c_z, x > c_x: the meridian is the 2-D half plane.
        let mut rng = crate::physics::plane_strain::tests::Rng::new(103);
        for (a, c_z) in variants() {
            let [cx, cy] = a.center;
            for _ in 0..2000 {
                let X2 = Vector2::new(cx + rng.uniform(1e-6, 10.0), cy + rng.uniform(-10.0, 10.0));
                let X3 = Vector3::new(X2.x, X2.y, c_z);
                assert_eq!(a.chi_pac_revolved(&X3, c_z), a.chi_pac(&X2));
                assert_eq!(a.chi_bottom_revolved(&X3, c_z), a.chi_bottom(&X2));
                for dom in DOMAINS {
                    for t_a in [0.0, 0.4, 1.0] {
                        let (f2, f3) = (a.fa(&X2, dom, t_a), a.fa_revolved(&X3, c_z, dom, t_a));
                        assert_eq!(f3, embed(&f2), "{X3:?} {dom} t_a {t_a}");
                    }
                }
            }
            // at the centre: I
            let c3 = Vector3::new(cx, cy, c_z);
            assert_eq!(
                a.fa_revolved(&c3, c_z, Domain::Cytoplasm, 1.0),
                Matrix3::identity()
            );
        }
    }

    #[test]
    fn fa_revolved_is_axisymmetric() {
        // X' = c + R(X − c) for R a rotation about the vertical axis: F_a(X') = R F_a(X) Rᵀ,
        // on and off the axis.
        let mut rng = crate::physics::plane_strain::tests::Rng::new(107);
        for (a, c_z) in variants() {
            let c = Vector3::new(a.center[0], a.center[1], c_z);
            for i in 0..500 {
                let p = offset(&mut rng, i % 50 == 0);
                let R = nalgebra::Rotation3::from_axis_angle(
                    &Vector3::y_axis(),
                    rng.uniform(-3.2, 3.2),
                )
                .into_inner();
                let (X, Xr) = (c + p, c + R * p);
                assert!((a.chi_pac_revolved(&Xr, c_z) - a.chi_pac_revolved(&X, c_z)).abs() < 1e-13);
                assert!(
                    (a.chi_bottom_revolved(&Xr, c_z) - a.chi_bottom_revolved(&X, c_z)).abs()
                        < 1e-13
                );
                for dom in DOMAINS {
                    let (F, Fr) = (
                        a.fa_revolved(&X, c_z, dom, 0.8),
                        a.fa_revolved(&Xr, c_z, dom, 0.8),
                    );
                    assert!((Fr - R * F * R.transpose()).norm() < 1e-12, "{p:?} {dom}");
                }
            }
        }
    }

    #[test]
    fn fa_revolved_bounds_and_indicators() {
        // det F_a ∈ [(1 − e_PAC)(1 − e_bot), 1], F_a symmetric with eigenvalues in
        // [1 − e, 1], indicators in [0, 1]; the fibre directions contract as stated.
        let mut rng = crate::physics::plane_strain::tests::Rng::new(109);
        for (a, c_z) in variants() {
            let (ep, eb) = (a.pac.unwrap().e, a.bottom.unwrap().e);
            let c = Vector3::new(a.center[0], a.center[1], c_z);
            for i in 0..3000 {
                let p = offset(&mut rng, i % 10 == 0);
                let X = c + p;
                let (cp, cb) = (a.chi_pac_revolved(&X, c_z), a.chi_bottom_revolved(&X, c_z));
                assert!((0.0..=1.0).contains(&cp) && (0.0..=1.0).contains(&cb));
                for dom in DOMAINS {
                    let Fa = a.fa_revolved(&X, c_z, dom, 1.0);
                    let det = Fa.determinant();
                    assert!(det >= (1.0 - ep) * (1.0 - eb) - 1e-12 && det <= 1.0 + 1e-12);
                    assert_eq!(Fa, Fa.transpose());
                    let ev = Fa.symmetric_eigenvalues();
                    assert!(
                        ev.iter()
                            .all(|&l| l >= 1.0 - ep.max(eb) - 1e-12 && l <= 1.0 + 1e-12)
                    );
                }
            }
        }
        // the PAC contracts along the meridian, the bottom fibres along N, off the plane
        let a = both();
        let (t, f) = (45f64.to_radians(), 1.1f64);
        let N = Vector3::new(t.cos() * f.cos(), t.sin(), t.cos() * f.sin());
        let T = Vector3::new(-t.sin() * f.cos(), t.cos(), -t.sin() * f.sin());
        let Phi = Vector3::new(-f.sin(), 0.0, f.cos()); // the azimuthal direction
        let X = Vector3::new(0.0, 8.5, 0.0) + N * 6.2;
        let Fa = a.fa_revolved(&X, 0.0, Domain::Cytoplasm, 0.6);
        assert!((Fa * T - T * (1.0 - 0.7 * 0.6)).norm() < 1e-15);
        assert!((Fa * N - N).norm() < 1e-15 && (Fa * Phi - Phi).norm() < 1e-15);
        let (t, f) = ((-70f64).to_radians(), -2.0f64);
        let N = Vector3::new(t.cos() * f.cos(), t.sin(), t.cos() * f.sin());
        let Fa = a.fa_revolved(
            &(Vector3::new(0.0, 8.5, 0.0) + N * 9.9),
            0.0,
            Domain::Membrane,
            0.6,
        );
        assert!((Fa * N - N * (1.0 - 0.7 * 0.6)).norm() < 1e-15);
    }

    #[test]
    fn on_the_axis_the_pac_reaches_the_apex_with_the_azimuthal_mean() {
        let a = both();
        let (e, t_a) = (a.pac.unwrap().e, 0.5);
        // default θ_PAC: the PAC covers the axis above the centre between the ellipsoids
        // (vertical semi-axes 4.5 and 7), not below it; the bottom covers it below
        let top = Vector3::new(0.0, 8.5 + 5.75, 0.0);
        assert_eq!(a.chi_pac_revolved(&top, 0.0), 1.0);
        assert_eq!(
            a.chi_pac_revolved(&Vector3::new(0.0, 8.5 - 5.75, 0.0), 0.0),
            0.0
        );
        assert_eq!(
            a.chi_bottom_revolved(&Vector3::new(0.0, 8.5 - 8.0, 0.0), 0.0),
            1.0
        );
        assert_eq!(a.chi_bottom_revolved(&top, 0.0), 0.0);
        // F_a there: the mean of T⊗T over the azimuth, ½(e_x⊗e_x + e_z⊗e_z)
        let Fa = a.fa_revolved(&top, 0.0, Domain::Cytoplasm, t_a);
        let mean =
            Matrix3::from_diagonal(&Vector3::new(1.0 - 0.5 * e * t_a, 1.0, 1.0 - 0.5 * e * t_a));
        assert_eq!(Fa, mean);
        // which is the average of F_a over a small circle about the axis
        let n = 64;
        let avg = (0..n)
            .map(|k| {
                let f = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                a.fa_revolved(
                    &(top + Vector3::new(f.cos(), 0.0, f.sin()) * 1e-9),
                    0.0,
                    Domain::Cytoplasm,
                    t_a,
                )
            })
            .fold(Matrix3::zeros(), |s, m| s + m)
            / n as f64;
        assert!((avg - mean).norm() < 1e-8, "{avg}");
        // (the 2-D half cell takes T = (−1, 0) on its symmetry line instead)
        let f2 = a.fa(&Vector2::new(0.0, top.y), Domain::Cytoplasm, t_a);
        assert_eq!(f2, Matrix2::new(1.0 - e * t_a, 0.0, 0.0, 1.0));
    }
}
