//! Six-node quadratic triangle (P2), isoparametric, and the three-node quadratic edge.
//!
//! Reference triangle T̂ = {(ξ, η): ξ, η ≥ 0, ξ + η ≤ 1}, barycentric coordinates
//! λ₀ = 1 − ξ − η, λ₁ = ξ, λ₂ = η. Local nodes: 0, 1, 2 the vertices (counter-clockwise),
//! 3 = mid(0,1), 4 = mid(1,2), 5 = mid(2,0):
//!
//! ```text
//!   2
//!   | \
//!   5   4
//!   |     \
//!   0 --3-- 1
//! ```
//!
//! Shape functions Nᵢ = λᵢ(2λᵢ − 1) at vertices and N₃ = 4λ₀λ₁, N₄ = 4λ₁λ₂, N₅ = 4λ₂λ₀ at
//! mid-sides. The element map is x(ξ) = Σ Nₐ(ξ) xₐ; when a mid-node is not the midpoint of
//! its edge (e.g. it lies on a circle), the edge is a parabola through the three nodes.

use nalgebra::Matrix2;
use thiserror::Error;

use super::quadrature::{EdgeRule, TriangleRule};

/// Reference coordinates (ξ, η) of the six local nodes.
pub const REFERENCE_NODES: [[f64; 2]; 6] = [
    [0.0, 0.0],
    [1.0, 0.0],
    [0.0, 1.0],
    [0.5, 0.0],
    [0.5, 0.5],
    [0.0, 0.5],
];

/// Local node triples (vertex, mid-node, vertex) of the three edges, each running
/// counter-clockwise around the element: edge k goes from vertex k to vertex (k + 1) mod 3.
pub const EDGES: [[usize; 3]; 3] = [[0, 3, 1], [1, 4, 2], [2, 5, 0]];

/// Errors of the element geometry.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum P2Error {
    /// The isoparametric Jacobian det(∂x/∂ξ) is not positive at a point: the element is
    /// inverted or degenerate there.
    #[error("non-positive element Jacobian {det:e} at reference point ({}, {})", xi[0], xi[1])]
    NonPositiveJacobian {
        /// det(∂x/∂ξ) found.
        det: f64,
        /// Reference point where it was evaluated.
        xi: [f64; 2],
    },
}

/// Shape function values N₀ … N₅ at reference point ξ = (ξ, η).
#[inline]
pub fn shape(xi: [f64; 2]) -> [f64; 6] {
    let l1 = xi[0];
    let l2 = xi[1];
    let l0 = 1.0 - l1 - l2;
    [
        l0 * (2.0 * l0 - 1.0),
        l1 * (2.0 * l1 - 1.0),
        l2 * (2.0 * l2 - 1.0),
        4.0 * l0 * l1,
        4.0 * l1 * l2,
        4.0 * l2 * l0,
    ]
}

/// Reference gradients (∂Nₐ/∂ξ, ∂Nₐ/∂η) at ξ; they sum to zero over a.
#[inline]
pub fn grad_shape(xi: [f64; 2]) -> [[f64; 2]; 6] {
    let l1 = xi[0];
    let l2 = xi[1];
    let l0 = 1.0 - l1 - l2;
    // ∂λ₀ = (−1, −1), ∂λ₁ = (1, 0), ∂λ₂ = (0, 1).
    let d0 = 1.0 - 4.0 * l0; // d/dλ₀ of λ₀(2λ₀ − 1) is 4λ₀ − 1, times ∂λ₀ = −1
    [
        [d0, d0],
        [4.0 * l1 - 1.0, 0.0],
        [0.0, 4.0 * l2 - 1.0],
        [4.0 * (l0 - l1), -4.0 * l1],
        [4.0 * l2, 4.0 * l1],
        [-4.0 * l2, 4.0 * (l0 - l2)],
    ]
}

/// The isoparametric map of an element with nodal coordinates `x` (local order above) at
/// reference point ξ: returns the physical point x(ξ), the Jacobian J = ∂x/∂ξ
/// (J[(i, j)] = ∂xᵢ/∂ξⱼ) and det J.
#[inline]
pub fn map(x: &[[f64; 2]; 6], xi: [f64; 2]) -> ([f64; 2], Matrix2<f64>, f64) {
    let n = shape(xi);
    let g = grad_shape(xi);
    let mut p = [0.0; 2];
    let mut jac = Matrix2::zeros();
    for a in 0..6 {
        for i in 0..2 {
            p[i] += n[a] * x[a][i];
            for j in 0..2 {
                jac[(i, j)] += x[a][i] * g[a][j];
            }
        }
    }
    let det = jac.determinant();
    (p, jac, det)
}

