//! The rigid substrate (MODEL.md §5): signed penetration depth `d(x)` (> 0 inside the
//! substrate) and outward unit normal `n(x)` at a current position `x`.
//!
//! Flat: `d = y_s − y`, `n = e_y`.
//!
//! Micropillars: pillars of width `w`, spacing `s`, height `h`, axes at
//! `x_k = first_center + k(w + s)` for every integer `k`, tops at `y_top`, floor at
//! `y_top − h`. Each pillar is the superellipse `|x̃/(w/2)|^q + |ỹ/(h/2)|^q ≤ 1`, `x̃` the
//! offset to the nearest axis, `ỹ = y − (y_top − h/2)`.
//!
//! **Level set.** MODEL.md allows the first-order distance `−l/|∇l|` of "its level set".
//! We take the level set homogeneous of degree one,
//! `l = (|u|^q + |v|^q)^{1/q} − 1`, `u = x̃/(w/2)`, `v = ỹ/(h/2)`,
//! rather than the polynomial `|u|^q + |v|^q − 1`. Both have the same zero set and normal,
//! but the homogeneous one gives the exact distance along the flat faces at any offset,
//! while the polynomial one (for q = 4) overestimates depth-from-outside by a factor that
//! makes the 1.5 µm fibronectin band `d > −e_f` about 2.7 µm thick above the pillar tops
//! instead of 1.5 µm. Near the rounded corners the homogeneous distance is still only
//! first-order (within a factor `2^{1/2 − 1/q}` for a square superellipse).
//!
//! **Pillar and floor.** `d = max(d_pillar, d_floor)` with the normal of the deeper one.
//! This is not smooth where `d_pillar = d_floor`, i.e. along a curve in the concave corner
//! between a pillar's side and the floor (and, for [`PillarFoot::Rounded`], under the
//! pillar's rounded bottom, which meets the floor in one point, leaving a thin undercut;
//! the default [`PillarFoot::Straight`] has none), rounded by the fillet; the contact band meets it only
//! if material reaches within `ε` of the floor next to a pillar foot. `d_pillar` is also
//! not smooth mid-way between two pillars (`x̃ = ±(w + s)/2`, where the nearest axis
//! changes: `d` is continuous there by symmetry but `n` flips); there `d_pillar ≈ −s/2`
//! (−4 µm by default), far outside every band unless `s/2 < e_f + ε`.
//!
//! **3-D** ([`LatticeSubstrate`], MODEL.md §10). The pillars stand on a square lattice of
//! period `P = w + s` in x and in z ([`Lattice`]); each is the superellipsoid
//! `|x̃/(w/2)|^q + |ỹ/(h/2)|^q + |z̃/(w/2)|^q ≤ 1`, `x̃`, `z̃` the offsets to the nearest
//! pillar axis in x and in z, with the same homogeneous level set
//! `l = (|u|^q + |v|^q + |w|^q)^{1/q} − 1` (`w = z̃/(w/2)`), the same first-order distance
//! `d = −l/|∇l|`, normal `∇l/|∇l|`, and the same floor, `d = max(d_pillar, d_floor)`. It is
//! exact above the middle of a top and beside the middle of a side face; on the plane
//! `z̃ = 0` through a row of axes it is the 2-D [`Substrate::eval`], bit for bit. The
//! non-smooth sets are the 2-D ones, now surfaces: the pillar/floor switch around each
//! pillar's foot, and the mid-planes `x̃ = ±P/2` and `z̃ = ±P/2` between pillars, where the
//! nearest axis changes (`d ≈ −s/2` there at the height of the tops, and lower between
//! the corners of four pillars).

#![allow(non_snake_case)]

use super::{PhysicsError, Real, abs, check, cst, powf, powi, re, sqrt};
use nalgebra::{SVector, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// How a pillar meets the floor.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum PillarFoot {
    /// The whole superellipse (superellipsoid in 3-D) of the paper's pillar table: its
    /// rounded lower half touches the floor at one point, under its axis, leaving an
    /// undercut that opens from there to h/2 under the pillar's edges (1.3 µm high where
    /// the 3-D push-pull cell jammed, under a corner 0.8 w/2 from the axis in x and z;
    /// in 2-D the membrane creases at the undercut's lip on refined meshes, MODEL.md §5).
    Rounded,
    /// The upper half of the superellipse (superellipsoid) continued straight down to the
    /// floor: a column with rounded top edges, its sides vertical where `ỹ < 0`, meeting
    /// the floor in a right-angled concave corner (no undercut). The level set is the same
    /// with `ỹ` replaced by `max(ỹ, 0)` (C³ across `ỹ = 0` for q = 4). The default in every
    /// dimension (MODEL.md §5): a micropillar stands on its floor.
    #[default]
    Straight,
}

/// Micropillar geometry. Lengths in µm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pillars {
    /// Pillar width `w` \[µm\] (MODEL.md: 8).
    pub width: f64,
    /// Spacing between pillars `s` \[µm\] (MODEL.md: 8); period `w + s`.
    pub spacing: f64,
    /// Pillar height `h` \[µm\] (MODEL.md: 8); the floor is at `y_top − h`.
    pub height: f64,
    /// Abscissa of the axis of pillar `k = 0` \[µm\] (MODEL.md: 8).
    pub first_center: f64,
    /// Superellipse exponent `q ≥ 2` (MODEL.md: 4); integers use exact integer powers.
    pub q: f64,
    /// Height of the pillar tops `y_top` \[µm\] (MODEL.md: placed by [`Pillars::y_top_for_gap`],
    /// ≈ −0.3 for the default cell).
    pub y_top: f64,
    /// How the pillar meets the floor (default [`PillarFoot::Straight`], MODEL.md §5).
    #[serde(default)]
    pub foot: PillarFoot,
    /// Width `k` \[µm\] of the fillet where the floor meets a pillar: 0 (default, MODEL.md)
    /// takes the deeper of the two surfaces, a kink in the concave corner; `k > 0` the
    /// smooth maximum of the two depths where they are within `k` of each other
    /// ([`floor_and_pillar`]).
    #[serde(default)]
    pub fillet: f64,
}

/// The union of the floor and a pillar: the deeper of the two (`d = max(d_f, d_p)` with
/// that one's normal), or, with a fillet `k > 0` where the depths are within `k` of each
/// other, their quadratic smooth maximum `max(d_f, d_p) + (k − |d_f − d_p|)²/(4k)` with the
/// normal `λ n_f + (1 − λ) n_p` normalised, `λ = 1/2 + (d_f − d_p)/(2k)` (the weight of
/// the floor in the gradient of that maximum): depth and normal then turn continuously
/// round the concave corner between a pillar's foot and the floor, which the surface
/// leaves by at most `k/4` on the corner's bisector.
#[inline(always)]
pub fn floor_and_pillar<T: Real, const D: usize>(
    d_f: T,
    n_f: nalgebra::SVector<T, D>,
    d_p: T,
    n_p: nalgebra::SVector<T, D>,
    k: f64,
) -> (T, nalgebra::SVector<T, D>) {
    let hard = if re(d_f) > re(d_p) {
        (d_f, n_f)
    } else {
        (d_p, n_p)
    };
    if k <= 0.0 || (re(d_f) - re(d_p)).abs() >= k {
        return hard;
    }
    let diff = d_f - d_p;
    let h = (-abs(diff) + k) / k;
    let d = hard.0 + h * h * (0.25 * k);
    let lambda = diff / (2.0 * k) + 0.5;
    let n = n_f * lambda + n_p * (-lambda + 1.0);
    let norm = n.norm();
    if re(norm) < 1e-9 {
        // Opposite normals (inside the undercut of a rounded foot): no direction between.
        return (d, hard.1);
    }
    (d, n / norm)
}

/// The substrate: a flat half-plane or a periodic row of pillars on a floor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Substrate {
    /// Half-plane `y < y_s` \[µm\] (MODEL.md: `y_s = −2`).
    Flat {
        /// Surface height `y_s` \[µm\].
        y_s: f64,
    },
    /// Micropillars on a floor.
    Pillars(Pillars),
}

