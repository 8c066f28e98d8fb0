//! The sections of a case file, one struct per concern (deal.II step-44 style).
//!
//! Every field documents its unit, its default (MODEL.md's value, which is the paper's) and
//! its valid range; [`super::Case::validate`] checks the ranges. Units are the solver's
//! (µm, s, pN, so stresses in Pa and viscosities in Pa·s) except where the field name
//! carries an SI unit (`rho_kg_m3`, `g_m_s2`, `mu_ct_n_m3`, ...): those are the values as the
//! paper states them, and each has an accessor returning the solver unit ([`units`]).

use serde::{Deserialize, Deserializer, Serialize};

pub use crate::physics::{AdhesionDirection, KinematicModel};
// The `solver` section is the solver's own settings type, with its defaults and its range
// check ([`crate::solver::Settings`]).
pub use crate::solver::{Integrator, Krylov, LinearSolver, MAX_ATOL, MAX_RTOL, Settings as Solver};

/// Conversion factors from the SI units of the paper to the solver's µm–s–pN system
/// (MODEL.md §1).
pub mod units {
    /// 1 kg/m³ in pN·s²/µm⁴.
    pub const KG_PER_M3: f64 = 1e-12;
    /// 1 m/s² in µm/s².
    pub const M_PER_S2: f64 = 1e6;
    /// 1 N/m³ in pN/µm³.
    pub const N_PER_M3: f64 = 1e-6;
    /// 1 N/(m³·s) in pN/(µm³·s).
    pub const N_PER_M3_S: f64 = 1e-6;
}

// ---------------------------------------------------------------------------------------
// Geometry

/// Reference geometry of the half cell (MODEL.md §2): three concentric disks about the
/// centre c = (0, `centre_y`), cut by the symmetry line x = 0; and the kinematic model
/// that makes it a cell (MODEL.md §10).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Geometry {
    /// Kinematic model: `PlaneStrain`, the paper's 2-D half cell (an infinite cylinder,
    /// quantities per unit thickness), or `Axisymmetric`, a 3-D spherical cell whose
    /// meridian half-plane (r, y) is meshed as the half cell (x → r; F₃₃ = 1 + u_r/r,
    /// quantities per radian: weights, forces and volume averages weighted by r; MODEL.md
    /// §10). Default `PlaneStrain`. Valid: `Axisymmetric` needs a `Flat` substrate (a
    /// pillar array is not axisymmetric). `ThreeD`: the 3-D quarter cell x ≥ 0, z ≥ 0 of
    /// the three balls (ten-node tetrahedra, meshed by gmsh; MODEL.md §10), on a flat
    /// substrate or a square lattice of pillars (`substrate.lattice`).
    pub model: KinematicModel,
    /// Height c_y of the cell centre (µm). Default 8.5 (Table 1). Any finite value; the
    /// substrate must lie below the cell. The centre's x is 0 by construction: x = 0 is the
    /// symmetry line of the half-cell model, so it is not a parameter.
    pub centre_y: f64,
    /// Nucleus radius r_n (µm). Default 5. Valid: 0 < r_n < r_cp.
    pub r_n: f64,
    /// Outer radius of the cytoplasm r_cp (µm). Default 9.75. Valid: r_n < r_cp < r_c.
    pub r_cp: f64,
    /// Cell radius r_c (µm); the membrane is the ring r_cp < r < r_c. Default 10.
    /// Valid: r_c > r_cp.
    pub r_c: f64,
    /// `ThreeD` only: the part of the cell that is computed, bounded by mirror planes of
    /// the problem. `Quarter`: x ≥ 0, z ≥ 0. `Eighth`: 0 ≤ z ≤ x, half the quarter's
    /// unknowns; the diagonal plane x = z must then be a mirror of the substrate too: a
    /// `Flat` substrate, or `Pillars` on the `FourPillars` lattice with the cell centre
    /// above a gap (`first_center` an odd multiple of half the period). `Auto`: `Eighth`
    /// where the substrate allows it, else `Quarter`. Default `Quarter`: the eighth's mesh
    /// is another discretisation (README, "the eighth cell"). The output files hold the
    /// quarter either way (the eighth and its mirror image).
    #[serde(skip_serializing_if = "WedgeChoice::is_quarter")]
    pub wedge: WedgeChoice,
}

/// Which wedge of the 3-D cell is computed ([`Geometry::wedge`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum WedgeChoice {
    /// The eighth where the substrate is symmetric about the plane x = z, else the quarter.
    Auto,
    /// The quarter x ≥ 0, z ≥ 0.
    #[default]
    Quarter,
    /// The eighth 0 ≤ z ≤ x.
    Eighth,
}

impl WedgeChoice {
    /// Whether this is the default (left out when a case is written).
    pub fn is_quarter(&self) -> bool {
        *self == WedgeChoice::Quarter
    }
}

impl Default for Geometry {
    fn default() -> Self {
        Geometry {
            model: KinematicModel::PlaneStrain,
            centre_y: 8.5,
            r_n: 5.0,
            r_cp: 9.75,
            r_c: 10.0,
            wedge: WedgeChoice::Quarter,
        }
    }
}

impl Geometry {
    /// The cell centre c = (0, c_y) in µm.
    pub fn centre(&self) -> [f64; 2] {
        [0.0, self.centre_y]
    }

    /// Height of the lowest point of the cell, c_y − r_c (µm).
    pub fn bottom_y(&self) -> f64 {
        self.centre_y - self.r_c
    }
}

// ---------------------------------------------------------------------------------------
// Mesh

