//! Quadrature-point kinematics of the displacement element: the deformation gradient
//! `F = I + Σₐ uₐ ⊗ ∇Nₐ`, its rate `Ḟ = Σₐ vₐ ⊗ ∇Nₐ`, the current position
//! `x = X + Σₐ Nₐ uₐ` and `J = det F`.
//!
//! The sums are written once for any spatial dimension `D` and node count `N` (const
//! generics); [`Kinematics`] describes the arrays of the in-plane model ([`Kin`]:
//! [`PlaneStrain`]'s 2 × 2 `F₂`). Two kinematic models complete `F₂` to three dimensions:
//! [`PlaneStrain`] (`F₃₃ = 1`) and [`Axisymmetric`] (`F₃₃ = λ_θ = 1 + u_r/r`, the same
//! in-plane arrays in the meridian half-plane). What each changes in the element kernels
//! is `super::kernels::Formulation`; the case chooses one
//! ([`crate::physics::KinematicModel`]) and the model dispatches on it once per element
//! loop.

use nalgebra::{Matrix2, SMatrix, SVector, Vector2};

use crate::physics::Real;

/// A kinematic model: the spatial dimension of positions and displacements, the tensor
/// type the material laws take for `F` and `Ḟ`, and `J = det F`.
pub trait Kinematics {
    /// Spatial dimension of positions and displacements.
    const DIM: usize;
    /// The deformation-gradient type the laws take, over a scalar `T` (`f64` or a dual
    /// number for tangents).
    type Tensor<T: Real>;
    /// A position or force over a scalar `T`.
    type Vector<T: Real>;
    /// `J = det F` (the volume ratio).
    fn det<T: Real>(f: &Self::Tensor<T>) -> T;
}

/// Plane strain: displacements in the (x, y) plane, `F₃₃ = 1`, so `F` is the in-plane
/// 2 × 2 block and `J = F₁₁F₂₂ − F₁₂F₂₁`.
#[derive(Debug, Clone, Copy)]
pub struct PlaneStrain;

impl Kinematics for PlaneStrain {
    const DIM: usize = 2;
    type Tensor<T: Real> = Matrix2<T>;
    type Vector<T: Real> = Vector2<T>;

    #[inline(always)]
    fn det<T: Real>(f: &Matrix2<T>) -> T {
        f[(0, 0)] * f[(1, 1)] - f[(0, 1)] * f[(1, 0)]
    }
}

/// Axisymmetric about the vertical axis r = 0 (MODEL.md §10): the half-plane is the
/// meridian (r, y), displacements (u_r, u_y), `F = F₂ ⊕ λ_θ` with `F₂` as in plane strain
/// and the hoop stretch `λ_θ = 1 + u_r/r`, `J = λ_θ det F₂`; every integral is weighted
/// by r (work per radian). u_r = 0 on the axis is the plane-strain symmetry condition.
#[derive(Debug, Clone, Copy)]
pub struct Axisymmetric;

/// The in-plane arrays of the cell model (`F₂`, positions, forces), shared by both
/// kinematic models.
pub type Kin = PlaneStrain;

/// Spatial dimension of the cell model.
pub const DIM: usize = <Kin as Kinematics>::DIM;

/// `F`, `Ḟ`, `F_a` of the cell model over `T`.
pub type Tensor<T> = <Kin as Kinematics>::Tensor<T>;

/// Positions and forces of the cell model over `T`.
pub type Vector<T> = <Kin as Kinematics>::Vector<T>;

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