/// `(|u|^q, |u|^{q−1} sgn u)`, exact integer powers for integer `q` (derivatives are then
/// exact at `u = 0` too); for non-integer `q > 1` both vanish with their derivatives at 0.
///
/// For the usual `q = 4` in `f64`, `u⁴ = (u²)²` and `u³ = u² u` by multiplication: the
/// same products, in the same order, as the integer power by squaring computes, so the
/// same bits without its call (the level set runs at every band point of every residual).
#[inline(always)]
fn abs_pow<T: Real>(u: T, q: f64) -> (T, T) {
    if q == 4.0 && T::NDERIV == 0 {
        let u2 = u * u;
        return (u2 * u2, u2 * u);
    }
    if q.fract() == 0.0 && q <= 64.0 {
        let n = q as i32;
        if n % 2 == 0 {
            (powi(u, n), powi(u, n - 1))
        } else {
            let au = abs(u);
            (au * powi(u, n - 1), au * powi(u, n - 2))
        }
    } else {
        let au = abs(u);
        if re(au) == 0.0 {
            (cst(0.0), cst(0.0))
        } else {
            let g = powf(au, q - 1.0);
            let g = if re(u) < 0.0 { -g } else { g };
            (powf(au, q), g)
        }
    }
}

impl Pillars {
    /// `ρ^{1/q}`: two square roots for the usual q = 4 (a third of the cost of powf).
    #[inline(always)]
    fn root<T: Real>(&self, rho: T) -> T {
        if self.q == 4.0 {
            sqrt(sqrt(rho))
        } else {
            powf(rho, 1.0 / self.q)
        }
    }

    /// Checks `w, h > 0`, `s ≥ 0`, `q ≥ 2` (so the normal is C¹), all finite.
    pub fn validate(&self) -> Result<(), PhysicsError> {
        check(
            self.width.is_finite() && self.width > 0.0,
            "pillars.width",
            self.width,
            "must be finite and > 0",
        )?;
        check(
            self.spacing.is_finite() && self.spacing >= 0.0,
            "pillars.spacing",
            self.spacing,
            "must be finite and >= 0",
        )?;
        check(
            self.height.is_finite() && self.height > 0.0,
            "pillars.height",
            self.height,
            "must be finite and > 0",
        )?;
        check(
            self.q.is_finite() && self.q >= 2.0,
            "pillars.q",
            self.q,
            "must be finite and >= 2",
        )?;
        check(
            self.first_center.is_finite(),
            "pillars.first_center",
            self.first_center,
            "must be finite",
        )?;
        check(
            self.y_top.is_finite(),
            "pillars.y_top",
            self.y_top,
            "must be finite",
        )?;
        check(
            self.fillet.is_finite()
                && self.fillet >= 0.0
                && self.fillet <= 0.5 * self.height.min(self.spacing),
            "pillars.fillet",
            self.fillet,
            "must be >= 0 and at most half the height and half the spacing",
        )
    }

    /// Period `w + s` \[µm\].
    pub fn period(&self) -> f64 {
        self.width + self.spacing
    }

    /// Axis of the pillar nearest to abscissa `x` \[µm\].
    pub fn nearest_axis(&self, x: f64) -> f64 {
        let k = ((x - self.first_center) / self.period()).round();
        self.first_center + k * self.period()
    }

    /// Penetration depth and outward normal of the pillar nearest to `x` alone (no floor),
    /// in 2-D the superellipse, in 3-D the superellipsoid on `lattice` (ignored in 2-D):
    /// `d = −l/|∇l|`, `n = ∇l/|∇l|`, `l = ρ^{1/q} − 1` with `ρ = Σᵢ |uᵢ|^q` over the
    /// scaled offsets `u = (x̃/(w/2), ỹ/(h/2)[, z̃/(w/2)])`. With `r = ρ^{1/q}` and
    /// `gᵢ = |uᵢ|^{q−1} sgn uᵢ / (its half-size)`: `∇l = r^{1−q} g`, so
    /// `d = (1 − r) ρ/(r|g|)`, `n = g/|g|`.
    #[inline(always)]
    pub fn eval_pillar<T: Real, const D: usize>(
        &self,
        x: &SVector<T, D>,
        lattice: Lattice,
    ) -> (T, SVector<T, D>) {
        let a = 0.5 * self.width;
        let b = 0.5 * self.height;
        let half = [a, b, a];
        let parts: [(T, T); D] = std::array::from_fn(|i| {
            let offset = match i {
                0 => x[0] - self.nearest_axis(re(x[0])),
                1 => self.above_mid_height(x[1] - (self.y_top - b)),
                _ => x[2] - self.nearest_axis_z(re(x[2]), lattice),
            };
            abs_pow(offset / half[i], self.q)
        });
        let rho = (1..D).fold(parts[0].0, |s, i| s + parts[i].0);
        if re(rho) <= 0.0 {
            // The pillar's centre, a·b deep inside: no direction; never reached in practice.
            let up = SVector::from_fn(|i, _| cst(if i == 1 { 1.0 } else { 0.0 }));
            return (cst(a.min(b)), up);
        }
        let r = self.root(rho);
        let g: SVector<T, D> = SVector::from_fn(|i, _| parts[i].1 / half[i]);
        let norm = sqrt((1..D).fold(g[0] * g[0], |s, i| s + g[i] * g[i]));
        let d = (-r + 1.0) * rho / (r * norm);
        (d, g.map(|gi| gi / norm))
    }

    /// The height `ỹ` above the pillar's mid-height as the level set sees it: `ỹ` itself
    /// for a rounded foot, `max(ỹ, 0)` for a straight one ([`PillarFoot`]).
    #[inline(always)]
    fn above_mid_height<T: Real>(&self, yt: T) -> T {
        match self.foot {
            PillarFoot::Straight if re(yt) < 0.0 => cst(0.0),
            _ => yt,
        }
    }

    /// Height `y` of the substrate surface (pillar top or floor) at abscissa `x` \[µm\]:
    /// `y_top − h/2 + (h/2)(1 − |x̃/(w/2)|^q)^{1/q}` over a pillar, else `y_top − h`.
    pub fn surface_height(&self, x: f64) -> f64 {
        let a = 0.5 * self.width;
        let u = ((x - self.nearest_axis(x)) / a).abs();
        self.height_over(u.powf(self.q))
    }

    /// The surface's height where `Σ |horizontal offset / (w/2)|^q` is `s`: the pillar's
    /// top `y_top − h/2 + (h/2)(1 − s)^{1/q}` for `s < 1`, not below the floor `y_top − h`.
    fn height_over(&self, s: f64) -> f64 {
        let b = 0.5 * self.height;
        let floor = self.y_top - self.height;
        if s >= 1.0 {
            floor
        } else {
            (self.y_top - b + b * (1.0 - s).powf(1.0 / self.q)).max(floor)
        }
    }

    /// `y_top` such that the smallest vertical gap between the reference circle
    /// (centre `cell_center`, radius `r_c`) and the substrate surface below it is `gap`
    /// \[µm\] (MODEL.md §5 \[choice\]). Only the geometry `w, s, h, first_center, q` of `self`
    /// is used.
    ///
    /// The gap at abscissa `x` is `c_y − √(r_c² − (x − c_x)²) − y_surf(x)` and `y_surf`
    /// is `y_top` plus a function of `x`, so `y_top = min_x(c_y − √(…) − (y_surf − y_top)) −
    /// gap`; the minimum is found by dense sampling of `[c_x − r_c, c_x + r_c]` and a
    /// golden-section refinement.
    pub fn y_top_for_gap(
        &self,
        gap: f64,
        cell_center: [f64; 2],
        r_c: f64,
    ) -> Result<f64, PhysicsError> {
        let sum = cell_center[0] + cell_center[1];
        self.check_gap_inputs(gap, &cell_center, sum, r_c)?;
        let (_, clearance) = self.lowest_clearance(cell_center, r_c);
        Ok(clearance - gap)
    }

    /// Checks the parameters, the gap, the cell's radius `r_c` and its centre `cell_center`
    /// (`sum`: the sum of its coordinates, for the message) of a `y_top` placement.
    fn check_gap_inputs(
        &self,
        gap: f64,
        cell_center: &[f64],
        sum: f64,
        r_c: f64,
    ) -> Result<(), PhysicsError> {
        self.validate()?;
        check(gap.is_finite(), "gap", gap, "must be finite")?;
        check(
            r_c.is_finite() && r_c > 0.0,
            "r_c",
            r_c,
            "must be finite and > 0",
        )?;
        check(
            cell_center.iter().all(|v| v.is_finite()),
            "cell_center",
            sum,
            "must be finite",
        )
    }