/// Jacobian J = ∂x/∂ξ and its determinant from precomputed reference gradients.
#[inline]
pub fn jacobian(x: &[[f64; 2]; 6], ref_grads: &[[f64; 2]; 6]) -> (Matrix2<f64>, f64) {
    let mut jac = Matrix2::zeros();
    for a in 0..6 {
        for i in 0..2 {
            for j in 0..2 {
                jac[(i, j)] += x[a][i] * ref_grads[a][j];
            }
        }
    }
    let det = jac.determinant();
    (jac, det)
}

/// Physical gradients ∇ₓNₐ = J⁻ᵀ ∇_ξ Nₐ from the Jacobian J, its determinant `det` (must
/// be non-zero; the caller checks its sign) and the reference gradients.
#[inline]
pub fn physical_gradients(
    jac: &Matrix2<f64>,
    det: f64,
    ref_grads: &[[f64; 2]; 6],
) -> [[f64; 2]; 6] {
    // J⁻¹ = adj(J)/det; J⁻ᵀ g = (1/det) [ J₁₁ g₀ − J₁₀ g₁ , −J₀₁ g₀ + J₀₀ g₁ ].
    let inv = 1.0 / det;
    let mut out = [[0.0; 2]; 6];
    for (o, g) in out.iter_mut().zip(ref_grads) {
        o[0] = inv * (jac[(1, 1)] * g[0] - jac[(1, 0)] * g[1]);
        o[1] = inv * (-jac[(0, 1)] * g[0] + jac[(0, 0)] * g[1]);
    }
    out
}

/// Shape functions of the 3-node quadratic edge (vertex a, mid-node m, vertex b) at
/// s ∈ [0, 1] (s = 0 at a, ½ at m, 1 at b): (1 − s)(1 − 2s), 4s(1 − s), s(2s − 1).
#[inline]
pub fn edge_shape(s: f64) -> [f64; 3] {
    [
        (1.0 - s) * (1.0 - 2.0 * s),
        4.0 * s * (1.0 - s),
        s * (2.0 * s - 1.0),
    ]
}

/// Derivatives d/ds of [`edge_shape`].
#[inline]
pub fn edge_grad_shape(s: f64) -> [f64; 3] {
    [4.0 * s - 3.0, 4.0 - 8.0 * s, 4.0 * s - 1.0]
}

/// The map of a quadratic edge with nodes `x` = (a, m, b) at s: the point x(s) and the
/// tangent dx/ds (its length is the line-element factor |dx/ds|).
#[inline]
pub fn edge_map(x: &[[f64; 2]; 3], s: f64) -> ([f64; 2], [f64; 2]) {
    let n = edge_shape(s);
    let d = edge_grad_shape(s);
    let mut p = [0.0; 2];
    let mut t = [0.0; 2];
    for a in 0..3 {
        for i in 0..2 {
            p[i] += n[a] * x[a][i];
            t[i] += d[a] * x[a][i];
        }
    }
    (p, t)
}

/// Shape values and reference gradients tabulated at the points of a triangle rule, so
/// that element loops do no polynomial evaluation.
#[derive(Debug, Clone)]
pub struct P2Tabulation {
    /// The rule's reference points.
    pub points: Vec<[f64; 2]>,
    /// The rule's weights (sum ½).
    pub weights: Vec<f64>,
    /// Nₐ(ξ_q) for each point q.
    pub values: Vec<[f64; 6]>,
    /// ∇_ξ Nₐ(ξ_q) for each point q.
    pub grads: Vec<[[f64; 2]; 6]>,
}

/// Geometry of one element of dimension `D` with `N` nodes at the points of a tabulation:
/// what a total-Lagrangian assembly needs, computed once on the reference configuration.
/// [`ElementGeometry`] is the six-node triangle's, [`super::tet::TetGeometry`] the ten-node
/// tetrahedron's.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GeometryOf<const D: usize, const N: usize> {
    /// Physical (reference-configuration) point x(ξ_q).
    pub x: Vec<[f64; D]>,
    /// det J(ξ_q) · w_q: the integration weight in physical space.
    pub jxw: Vec<f64>,
    /// Physical gradients ∇ₓNₐ(ξ_q).
    pub grads: Vec<[[f64; D]; N]>,
}