/// Mesh sizes and the quadrature of the thin contact and adhesion layers (MODEL.md §2, §9).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Mesh {
    /// Element size at the lower edge of the cell (µm), before `refine`. Default 0.3 (the
    /// paper's mesh). Valid: 0 < h_bottom ≤ r_c.
    pub h_bottom: f64,
    /// Element size in the nucleus (µm), before `refine`. Default 1.0 (the paper's mesh).
    /// Valid: 0 < h_nucleus ≤ r_c.
    pub h_nucleus: f64,
    /// Refinement factor for convergence studies: the mesh uses h / refine, so 2 halves
    /// every element size and 0.5 doubles it. Default 1. Valid: refine > 0.
    pub refine: f64,
    /// Largest element size at the cell surface below the cell centre's height (µm, before
    /// `refine`), where the cell meets the substrate and the contact radius is read: the
    /// size there is min(grading law, h_surface + ½ × depth below r_cp + ½ × height above
    /// the centre), so it grows back to the grading law half a µm per µm inward and
    /// upward. In 3-D the membrane's elements then follow it; in 2-D the membrane's
    /// spacing is already at most twice its layer thickness (0.5 µm at refine 1), so only
    /// a smaller value acts. Default none (the grading law alone). Valid: 0 < h_surface ≤
    /// r_c.
    pub h_surface: Option<f64>,
    /// Polynomial degree integrated exactly by the quadrature of the elements that the
    /// contact and fibronectin bands cross (the band at rest is ≈ 0.05 µm thick, far
    /// thinner than an element; degree 4 gave a 15 % error in the contact force, MODEL.md
    /// §9). Default 10. Valid: 2 ≤ degree ≤ 20.
    pub contact_quadrature_degree: u32,
    /// Levels of uniform sub-division of those elements before quadrature (each level
    /// splits a triangle into 4). Default 0. Valid: 0 ≤ levels ≤ 4.
    pub contact_subdivisions: u32,
}

impl Default for Mesh {
    fn default() -> Self {
        Mesh {
            h_bottom: 0.3,
            h_nucleus: 1.0,
            refine: 1.0,
            h_surface: None,
            contact_quadrature_degree: 10,
            contact_subdivisions: 0,
        }
    }
}

impl Mesh {
    /// Element size at the lower edge of the cell after refinement, h_bottom / refine (µm).
    pub fn h_bottom_refined(&self) -> f64 {
        self.h_bottom / self.refine
    }

    /// Element size in the nucleus after refinement, h_nucleus / refine (µm).
    pub fn h_nucleus_refined(&self) -> f64 {
        self.h_nucleus / self.refine
    }
}

// ---------------------------------------------------------------------------------------
// Materials

/// Elastic constants and density of one sub-domain (MODEL.md §3).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Material {
    /// Young's modulus E (Pa = pN/µm²), the small-strain modulus of the compressible Yeoh
    /// law. Default 500 in the nucleus, 100 in the cytoplasm and membrane (Table 1; the
    /// membrane value is MODEL.md's choice). Valid: E > 0.
    pub e: f64,
    /// Poisson ratio ν. Default 0.485 (Table 1). Valid: −1 < ν < 0.5.
    pub nu: f64,
    /// Mass density ρ₀ (kg/m³, SI as in the paper; [`Material::rho`] gives the solver
    /// unit). Default 1400 in the nucleus, 1000 elsewhere (Table 1). Valid: ρ ≥ 0.
    pub rho_kg_m3: f64,
}

impl Material {
    /// Mass density in the solver unit, pN·s²/µm⁴ (1 kg/m³ = 1e-12 pN·s²/µm⁴).
    pub fn rho(&self) -> f64 {
        self.rho_kg_m3 * units::KG_PER_M3
    }

    /// The paper's nucleus: E = 500 Pa, ν = 0.485, ρ = 1400 kg/m³.
    pub fn nucleus() -> Self {
        Material {
            e: 500.0,
            nu: 0.485,
            rho_kg_m3: 1400.0,
        }
    }

    /// The paper's cytoplasm (and MODEL.md's membrane): E = 100 Pa, ν = 0.485,
    /// ρ = 1000 kg/m³.
    pub fn cytoplasm() -> Self {
        Material {
            e: 100.0,
            nu: 0.485,
            rho_kg_m3: 1000.0,
        }
    }
}

/// Solid-phase material parameters of the three sub-domains (MODEL.md §3).
///
/// In a file, each domain may state any subset of its fields; the others take *that
/// domain's* default (so `nucleus: (nu: 0.49)` keeps E = 500 Pa).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "MaterialsRepr")]
pub struct Materials {
    /// Nucleus Ω_n. Default E 500 Pa, ν 0.485, ρ 1400 kg/m³.
    pub nucleus: Material,
    /// Cytoplasm Ω_cp. Default E 100 Pa, ν 0.485, ρ 1000 kg/m³.
    pub cytoplasm: Material,
    /// Membrane Ω_m. Default E 100 Pa, ν 0.485, ρ 1000 kg/m³ (MODEL.md's choice: the paper
    /// gives the membrane no modulus).
    pub membrane: Material,
    /// Yeoh stiffening γ: α₂ = −γα₁, α₃ = γα₁ (dimensionless). Default 0.1 ("kept low",
    /// MODEL.md's choice). Valid: 0 ≤ γ < 3 (dW/dX > 0 needs γ < 3).
    pub gamma: f64,
    /// Mooney fraction: β = beta_fraction · μ_e / 2, α₁ = μ_e/2 − β (dimensionless).
    /// Default 0.2. Valid: 0 ≤ beta_fraction < 1 (so that α₁ > 0).
    pub beta_fraction: f64,
    /// Fibres in the cytoplasm (MODEL.md §11): `Some((k1_pa: 100))` adds the fibre term
    /// along T in the PAC and along N in the bottom region (the regions of `active`, which
    /// must have at least one). Default none: the paper's isotropic cell.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fibres: Option<Fibres>,
}

