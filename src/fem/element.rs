//! What a finite-element model needs of its mesh and of its element's shape functions,
//! written once for the six-node triangles of the half cell ([`super::Mesh`],
//! [`super::tri6`]) and the ten-node tetrahedra of the quarter cell ([`super::TetMesh`],
//! [`super::tet10`]): `D` the spatial dimension, `N` the nodes per element. An element is a
//! [`Lagrange`] type (its edges and quadrature rules; the quadratic shape functions are
//! written once); the tabulation at quadrature points, the isoparametric Jacobian and the
//! element geometry are generic.

use std::marker::PhantomData;

use nalgebra::{Const, DimMin, SMatrix};
use thiserror::Error;

use super::quadrature::{Rule, Subdivision};
use super::{Domain, Mesh, MeshError, NamedPoints, P2Tabulation, TetMesh, TetTabulation};
use crate::tensor::cofactor;

/// An isoparametric quadratic (P2) Lagrange element on the reference simplex of dimension
/// `D` with `N` nodes: the `D + 1` vertices, then one mid-node per edge of
/// [`Lagrange::EDGES`]. With the barycentric coordinates λ₀ = 1 − Σ ξ, λₖ = ξₖ₋₁, the shape
/// functions are λᵢ(2λᵢ − 1) at vertex i and 4λᵢλⱼ at the mid-node of edge i–j.
pub trait Lagrange<const D: usize, const N: usize>: Send + Sync {
    /// The vertex pairs of the edges: edge k carries local node `D + 1 + k`.
    const EDGES: &'static [[usize; 2]];
    /// The reference simplex's rule exact to a degree.
    const RULE: fn(usize) -> Rule<[f64; D]>;
    /// A rule applied on each sub-simplex of `levels` regular refinements.
    const SUBDIVIDED: Subdivision<[f64; D]>;

    /// Shape function values at reference point ξ.
    #[inline]
    fn shape(xi: [f64; D]) -> [f64; N] {
        let l0 = xi.iter().fold(1.0, |s, x| s - x);
        let l = |k: usize| if k == 0 { l0 } else { xi[k - 1] };
        std::array::from_fn(|a| {
            if a <= D {
                l(a) * (2.0 * l(a) - 1.0)
            } else {
                let [i, j] = Self::EDGES[a - D - 1];
                4.0 * l(i) * l(j)
            }
        })
    }

    /// Reference gradients ∇_ξ Nₐ at ξ (∂λ₀ = (−1, …, −1), ∂λₖ = eₖ); they sum to zero
    /// over a.
    #[inline]
    fn grad_shape(xi: [f64; D]) -> [[f64; D]; N] {
        let l0 = xi.iter().fold(1.0, |s, x| s - x);
        let l = |k: usize| if k == 0 { l0 } else { xi[k - 1] };
        std::array::from_fn(|a| {
            std::array::from_fn(|c| match a {
                // d/dλ₀ of λ₀(2λ₀ − 1) is 4λ₀ − 1, times ∂λ₀ = −1.
                0 => 1.0 - 4.0 * l0,
                _ if a <= D => {
                    if a == c + 1 {
                        4.0 * l(a) - 1.0
                    } else {
                        0.0
                    }
                }
                _ => match Self::EDGES[a - D - 1] {
                    // 4λ₀λₒ: 4(λ₀ − λₒ) along ξ of λₒ, −4λₒ along the others.
                    [0, o] | [o, 0] if c + 1 == o => 4.0 * (l0 - l(o)),
                    [0, o] | [o, 0] => -4.0 * l(o),
                    // 4λᵢλⱼ, i, j ≠ 0: 4λⱼ along ξ of λᵢ, 4λᵢ along that of λⱼ.
                    [i, j] if c + 1 == i => 4.0 * l(j),
                    [i, j] if c + 1 == j => 4.0 * l(i),
                    _ => 0.0,
                },
            })
        })
    }

