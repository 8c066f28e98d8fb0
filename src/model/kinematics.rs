//! Quadrature-point kinematics of the displacement element: the deformation gradient
//! `F = I + Σₐ uₐ ⊗ ∇Nₐ`, its rate `Ḟ = Σₐ vₐ ⊗ ∇Nₐ`, the current position
//! `x = X + Σₐ Nₐ uₐ` and `J = det F`, written once for any spatial dimension `D` and node
//! count `N` (const generics).
//!
//! Three kinematic models make `F` a 3-D deformation ([`crate::physics::KinematicModel`]):
//! [`PlaneStrain`] (`F = F₂ ⊕ 1` on the half-plane's triangles), [`Axisymmetric`]
//! (`F = F₂ ⊕ λ_θ`, `λ_θ = 1 + u_r/r`, the same triangles read as the meridian of a ball)
//! and [`ThreeD`] (the 3 × 3 `F` of the quarter cell's tetrahedra). What each changes in
//! the element kernels is its `super::kernels::Formulation`.

use nalgebra::{SMatrix, SVector};

use crate::physics::Real;

/// Plane strain: displacements in the (x, y) plane, `F₃₃ = 1`.
#[derive(Debug, Clone, Copy)]
pub struct PlaneStrain;

/// Axisymmetric about the vertical axis r = 0 (MODEL.md §10): the half-plane is the
/// meridian (r, y), displacements (u_r, u_y), `F = F₂ ⊕ λ_θ` with the hoop stretch
/// `λ_θ = 1 + u_r/r`, `J = λ_θ det F₂`; every integral is weighted by r (work per
/// radian). u_r = 0 on the axis is the plane-strain symmetry condition.
#[derive(Debug, Clone, Copy)]
pub struct Axisymmetric;

/// Three dimensions: the quarter cell's 3 × 3 `F` (MODEL.md §10).
#[derive(Debug, Clone, Copy)]
pub struct ThreeD;

/// A vector per node: `[[f64; D]; N]`.
pub type NodalOf<const D: usize, const N: usize> = [[f64; D]; N];

/// `A + Σₐ wₐ ⊗ ∇Nₐ`: entry (i, L) gets `Σₐ wₐ,ᵢ ∂Nₐ/∂X_L`, summed over the nodes in order.
#[inline]
fn add_gradient<const D: usize, const N: usize>(
    mut f: SMatrix<f64, D, D>,
    w: &NodalOf<D, N>,
    grads: &NodalOf<D, N>,
) -> SMatrix<f64, D, D> {
    for a in 0..N {
        for i in 0..D {
            for l in 0..D {
                f[(i, l)] += w[a][i] * grads[a][l];
            }
        }
    }
    f
}

/// Deformation gradient `F = I + Σₐ uₐ ⊗ ∇Nₐ` from nodal displacements `ue` and the
/// shape-function gradients (reference configuration) at a point.
#[inline]
pub fn deformation<const D: usize, const N: usize>(
    ue: &NodalOf<D, N>,
    grads: &NodalOf<D, N>,
) -> SMatrix<f64, D, D> {
    add_gradient(SMatrix::identity(), ue, grads)
}

/// Its rate `Ḟ = Σₐ vₐ ⊗ ∇Nₐ` from nodal velocities `ve`.
#[inline]
pub fn rate<const D: usize, const N: usize>(
    ve: &NodalOf<D, N>,
    grads: &NodalOf<D, N>,
) -> SMatrix<f64, D, D> {
    add_gradient(SMatrix::zeros(), ve, grads)
}

/// Current position `x = X + Σₐ Nₐ uₐ` of the point with reference position `x_ref` and
/// shape-function values `values`.
#[inline]
pub fn current_position<const D: usize, const N: usize>(
    x_ref: &[f64; D],
    values: &[f64; N],
    ue: &NodalOf<D, N>,
) -> SVector<f64, D> {
    let mut x = SVector::from(*x_ref);
    for a in 0..N {
        for i in 0..D {
            x[i] += values[a] * ue[a][i];
        }
    }
    x
}

/// `Σ_L f(L)` for L = 0 … D−1, summed left to right from the first term.
#[inline(always)]
pub fn contract<const D: usize>(f: impl Fn(usize) -> f64) -> f64 {
    let mut s = f(0);
    for l in 1..D {
        s += f(l);
    }
    s
}

/// `det F` of a 2 × 2 or 3 × 3 `F`, by cofactors along the first row (the products and
/// sums nalgebra forms, so that values and dual derivatives are those of
/// `SMatrix::determinant`).
#[inline(always)]
pub fn det<T: Real, const D: usize>(f: &SMatrix<T, D, D>) -> T {
    if D == 2 {
        f[(0, 0)] * f[(1, 1)] - f[(1, 0)] * f[(0, 1)]
    } else {
        let minor_12_23 = f[(1, 1)] * f[(2, 2)] - f[(2, 1)] * f[(1, 2)];
        let minor_11_23 = f[(1, 0)] * f[(2, 2)] - f[(2, 0)] * f[(1, 2)];
        let minor_11_22 = f[(1, 0)] * f[(2, 1)] - f[(2, 0)] * f[(1, 1)];
        f[(0, 0)] * minor_12_23 - f[(0, 1)] * minor_11_23 + f[(0, 2)] * minor_11_22
    }
}