/// The fibre term W_fib = χ (k₁/(2k₂)) [exp(k₂ ⟨I₄ − 1⟩²) − 1], I₄ = a·C_e a, of the
/// cytoplasm's active regions (MODEL.md §11): the fibres resist stretch, not shortening.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Fibres {
    /// Stiffness k₁ (Pa). Default 100. Valid: k₁ ≥ 0.
    pub k1_pa: f64,
    /// Exponential stiffening k₂ (dimensionless). Default 1. Valid: 0 < k₂ ≤ 10.
    pub k2: f64,
    /// Half-width δ of the ramp ⟨x⟩ = x S(x; −δ, δ) that makes the fibres slack in
    /// shortening. Default 1e-3 (MODEL.md §11). Valid: 0 < δ ≤ 0.1.
    pub delta: f64,
}

impl Default for Fibres {
    fn default() -> Self {
        Fibres {
            k1_pa: 100.0,
            k2: 1.0,
            delta: 1e-3,
        }
    }
}

impl Default for Materials {
    fn default() -> Self {
        Materials {
            nucleus: Material::nucleus(),
            cytoplasm: Material::cytoplasm(),
            membrane: Material::cytoplasm(),
            gamma: 0.1,
            beta_fraction: 0.2,
            fibres: None,
        }
    }
}

/// Accepts a present value only: `e: None` or `e: Some(1)` are errors, an absent field
/// takes the domain default.
fn present_f64<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f64>, D::Error> {
    f64::deserialize(d).map(Some)
}

/// A material as written in a file: absent fields are filled from the domain's default.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields, rename = "Material")]
struct MaterialRepr {
    #[serde(default, deserialize_with = "present_f64")]
    e: Option<f64>,
    #[serde(default, deserialize_with = "present_f64")]
    nu: Option<f64>,
    #[serde(default, deserialize_with = "present_f64")]
    rho_kg_m3: Option<f64>,
}

impl MaterialRepr {
    fn or(self, default: Material) -> Material {
        Material {
            e: self.e.unwrap_or(default.e),
            nu: self.nu.unwrap_or(default.nu),
            rho_kg_m3: self.rho_kg_m3.unwrap_or(default.rho_kg_m3),
        }
    }
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields, rename = "Materials")]
struct MaterialsRepr {
    #[serde(default)]
    nucleus: MaterialRepr,
    #[serde(default)]
    cytoplasm: MaterialRepr,
    #[serde(default)]
    membrane: MaterialRepr,
    #[serde(default = "default_gamma")]
    gamma: f64,
    #[serde(default = "default_beta_fraction")]
    beta_fraction: f64,
    #[serde(default)]
    fibres: Option<Fibres>,
}

/// Functions giving the default of a field of a section (`name: Section.field`), for
/// `#[serde(default = "name")]`.
macro_rules! field_defaults {
    ($($name:ident: $section:ident.$field:ident),+ $(,)?) => {
        $(fn $name() -> f64 {
            $section::default().$field
        })+
    };
}

field_defaults!(
    default_gamma: Materials.gamma,
    default_beta_fraction: Materials.beta_fraction,
);

