//! Material laws, active strain, substrate, contact, adhesion, gravity and phases: pure functions.
//!
//! Everything here is in solver units (µm, s, pN; stress in Pa = pN/µm², body forces in
//! pN/µm³ per unit reference volume). Nothing here knows about meshes or integrators.
//!
//! Functions of the unknowns (deformation gradient `F`, its rate `Ḟ`, the current position
//! `x`, the adhesion coefficient `μ_as`) are generic over a scalar [`Real`], so the model
//! gets exact tangents by evaluating them with forward-mode dual numbers
//! (`num_dual::DualSVec64<N>`) and cheap residuals with `f64`. Quantities of the
//! reference position or of time only (active strain `F_a`, phase functions, domain
//! indicators) are plain `f64`.
//!
//! Module map (sections of `MODEL.md`):
//! - [`smooth`]: the C² smooth step `S(s; a, b)` and regularised Heaviside `H_ε` (§5);
//! - [`phases`]: the time switches `t_g`, `t_as`, `t_a` and the gravity flip `s_g` (§5);
//! - [`law`]: compressible Yeoh solid with active strain and Kelvin–Voigt viscosity (§3),
//!   whatever the kinematics, and the material point the kernels take;
//! - [`plane_strain`]: the laws with the 2 × 2 `F` of plane strain (§3);
//! - [`hoop`]: the same laws with the hoop stretch of the axisymmetric model (§10);
//! - [`three_d`]: the same laws with a full 3 × 3 `F`, for the 3-D quarter cell (§10), with
//!   a closed-form tangent;
//! - [`fibres`]: the fibre term of the cytoplasm (§11), written once for every kinematics;
//! - [`active`]: the active-strain tensor `F_a` of the PAC and bottom fibres (§6), in 2-D
//!   and about the vertical axis of the 3-D cell (§10);
//! - [`substrate`]: flat and micropillared substrates, penetration depth and normal (§5),
//!   and their 3-D extension on a square lattice of pillars (§10);
//! - [`loads`]: contact, adhesion, adhesion-rate and gravity body forces (§5), and their
//!   3-D twins (§10).
//!
//! **The 3-D functions that are not generic carry `#[inline]`** (`material_point_full`,
//! `fa_revolved`, `surface_height_on_lattice`, …). The 2-D code paths keep their own
//! functions, but adding compiled code to the crate changes how rustc splits it into
//! codegen units, and with that what LLVM inlines in the 2-D element loops: with these
//! functions compiled eagerly, callgrind on `cases/fast/push-pull-short.ron` counted plane
//! strain's `material_point` 3.3 % more instructions and `piola_total` 3.0 % fewer, and the
//! assembly's `BlockPositions::scatter` was no longer inlined, for the same results.
//! `#[inline]` functions are compiled only where they are called, so until the 3-D model
//! calls them the 2-D binary is the one it was (the same symbols of the same sizes, the
//! same instruction counts per function).

pub mod active;
#[cfg(test)]
mod checks;
pub mod fibres;
pub mod hoop;
pub mod law;
pub mod loads;
pub mod phases;
pub mod plane_strain;
pub mod smooth;
pub mod substrate;
pub mod three_d;

pub use active::{ActiveStrain, Bottom, Pac};
pub use fibres::{ActiveFibre, Fibre, Fibres};
pub use hoop::{
    BlockDiag, MaterialPointHoop, admissible_hoop, material_point_hoop, piola_total_hoop,
};
pub use law::{
    Invariants, IsotropicSolid, MaterialPointOf, StressScalars, TangentScalars, Viscosity, Yeoh,
    dual_material_point,
};
pub use loads::{
    ADHESION_TURN, Adhesion, AdhesionDirection, Contact, adhesion_force, adhesion_hoop_factor,
    adhesion_rate, contact_force, layer, self_contact_force,
};
pub use phases::{Condition, Flip, Phases};
pub use plane_strain::{MaterialPoint, admissible, material_point, piola_total};
pub use smooth::{heaviside, smooth_step};
pub use substrate::{Lattice, LatticeSubstrate, PillarFoot, Pillars, Substrate, Surface};
pub use three_d::{MaterialPointFull, admissible_full, material_point_full, piola_total_full};

