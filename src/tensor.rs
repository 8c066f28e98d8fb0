//! The scalars and the one tensor operation that the finite elements ([`crate::fem`]) and
//! the material laws ([`crate::physics`]) share: the [`Real`] scalar of every function of
//! the unknowns and the [`cofactor`] of a deformation gradient.

#![allow(non_snake_case)]

use nalgebra::{RealField, SMatrix};
use num_dual::DualNum;

/// The scalar type of every function of the unknowns: `f64` for residuals, a forward-mode
/// dual number such as `num_dual::DualSVec64<N>` for exact tangents.
///
/// Implemented automatically for every type meeting the bounds. Both `DualNum` and
/// `RealField` provide `sqrt`, `powi`, … under the same names; inside [`crate::physics`]
/// its helpers pick the `DualNum` ones so calls are unambiguous.
pub trait Real: DualNum<Primitive = f64> + RealField + Copy {}

impl<T: DualNum<Primitive = f64> + RealField + Copy> Real for T {}

/// Cofactor `cof(F) = J F⁻ᵀ`, polynomial in `F`: in 2-D `[[F₁₁, −F₁₀], [−F₀₁, F₀₀]]`, in
/// 3-D `cof_ij = F_{i+1,j+1} F_{i+2,j+2} − F_{i+1,j+2} F_{i+2,j+1}` (indices mod 3).
#[inline(always)]
pub fn cofactor<T: Real, const D: usize>(F: &SMatrix<T, D, D>) -> SMatrix<T, D, D> {
    SMatrix::from_fn(|i, j| {
        if D == 2 {
            let f = F[(1 - i, 1 - j)];
            if i == j { f } else { -f }
        } else {
            let (i1, i2) = ((i + 1) % 3, (i + 2) % 3);
            let (j1, j2) = ((j + 1) % 3, (j + 2) % 3);
            F[(i1, j1)] * F[(i2, j2)] - F[(i1, j2)] * F[(i2, j1)]
        }
    })
}