impl From<MaterialsRepr> for Materials {
    fn from(r: MaterialsRepr) -> Self {
        let d = Materials::default();
        Materials {
            nucleus: r.nucleus.or(d.nucleus),
            cytoplasm: r.cytoplasm.or(d.cytoplasm),
            membrane: r.membrane.or(d.membrane),
            gamma: r.gamma,
            beta_fraction: r.beta_fraction,
            fibres: r.fibres,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Viscosity

/// Kelvin–Voigt Newtonian viscosity of the fluid phase, in the whole cell (MODEL.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Viscosity {
    /// Isotropic (bulk) viscosity λ_f (Pa·s = pN·s/µm²). Default 1000 (Table 1).
    /// Valid: λ_f ≥ 0.
    pub lambda_f: f64,
    /// Deviatoric (shear) viscosity μ_f (Pa·s). Default 2e-3 (Table 1). Valid: μ_f ≥ 0.
    pub mu_f: f64,
}

impl Default for Viscosity {
    fn default() -> Self {
        Viscosity {
            lambda_f: 1000.0,
            mu_f: 2e-3,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Gravity

/// Gravity b_g = −ρ₀ g s_g(t) t_g(t) e_y (MODEL.md §5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Gravity {
    /// Gravitational acceleration g (m/s², SI; [`Gravity::g`] gives µm/s²). Default 9.81.
    /// Valid: g ≥ 0.
    pub g_m_s2: f64,
    /// Turn the device upside down after the active phase: the sign s_g goes smoothly from
    /// +1 to −1 over [T_a0, T_a0 + flip_duration] (the paper's Sect. 3.3). Default false.
    pub upside_down: bool,
    /// Duration of the flip (s). Default 10 000 (MODEL.md §5). Valid: > 0. Unused unless
    /// `upside_down`.
    pub flip_duration: f64,
}

impl Default for Gravity {
    fn default() -> Self {
        Gravity {
            g_m_s2: 9.81,
            upside_down: false,
            flip_duration: 10_000.0,
        }
    }
}

impl Gravity {
    /// g in the solver unit, µm/s² (1 m/s² = 1e6 µm/s²).
    pub fn g(&self) -> f64 {
        self.g_m_s2 * units::M_PER_S2
    }
}

// ---------------------------------------------------------------------------------------
// Substrate

/// The rigid substrate under the cell (MODEL.md §5). Written `Flat(...)` or `Pillars(...)`;
/// the fields inside may be left out and take their defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "SubstrateRepr", into = "SubstrateRepr")]
pub enum Substrate {
    /// A flat surface y = y_s.
    Flat(Flat),
    /// A periodic array of superelliptic micropillars on a floor.
    Pillars(Pillars),
}

impl Substrate {
    /// The paper's flat substrate, y_s = −2 µm.
    pub fn flat() -> Self {
        Substrate::Flat(Flat::default())
    }

    /// MODEL.md's micropillars (width 8, spacing 8, height 8, first at x = 8, q = 4, 0.5 µm
    /// initial gap).
    pub fn pillars() -> Self {
        Substrate::Pillars(Pillars::default())
    }

    /// Whether the plane x = z through the cell's axis is a mirror of the 3-D substrate:
    /// flat, or pillars on the four-pillar lattice whose axes lie at the same offsets in x
    /// as in z (`first_center` an odd multiple of half the period: the centre above a gap).
    pub fn mirrors_diagonal(&self) -> bool {
        match self {
            Substrate::Flat(_) => true,
            Substrate::Pillars(p) => {
                p.lattice == crate::physics::Lattice::FourPillars
                    && p.half_periods().is_some_and(|k| k.rem_euclid(2.0) == 1.0)
            }
        }
    }
}

/// Flat substrate.
#[derive(Debug, Clone, PartialEq)]
pub struct Flat {
    /// Height y_s of the surface (µm). Default −2 (Table 1 y_flat): the cell bottom is at
    /// c_y − r_c = −1.5, 0.5 µm above. Valid: y_s < c_y − r_c (the surface is below the
    /// cell).
    pub y_s: f64,
}

impl Default for Flat {
    fn default() -> Self {
        Flat { y_s: -2.0 }
    }
}

/// Micropillars: pillars of width w and height h every w + s, the first centred at
/// x = first_center; each pillar is the superellipse |x̃/(w/2)|^q + |ỹ/(h/2)|^q ≤ 1 standing
/// on the floor y = y_top − h (MODEL.md §5).
#[derive(Debug, Clone, PartialEq)]
pub struct Pillars {
    /// Pillar width w (µm). Default 8 (Table 1 w_mp). Valid: > 0.
    pub width: f64,
    /// Space between neighbouring pillars s (µm); the period is w + s. Default 8 (Table 1
    /// s_mp). Valid: > 0.
    pub spacing: f64,
    /// Pillar height h (µm). Default 8 (MODEL.md §5). Valid: > 0.
    pub height: f64,
    /// Abscissa of the axis of the first pillar (µm). Default 8 (Table 1 x_mp), so that the
    /// cell centre sits above the middle of a gap. Valid: the pillar array must be mirror
    /// symmetric about the symmetry line x = 0, i.e. first_center is a multiple of half
    /// the period (w + s)/2.
    pub first_center: f64,
    /// Superellipse exponent q (rounded corners). Default 4 (MODEL.md §5). Valid: q ≥ 2.
    pub q: f64,
    /// Smallest initial vertical gap between the cell and the substrate (µm), from which
    /// the pillar tops y_top are placed (see [`Pillars::resolved_y_top`]). Default 0.5 (as on the
    /// flat substrate; MODEL.md §5). Valid: > 0. Ignored when `y_top` is given.
    pub gap: f64,
    /// Where the pillar axes lie in z in the 3-D model (`geometry.model: ThreeD`; ignored in
    /// the half-plane models): `FourPillars`, the cell centre above the centre of a square
    /// of four pillars (axes at z = P/2 + kP), or `Gap`, above the middle of the gap between
    /// two pillars (axes at z = kP). Default `FourPillars` (MODEL.md §10).
    pub lattice: crate::physics::Lattice,
    /// Explicit height of the pillar tops (µm), overriding `gap`. Default none (derived:
    /// −0.30 µm for the defaults). Valid: the pillars must start below the cell (smallest
    /// initial gap > 0). Use [`Pillars::resolved_y_top`] for the value in effect.
    pub y_top: Option<f64>,
    /// How a pillar meets the floor: `Straight`, the superellipse's (superellipsoid's)
    /// upper half continued straight down to the floor (a column with rounded top edges,
    /// no undercut), or `Rounded`, the whole superellipse of the paper's pillar table,
    /// whose rounded lower half leaves an undercut under the pillar's lower edges. Default
    /// `Straight` in every dimension (MODEL.md §5: in 2-D the membrane creases at the
    /// undercut's lip on refined meshes until an element inverts; in 3-D the cell that
    /// reaches the floor beside a pillar's corner flows into the undercut and jams).
    pub foot: crate::physics::PillarFoot,
    /// Width k of the fillet where the floor meets a pillar (µm): 0 takes the deeper of
    /// floor and pillar, a kink in the concave corner at the pillar's foot; k > 0 their
    /// smooth maximum where the two depths are within k of each other (the normal turns
    /// continuously round the corner; the surface moves out by at most k/4 there).
    /// Default 0.5 (`DEFAULT_FILLET`: the sharp corner of MODEL.md §5 stalls Newton's
    /// method where the membrane reaches it, and a 0.25 µm fillet does on refined meshes).
    /// Valid: 0 ≤ k ≤ min(h, s)/2.
    pub fillet: f64,
}

impl Default for Pillars {
    fn default() -> Self {
        Pillars {
            width: 8.0,
            spacing: 8.0,
            height: 8.0,
            first_center: 8.0,
            q: 4.0,
            gap: 0.5,
            lattice: crate::physics::Lattice::FourPillars,
            y_top: None,
            foot: crate::physics::PillarFoot::Straight,
            fillet: DEFAULT_FILLET,
        }
    }
}

impl Pillars {
    /// Period of the array, w + s (µm).
    pub fn period(&self) -> f64 {
        self.width + self.spacing
    }

    /// `k` where `first_center` is `k` half periods (to 1e-9 of the period), else `None`:
    /// the pillars are then mirror symmetric about x = 0 (any `k`), and on the `FourPillars`
    /// lattice about the diagonal plane x = z too (odd `k`: the centre above a gap).
    pub fn half_periods(&self) -> Option<f64> {
        let half = 0.5 * self.period();
        let k = (self.first_center / half).round();
        (self.period().is_finite() && (k * half - self.first_center).abs() <= 1e-9 * self.period())
            .then_some(k)
    }

    /// The pillar geometry in the physics module's terms, with tops at `y_top` (µm).
    pub fn at_height(&self, y_top: f64) -> crate::physics::Pillars {
        crate::physics::Pillars {
            width: self.width,
            spacing: self.spacing,
            height: self.height,
            first_center: self.first_center,
            q: self.q,
            y_top,
            foot: self.foot,
            fillet: self.fillet,
        }
    }

    /// Smallest vertical distance between the lower half of the undeformed cell and the
    /// substrate surface for pillar tops at `y_top` (µm); negative if they overlap.
    /// In the 3-D model over the lattice's pillars (the cell is a ball there).
    pub fn smallest_gap(&self, geometry: &Geometry, y_top: f64) -> f64 {
        let pillars = self.at_height(y_top);
        let clearance = if geometry.model == KinematicModel::ThreeD {
            let [cx, cy] = geometry.centre();
            pillars
                .lowest_clearance_on_lattice(self.lattice, [cx, cy, 0.0], geometry.r_c)
                .1
        } else {
            pillars.lowest_clearance(geometry.centre(), geometry.r_c).1
        };
        clearance - y_top
    }

    /// Height of the pillar tops (µm): `y_top` if given, otherwise placed so that the
    /// smallest initial vertical gap between cell and substrate equals `gap` (MODEL.md §5:
    /// −0.30 µm for the defaults, the gap being smallest near x ≈ 5 µm).
    pub fn resolved_y_top(&self, geometry: &Geometry) -> f64 {
        match self.y_top {
            Some(y) => y,
            // The gap is y_top-independent up to a shift: gap(y) = gap(0) − y.
            None => self.smallest_gap(geometry, 0.0) - self.gap,
        }
    }
}

field_defaults!(
    default_y_s: Flat.y_s,
    default_width: Pillars.width,
    default_spacing: Pillars.spacing,
    default_height: Pillars.height,
    default_first_center: Pillars.first_center,
    default_q: Pillars.q,
    default_gap: Pillars.gap,
);

/// The substrate as written in a file: struct variants, so that a file says
/// `Pillars(width: 8)` rather than `Pillars((width: 8))`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, rename = "Substrate")]
enum SubstrateRepr {
    Flat {
        #[serde(default = "default_y_s")]
        y_s: f64,
    },
    Pillars {
        #[serde(default = "default_width")]
        width: f64,
        #[serde(default = "default_spacing")]
        spacing: f64,
        #[serde(default = "default_height")]
        height: f64,
        #[serde(default = "default_first_center")]
        first_center: f64,
        #[serde(default = "default_q")]
        q: f64,
        #[serde(default = "default_gap")]
        gap: f64,
        #[serde(default, skip_serializing_if = "is_four_pillars")]
        lattice: crate::physics::Lattice,
        #[serde(default)]
        y_top: Option<f64>,
        #[serde(default, skip_serializing_if = "is_straight")]
        foot: crate::physics::PillarFoot,
        #[serde(default = "default_fillet", skip_serializing_if = "is_default_fillet")]
        fillet: f64,
    },
}

/// The default lattice is not written out (a 2-D case prints as before).
fn is_four_pillars(l: &crate::physics::Lattice) -> bool {
    *l == crate::physics::Lattice::FourPillars
}

/// The default foot is not written out either.
fn is_straight(f: &crate::physics::PillarFoot) -> bool {
    *f == crate::physics::PillarFoot::Straight
}

/// Width of the default fillet at a pillar's foot (µm; docs/MODEL.md §5): where the
/// membrane reaches the concave corner between floor and pillar, the deeper-of-two normal
/// jumps by 90–150° between neighbouring quadrature points, and Newton's method fails at
/// every step size (the geometry map's narrow pillars with wide gaps stalled there).
/// 0.5 µm, in every dimension (the 3-D scenes' value): both points finish with 0.1, 0.25
/// and 0.5 µm; 0.1 µm (the band's ε_ct) turns the normal so fast that
/// `cases/hard/rtol-loose.ron` fails at t = 43 553 s; with 0.25 µm (the default until
/// 2026-12-07) the fine map refined ×1.5 stopped at three narrow gaps (w = 3, s = 6 and
/// w = 4, s = 5, 6 µm) where the cell's lower lobe reached the corner: Newton's method on
/// IDA's kept matrix diverged at every step size there (`examples/newton_probe.rs`).
pub const DEFAULT_FILLET: f64 = 0.5;

fn default_fillet() -> f64 {
    DEFAULT_FILLET
}

/// Nor is the default fillet.
fn is_default_fillet(k: &f64) -> bool {
    *k == DEFAULT_FILLET
}

/// The conversions between [`Substrate`] and its file form [`SubstrateRepr`], field for
/// field, the pillars' fields listed once.
macro_rules! substrate_repr_conversions {
    ($($field:ident),* $(,)?) => {
        impl From<SubstrateRepr> for Substrate {
            fn from(r: SubstrateRepr) -> Self {
                match r {
                    SubstrateRepr::Flat { y_s } => Substrate::Flat(Flat { y_s }),
                    SubstrateRepr::Pillars { $($field),* } => {
                        Substrate::Pillars(Pillars { $($field),* })
                    }
                }
            }
        }

        impl From<Substrate> for SubstrateRepr {
            fn from(s: Substrate) -> Self {
                match s {
                    Substrate::Flat(Flat { y_s }) => SubstrateRepr::Flat { y_s },
                    Substrate::Pillars(Pillars { $($field),* }) => {
                        SubstrateRepr::Pillars { $($field),* }
                    }
                }
            }
        }
    };
}

substrate_repr_conversions!(
    width,
    spacing,
    height,
    first_center,
    q,
    gap,
    lattice,
    y_top,
    foot,
    fillet,
);

// ---------------------------------------------------------------------------------------
// Contact

/// Penalty contact with the substrate, b_ct = J μ_ct H_ε(d_sub) n_sub (MODEL.md §5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Contact {
    /// Penalty coefficient μ_ct (N/m³, SI as in the paper; [`Contact::mu_ct`] gives
    /// pN/µm³). Default 2e9 (Table 1, there printed in N). Valid: > 0.
    pub mu_ct_n_m3: f64,
    /// Half-width ε_ct of the smoothed Heaviside of the penetration depth (µm); also the
    /// distance within which boundary counts as "in contact" for the contact radius.
    /// Default 0.1. Valid: > 0.
    pub eps_ct: f64,
    /// Stiffening κ beyond the band: where material is deeper than ε_ct the force grows as
    /// μ_ct (1 + κ ξ³), ξ = (d − ε_ct)/ε_ct (C² at d = ε_ct; below ε_ct the force is the
    /// paper's). Default 0: the paper's force, which stays μ_ct however deep. Valid: ≥ 0.
    #[serde(skip_serializing_if = "is_zero")]
    pub stiffening: f64,
    /// Whether the cell's outer surface is kept from passing through itself, by the same
    /// penalty (plane strain and axisymmetric; ignored in 3-D). Where the membrane folds
    /// against a pillar (wide gaps, late in the active phase) the fold's two faces meet;
    /// without it they pass through each other and the element at the fold's tip turns
    /// inside out (README, "Maps without holes"). The pressure on a point of the outline
    /// behind a face of it: μ_ct H_ε(d)(d + ε)/2 at depth d, for faces turned towards the
    /// point and within 1.5ε (released by 2.5ε), within 4 µm of it along the reference
    /// outline. It is in the model only where the outline can fold: on pillars, once
    /// adhesion acts (as the μ_as unknowns join at T_g0; from the start without adhesion);
    /// on a flat substrate and during the fall its pairs would only widen the Jacobian.
    /// Default true (cellsim's choice, beyond MODEL.md); false: the model as MODEL.md
    /// states it.
    #[serde(skip_serializing_if = "is_true")]
    pub self_contact: bool,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

fn is_true(x: &bool) -> bool {
    *x
}

impl Default for Contact {
    fn default() -> Self {
        Contact {
            mu_ct_n_m3: 2e9,
            eps_ct: 0.1,
            stiffening: 0.0,
            self_contact: true,
        }
    }
}

impl Contact {
    /// μ_ct in the solver unit, pN/µm³ (1 N/m³ = 1e-6 pN/µm³).
    pub fn mu_ct(&self) -> f64 {
        self.mu_ct_n_m3 * units::N_PER_M3
    }
}

// ---------------------------------------------------------------------------------------
// Adhesion

/// Fibronectin layer, adhesive spreading force and focal-adhesion maturation (MODEL.md §5).
/// Present in a case: the membrane nodes carry the μ_as unknowns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Adhesion {
    /// Thickness e_f of the fibronectin band over the substrate (µm). Default 1.5
    /// (Table 1). Valid: > 0.
    pub e_f: f64,
    /// Half-width ε of the smoothed Heaviside of the band indicator H_ε(d_sub + e_f) (µm).
    /// Default 0.1. Valid: > 0.
    pub eps: f64,
    /// Maturation rate μ_as0 (N/(m³·s), SI as in the paper; [`Adhesion::mu_as0`] gives
    /// pN/(µm³·s)). Default 1e6 (Table 1, there printed in N/s). Valid: > 0.
    pub mu_as0_n_m3s: f64,
    /// Cap μ_as,max of the adhesion coefficient (N/m³, SI; [`Adhesion::mu_as_max`] gives
    /// pN/µm³). Default 1.4e9 (Table 1, there printed in N). Valid: > 0.
    pub mu_as_max_n_m3: f64,
    /// Direction of the spreading force, a reading of the paper's Eq. (26), which writes
    /// cof(F) N: `Cofactor` (cof(F) N as written, whose length is the area stretch of the
    /// surface with reference normal N) or `Unit` (its unit vector cof(F) N/|cof(F) N|).
    /// Default `Cofactor` (MODEL.md §5).
    pub direction: AdhesionDirection,
    /// Multiply the spreading force by J = det F, the paper's "J f_as" in its weak form,
    /// Eq. (37). Default false (MODEL.md §5: b_as is Eq. (26)'s f_as per unit reference
    /// volume).
    pub jacobian_factor: bool,
    /// Whether the fibronectin layer excludes the substrate itself: the paper obtains the
    /// layer "by subtracting g_flat from a higher flat substrate" (Sect. 2.2.1; the layer
    /// g_f,l enters Eqs. (26) and (28)), i.e. the indicator H_ε(d_sub + e_f) −
    /// H_ε_ct(d_sub), with the substrate's own indicator of the contact band. Default false
    /// (MODEL.md §5: H_ε(d_sub + e_f), substrate included). Valid when true:
    /// e_f >= eps + contact.eps_ct (so that the indicator stays in [0, 1]).
    pub layer_excludes_substrate: bool,
    /// Whether the spreading force lets go of membrane turned over onto the cell: times a
    /// switch on the cosine c between the membrane's current outward normal (cof(F) N)
    /// and its reference one N, whole for c ≥ −0.3 (turned up to 107°), none for
    /// c ≤ −0.6 (beyond 127°) ([`crate::physics::ADHESION_TURN`]). Default true
    /// (docs/MODEL.md §5: the paper's force pulls a fold's inner face beside a pillar wall
    /// along its turned normal, into the cell, deeper the finer the mesh; spreading turns no
    /// adhered membrane that far). `false`: the paper's force however far the membrane
    /// turns.
    pub fold_release: bool,
}

impl Default for Adhesion {
    fn default() -> Self {
        Adhesion {
            e_f: 1.5,
            eps: 0.1,
            mu_as0_n_m3s: 1e6,
            mu_as_max_n_m3: 1.4e9,
            direction: AdhesionDirection::Cofactor,
            jacobian_factor: false,
            layer_excludes_substrate: false,
            fold_release: true,
        }
    }
}

impl Adhesion {
    /// μ_as0 in the solver unit, pN/(µm³·s).
    pub fn mu_as0(&self) -> f64 {
        self.mu_as0_n_m3s * units::N_PER_M3_S
    }

    /// μ_as,max in the solver unit, pN/µm³.
    pub fn mu_as_max(&self) -> f64 {
        self.mu_as_max_n_m3 * units::N_PER_M3
    }
}

// ---------------------------------------------------------------------------------------
// Active strain

/// Active strain F_a = I − e_PAC t_a χ_PAC (T⊗T) − e_bot t_a χ_bot (N⊗N) (MODEL.md §6).
/// Absent regions do not contract.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Active {
    /// The perinuclear actin cap ("push", tangential fibres). Default none.
    pub pac: Option<Pac>,
    /// The region beneath the nucleus ("pull", radial fibres). Default none.
    pub bottom: Option<Bottom>,
    /// Half-width ε_a of the smoothed Heavisides bounding the regions (µm). Default 0.25.
    /// Valid: > 0.
    pub eps_a: f64,
}

impl Default for Active {
    fn default() -> Self {
        Active {
            pac: None,
            bottom: None,
            eps_a: 0.25,
        }
    }
}

/// The PAC region: cytoplasm points with θ ≥ θ_PAC between two ellipses centred at c.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Pac {
    /// Contraction amplitude e_PAC (dimensionless; the target fibre stretch is 1 − e).
    /// Default 0.7 (Table 1). Valid: 0 ≤ e < 1.
    pub e: f64,
    /// Bounding angle θ_PAC (degrees, θ = atan((y − c_y)/x)); the region is θ ≥ θ_PAC.
    /// Default −18 (Table 1). Valid: −90 < θ < 90.
    pub theta_deg: f64,
    /// Semi-axes (a_x, a_y) of the inner ellipse (µm). Default (5, 4.5) (MODEL.md's
    /// reading of Table 1's 10, 9 µm as full axes). Valid: 0 < inner < outer, each axis.
    pub inner_semi_axes: (f64, f64),
    /// Semi-axes (a_x, a_y) of the outer ellipse (µm). Default (7.5, 7) (Table 1's 15,
    /// 14 µm read as full axes). Valid: inner < outer < r_c, each axis (an outer ellipse
    /// leaving the cell is the symptom of semi-axes given as full axes), unless
    /// `clip_to_cell`.
    pub outer_semi_axes: (f64, f64),
    /// Let the ellipses extend beyond the cell, the PAC being the part of the cytoplasm
    /// between them (clipped by the cell). This is the other reading of Table 1: its 10, 9,
    /// 15, 14 µm taken as the semi-axes a, b of the paper's Eq. (31), which the text calls
    /// axes: `inner_semi_axes: (10, 9), outer_semi_axes: (15, 14), clip_to_cell: true`
    /// gives a thin cap under the apical membrane. Default false (MODEL.md §6 reads them
    /// as full axes, and then an ellipse leaving the cell is a mistake). Valid when true:
    /// the smaller inner semi-axis < r_cp (otherwise the inner ellipse holds the whole
    /// cytoplasm and the PAC is empty).
    pub clip_to_cell: bool,
}

impl Default for Pac {
    fn default() -> Self {
        Pac {
            e: 0.7,
            theta_deg: -18.0,
            inner_semi_axes: (5.0, 4.5),
            outer_semi_axes: (7.5, 7.0),
            clip_to_cell: false,
        }
    }
}

/// The bottom region: cytoplasm and membrane points with θ ≤ θ_bot.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Bottom {
    /// Contraction amplitude e_bot (dimensionless). Default 0.7 (Table 1).
    /// Valid: 0 ≤ e < 1.
    pub e: f64,
    /// Bounding angle θ_bot (degrees); the region is θ ≤ θ_bot. Default −35 (Table 1).
    /// Valid: −90 < θ < 90.
    pub theta_deg: f64,
}