    /// `(x*, G(x*))` minimising `G(x) = circle bottom(x) − (y_surf(x) − y_top)` over the
    /// circle's span: the abscissa of the smallest vertical gap and `y_top + gap` there.
    pub fn lowest_clearance(&self, cell_center: [f64; 2], r_c: f64) -> (f64, f64) {
        let [cx, cy] = cell_center;
        let g = |x: f64| {
            let dx = (x - cx).clamp(-r_c, r_c);
            cy - (r_c * r_c - dx * dx).max(0.0).sqrt() - (self.surface_height(x) - self.y_top)
        };
        let n = 8000;
        let step = 2.0 * r_c / n as f64;
        let (mut i_best, mut g_best) = (0, f64::INFINITY);
        for i in 0..=n {
            let v = g(cx - r_c + i as f64 * step);
            if v < g_best {
                (i_best, g_best) = (i, v);
            }
        }
        // golden section on [x_{i−1}, x_{i+1}]
        let mut lo = cx - r_c + (i_best.max(1) - 1) as f64 * step;
        let mut hi = (lo + 2.0 * step).min(cx + r_c);
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        let mut x1 = hi - phi * (hi - lo);
        let mut x2 = lo + phi * (hi - lo);
        let (mut g1, mut g2) = (g(x1), g(x2));
        for _ in 0..80 {
            if g1 < g2 {
                hi = x2;
                (x2, g2) = (x1, g1);
                x1 = hi - phi * (hi - lo);
                g1 = g(x1);
            } else {
                lo = x1;
                (x1, g1) = (x2, g2);
                x2 = lo + phi * (hi - lo);
                g2 = g(x2);
            }
        }
        let (xm, gm) = if g1 < g2 { (x1, g1) } else { (x2, g2) };
        if gm < g_best {
            (xm, gm)
        } else {
            (cx - r_c + i_best as f64 * step, g_best)
        }
    }
}

impl Substrate {
    /// Checks the parameters (finite `y_s`; see [`Pillars::validate`]).
    pub fn validate(&self) -> Result<(), PhysicsError> {
        match self {
            Substrate::Flat { y_s } => check(y_s.is_finite(), "y_s", *y_s, "must be finite"),
            Substrate::Pillars(p) => p.validate(),
        }
    }

    /// Signed penetration depth `d(x)` \[µm\] (> 0 inside the substrate) and outward unit
    /// normal `n(x)` at the current position `x` \[µm\]. Generic, for exact tangents.
    ///
    /// Flat: `d = y_s − y`, `n = e_y`. Pillars: the deeper of pillar and floor,
    /// `d = max(d_pillar, y_top − h − y)` (see the module notes on where this is not smooth).
    ///
    /// In `f64` (residuals, observables) it is inlined into its callers; with dual numbers
    /// (tangents, several times the code) it is one function per number type. The model's
    /// element loops, instantiated per kinematic model, call it from several places, and
    /// left to itself the compiler inlined neither (see `model::kernels`).
    #[inline(always)]
    pub fn eval<T: Real>(&self, x: &Vector2<T>) -> (T, Vector2<T>) {
        Surface::eval(self, x)
    }

    /// The substrate surface as a polyline for plotting, over `[x_min, x_max]` \[µm\].
    ///
    /// Flat: the two end points. Pillars: the floor, and at each pillar axis the full
    /// superellipse traced from its bottom point clockwise (left side, top, right side)
    /// with `n` points (at least 8), its lower half straight down for a straight foot
    /// ([`PillarFoot::Straight`]); pillars overlapping the interval are drawn whole.
    pub fn outline(&self, x_min: f64, x_max: f64, n: usize) -> Vec<[f64; 2]> {
        match self {
            Substrate::Flat { y_s } => vec![[x_min, *y_s], [x_max, *y_s]],
            Substrate::Pillars(p) => {
                let n = n.max(8);
                let a = 0.5 * p.width;
                let b = 0.5 * p.height;
                let yc = p.y_top - b;
                let floor = p.y_top - p.height;
                let per = p.period();
                let k0 = ((x_min - a - p.first_center) / per).ceil() as i64;
                let k1 = ((x_max + a - p.first_center) / per).floor() as i64;
                let mut pts = vec![[x_min, floor]];
                for k in k0..=k1 {
                    let axis = p.first_center + k as f64 * per;
                    for j in 0..=n {
                        let t = 1.5 * std::f64::consts::PI
                            - 2.0 * std::f64::consts::PI * j as f64 / n as f64;
                        let (s, c) = t.sin_cos();
                        let mut u = c.signum() * c.abs().powf(2.0 / p.q);
                        let v = s.signum() * s.abs().powf(2.0 / p.q);
                        if p.foot == PillarFoot::Straight && v < 0.0 && c != 0.0 {
                            // The lower half is the column's vertical side.
                            u = c.signum();
                        }
                        pts.push([axis + a * u, yc + b * v]);
                    }
                }
                pts.push([x_max, floor]);
                pts
            }
        }
    }
}

/// A substrate in `D` dimensions: its signed penetration depth `d(x)` (> 0 inside) and
/// outward unit normal `n(x)` at a current position, generic over [`Real`] for exact
/// tangents. The 2-D section ([`Substrate`]) and the 3-D substrate ([`LatticeSubstrate`]).
pub trait Surface<const D: usize> {
    /// `(d(x), n(x))`: inlined in `f64`, one function per dual type otherwise (see
    /// [`Substrate::eval`]).
    #[inline(always)]
    fn eval<T: Real>(&self, x: &SVector<T, D>) -> (T, SVector<T, D>) {
        if T::NDERIV == 0 {
            self.eval_inline(x)
        } else {
            self.eval_dual(x)
        }
    }

    #[doc(hidden)]
    #[inline(never)]
    fn eval_dual<T: Real>(&self, x: &SVector<T, D>) -> (T, SVector<T, D>) {
        self.eval_inline(x)
    }

    /// `(d(x), n(x))`, the implementation.
    #[doc(hidden)]
    fn eval_inline<T: Real>(&self, x: &SVector<T, D>) -> (T, SVector<T, D>);
}

/// `(d(x), n(x))` of the floor and pillars `plane` at `x` (`y` its second entry), with
/// `(d, n)` of the pillars from `pillar`.
#[inline(always)]
fn plane_eval<T: Real, const D: usize>(
    plane: &Substrate,
    x: &SVector<T, D>,
    pillar: impl FnOnce(&Pillars) -> (T, SVector<T, D>),
) -> (T, SVector<T, D>) {
    let up = SVector::from_fn(|i, _| cst(if i == 1 { 1.0 } else { 0.0 }));
    match plane {
        Substrate::Flat { y_s } => (-x[1] + *y_s, up),
        Substrate::Pillars(p) => {
            let d_floor = -x[1] + (p.y_top - p.height);
            let (d_p, n_p) = pillar(p);
            floor_and_pillar(d_floor, up, d_p, n_p, p.fillet)
        }
    }
}

impl Surface<2> for Substrate {
    #[inline(always)]
    fn eval_inline<T: Real>(&self, x: &Vector2<T>) -> (T, Vector2<T>) {
        plane_eval(self, x, |p| p.eval_pillar(x, Lattice::Gap))
    }
}

impl Surface<3> for LatticeSubstrate {
    #[inline(always)]
    fn eval_inline<T: Real>(&self, x: &Vector3<T>) -> (T, Vector3<T>) {
        plane_eval(&self.plane, x, |p| p.eval_pillar(x, self.lattice))
    }
}

/// The horizontal layout of the pillars in 3-D (MODEL.md §10): a square lattice of period
/// `P = w + s` in x and in z, the x axes at `first_center + kP` as in 2-D. With
/// `first_center = P/2` (the default) both layouts keep the quarter symmetry of the cell,
/// `d(x, y, z) = d(−x, y, z) = d(x, y, −z)` about the cell's axis `x = z = 0`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Lattice {
    /// The cell centre above the centre of a square of four pillars (MODEL.md's default):
    /// axes at `x = first_center + kP` and `z = P/2 + kP`, `z̃` measured from the nearest of
    /// `±P/2 + kP`.
    #[default]
    FourPillars,
    /// The cell centre above the middle of the gap between two pillars: axes at
    /// `x = first_center + kP` and `z = kP`, so the section `z = 0` is the 2-D substrate.
    Gap,
}