use num_dual::DualNum;
use serde::{Deserialize, Serialize};

/// How the in-plane deformation of the half-plane model is completed to three dimensions
/// (the case's `geometry.model`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum KinematicModel {
    /// Plane strain, `F₃₃ = 1`: the paper's 2-D half cell (a cylinder along z), per unit
    /// thickness.
    #[default]
    PlaneStrain,
    /// Axisymmetric about the vertical axis through the cell centre: the (x, y) half-plane
    /// is the meridian (r, y), `F₃₃ = 1 + u_r/r`, every integral weighted by r (per
    /// radian). A real 3-D (spherical) cell; MODEL.md §10.
    Axisymmetric,
    /// The 3-D quarter cell x ≥ 0, z ≥ 0 on ten-node tetrahedra, meshed by gmsh
    /// (`crate::model3d`; MODEL.md §10): no half-plane, the section z = 0 is the 2-D
    /// model's.
    ThreeD,
}

pub use crate::tensor::{Real, cofactor};

/// Invalid physical parameters, caught when a parameter set is built or validated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PhysicsError {
    /// A parameter lies outside its admissible range.
    #[error("invalid parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Name of the parameter as in MODEL.md.
        name: &'static str,
        /// The offending value (solver units).
        value: f64,
        /// What the admissible range is.
        reason: &'static str,
    },
}

/// Shorthand used by the validators: `Err(InvalidParameter { .. })` unless `ok`.
pub(crate) fn check(
    ok: bool,
    name: &'static str,
    value: f64,
    reason: &'static str,
) -> Result<(), PhysicsError> {
    if ok {
        Ok(())
    } else {
        Err(PhysicsError::InvalidParameter {
            name,
            value,
            reason,
        })
    }
}

/// `T` from an `f64` constant (no derivative part).
#[inline(always)]
pub(crate) fn cst<T: Real>(v: f64) -> T {
    T::from(v)
}

/// Real part (value) of a scalar, as `f64`.
#[inline(always)]
pub(crate) fn re<T: Real>(x: T) -> f64 {
    x.re()
}

/// `x^n`, integer power (the `DualNum` one).
#[inline(always)]
pub(crate) fn powi<T: Real>(x: T, n: i32) -> T {
    DualNum::powi(&x, n)
}

/// `x^p`, real power of a positive `x`.
#[inline(always)]
pub(crate) fn powf<T: Real>(x: T, p: f64) -> T {
    DualNum::powf(&x, p)
}

/// Square root.
#[inline(always)]
pub(crate) fn sqrt<T: Real>(x: T) -> T {
    DualNum::sqrt(&x)
}

/// Cube root.
#[inline(always)]
pub(crate) fn cbrt<T: Real>(x: T) -> T {
    DualNum::cbrt(&x)
}

/// Natural logarithm.
#[inline(always)]
pub(crate) fn ln<T: Real>(x: T) -> T {
    DualNum::ln(&x)
}

/// `|x|`, with the derivative of `x` for `x ≥ 0` (only used where the derivative at 0
/// does not matter or is multiplied by 0).
#[inline(always)]
pub(crate) fn abs<T: Real>(x: T) -> T {
    if x.re() < 0.0 { -x } else { x }
}

/// MODEL.md's parameters for this layer's tests, taken from the case schema (the one
/// place the defaults live; this layer holds no default numbers of its own).
#[cfg(test)]
pub(crate) mod reference {
    use crate::case::Case;
    use crate::scene::terms;

    pub fn contact() -> super::Contact {
        terms::contact(&Case::reference())
    }

    pub fn adhesion() -> super::Adhesion {
        terms::adhesion(&Case::reference()).expect("the reference case has adhesion")
    }

    pub fn viscosity() -> super::Viscosity {
        terms::viscosity(&Case::reference())
    }

    pub fn phases() -> super::Phases {
        terms::phases(&Case::reference())
    }

    /// The default pillars, placed 0.5 µm below the default cell.
    pub fn pillars() -> super::substrate::Pillars {
        let mut c = Case::reference();
        c.substrate = crate::case::Substrate::pillars();
        match terms::substrate(&c) {
            super::Substrate::Pillars(p) => p,
            super::Substrate::Flat { .. } => unreachable!("a pillar case"),
        }
    }
}