impl Default for Bottom {
    fn default() -> Self {
        Bottom {
            e: 0.7,
            theta_deg: -35.0,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Phases

/// The three loading phases, switched on by smooth steps: t_g = S(t; 0, T_g0),
/// t_as = S(t; T_g0, T_as0), t_a = S(t; T_as0, T_a0) (MODEL.md §5), and the end time.
/// All are breakpoints the integrators must stop at.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Phases {
    /// End of the gravity ramp T_g0 (s). Default 10 000 (Table 1). Valid: T_g0 > 0.
    #[serde(default = "default_t_g0")]
    pub t_g0: f64,
    /// End of the adhesion ramp T_as0 (s). Default 40 000 (Table 1). Valid: T_as0 > T_g0
    /// (strict: an empty ramp would be a jump, and the model keeps every switch smooth).
    #[serde(default = "default_t_as0")]
    pub t_as0: f64,
    /// End of the active-strain ramp T_a0 (s). Default 50 000 (Table 1).
    /// Valid: T_a0 > T_as0.
    #[serde(default = "default_t_a0")]
    pub t_a0: f64,
    /// End of the simulation (s). Required: each scene states it. Valid: > 0.
    pub t_end: f64,
    /// When the adhesion ramp starts (MODEL.md §11): `At(t)`, or `Settled(speed)` (the
    /// cell has come to rest: the centre's vertical speed below `speed` µm/s once the
    /// contact carries half the weight; MODEL.md's choice 1e-5). Default `At(T_g0)`, the
    /// paper. The ramp lasts T_as0 − T_g0 from its start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub adhesion_start: Option<Start>,
    /// When the active-strain ramp starts: `At(t)`, or `SpreadingSlows(rate)` (the adhered
    /// reference radius grows slower than `rate` µm/s, after growing faster since
    /// adhesion started; MODEL.md's choice 1e-4). Default `At(T_as0)`, the paper. The ramp
    /// lasts T_a0 − T_as0 from its start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active_start: Option<Start>,
}

/// When a phase starts (MODEL.md §11). A case's times after a phase's paper start
/// (T_g0 for adhesion, T_as0 for the active strain) — the end time, the output times, the
/// gravity flip — move with that phase's start: they are read as times after it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Start {
    /// At a time (s). Valid: finite, ≥ 0.
    At(f64),
    /// When the cell has settled on the substrate: the centre's vertical speed falls below
    /// this (µm/s), once the contact carries half the weight then acting. Adhesion only.
    /// Valid: > 0.
    Settled(f64),
    /// When spreading slows: the adhered reference radius (the adhered length of the
    /// half cell's outline; √(A/π) of the adhered area A in 3-D) grows slower than this
    /// (µm/s), once it has grown faster after adhesion started. Active strain only.
    /// Valid: > 0.
    SpreadingSlows(f64),
}

fn default_t_g0() -> f64 {
    10_000.0
}
fn default_t_as0() -> f64 {
    40_000.0
}
fn default_t_a0() -> f64 {
    50_000.0
}

impl Phases {
    /// The paper's phases (T_g0 = 10 000 s, T_as0 = 40 000 s, T_a0 = 50 000 s) ending at
    /// `t_end`.
    pub fn paper(t_end: f64) -> Self {
        Phases {
            t_g0: default_t_g0(),
            t_as0: default_t_as0(),
            t_a0: default_t_a0(),
            t_end,
            adhesion_start: None,
            active_start: None,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Inertia

/// Whether the balance law keeps the inertia term ρ₀ v̇ (MODEL.md §8).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum InertiaMode {
    /// Inertia throughout: unknowns (u, v, μ_as).
    On,
    /// No inertia: unknowns (u, μ_as). Needs `drag > 0` (otherwise the vertical rigid mode
    /// has no stiffness before the contact carries load).
    Off,
    /// Inertia until time t (s), then switch it off and re-initialise the integrator on the
    /// smaller system from the current (u, μ_as): the fall needs inertia, the long
    /// spreading and active phases do not. Valid: t > 0; choose t after the cell rests on
    /// the substrate (e.g. T_g0).
    OffAfter(f64),
}

/// Inertia and the drag of the culture medium (MODEL.md §8).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Inertia {
    /// `On`, `Off` or `OffAfter(t)`. Default `On`.
    pub mode: InertiaMode,
    /// Medium drag coefficient c_d, b_drag = −c_d v per unit reference volume
    /// (pN·s/µm⁴ = Pa·s/µm² = 1e12 N·s/m⁴). Default 0 (no drag). Valid: c_d ≥ 0, and
    /// c_d > 0 when mode is `Off`.
    pub drag: f64,
}

impl Default for Inertia {
    fn default() -> Self {
        Inertia {
            mode: InertiaMode::On,
            drag: 0.0,
        }
    }
}

// ---------------------------------------------------------------------------------------
// Output

/// What the run writes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Output {
    /// Number of equally spaced output times in [0, t_end] for the time series (contact
    /// radius, displacements of p_t, c, p_b, mean ‖E‖ per domain). Default 400.
    /// Valid: 200 ≤ n_times ≤ 100 000 ([`Output::MIN_TIMES`], [`Output::MAX_TIMES`]; the
    /// upper bound stops a typo from allocating gigabytes of output times).
    pub n_times: u32,
    /// Also write the full state (deformed shape, domains, active regions, substrate) at
    /// the ends of the phases T_g0, T_as0, T_a0 and at t_end. Default true.
    pub phase_states: bool,
}

impl Output {
    /// Fewest output times a case may ask for (`n_times`).
    pub const MIN_TIMES: u32 = 200;
    /// Most output times a case may ask for (`n_times`): 100 000, far more than a plot
    /// resolves.
    pub const MAX_TIMES: u32 = 100_000;
}

impl Default for Output {
    fn default() -> Self {
        Output {
            n_times: 400,
            phase_states: true,
        }
    }
}