impl Lattice {
    /// The z of the axes of the row `k = 0` \[µm\] for the period `period`: `P/2`
    /// ([`Lattice::FourPillars`]) or 0 ([`Lattice::Gap`]).
    #[inline]
    pub fn z_offset(self, period: f64) -> f64 {
        match self {
            Lattice::FourPillars => 0.5 * period,
            Lattice::Gap => 0.0,
        }
    }
}

/// The substrate of the 3-D model (MODEL.md §10): the 2-D one, flat or pillared, extended
/// along z; the pillars become superellipsoids on the square lattice `lattice` (ignored
/// for a flat substrate).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LatticeSubstrate {
    /// The section: a flat surface `y_s`, or the pillars' `w, s, h, first_center, q,
    /// y_top` (the same fields mean the same in 3-D).
    pub plane: Substrate,
    /// Where the rows of pillars stand in z.
    pub lattice: Lattice,
}

impl Pillars {
    /// Axis (in z) of the pillar row nearest to `z` \[µm\] on `lattice`.
    #[inline]
    pub fn nearest_axis_z(&self, z: f64, lattice: Lattice) -> f64 {
        let z0 = lattice.z_offset(self.period());
        let k = ((z - z0) / self.period()).round();
        z0 + k * self.period()
    }

    /// Height `y` of the substrate surface at `(x, z)` \[µm\] on `lattice`:
    /// `y_top − h/2 + (h/2)(1 − |u|^q − |w|^q)^{1/q}` over a pillar
    /// (`|u|^q + |w|^q < 1`), else the floor `y_top − h`.
    #[inline]
    pub fn surface_height_on_lattice(&self, x: f64, z: f64, lattice: Lattice) -> f64 {
        let a = 0.5 * self.width;
        let u = ((x - self.nearest_axis(x)) / a).abs();
        let w = ((z - self.nearest_axis_z(z, lattice)) / a).abs();
        self.height_over(u.powf(self.q) + w.powf(self.q))
    }
}

impl Pillars {
    /// `y_top` such that the smallest vertical gap between the reference sphere (centre
    /// `cell_center`, radius `r_c`) and the 3-D substrate surface on `lattice` below it is
    /// `gap` \[µm\] (MODEL.md §10, placed "as in §5"); the 3-D twin of
    /// [`Pillars::y_top_for_gap`]. Only `w, s, h, first_center, q` of `self` are used.
    ///
    /// On [`Lattice::Gap`] (pillars at z = 0) the smallest gap lies in the plane z = 0 and
    /// this is the 2-D placement; on [`Lattice::FourPillars`] it lies over the pillars'
    /// rounded corners nearest the axis.
    #[inline]
    pub fn y_top_for_gap_on_lattice(
        &self,
        gap: f64,
        lattice: Lattice,
        cell_center: [f64; 3],
        r_c: f64,
    ) -> Result<f64, PhysicsError> {
        self.check_gap_inputs(gap, &cell_center, cell_center.iter().sum(), r_c)?;
        let (_, clearance) = self.lowest_clearance_on_lattice(lattice, cell_center, r_c);
        Ok(clearance - gap)
    }

    /// `([x*, z*], G(x*, z*))` minimising `G(x, z) = sphere bottom(x, z) −
    /// (y_surf(x, z) − y_top)` over the sphere's horizontal disk: where the vertical gap is
    /// smallest, and `y_top + gap` there. A 201 × 201 grid over the disk's square (outside
    /// the disk the sphere's "bottom" is its equator height, never the minimum), then
    /// zooming 11 × 11 grids, each 2.5 × finer, down to 1e-10 µm.
    #[inline]
    pub fn lowest_clearance_on_lattice(
        &self,
        lattice: Lattice,
        cell_center: [f64; 3],
        r_c: f64,
    ) -> ([f64; 2], f64) {
        let [cx, cy, cz] = cell_center;
        let g = |x: f64, z: f64| {
            let (dx, dz) = (x - cx, z - cz);
            cy - (r_c * r_c - dx * dx - dz * dz).max(0.0).sqrt()
                - (self.surface_height_on_lattice(x, z, lattice) - self.y_top)
        };
        let n = 200;
        let mut h = 2.0 * r_c / n as f64;
        let mut best = ([cx, cz], g(cx, cz));
        for i in 0..=n {
            for j in 0..=n {
                let (x, z) = (cx - r_c + i as f64 * h, cz - r_c + j as f64 * h);
                let v = g(x, z);
                if v < best.1 {
                    best = ([x, z], v);
                }
            }
        }
        while h > 1e-10 {
            let [x0, z0] = best.0;
            // ±2 old steps around the best point, 11 points a side
            let hn = 0.4 * h;
            for i in -5..=5 {
                for j in -5..=5 {
                    let (x, z) = (x0 + i as f64 * hn, z0 + j as f64 * hn);
                    let v = g(x, z);
                    if v < best.1 {
                        best = ([x, z], v);
                    }
                }
            }
            h = hn;
        }
        best
    }
}

impl LatticeSubstrate {
    /// Checks the parameters (those of [`Substrate::validate`]; a lattice has none).
    #[inline]
    pub fn validate(&self) -> Result<(), PhysicsError> {
        self.plane.validate()
    }

    /// Signed penetration depth `d(x)` \[µm\] (> 0 inside the substrate) and outward unit
    /// normal `n(x)` at the current position `x` \[µm\]. Generic, for exact tangents.
    ///
    /// Flat: `d = y_s − y`, `n = e_y`. Pillars: `d = max(d_pillar, y_top − h − y)` with
    /// the normal of the deeper one (module notes). Inlined in `f64`, one function per
    /// dual type otherwise, as [`Substrate::eval`].
    #[inline(always)]
    pub fn eval<T: Real>(&self, x: &Vector3<T>) -> (T, Vector3<T>) {
        Surface::eval(self, x)
    }