    /// The isoparametric map of an element with nodal coordinates `x` at reference point
    /// ξ: the physical point x(ξ), J = ∂x/∂ξ and det J.
    fn map(x: &[[f64; D]; N], xi: [f64; D]) -> ([f64; D], SMatrix<f64, D, D>, f64)
    where
        SMatrix<f64, D, D>: JacobianMatrix<D>,
    {
        let (jac, det) = jacobian(x, &Self::grad_shape(xi));
        (interpolate(x, &Self::shape(xi)), jac, det)
    }
}

/// The algebra of a `D`×`D` Jacobian matrix that the element geometry needs.
pub trait JacobianMatrix<const D: usize> {
    /// det J.
    fn det(&self) -> f64;
    /// Physical gradients J⁻ᵀ gₐ of the reference gradients gₐ, given det J (non-zero).
    fn inverse_transpose<const N: usize>(&self, det: f64, grads: &[[f64; D]; N]) -> [[f64; D]; N];
}

impl<const D: usize> JacobianMatrix<D> for SMatrix<f64, D, D>
where
    Const<D>: DimMin<Const<D>, Output = Const<D>>,
{
    fn det(&self) -> f64 {
        self.determinant()
    }
    /// J⁻ᵀ = cof(J)/det.
    fn inverse_transpose<const N: usize>(&self, det: f64, grads: &[[f64; D]; N]) -> [[f64; D]; N] {
        let (m, inv) = (cofactor(self), 1.0 / det);
        grads.map(|g| {
            std::array::from_fn(|i| {
                inv * (1..D).fold(m[(i, 0)] * g[0], |s, k| s + m[(i, k)] * g[k])
            })
        })
    }
}

/// Σₐ nₐ xₐ: the point with shape values `n` of the element with nodes `x`.
#[inline]
fn interpolate<const D: usize, const N: usize>(x: &[[f64; D]; N], n: &[f64; N]) -> [f64; D] {
    let mut p = [0.0; D];
    for a in 0..N {
        for i in 0..D {
            p[i] += n[a] * x[a][i];
        }
    }
    p
}

/// Jacobian J = ∂x/∂ξ (J[(i, j)] = ∂xᵢ/∂ξⱼ) and its determinant from the nodal coordinates
/// `x` and precomputed reference gradients.
#[inline]
pub fn jacobian<const D: usize, const N: usize>(
    x: &[[f64; D]; N],
    ref_grads: &[[f64; D]; N],
) -> (SMatrix<f64, D, D>, f64)
where
    SMatrix<f64, D, D>: JacobianMatrix<D>,
{
    let mut jac = SMatrix::<f64, D, D>::zeros();
    for a in 0..N {
        for i in 0..D {
            for j in 0..D {
                jac[(i, j)] += x[a][i] * ref_grads[a][j];
            }
        }
    }
    let det = jac.det();
    (jac, det)
}

/// Physical gradients ∇ₓNₐ = J⁻ᵀ ∇_ξ Nₐ from the Jacobian J, its determinant `det` (must be
/// non-zero; the caller checks its sign) and the reference gradients.
#[inline]
pub fn physical_gradients<const D: usize, const N: usize>(
    jac: &SMatrix<f64, D, D>,
    det: f64,
    ref_grads: &[[f64; D]; N],
) -> [[f64; D]; N]
where
    SMatrix<f64, D, D>: JacobianMatrix<D>,
{
    jac.inverse_transpose(det, ref_grads)
}

/// Errors of an element's geometry.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum JacobianError<const D: usize> {
    /// The isoparametric Jacobian det(∂x/∂ξ) is not positive at a point: the element is
    /// inverted or degenerate there.
    #[error(
        "non-positive element Jacobian {det:e} at reference point ({})",
        coordinates(xi)
    )]
    NonPositiveJacobian {
        /// det(∂x/∂ξ) found.
        det: f64,
        /// Reference point where it was evaluated.
        xi: [f64; D],
    },
}

/// "a, b, …": a point's coordinates for messages.
fn coordinates(xi: &[f64]) -> String {
    xi.iter().map(f64::to_string).collect::<Vec<_>>().join(", ")
}

