//! Active strain of the actin fibres (MODEL.md §6).
//!
//! `F_a = I − e_PAC t_a χ_PAC (T⊗T) − e_bot t_a χ_bot (N⊗N)`, with `N = (p − c)/|p − c|`
//! the radial and `T = (−N_y, N_x)` the tangential reference direction about the cell
//! centre `c`. PAC ("push", tangential fibres) acts in the cytoplasm only; bottom ("pull",
//! radial fibres) in the cytoplasm and the membrane. `χ` are products of regularised
//! Heavisides `H_ε` of signed distances to the bounding curves (in reference coordinates),
//! so `F_a` is smooth in `p`. Everything here is `f64`: it depends on the reference
//! position and time only.

#![allow(non_snake_case)]

use super::smooth::heaviside;
use super::{PhysicsError, check};
use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

/// Which sub-domain of the cell a material point belongs to (MODEL.md §2; the mesh is
/// conforming, so each element lies in exactly one).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Domain {
    /// `|p − c| < r_n`: no active strain.
    Nucleus,
    /// `r_n < |p − c| < r_cp`: PAC and bottom active strains.
    Cytoplasm,
    /// `r_cp < |p − c| < r_c`: bottom active strain only; adhesion acts here.
    Membrane,
}

impl Domain {
    /// All domains, inside out.
    pub const ALL: [Domain; 3] = [Domain::Nucleus, Domain::Cytoplasm, Domain::Membrane];
}

impl std::fmt::Display for Domain {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Domain::Nucleus => "nucleus",
            Domain::Cytoplasm => "cytoplasm",
            Domain::Membrane => "membrane",
        })
    }
}

/// Perinuclear actin cap ("push"): tangential contraction in the cytoplasm between two
/// ellipses centred at `c`, for `θ ≥ θ_PAC`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pac {
    /// Contraction amplitude `e_PAC` (dimensionless, in [0, 1); target fibre stretch `1 − e`).
    pub e: f64,
    /// Bounding angle `θ_PAC` [degrees], measured from the +x axis; the PAC is `θ ≥ θ_PAC`.
    pub theta_deg: f64,
    /// Semi-axes (along x, along y) of the inner ellipse [µm].
    pub inner_axes: [f64; 2],
    /// Semi-axes (along x, along y) of the outer ellipse [µm].
    pub outer_axes: [f64; 2],
}

/// Bottom fibres ("pull"): radial contraction in the cytoplasm and membrane for
/// `θ ≤ θ_bot`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bottom {
    /// Contraction amplitude `e_bot` (dimensionless, in [0, 1)).
    pub e: f64,
    /// Bounding angle `θ_bot` [degrees]; the bottom region is `θ ≤ θ_bot`.
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
    /// Smoothing half-width `ε_a` of the indicator Heavisides [µm] (MODEL.md: 0.25).
    pub eps: f64,
    /// Cell centre `c` [µm] (MODEL.md: (0, 8.5)).
    pub center: [f64; 2],
}

/// Signed distance to the line through the origin at angle `theta` (radians) from the
/// +x axis, positive on the counter-clockwise side (larger polar angle for points with
/// `x > 0`): `d = cos θ · p_y − sin θ · p_x`.
fn side_of_ray(p: &Vector2<f64>, theta: f64) -> f64 {
    theta.cos() * p.y - theta.sin() * p.x
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
    /// Checks `ε_a > 0`, amplitudes in [0, 1) (so `det F_a ≥ (1 − e_PAC)(1 − e_bot) > 0`),
    /// angles in (−90°, 90°], positive semi-axes with the inner ellipse smaller than the
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
        let angle_ok = |t: f64| t.is_finite() && t > -90.0 && t <= 90.0;
        if let Some(p) = self.pac {
            check(
                p.e.is_finite() && (0.0..1.0).contains(&p.e),
                "pac.e",
                p.e,
                "must lie in [0, 1)",
            )?;
            check(
                angle_ok(p.theta_deg),
                "pac.theta_deg",
                p.theta_deg,
                "must lie in (-90, 90]",
            )?;
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
            check(
                b.e.is_finite() && (0.0..1.0).contains(&b.e),
                "bottom.e",
                b.e,
                "must lie in [0, 1)",
            )?;
            check(
                angle_ok(b.theta_deg),
                "bottom.theta_deg",
                b.theta_deg,
                "must lie in (-90, 90]",
            )?;
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
        let p = self.offset(X);
        let r = p.norm();
        if r == 0.0 {
            return I;
        }
        let N = p / r;
        let T = Vector2::new(-N.y, N.x);
        let mut Fa = I;
        if let (Some(pac), Domain::Cytoplasm) = (self.pac, domain) {
            let a = pac.e * t_a * self.chi_pac(X);
            if a != 0.0 {
                Fa -= T * T.transpose() * a;
            }
        }
        if let Some(bot) = self.bottom {
            let b = bot.e * t_a * self.chi_bottom(X);
            if b != 0.0 {
                Fa -= N * N.transpose() * b;
            }
        }
        Fa
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both regions at the case's defaults (the one source of MODEL.md's numbers).
    fn both() -> ActiveStrain {
        crate::case::terms::active(&crate::case::Case::reference_active())
            .expect("the reference case has both regions")
    }

    fn at(r: f64, deg: f64) -> Vector2<f64> {
        let t = deg.to_radians();
        Vector2::new(r * t.cos(), 8.5 + r * t.sin())
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
}