    /// Height `y` of the substrate surface at `(x, z)` \[µm\], for plotting: `y_s` (flat) or
    /// [`Pillars::surface_height_on_lattice`].
    #[inline]
    pub fn surface_height(&self, x: f64, z: f64) -> f64 {
        match &self.plane {
            Substrate::Flat { y_s } => *y_s,
            Substrate::Pillars(p) => p.surface_height_on_lattice(x, z, self.lattice),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use num_dual::DualSVec64;

    type D2 = DualSVec64<2>;

    fn dual_point(x: f64, y: f64) -> Vector2<D2> {
        Vector2::new(D2::from_re(x).derivative(0), D2::from_re(y).derivative(1))
    }

    fn grad(v: &D2) -> [f64; 2] {
        let g = v.eps.unwrap_generic(nalgebra::U2, nalgebra::U1);
        [g[0], g[1]]
    }

    /// A point on the boundary of the superellipse of the pillar with axis `axis`,
    /// parameter `t`: `u = sgn(cos t)|cos t|^{2/q}`, `v = sgn(sin t)|sin t|^{2/q}`.
    fn on_pillar(p: &Pillars, axis: f64, t: f64) -> Vector2<f64> {
        let (s, c) = t.sin_cos();
        let u = c.signum() * c.abs().powf(2.0 / p.q);
        let v = s.signum() * s.abs().powf(2.0 / p.q);
        Vector2::new(
            axis + 0.5 * p.width * u,
            p.y_top - 0.5 * p.height + 0.5 * p.height * v,
        )
    }

    #[test]
    fn the_fourth_power_by_multiplication_is_the_integer_power() {
        // abs_pow's f64 shortcut for q = 4 must give the bits powi gives (the level set's
        // results, and so every run on pillars, do not depend on which computes them).
        let mut rng = oorandom::Rand64::new(11);
        for k in 0..100_000 {
            let u = match k % 4 {
                0 => rng.rand_float() * 4.0 - 2.0,
                1 => (rng.rand_float() - 0.5) * 1e-3,
                2 => (rng.rand_float() - 0.5) * 1e3,
                _ => f64::from_bits(rng.rand_u64() >> 2) * if k % 8 == 3 { -1.0 } else { 1.0 },
            };
            let (p4, p3) = abs_pow(u, 4.0);
            // exponents the compiler cannot see: the runtime integer power
            let (four, three) = (std::hint::black_box(4), std::hint::black_box(3));
            assert_eq!(p4.to_bits(), u.powi(four).to_bits(), "u = {u:e}");
            assert_eq!(p3.to_bits(), u.powi(three).to_bits(), "u = {u:e}");
        }
    }

    #[test]
    fn flat_is_exact() {
        let s = Substrate::Flat { y_s: -2.0 };
        for (x, y) in [(0.0, -1.5), (3.0, -2.0), (-7.0, -2.3)] {
            let (d, n) = s.eval(&Vector2::new(x, y));
            assert_eq!(d, -2.0 - y);
            assert_eq!(n, Vector2::new(0.0, 1.0));
        }
        let (d, n) = s.eval(&dual_point(1.0, -1.9));
        assert_eq!(grad(&d), [0.0, -1.0]);
        assert_eq!(grad(&n.x), [0.0, 0.0]);
        assert_eq!(grad(&n.y), [0.0, 0.0]);
    }

    #[test]
    fn pillar_surface_has_zero_depth_and_unit_normal() {
        // The whole superellipse (`Rounded`), traced below mid-height too.
        let p = Pillars {
            foot: PillarFoot::Rounded,
            ..crate::physics::reference::pillars()
        };
        let s = Substrate::Pillars(p);
        for axis in [8.0, 24.0, -8.0, -40.0] {
            // upper half of the boundary (the lower half is below the floor level only at
            // its bottom point; it is part of the pillar surface too)
            for i in 1..40 {
                let t = std::f64::consts::PI * i as f64 / 40.0 - 0.5;
                let X = on_pillar(&p, axis, t);
                let (d, n) = s.eval(&X);
                assert!(d.abs() < 1e-13, "d = {d} at {X:?}");
                assert!((n.norm() - 1.0).abs() < 1e-14);
                // the normal points out: a step along it leaves the substrate
                let (d_out, _) = s.eval(&(X + n * 1e-3));
                assert!(d_out < 0.0);
            }
        }
    }

    #[test]
    fn pillar_distance_is_exact_on_flat_faces_and_first_order_near_corners() {
        let p = crate::physics::reference::pillars();
        let s = Substrate::Pillars(p);
        // above the middle of a top: exact
        for dy in [-0.7, -0.1, 0.0, 0.05, 0.5, 1.5, 3.0] {
            let (d, n) = s.eval(&Vector2::new(8.0, p.y_top + dy));
            assert!((d + dy).abs() < 1e-13, "dy = {dy}: d = {d}");
            assert!((n - Vector2::new(0.0, 1.0)).norm() < 1e-14);
        }
        // beside the middle of a side (mid-height): exact
        for dx in [0.3, 1.5] {
            let (d, n) = s.eval(&Vector2::new(8.0 + 4.0 + dx, p.y_top - 4.0));
            assert!((d + dx).abs() < 1e-13);
            assert!((n - Vector2::new(1.0, 0.0)).norm() < 1e-14);
        }
        // along the normal at a rounded corner: d = −δ + O(δ²)
        let X0 = on_pillar(&p, 8.0, 0.6);
        let (_, n0) = s.eval(&X0);
        for delta in [1e-2, 1e-3] {
            let (d, _) = s.eval(&(X0 + n0 * delta));
            assert!(
                (d + delta).abs() < 2.0 * delta * delta,
                "δ = {delta}: d = {d}"
            );
        }
    }

    #[test]
    fn pillar_floor_and_periodicity() {
        let p = crate::physics::reference::pillars();
        let s = Substrate::Pillars(p);
        // mid-gap above the floor: the floor is nearer (gap half-width 4 µm)
        let floor = p.y_top - p.height;
        let (d, n) = s.eval(&Vector2::new(0.0, floor + 0.2));
        assert!((d + 0.2).abs() < 1e-14);
        assert_eq!(n, Vector2::new(0.0, 1.0));
        // periodic with period w + s, including negative pillar indices
        for (x, y) in [
            (5.0_f64, -0.2_f64),
            (9.3, -0.6),
            (11.9, -3.0),
            (2.0, -7.9),
            (13.0, -1.0),
        ] {
            let (d0, n0) = s.eval(&Vector2::new(x, y));
            for k in [-3.0, -1.0, 1.0, 2.0] {
                let (d1, n1) = s.eval(&Vector2::new(x + 16.0 * k, y));
                assert!((d1 - d0).abs() < 1e-12 && (n1 - n0).norm() < 1e-12);
            }
            // and symmetric about x = 0 for the default layout
            let (d2, n2) = s.eval(&Vector2::new(-x, y));
            assert!((d2 - d0).abs() < 1e-12);
            assert!((n2 - Vector2::new(-n0.x, n0.y)).norm() < 1e-12);
        }
    }

    #[test]
    fn dual_derivatives_of_depth_and_normal_match_finite_differences() {
        let h = 1e-6;
        let subs = [
            Substrate::Pillars(crate::physics::reference::pillars()),
            Substrate::Pillars(Pillars {
                q: 3.0,
                ..crate::physics::reference::pillars()
            }),
            Substrate::Pillars(Pillars {
                foot: PillarFoot::Straight,
                ..crate::physics::reference::pillars()
            }),
            Substrate::Pillars(Pillars {
                foot: PillarFoot::Straight,
                fillet: 0.5,
                ..crate::physics::reference::pillars()
            }),
            Substrate::Pillars(Pillars {
                q: 4.5,
                ..crate::physics::reference::pillars()
            }),
        ];
        // points near the top, the rounded corners, and the sides (away from the
        // non-smooth pillar/floor switch and the mid-gap line); the last three in the
        // concave corner at a straight foot (x = 4, floor y = −8.3), inside the 0.5 µm
        // fillet's reach (|d_floor − d_pillar| < 0.5) for the filleted substrate
        let pts = [
            (8.0, -0.25),
            (8.3, 0.4),
            (5.0, -0.2),
            (4.6, -1.1),
            (11.2, -0.9),
            (3.7, -3.5),
            (12.5, -4.6),
            (-4.8, -0.5),
            (7.0, -2.0),
            (3.85, -8.2),
            (3.7, -7.95),
            (3.95, -8.25),
        ];
        for s in &subs {
            for &(x, y) in &pts {
                let (d, n) = s.eval(&dual_point(x, y));
                let gd = grad(&d);
                let gnx = grad(&n.x);
                let gny = grad(&n.y);
                for k in 0..2 {
                    let e = if k == 0 {
                        Vector2::new(h, 0.0)
                    } else {
                        Vector2::new(0.0, h)
                    };
                    let X = Vector2::new(x, y);
                    let (dp, np) = s.eval(&(X + e));
                    let (dm, nm) = s.eval(&(X - e));
                    let fd = (dp - dm) / (2.0 * h);
                    let fn_ = (np - nm) / (2.0 * h);
                    assert!(
                        (fd - gd[k]).abs() < 1e-7,
                        "∂d at ({x},{y}): {fd} vs {}",
                        gd[k]
                    );
                    assert!((fn_.x - gnx[k]).abs() < 1e-7, "∂n_x at ({x},{y})");
                    assert!((fn_.y - gny[k]).abs() < 1e-7, "∂n_y at ({x},{y})");
                }
                // same value up to round-off (the dual powers are evaluated differently)
                let d64 = s.eval(&Vector2::new(x, y)).0;
                assert!((re(d) - d64).abs() < 1e-14 * (1.0 + d64.abs()));
            }
        }
    }

    #[test]
    fn y_top_for_gap_gives_the_requested_gap() {
        let p = crate::physics::reference::pillars();
        let c = [0.0, 8.5];
        // MODEL.md: y_top ≈ −0.3 µm for a 0.5 µm gap, smallest gap near x ≈ 5 µm
        let y_top = p.y_top_for_gap(0.5, c, 10.0).unwrap();
        assert!((y_top + 0.3).abs() < 0.02, "y_top = {y_top}");
        let placed = Pillars { y_top, ..p };
        let (x_star, _) = placed.lowest_clearance(c, 10.0);
        assert!((x_star.abs() - 5.0).abs() < 0.5, "x* = {x_star}");
        // Independent check: brute-force vertical gap on a fine grid of the circle.
        let mut min_gap = f64::INFINITY;
        let n = 200_000;
        for i in 0..=n {
            let x = -10.0 + 20.0 * i as f64 / n as f64;
            let y_circle = 8.5 - (100.0 - x * x).max(0.0).sqrt();
            min_gap = min_gap.min(y_circle - placed.surface_height(x));
        }
        assert!((min_gap - 0.5).abs() < 1e-6, "min gap {min_gap}");
        // The circle point there lies outside the pillar, 0.5 µm above it vertically (its
        // distance along the normal of the rounded top is a little less).
        let y_c = 8.5 - (100.0 - x_star * x_star).sqrt();
        assert!(
            Substrate::Pillars(placed)
                .eval(&Vector2::new(x_star, y_c))
                .0
                < -0.3
        );
        // other gaps shift y_top rigidly
        let y2 = p.y_top_for_gap(1.0, c, 10.0).unwrap();
        assert!((y_top - y2 - 0.5).abs() < 1e-9);
        assert!(p.y_top_for_gap(0.5, c, 0.0).is_err());
    }

    #[test]
    fn outline_runs_along_the_surface() {
        // The outline traces the superellipses and the floor: the sharp foot.
        let p = Pillars {
            fillet: 0.0,
            ..crate::physics::reference::pillars()
        };
        let s = Substrate::Pillars(p);
        let pts = s.outline(0.0, 20.0, 64);
        // pillars at 8 and 24 (24 − 4 = 20 ≤ x_max): two closed curves of 65 points + ends
        assert_eq!(pts.len(), 2 + 2 * 65);
        for q in &pts {
            let (d, _) = s.eval(&Vector2::new(q[0], q[1]));
            assert!(d.abs() < 1e-9, "outline point {q:?} has d = {d}");
        }
        assert_eq!(
            Substrate::Flat { y_s: -2.0 }.outline(-1.0, 1.0, 10),
            vec![[-1.0, -2.0], [1.0, -2.0]]
        );
    }
}

#[cfg(test)]
mod lattice_tests {
    use super::*;
    use num_dual::DualSVec64;

    type D3 = DualSVec64<3>;

    fn pillars() -> Pillars {
        crate::physics::reference::pillars()
    }

    fn both(p: Pillars) -> [LatticeSubstrate; 2] {
        [Lattice::FourPillars, Lattice::Gap].map(|lattice| LatticeSubstrate {
            plane: Substrate::Pillars(p),
            lattice,
        })
    }

    /// All the 3-D substrates of the tests: flat, and the default pillars on both
    /// lattices with q = 4 and with non-integer q.
    fn substrates() -> Vec<LatticeSubstrate> {
        let mut v = vec![LatticeSubstrate {
            plane: Substrate::Flat { y_s: -2.0 },
            lattice: Lattice::FourPillars,
        }];
        v.extend(both(pillars()));
        v.extend(both(Pillars {
            q: 4.5,
            ..pillars()
        }));
        v.extend(both(Pillars {
            foot: PillarFoot::Straight,
            ..pillars()
        }));
        v.extend(both(Pillars {
            foot: PillarFoot::Straight,
            fillet: 0.5,
            ..pillars()
        }));
        v
    }

    #[test]
    fn a_fillet_turns_the_normal_continuously_round_the_foot() {
        // Along a quarter circle of radius 0.6 µm about the concave corner between the
        // middle of a side face (x̃ = −w/2) and the floor, from the side to the floor: with
        // the 0.5 µm fillet the normal turns from sideways to up in small steps; without it
        // it flips at once on the bisector.
        let p = Pillars {
            foot: PillarFoot::Straight,
            ..pillars()
        };
        let floor = p.y_top - p.height;
        for lattice in [Lattice::FourPillars, Lattice::Gap] {
            let az = p.nearest_axis_z(0.0, lattice);
            let largest_turn = |fillet: f64| {
                let s = LatticeSubstrate {
                    plane: Substrate::Pillars(Pillars { fillet, ..p }),
                    lattice,
                };
                let n = 400;
                let normals: Vec<Vector3<f64>> = (0..=n)
                    .map(|i| {
                        let t = 0.5 * std::f64::consts::PI * i as f64 / n as f64;
                        let x = Vector3::new(4.0 - 0.6 * t.sin(), floor + 0.6 * t.cos(), az);
                        s.eval(&x).1
                    })
                    .collect();
                assert!((normals[0] - Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-12);
                assert!((normals[n] - Vector3::new(0.0, 1.0, 0.0)).norm() < 1e-12);
                normals
                    .windows(2)
                    .map(|w| (w[1] - w[0]).norm())
                    .fold(0.0, f64::max)
            };
            let sharp = largest_turn(0.0);
            let filleted = largest_turn(0.5);
            assert!(sharp > 1.4, "{sharp}");
            assert!(filleted < 0.02, "{filleted}");
            // The fillet lies within k/4 of the sharp corner: on the bisector, the surface
            // (d = 0) moves out by (k − 0)²/(4k) = k/4 in depth.
            let s = LatticeSubstrate {
                plane: Substrate::Pillars(Pillars { fillet: 0.5, ..p }),
                lattice,
            };
            let corner = Vector3::new(4.0 - 0.01, floor + 0.01, az);
            let (d, _) = s.eval(&corner);
            assert!((d - (-0.01 + 0.125)).abs() < 1e-12, "{d}");
        }
    }

    #[test]
    fn a_straight_foot_closes_the_undercut_and_keeps_the_upper_half() {
        let rounded = Pillars {
            fillet: 0.0,
            foot: PillarFoot::Rounded,
            ..pillars()
        };
        let straight = Pillars {
            foot: PillarFoot::Straight,
            ..rounded
        };
        let floor = rounded.y_top - rounded.height;
        for lattice in [Lattice::FourPillars, Lattice::Gap] {
            let [r, st] = [rounded, straight].map(|p| LatticeSubstrate {
                plane: Substrate::Pillars(p),
                lattice,
            });
            let az = rounded.nearest_axis_z(0.0, lattice);
            // Under a lower corner, 0.3 µm above the floor, inside the footprint
            // (|u|^4 + |w|^4 = 0.82): outside the rounded pillar (in its undercut, where the
            // floor is the nearer surface), inside the straight one, pushed out sideways.
            let x = Vector3::new(8.0 - 3.2, floor + 0.3, az - 3.2);
            let (dr, nr) = r.eval(&x);
            assert!((dr + 0.3).abs() < 1e-12, "rounded: {dr}");
            assert_eq!(nr, Vector3::new(0.0, 1.0, 0.0));
            let (ds, ns) = st.eval(&x);
            assert!(ds > 0.2, "straight: {ds}");
            assert_eq!(ns.y, 0.0);
            assert!(ns.x < 0.0 && ns.z < 0.0, "{ns:?}");
            // Beside the middle of a side face, below mid-height: the exact distance to
            // the face for the straight foot.
            let x = Vector3::new(8.0 - 3.9, floor + 1.0, az);
            let (ds, ns) = st.eval(&x);
            assert!((ds - 0.1).abs() < 1e-12, "{ds}");
            assert!((ns - Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-12);
            // At and above mid-height the two are the same surface, bit for bit.
            let mut rng = crate::physics::plane_strain::tests::Rng::new(5);
            for _ in 0..500 {
                let x = Vector3::new(
                    rng.uniform(-20.0, 20.0),
                    rng.uniform(rounded.y_top - 0.5 * rounded.height, 2.0),
                    rng.uniform(-20.0, 20.0),
                );
                assert_eq!(r.eval(&x), st.eval(&x), "{x:?}");
            }
        }
        // In 2-D the same: under the rounded lower edge, inside the straight column only.
        let x = Vector2::new(8.0 - 3.9, floor + 0.2);
        let dr = Substrate::Pillars(rounded).eval(&x).0;
        let (ds, ns) = Substrate::Pillars(straight).eval(&x);
        assert!((dr + 0.2).abs() < 1e-12, "{dr}");
        assert!((ds - 0.1).abs() < 1e-12, "{ds}");
        assert!((ns - Vector2::new(-1.0, 0.0)).norm() < 1e-12);
    }

    /// A point on the superellipsoid of the pillar with axes (`ax`, `az`), elevation `t`
    /// and azimuth `f`: `u = c(cos t cos f)`, `v = c(sin t)`, `w = c(cos t sin f)`,
    /// `c(s) = sgn(s)|s|^{2/q}`, so `|u|^q + |v|^q + |w|^q = 1`.
    fn on_pillar(p: &Pillars, ax: f64, az: f64, t: f64, f: f64) -> Vector3<f64> {
        let c = |s: f64| s.signum() * s.abs().powf(2.0 / p.q);
        let (a, b) = (0.5 * p.width, 0.5 * p.height);
        Vector3::new(
            ax + a * c(t.cos() * f.cos()),
            p.y_top - b + b * c(t.sin()),
            az + a * c(t.cos() * f.sin()),
        )
    }

    /// Central differences of the depth: the gradient ∇d at `x`.
    fn grad_fd(s: &LatticeSubstrate, x: &Vector3<f64>, h: f64) -> Vector3<f64> {
        Vector3::from_fn(|k, _| {
            let mut e = Vector3::zeros();
            e[k] = h;
            (s.eval(&(x + e)).0 - s.eval(&(x - e)).0) / (2.0 * h)
        })
    }

    #[test]
    fn flat_is_exact_in_3d() {
        let s = LatticeSubstrate {
            plane: Substrate::Flat { y_s: -2.0 },
            lattice: Lattice::Gap,
        };
        for (x, y, z) in [(0.0, -1.5, 3.0), (3.0, -2.0, -7.0), (-7.0, -2.3, 0.1)] {
            let (d, n) = s.eval(&Vector3::new(x, y, z));
            assert_eq!(d, -2.0 - y);
            assert_eq!(n, Vector3::new(0.0, 1.0, 0.0));
            assert_eq!(s.surface_height(x, z), -2.0);
        }
        s.validate().unwrap();
    }

    #[test]
    fn flat_faces_give_the_exact_distance() {
        let p = pillars();
        let (a, mid) = (0.5 * p.width, p.y_top - 0.5 * p.height);
        for s in both(p) {
            // a pillar of this lattice: x axis 8, z axis nearest to 8
            let Substrate::Pillars(pp) = s.plane else {
                unreachable!()
            };
            let (ax, az) = (8.0, pp.nearest_axis_z(8.0, s.lattice));
            // above the middle of the top
            for dy in [-0.7, -0.1, 0.0, 0.05, 0.5, 1.5, 3.0] {
                let (d, n) = s.eval(&Vector3::new(ax, p.y_top + dy, az));
                assert!((d + dy).abs() < 1e-13, "{:?} dy = {dy}: d = {d}", s.lattice);
                assert!((n - Vector3::y()).norm() < 1e-14);
            }
            // beside the middle of each side face, at mid-height
            for dx in [-0.4, 0.3, 1.5] {
                for (e, sign) in [
                    (Vector3::x(), 1.0),
                    (Vector3::z(), 1.0),
                    (Vector3::x(), -1.0),
                ] {
                    let X = Vector3::new(ax, mid, az) + e * (sign * (a + dx));
                    let (d, n) = s.eval(&X);
                    assert!(
                        (d + dx).abs() < 1e-13,
                        "{:?}: d = {d}, dx = {dx}",
                        s.lattice
                    );
                    assert!((n - e * sign).norm() < 1e-14);
                }
            }
            // over the floor far from the pillars (the middle of a square of four pillars
            // or of a gap; the floor is 0.2 µm below)
            let floor = p.y_top - p.height;
            for (x, z) in [(0.0, 0.0), (16.0, 32.0), (0.0, az + 8.0)] {
                let (d, n) = s.eval(&Vector3::new(x, floor + 0.2, z));
                assert!(
                    (d + 0.2).abs() < 1e-14,
                    "{:?} ({x}, {z}): d = {d}",
                    s.lattice
                );
                assert_eq!(n, Vector3::y());
                assert_eq!(s.surface_height(x, z), floor);
            }
            // the top's height at its middle, the floor between pillars
            assert!((s.surface_height(ax, az) - p.y_top).abs() < 1e-14);
        }
    }

    #[test]
    fn surface_has_zero_depth_unit_outward_normal_and_the_depth_gradient() {
        // On the surface l = 0, ∇d = −∇l/|∇l| = −n exactly; checked by central
        // differences at points of the upper half and the sides of several pillars, down
        // the whole superellipsoid's sides (`Rounded`) below mid-height.
        let h = 1e-6;
        let rounded = Pillars {
            foot: PillarFoot::Rounded,
            ..pillars()
        };
        for p in [rounded, Pillars { q: 4.5, ..rounded }] {
            for s in both(p) {
                for (ax, k) in [(8.0, 0.0), (-24.0, 1.0), (40.0, -2.0)] {
                    let az = p.nearest_axis_z(0.3, s.lattice) + k * p.period();
                    for i in 1..12 {
                        for j in 0..16 {
                            // elevation in (−0.5, π/2): down the sides, not into the floor
                            let t = -0.5 + 2.0 * i as f64 / 12.0;
                            let f = 2.0 * std::f64::consts::PI * (j as f64 + 0.3) / 16.0;
                            let X = on_pillar(&p, ax, az, t, f);
                            let (d, n) = s.eval(&X);
                            assert!(d.abs() < 1e-12, "d = {d} at {X:?}");
                            assert!((n.norm() - 1.0).abs() < 1e-14);
                            let (d_out, _) = s.eval(&(X + n * 1e-3));
                            assert!(d_out < 0.0);
                            let g = grad_fd(&s, &X, h);
                            assert!((g + n).norm() < 1e-6, "∇d = {g:?}, n = {n:?} at {X:?}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn the_plane_through_a_row_of_axes_is_the_2d_substrate() {
        // z̃ = 0: z = 0 on the gap lattice, z = ±P/2 (+kP) on the four-pillar one. The same
        // depth and in-plane normal as 2-D, bit for bit, and n_z = 0.
        let mut rng = crate::physics::plane_strain::tests::Rng::new(83);
        for p in [
            pillars(),
            Pillars {
                q: 3.0,
                ..pillars()
            },
            Pillars {
                q: 4.5,
                ..pillars()
            },
        ] {
            let s2 = Substrate::Pillars(p);
            for (lattice, z) in [
                (Lattice::Gap, 0.0),
                (Lattice::Gap, 32.0),
                (Lattice::FourPillars, 8.0),
                (Lattice::FourPillars, -8.0),
            ] {
                let s3 = LatticeSubstrate { plane: s2, lattice };
                for _ in 0..200 {
                    let (x, y) = (rng.uniform(-20.0, 20.0), rng.uniform(-10.0, 1.0));
                    let (d2, n2) = s2.eval(&Vector2::new(x, y));
                    let (d3, n3) = s3.eval(&Vector3::new(x, y, z));
                    assert_eq!(d3, d2, "{lattice:?} ({x}, {y}, {z})");
                    assert_eq!(n3, Vector3::new(n2.x, n2.y, 0.0));
                    assert_eq!(s3.surface_height(x, z), p.surface_height(x));
                }
            }
        }
        // and a flat substrate anywhere
        let f = Substrate::Flat { y_s: -2.0 };
        let f3 = LatticeSubstrate {
            plane: f,
            lattice: Lattice::FourPillars,
        };
        assert_eq!(
            f3.eval(&Vector3::new(1.0, -1.7, 5.0)).0,
            f.eval(&Vector2::new(1.0, -1.7)).0
        );
    }

    #[test]
    fn dual_derivatives_match_finite_differences_in_3d() {
        let h = 1e-6;
        // Offsets (x̃, y, z̃) from the axes of a pillar: near the top, the rounded edges and
        // corners, the sides, away from the pillar/floor switch and the mid-planes.
        let pts = [
            (0.0, -0.25, 0.0),
            (0.3, 0.4, -0.9),
            (-3.0, -0.2, -2.0),
            (-3.4, -1.1, -3.3),
            (3.2, -0.9, 1.0),
            (-4.3, -3.5, 0.5),
            (0.5, -4.6, 4.4),
            (-4.8, -0.5, -5.5),
            (-1.0, -2.0, -6.0),
            (1.0, -0.6, -7.5),
            (-3.5, -2.5, -7.0),
            // in the concave corner at a straight foot (floor y = −8.3), within the reach
            // of the 0.5 µm fillet
            (-3.85, -8.2, 0.0),
            (-4.3, -7.95, 0.3),
            (3.95, -8.25, -0.2),
        ];
        for s in substrates() {
            let az = pillars().nearest_axis_z(0.3, s.lattice);
            for &(x, y, z) in &pts {
                let X = Vector3::new(8.0 + x, y, az + z);
                let Xd = Vector3::from_fn(|k, _| D3::from_re(X[k]).derivative(k));
                let (d, n) = s.eval(&Xd);
                let grad = |v: &D3| v.eps.unwrap_generic(nalgebra::U3, nalgebra::U1);
                for k in 0..3 {
                    let mut e = Vector3::zeros();
                    e[k] = h;
                    let (dp, np) = s.eval(&(X + e));
                    let (dm, nm) = s.eval(&(X - e));
                    let fd = (dp - dm) / (2.0 * h);
                    let fn_ = (np - nm) / (2.0 * h);
                    assert!(
                        (fd - grad(&d)[k]).abs() < 1e-7,
                        "{s:?} ∂d/∂x_{k} at {X:?}: {fd} vs {}",
                        grad(&d)[k]
                    );
                    for c in 0..3 {
                        assert!(
                            (fn_[c] - grad(&n[c])[k]).abs() < 1e-7,
                            "∂n_{c}/∂x_{k} at {X:?}"
                        );
                    }
                }
                let d64 = s.eval(&X).0;
                assert!((d.re - d64).abs() < 1e-14 * (1.0 + d64.abs()));
            }
        }
    }

    #[test]
    fn both_lattices_keep_the_quarter_symmetry_and_are_periodic() {
        let mut rng = crate::physics::plane_strain::tests::Rng::new(89);
        let per = pillars().period();
        for s in both(pillars()) {
            for _ in 0..500 {
                let X = Vector3::new(
                    rng.uniform(-20.0, 20.0),
                    rng.uniform(-9.0, 1.0),
                    rng.uniform(-20.0, 20.0),
                );
                let (d, n) = s.eval(&X);
                let (dx, nx) = s.eval(&Vector3::new(-X.x, X.y, X.z));
                let (dz, nz) = s.eval(&Vector3::new(X.x, X.y, -X.z));
                assert!((dx - d).abs() < 1e-12 && (dz - d).abs() < 1e-12, "{X:?}");
                // the normals mirror (except on the mid-planes, where they flip: measure
                // zero, not drawn)
                assert!((nx - Vector3::new(-n.x, n.y, n.z)).norm() < 1e-12);
                assert!((nz - Vector3::new(n.x, n.y, -n.z)).norm() < 1e-12);
                for (kx, kz) in [(1.0, 0.0), (0.0, -2.0), (-3.0, 1.0)] {
                    let (dp, np) = s.eval(&Vector3::new(X.x + kx * per, X.y, X.z + kz * per));
                    assert!((dp - d).abs() < 1e-12 && (np - n).norm() < 1e-12);
                }
            }
        }
    }

    #[test]
    fn the_lattices_place_the_pillars_as_documented() {
        let p = pillars();
        let [four, gap] = both(p);
        let above =
            |s: &LatticeSubstrate, x: f64, z: f64| s.eval(&Vector3::new(x, p.y_top + 0.1, z)).0;
        // 0.1 µm above a top, or at least s/2 − 0.5 µm from every pillar (a side face
        // s/2 = 4 µm away, the first-order distance past a rounded edge a bit less)
        let far = -0.5 * p.spacing + 0.5;
        // four pillars: tops over (±8, ±8), none over (±8, 0) nor the cell's axis
        for (x, z) in [
            (8.0, 8.0),
            (-8.0, 8.0),
            (8.0, -8.0),
            (-8.0, -8.0),
            (24.0, 24.0),
        ] {
            assert!((above(&four, x, z) + 0.1).abs() < 1e-13);
            assert!(above(&gap, x, z) < far);
        }
        // gap: tops over (±8, 0), the cell's axis above the gap between two of them
        for (x, z) in [(8.0, 0.0), (-8.0, 0.0), (8.0, 16.0)] {
            assert!((above(&gap, x, z) + 0.1).abs() < 1e-13);
            assert!(above(&four, x, z) < far);
        }
        for s in [four, gap] {
            assert!(above(&s, 0.0, 0.0) < far);
        }
        assert_eq!(p.nearest_axis_z(0.0, Lattice::Gap), 0.0);
        assert_eq!(p.nearest_axis_z(3.0, Lattice::FourPillars), 8.0);
        assert_eq!(p.nearest_axis_z(-3.0, Lattice::FourPillars), -8.0);
        assert_eq!(p.nearest_axis_z(-9.0, Lattice::Gap), -16.0);
        assert_eq!(Lattice::default(), Lattice::FourPillars);
        // a bad parameter is refused through the section
        let bad = LatticeSubstrate {
            plane: Substrate::Pillars(Pillars { q: 1.5, ..p }),
            lattice: Lattice::Gap,
        };
        assert!(bad.validate().is_err());
    }

    #[test]
    fn y_top_for_gap_on_lattice_gives_the_requested_gap() {
        let p = pillars();
        let (c, r_c) = ([0.0, 8.5, 0.0], 10.0);
        // Gap lattice: the smallest gap lies in the plane z = 0, the 2-D placement
        let y2 = p.y_top_for_gap(0.5, [0.0, 8.5], r_c).unwrap();
        let yg = p
            .y_top_for_gap_on_lattice(0.5, Lattice::Gap, c, r_c)
            .unwrap();
        assert!((yg - y2).abs() < 1e-9, "{yg} vs {y2}");
        // Four pillars: brute force over a fine grid of the disk, and the minimiser on the
        // rounded corner of a pillar, near the diagonal x = ±z (quarter symmetry)
        let y4 = p
            .y_top_for_gap_on_lattice(0.5, Lattice::FourPillars, c, r_c)
            .unwrap();
        let placed = Pillars { y_top: y4, ..p };
        let ([xs, zs], _) = placed.lowest_clearance_on_lattice(Lattice::FourPillars, c, r_c);
        assert!((xs.abs() - zs.abs()).abs() < 1e-4, "minimiser ({xs}, {zs})");
        assert!(xs.abs() > 4.0 && xs.abs() < 8.0);
        let n = 1000;
        let mut min_gap = f64::INFINITY;
        for i in 0..=n {
            for j in 0..=n {
                let (x, z) = (
                    -10.0 + 20.0 * i as f64 / n as f64,
                    -10.0 + 20.0 * j as f64 / n as f64,
                );
                let rr = 100.0 - x * x - z * z;
                if rr < 0.0 {
                    continue;
                }
                let gap =
                    8.5 - rr.sqrt() - placed.surface_height_on_lattice(x, z, Lattice::FourPillars);
                min_gap = min_gap.min(gap);
            }
        }
        // the grid's minimum is not below the true one, and above it by little (measured
        // 4e-8 µm: a 0.02 µm grid near a smooth minimum)
        assert!(
            (0.5 - 1e-9..0.5 + 1e-6).contains(&min_gap),
            "min gap {min_gap}"
        );
        // the four pillars' corners nearest the axis (ρ ≈ 4√2 µm) are farther from it than
        // the gap's side faces (ρ = 4 µm), where the sphere hangs lower: higher tops
        // (measured −0.30 µm on the gap lattice, +1.80 µm over four pillars, the smallest
        // gap at (±5.08, ±5.08))
        assert!(y4 > yg + 0.1, "{y4} vs {yg}");
        // other gaps shift y_top rigidly; bad inputs are refused
        let y41 = p
            .y_top_for_gap_on_lattice(1.0, Lattice::FourPillars, c, r_c)
            .unwrap();
        assert!((y4 - y41 - 0.5).abs() < 1e-9);
        assert!(
            p.y_top_for_gap_on_lattice(0.5, Lattice::Gap, c, 0.0)
                .is_err()
        );
        assert!(
            p.y_top_for_gap_on_lattice(f64::NAN, Lattice::Gap, c, r_c)
                .is_err()
        );
    }
}