/// Geometry of one element of dimension `D` with `N` nodes at the points of a tabulation:
/// what a total-Lagrangian assembly needs, computed once on the reference configuration.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GeometryOf<const D: usize, const N: usize> {
    /// Physical (reference-configuration) point x(ξ_q).
    pub x: Vec<[f64; D]>,
    /// det J(ξ_q) · w_q: the integration weight in physical space.
    pub jxw: Vec<f64>,
    /// Physical gradients ∇ₓNₐ(ξ_q).
    pub grads: Vec<[[f64; D]; N]>,
}

/// Shape values and reference gradients of element `E` tabulated at the points of a rule,
/// so that element loops do no polynomial evaluation.
#[derive(Debug, Clone)]
pub struct Tabulation<E, const D: usize, const N: usize> {
    /// The rule's reference points.
    pub points: Vec<[f64; D]>,
    /// The rule's weights (summing to the reference simplex's measure).
    pub weights: Vec<f64>,
    /// Nₐ(ξ_q) for each point q.
    pub values: Vec<[f64; N]>,
    /// ∇_ξ Nₐ(ξ_q) for each point q.
    pub grads: Vec<[[f64; D]; N]>,
    element: PhantomData<E>,
}

impl<E: Lagrange<D, N>, const D: usize, const N: usize> Tabulation<E, D, N>
where
    SMatrix<f64, D, D>: JacobianMatrix<D>,
{
    /// Tabulates the element's basis at the points of `rule`.
    pub fn new(rule: &Rule<[f64; D]>) -> Self {
        Self {
            points: rule.points.clone(),
            weights: rule.weights.clone(),
            values: rule.points.iter().map(|&p| E::shape(p)).collect(),
            grads: rule.points.iter().map(|&p| E::grad_shape(p)).collect(),
            element: PhantomData,
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True if there are no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Geometry of the element with nodal coordinates `x` at every tabulated point; fails
    /// if det J ≤ 0 at any of them.
    pub fn geometry(&self, x: &[[f64; D]; N]) -> Result<GeometryOf<D, N>, JacobianError<D>> {
        let mut out = GeometryOf::default();
        self.geometry_into(x, &mut out)?;
        Ok(out)
    }

    /// As [`Tabulation::geometry`], reusing the buffers of `out`.
    pub fn geometry_into(
        &self,
        x: &[[f64; D]; N],
        out: &mut GeometryOf<D, N>,
    ) -> Result<(), JacobianError<D>> {
        out.x.clear();
        out.jxw.clear();
        out.grads.clear();
        for q in 0..self.len() {
            let (jac, det) = jacobian(x, &self.grads[q]);
            if det <= 0.0 || !det.is_finite() {
                return Err(JacobianError::NonPositiveJacobian {
                    det,
                    xi: self.points[q],
                });
            }
            out.x.push(interpolate(x, &self.values[q]));
            out.jxw.push(det * self.weights[q]);
            out.grads.push(jac.inverse_transpose(det, &self.grads[q]));
        }
        Ok(())
    }
}

/// A conforming mesh of the cell: nodes, elements of `N` nodes, their domains and the
/// named points on the vertical axis.
pub trait CellMesh<const D: usize, const N: usize>: Clone + Send + Sync {
    /// The element's shape functions on a quadrature rule.
    type Tab: ElementTabulation<D, N>;
    /// What its elements are called in messages.
    const ELEMENTS: &'static str;

    /// Node coordinates (reference configuration, µm).
    fn nodes(&self) -> &[[f64; D]];
    /// Element connectivity.
    fn elements(&self) -> &[[usize; N]];
    /// Domain of each element.
    fn domains(&self) -> &[Domain];
    /// The named points on the vertical axis through the centre.
    fn points(&self) -> &NamedPoints;

    /// Indices of the elements of domain `d`.
    fn elements_of(&self, d: Domain) -> Vec<usize> {
        (0..self.elements().len())
            .filter(|&e| self.domains()[e] == d)
            .collect()
    }

    /// Whether each node belongs to an element of domain `d` (nodes on an interface belong
    /// to both sides).
    fn nodes_of_domain(&self, d: Domain) -> Vec<bool> {
        let mut on = vec![false; self.nodes().len()];
        for (el, &dom) in self.elements().iter().zip(self.domains()) {
            if dom == d {
                for &i in el {
                    on[i] = true;
                }
            }
        }
        on
    }

    /// The nodes of element `e`'s corners and mid-nodes, in its order.
    fn element_coords(&self, e: usize) -> [[f64; D]; N] {
        self.elements()[e].map(|i| self.nodes()[i])
    }

    /// Minimum and maximum of det J over element `e`, and where the minimum is (reference
    /// coordinates).
    fn jacobian_range(&self, e: usize) -> (f64, f64, [f64; D]);

    /// Fails with the first element whose det J is not positive everywhere it is checked.
    fn check_jacobians(&self) -> Result<(), MeshError> {
        for element in 0..self.elements().len() {
            let (det, _, at) = self.jacobian_range(element);
            if det <= 0.0 || det.is_nan() {
                let xi = at.to_vec();
                return Err(MeshError::NonPositiveJacobian { element, det, xi });
            }
        }
        Ok(())
    }
}

/// The smallest and largest of `f` over `points` (NaN counts as the smallest), and where
/// the smallest is.
pub(crate) fn extremes<P: Copy + Default>(
    points: impl IntoIterator<Item = P>,
    f: impl Fn(P) -> f64,
) -> (f64, f64, P) {
    let (mut min, mut max, mut at) = (f64::INFINITY, f64::NEG_INFINITY, P::default());
    for p in points {
        let v = f(p);
        if v < min || v.is_nan() {
            (min, at) = (v, p);
        }
        max = max.max(v);
    }
    (min, max, at)
}

/// The [`CellMesh`] of a mesh type with the fields `nodes`, `elements`, `domains`, `points`.
macro_rules! cell_mesh {
    ($mesh:ty, $d:literal, $n:literal, $tab:ty, $elements:literal) => {
        impl CellMesh<$d, $n> for $mesh {
            type Tab = $tab;
            const ELEMENTS: &'static str = $elements;
            fn nodes(&self) -> &[[f64; $d]] {
                &self.nodes
            }
            fn elements(&self) -> &[[usize; $n]] {
                &self.elements
            }
            fn domains(&self) -> &[Domain] {
                &self.domains
            }
            fn points(&self) -> &NamedPoints {
                &self.points
            }
            fn jacobian_range(&self, e: usize) -> (f64, f64, [f64; $d]) {
                <$mesh>::jacobian_range(self, e)
            }
        }
    };
}

cell_mesh!(Mesh, 2, 6, P2Tabulation, "triangles");
cell_mesh!(TetMesh, 3, 10, TetTabulation, "tetrahedra");

/// An element whose reference geometry is not valid: inverted or degenerate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementGeometryError {
    /// A six-node triangle's.
    #[error(transparent)]
    Triangle(#[from] JacobianError<2>),
    /// A ten-node tetrahedron's.
    #[error(transparent)]
    Tetrahedron(#[from] JacobianError<3>),
}

/// The element's shape functions tabulated at the points of a quadrature rule, and the
/// geometry of an element at those points.
pub trait ElementTabulation<const D: usize, const N: usize>: Send + Sync {
    /// The tabulation on the element's rule exact to `degree`, subdivided `levels` times
    /// (4 sub-triangles or 8 sub-tetrahedra per level).
    fn on_rule(degree: usize, levels: u32) -> Self;
    /// Shape-function values at each point.
    fn values(&self) -> &[[f64; N]];
    /// Number of points.
    fn len(&self) -> usize {
        self.values().len()
    }
    /// Whether the rule has no points.
    fn is_empty(&self) -> bool {
        self.values().is_empty()
    }
    /// Positions, weights times the Jacobian, and physical gradients at the points, for
    /// the element with nodes `x`.
    fn element_geometry(&self, x: &[[f64; D]; N])
    -> Result<GeometryOf<D, N>, ElementGeometryError>;
    /// Whether the element with reference nodes `xr` and current nodes `x` is certainly
    /// not folded anywhere: its current map's det ∂x/∂ξ has the sign of the reference
    /// map's (at its centroid) at every point, not only at a rule's points. A sufficient
    /// test, cheap next to a dense rule: ∂x/∂ξ of a quadratic element is linear in ξ, the
    /// interpolation J = Σ_v λ_v J_v of its values at the D + 1 vertices, so det J is a
    /// polynomial of degree D in the barycentric coordinates; by multilinearity in the
    /// columns its Bernstein coefficients are b_α = (α!/D!) Σ det[J_{s₁}e₁ … J_{s_D}e_D]
    /// over the sequences s whose multiset of vertices is α, and det J lies between the
    /// smallest and the largest of them on the element. All of the reference's sign: not
    /// folded. False means "not shown", not "folded".
    fn unfolded_throughout(xr: &[[f64; D]; N], x: &[[f64; D]; N]) -> bool;
}

impl<E: Lagrange<D, N>, const D: usize, const N: usize> ElementTabulation<D, N>
    for Tabulation<E, D, N>
where
    SMatrix<f64, D, D>: JacobianMatrix<D>,
    ElementGeometryError: From<JacobianError<D>>,
{
    fn on_rule(degree: usize, levels: u32) -> Self {
        let rule = E::RULE(degree);
        Self::new(&if levels == 0 {
            rule
        } else {
            E::SUBDIVIDED(&rule, levels)
        })
    }
    fn values(&self) -> &[[f64; N]] {
        &self.values
    }
    fn element_geometry(
        &self,
        x: &[[f64; D]; N],
    ) -> Result<GeometryOf<D, N>, ElementGeometryError> {
        Ok(self.geometry(x)?)
    }
    fn unfolded_throughout(xr: &[[f64; D]; N], x: &[[f64; D]; N]) -> bool {
        let vertex = |v: usize| -> [f64; D] { std::array::from_fn(|k| f64::from(v == k + 1)) };
        let js: Vec<SMatrix<f64, D, D>> = (0..=D)
            .map(|v| jacobian(x, &E::grad_shape(vertex(v))).0)
            .collect();
        let sign = jacobian(xr, &E::grad_shape([1.0 / (D + 1) as f64; D])).1;
        // Σ of the mixed determinants per multiset α of vertices (α as counts per vertex).
        let mut sums: Vec<([u8; 4], f64)> = Vec::with_capacity(20);
        for code in 0..(D + 1).pow(D as u32) {
            let mut counts = [0u8; 4];
            let mut seq = [0usize; D];
            let mut c = code;
            for s in seq.iter_mut() {
                *s = c % (D + 1);
                c /= D + 1;
                counts[*s] += 1;
            }
            let m = SMatrix::<f64, D, D>::from_fn(|i, col| js[seq[col]][(i, col)]);
            let d = m.det();
            match sums.iter_mut().find(|(a, _)| *a == counts) {
                Some((_, s)) => *s += d,
                None => sums.push((counts, d)),
            }
        }
        let factorial = |n: u8| (1..=u32::from(n)).product::<u32>() as f64;
        let d_fact = factorial(D as u8);
        sums.iter().all(|(alpha, sum)| {
            let b = sum * alpha.iter().map(|&a| factorial(a)).product::<f64>() / d_fact;
            b * sign > 0.0
        })
    }
}

/// Checks every Lagrange element passes, written once for the triangle and the
/// tetrahedron: `nodes` are the reference nodes, `points` sample points, `x` a curved
/// element.
#[cfg(test)]
pub(crate) mod checks {
    use super::{JacobianMatrix, Lagrange};
    use nalgebra::SMatrix;

    /// Every check below, for the element with reference nodes `nodes`, a curved physical
    /// element `x` and sample `points`.
    pub fn shape_functions_and_map<E: Lagrange<D, N>, const D: usize, const N: usize>(
        nodes: &[[f64; D]; N],
        x: &[[f64; D]; N],
        points: &[[f64; D]],
    ) where
        SMatrix<f64, D, D>: JacobianMatrix<D>,
    {
        partition_of_unity::<E, D, N>(points);
        kronecker::<E, D, N>(nodes);
        gradients_are_derivatives::<E, D, N>(points);
        map_interpolates_and_jacobian::<E, D, N>(nodes, x, points);
    }

    /// The six nodes of the straight quadratic triangle with vertices `v` (in the plane or
    /// in space): the vertices, then the midpoints of edges 0–1, 1–2, 2–0.
    pub fn straight_triangle<const D: usize>(v: [[f64; D]; 3]) -> [[f64; D]; 6] {
        let mid = |a: usize, b: usize| std::array::from_fn(|i| 0.5 * (v[a][i] + v[b][i]));
        [v[0], v[1], v[2], mid(0, 1), mid(1, 2), mid(2, 0)]
    }

    /// The sufficient test of [`super::ElementTabulation::unfolded_throughout`] on the
    /// element with reference nodes `xr`: the element itself passes; moving one mid-node
    /// far across its element folds the map (det ∂x/∂ξ of both signs on a fine sample of
    /// `points`) and the test does not pass; and over random moves of the nodes by up to
    /// `amplitude`, wherever the test passes det ∂x/∂ξ has the reference's sign at every
    /// sample point (the test is sufficient), and it passes for most small moves (it is
    /// useful).
    pub fn unfolded_test_is_sufficient<E: Lagrange<D, N>, const D: usize, const N: usize>(
        xr: &[[f64; D]; N],
        points: &[[f64; D]],
    ) where
        SMatrix<f64, D, D>: JacobianMatrix<D>,
        super::Tabulation<E, D, N>: super::ElementTabulation<D, N>,
    {
        use super::{ElementTabulation, Tabulation};
        let passes = |x: &[[f64; D]; N]| Tabulation::<E, D, N>::unfolded_throughout(xr, x);
        let dets =
            |x: &[[f64; D]; N]| -> Vec<f64> { points.iter().map(|&xi| E::map(x, xi).2).collect() };
        let sign = E::map(xr, [1.0 / (D + 1) as f64; D]).2.signum();
        assert!(passes(xr));
        // Mid-node D + 1 (edge 0–1) pushed across the element, beyond the opposite vertex.
        let mut folded = *xr;
        let far = if D == 2 { 2 } else { 3 };
        folded[D + 1] = std::array::from_fn(|k| 2.5 * xr[far][k] - 1.5 * xr[D + 1][k]);
        let d = dets(&folded);
        assert!(d.iter().any(|j| j * sign > 0.0) && d.iter().any(|j| j * sign < 0.0));
        assert!(!passes(&folded));
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        let mut rnd = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for amplitude in [0.05, 0.2, 0.5, 1.0] {
            let mut passed = 0;
            for _ in 0..400 {
                let x: [[f64; D]; N] =
                    std::array::from_fn(|a| std::array::from_fn(|k| xr[a][k] + amplitude * rnd()));
                if passes(&x) {
                    passed += 1;
                    assert!(dets(&x).iter().all(|j| j * sign > 0.0), "{x:?}");
                }
            }
            if amplitude == 0.05 {
                assert!(passed > 300, "{passed} of 400 small moves shown unfolded");
            }
        }
    }

    /// Σ Nₐ = 1 and Σ ∇Nₐ = 0.
    pub fn partition_of_unity<E: Lagrange<D, N>, const D: usize, const N: usize>(
        points: &[[f64; D]],
    ) {
        for &xi in points {
            let n = E::shape(xi);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            let g = E::grad_shape(xi);
            for j in 0..D {
                assert!(g.iter().map(|ga| ga[j]).sum::<f64>().abs() < 1e-13);
            }
        }
    }

    /// Nₐ(node b) = δₐᵦ.
    pub fn kronecker<E: Lagrange<D, N>, const D: usize, const N: usize>(nodes: &[[f64; D]; N]) {
        for (b, xi) in nodes.iter().enumerate() {
            let n = E::shape(*xi);
            for (a, na) in n.iter().enumerate() {
                let expect = if a == b { 1.0 } else { 0.0 };
                assert!((na - expect).abs() < 1e-15, "N{a} at node {b} = {na}");
            }
        }
    }

    /// The reference gradients are the central differences of the shape functions.
    pub fn gradients_are_derivatives<E: Lagrange<D, N>, const D: usize, const N: usize>(
        points: &[[f64; D]],
    ) {
        let h = 1e-6;
        for &xi in points {
            let g = E::grad_shape(xi);
            for j in 0..D {
                let (mut p, mut m) = (xi, xi);
                p[j] += h;
                m[j] -= h;
                let (np, nm) = (E::shape(p), E::shape(m));
                for a in 0..N {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!(
                        (fd - g[a][j]).abs() < 1e-8,
                        "a={a} j={j}: {fd} vs {}",
                        g[a][j]
                    );
                }
            }
        }
    }

    /// At ξ on the element with nodes `x`: the point x(ξ), J, and the interpolant of the
    /// nodal values `nodal` with its physical gradient.
    #[allow(clippy::type_complexity)]
    pub fn interpolant<E: Lagrange<D, N>, const D: usize, const N: usize>(
        x: &[[f64; D]; N],
        nodal: &[f64],
        xi: [f64; D],
    ) -> ([f64; D], SMatrix<f64, D, D>, f64, [f64; D])
    where
        SMatrix<f64, D, D>: JacobianMatrix<D>,
    {
        let (p, jac, det) = E::map(x, xi);
        let n = E::shape(xi);
        let g = jac.inverse_transpose(det, &E::grad_shape(xi));
        let val = (0..N).map(|a| n[a] * nodal[a]).sum();
        let grad = std::array::from_fn(|i| (0..N).map(|a| g[a][i] * nodal[a]).sum());
        (p, jac, val, grad)
    }

    /// The field `c₀ + c · x`, linear in the physical coordinates, is interpolated
    /// exactly, with its gradient `c`, at the `points` of the (curved) element `x`.
    pub fn linear_fields_exact<E: Lagrange<D, N>, const D: usize, const N: usize>(
        x: &[[f64; D]; N],
        points: &[[f64; D]],
        c0: f64,
        c: [f64; D],
    ) where
        SMatrix<f64, D, D>: JacobianMatrix<D>,
    {
        let f = |p: [f64; D]| c0 + (0..D).map(|i| c[i] * p[i]).sum::<f64>();
        let nodal = x.map(f);
        for &xi in points {
            let (p, _, val, grad) = interpolant::<E, D, N>(x, &nodal, xi);
            assert!((val - f(p)).abs() < 1e-13);
            for i in 0..D {
                assert!((grad[i] - c[i]).abs() < 1e-12, "{} vs {}", grad[i], c[i]);
            }
        }
    }

    /// The map interpolates the nodes, and J is the central difference of the map.
    pub fn map_interpolates_and_jacobian<E: Lagrange<D, N>, const D: usize, const N: usize>(
        nodes: &[[f64; D]; N],
        x: &[[f64; D]; N],
        points: &[[f64; D]],
    ) where
        SMatrix<f64, D, D>: JacobianMatrix<D>,
    {
        for (a, xi) in nodes.iter().enumerate() {
            let (p, _, _) = E::map(x, *xi);
            for i in 0..D {
                assert!((p[i] - x[a][i]).abs() < 1e-15);
            }
        }
        let h = 1e-6;
        for &xi in points {
            let (_, jac, det) = E::map(x, xi);
            assert!(det > 0.0);
            for j in 0..D {
                let (mut p, mut m) = (xi, xi);
                p[j] += h;
                m[j] -= h;
                let (xp, _, _) = E::map(x, p);
                let (xm, _, _) = E::map(x, m);
                for i in 0..D {
                    let fd = (xp[i] - xm[i]) / (2.0 * h);
                    assert!((fd - jac[(i, j)]).abs() < 1e-8);
                }
            }
        }
    }
}