/// Geometry of one six-node triangle at the points of a [`P2Tabulation`].
pub type ElementGeometry = GeometryOf<2, 6>;

impl P2Tabulation {
    /// Tabulates the P2 basis at the points of `rule`.
    pub fn new(rule: &TriangleRule) -> Self {
        Self {
            points: rule.points.clone(),
            weights: rule.weights.clone(),
            values: rule.points.iter().map(|&p| shape(p)).collect(),
            grads: rule.points.iter().map(|&p| grad_shape(p)).collect(),
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
    pub fn geometry(&self, x: &[[f64; 2]; 6]) -> Result<ElementGeometry, P2Error> {
        let mut out = ElementGeometry::default();
        self.geometry_into(x, &mut out)?;
        Ok(out)
    }

    /// As [`P2Tabulation::geometry`], reusing the buffers of `out`.
    pub fn geometry_into(
        &self,
        x: &[[f64; 2]; 6],
        out: &mut ElementGeometry,
    ) -> Result<(), P2Error> {
        out.x.clear();
        out.jxw.clear();
        out.grads.clear();
        for q in 0..self.len() {
            let (jac, det) = jacobian(x, &self.grads[q]);
            if det <= 0.0 || !det.is_finite() {
                return Err(P2Error::NonPositiveJacobian {
                    det,
                    xi: self.points[q],
                });
            }
            let n = &self.values[q];
            let mut p = [0.0; 2];
            for a in 0..6 {
                p[0] += n[a] * x[a][0];
                p[1] += n[a] * x[a][1];
            }
            out.x.push(p);
            out.jxw.push(det * self.weights[q]);
            out.grads
                .push(physical_gradients(&jac, det, &self.grads[q]));
        }
        Ok(())
    }
}

/// Edge shape values and derivatives tabulated at the points of an edge rule.
#[derive(Debug, Clone)]
pub struct EdgeTabulation {
    /// The rule's points s_q ∈ (0, 1).
    pub points: Vec<f64>,
    /// The rule's weights (sum 1).
    pub weights: Vec<f64>,
    /// Edge shape values at each point.
    pub values: Vec<[f64; 3]>,
    /// d/ds of the edge shape functions at each point.
    pub derivs: Vec<[f64; 3]>,
}

impl EdgeTabulation {
    /// Tabulates the 3-node edge basis at the points of `rule`.
    pub fn new(rule: &EdgeRule) -> Self {
        Self {
            points: rule.points.clone(),
            weights: rule.weights.clone(),
            values: rule.points.iter().map(|&s| edge_shape(s)).collect(),
            derivs: rule.points.iter().map(|&s| edge_grad_shape(s)).collect(),
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A curved element: vertices (0,0), (2,0.2), (0.3,1.5) with the mid-node of edge 1–2
    /// pushed outward (as on a circle) and the mid-node of edge 0–1 pulled inward.
    fn curved() -> [[f64; 2]; 6] {
        let v = [[0.0, 0.0], [2.0, 0.2], [0.3, 1.5]];
        let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let m01 = mid(v[0], v[1]);
        let m12 = mid(v[1], v[2]);
        let m20 = mid(v[2], v[0]);
        [
            v[0],
            v[1],
            v[2],
            [m01[0] - 0.02, m01[1] + 0.08],
            [m12[0] + 0.12, m12[1] + 0.1],
            m20,
        ]
    }

    fn sample_points() -> Vec<[f64; 2]> {
        let mut pts = REFERENCE_NODES.to_vec();
        pts.extend(TriangleRule::degree(6).points);
        pts.push([0.1, 0.7]);
        pts
    }

    #[test]
    fn partition_of_unity_and_zero_gradient_sum() {
        for xi in sample_points() {
            let n = shape(xi);
            assert!((n.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            let g = grad_shape(xi);
            for j in 0..2 {
                assert!(g.iter().map(|ga| ga[j]).sum::<f64>().abs() < 1e-13);
            }
        }
    }

    #[test]
    fn kronecker_property_at_nodes() {
        for (b, xi) in REFERENCE_NODES.iter().enumerate() {
            let n = shape(*xi);
            for (a, na) in n.iter().enumerate() {
                let expect = if a == b { 1.0 } else { 0.0 };
                assert!((na - expect).abs() < 1e-15, "N{a} at node {b} = {na}");
            }
        }
        for (b, s) in [0.0, 0.5, 1.0].iter().enumerate() {
            let n = edge_shape(*s);
            for (a, na) in n.iter().enumerate() {
                assert!((na - if a == b { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn reference_gradients_match_finite_differences() {
        let h = 1e-6;
        for xi in sample_points() {
            let g = grad_shape(xi);
            for j in 0..2 {
                let mut p = xi;
                let mut m = xi;
                p[j] += h;
                m[j] -= h;
                let (np, nm) = (shape(p), shape(m));
                for a in 0..6 {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!((fd - g[a][j]).abs() < 1e-8, "a={a} j={j}");
                }
            }
        }
        for s in [0.0, 0.2, 0.5, 0.9] {
            let d = edge_grad_shape(s);
            let (p, m) = (edge_shape(s + h), edge_shape(s - h));
            for a in 0..3 {
                assert!(((p[a] - m[a]) / (2.0 * h) - d[a]).abs() < 1e-8);
            }
        }
    }

    #[test]
    fn map_interpolates_nodes_and_jacobian_matches_finite_differences() {
        let x = curved();
        for (a, xi) in REFERENCE_NODES.iter().enumerate() {
            let (p, _, _) = map(&x, *xi);
            assert!((p[0] - x[a][0]).abs() < 1e-15 && (p[1] - x[a][1]).abs() < 1e-15);
        }
        let h = 1e-6;
        for xi in sample_points() {
            let (_, jac, det) = map(&x, xi);
            assert!(det > 0.0);
            for j in 0..2 {
                let (mut p, mut m) = (xi, xi);
                p[j] += h;
                m[j] -= h;
                let (xp, _, _) = map(&x, p);
                let (xm, _, _) = map(&x, m);
                for i in 0..2 {
                    let fd = (xp[i] - xm[i]) / (2.0 * h);
                    assert!((fd - jac[(i, j)]).abs() < 1e-8);
                }
            }
        }
    }

    /// Isoparametric completeness: on a curved element the P2 space contains every field
    /// that is linear in the physical coordinates (x itself is interpolated), with exact
    /// physical gradients. A physical quadratic is *not* in the space of a curved element
    /// (x² is quartic in ξ there); quadratics are checked on straight-sided elements and as
    /// fields quadratic in ξ below.
    #[test]
    fn linear_physical_fields_exact_on_curved_element() {
        let x = curved();
        let f = |p: [f64; 2]| 0.7 - 1.3 * p[0] + 2.1 * p[1];
        let nodal: Vec<f64> = x.iter().map(|p| f(*p)).collect();
        for xi in sample_points() {
            let (p, jac, det) = map(&x, xi);
            let n = shape(xi);
            let g = physical_gradients(&jac, det, &grad_shape(xi));
            let val: f64 = (0..6).map(|a| n[a] * nodal[a]).sum();
            let gx: f64 = (0..6).map(|a| g[a][0] * nodal[a]).sum();
            let gy: f64 = (0..6).map(|a| g[a][1] * nodal[a]).sum();
            assert!((val - f(p)).abs() < 1e-13);
            assert!((gx + 1.3).abs() < 1e-12 && (gy - 2.1).abs() < 1e-12);
        }
    }

    #[test]
    fn quadratic_fields_exact_on_straight_element() {
        let v = [[0.2, -0.1], [1.7, 0.4], [0.5, 1.3]];
        let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let x = [
            v[0],
            v[1],
            v[2],
            mid(v[0], v[1]),
            mid(v[1], v[2]),
            mid(v[2], v[0]),
        ];
        let f = |p: [f64; 2]| {
            1.0 + p[0] - 2.0 * p[1] + 3.0 * p[0] * p[0] - p[0] * p[1] + 0.5 * p[1] * p[1]
        };
        let grad = |p: [f64; 2]| [1.0 + 6.0 * p[0] - p[1], -2.0 - p[0] + p[1]];
        let nodal: Vec<f64> = x.iter().map(|p| f(*p)).collect();
        for xi in sample_points() {
            let (p, jac, det) = map(&x, xi);
            let n = shape(xi);
            let g = physical_gradients(&jac, det, &grad_shape(xi));
            let val: f64 = (0..6).map(|a| n[a] * nodal[a]).sum();
            let gx: f64 = (0..6).map(|a| g[a][0] * nodal[a]).sum();
            let gy: f64 = (0..6).map(|a| g[a][1] * nodal[a]).sum();
            let ge = grad(p);
            assert!((val - f(p)).abs() < 1e-12);
            assert!((gx - ge[0]).abs() < 1e-11 && (gy - ge[1]).abs() < 1e-11);
        }
    }

    /// On the curved element a field quadratic in ξ, φ(ξ, η) = q(ξ, η), is reproduced
    /// exactly, and its physical gradient is J⁻ᵀ ∇_ξ q (chain rule).
    #[test]
    fn reference_quadratics_exact_with_chain_rule_gradients_on_curved_element() {
        let x = curved();
        let q = |s: [f64; 2]| {
            0.3 - s[0] + 2.0 * s[1] + 1.5 * s[0] * s[0] - 0.7 * s[0] * s[1] + 0.9 * s[1] * s[1]
        };
        let dq = |s: [f64; 2]| {
            [
                -1.0 + 3.0 * s[0] - 0.7 * s[1],
                2.0 - 0.7 * s[0] + 1.8 * s[1],
            ]
        };
        let nodal: Vec<f64> = REFERENCE_NODES.iter().map(|s| q(*s)).collect();
        for xi in sample_points() {
            let (_, jac, det) = map(&x, xi);
            let n = shape(xi);
            let g = physical_gradients(&jac, det, &grad_shape(xi));
            let val: f64 = (0..6).map(|a| n[a] * nodal[a]).sum();
            assert!((val - q(xi)).abs() < 1e-13);
            let d = dq(xi);
            let inv_t = jac.try_inverse().expect("regular Jacobian").transpose();
            let expect = [
                inv_t[(0, 0)] * d[0] + inv_t[(0, 1)] * d[1],
                inv_t[(1, 0)] * d[0] + inv_t[(1, 1)] * d[1],
            ];
            let gx: f64 = (0..6).map(|k| g[k][0] * nodal[k]).sum();
            let gy: f64 = (0..6).map(|k| g[k][1] * nodal[k]).sum();
            assert!((gx - expect[0]).abs() < 1e-12 && (gy - expect[1]).abs() < 1e-12);
        }
    }

    #[test]
    fn tabulated_geometry_integrates_area_of_curved_element() {
        // Area of a P2 element = straight triangle area + Σ (2/3)·chord·(signed offset of
        // the mid-node from the chord midpoint, along the outward normal), for mid-nodes
        // displaced normally; here an arbitrary displacement: the offset's normal part.
        let x = curved();
        let tri = 0.5
            * ((x[1][0] - x[0][0]) * (x[2][1] - x[0][1])
                - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]));
        let mut area = tri;
        for e in EDGES {
            let (a, m, b) = (x[e[0]], x[e[1]], x[e[2]]);
            let t = [b[0] - a[0], b[1] - a[1]];
            // Outward normal of a CCW edge, scaled by the chord length: (t_y, −t_x).
            let n = [t[1], -t[0]];
            let off = [m[0] - (a[0] + b[0]) / 2.0, m[1] - (a[1] + b[1]) / 2.0];
            // ∫ over the parabolic cap: (2/3) · chord · normal offset = (2/3)(off · n).
            area += 2.0 / 3.0 * (off[0] * n[0] + off[1] * n[1]);
        }
        let tab = P2Tabulation::new(&TriangleRule::degree(2));
        let geo = tab.geometry(&x).expect("valid element");
        let integral: f64 = geo.jxw.iter().sum();
        assert!((integral - area).abs() < 1e-14, "{integral} vs {area}");
        // An inverted element is refused.
        let mut bad = x;
        bad.swap(1, 2);
        assert!(matches!(
            tab.geometry(&bad),
            Err(P2Error::NonPositiveJacobian { .. })
        ));
    }

    #[test]
    fn edge_map_length_of_parabolic_arc() {
        // Edge (−1,0), (0,1), (1,0) is the parabola y = 1 − x²; its length is
        // √5 + asinh(2)/2.
        let x = [[-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]];
        let tab = EdgeTabulation::new(&EdgeRule::degree(20).subdivided(3));
        let len: f64 = (0..tab.len())
            .map(|q| {
                let (_, t) = edge_map(&x, tab.points[q]);
                tab.weights[q] * t[0].hypot(t[1])
            })
            .sum();
        let exact = 5f64.sqrt() + 2f64.asinh() / 2.0;
        assert!((len - exact).abs() < 1e-12, "{len} vs {exact}");
        let (p, _) = edge_map(&x, 0.25);
        assert!((p[0] + 0.5).abs() < 1e-15 && (p[1] - 0.75).abs() < 1e-15);
    }
}
