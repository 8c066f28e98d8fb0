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

use super::element::{GeometryOf, JacobianError, Lagrange, Tabulation};
pub use super::element::{jacobian, physical_gradients};
use super::quadrature::TriangleRule;

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

/// The six-node triangle, as a [`Lagrange`] element.
#[derive(Debug, Clone, Copy)]
pub struct Tri6;

/// Errors of the triangle's geometry.
pub type P2Error = JacobianError<2>;

impl Lagrange<2, 6> for Tri6 {
    const EDGES: &'static [[usize; 2]] = &[[0, 1], [1, 2], [2, 0]];
    const RULE: fn(usize) -> TriangleRule = TriangleRule::degree;
    const SUBDIVIDED: fn(&TriangleRule, u32) -> TriangleRule = TriangleRule::subdivided;
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

/// Shape values and reference gradients tabulated at the points of a triangle rule.
pub type P2Tabulation = Tabulation<Tri6, 2, 6>;

/// Geometry of one six-node triangle at the points of a [`P2Tabulation`].
pub type ElementGeometry = GeometryOf<2, 6>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fem::element::checks;

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

    #[test]
    fn shape_functions_and_map() {
        let points = sample_points();
        checks::shape_functions_and_map::<Tri6, 2, 6>(&REFERENCE_NODES, &curved(), &points);
        checks::unfolded_test_is_sufficient::<Tri6, 2, 6>(&curved(), &points);
        for (b, s) in [0.0, 0.5, 1.0].iter().enumerate() {
            let n = edge_shape(*s);
            for (a, na) in n.iter().enumerate() {
                assert!((na - if a == b { 1.0 } else { 0.0 }).abs() < 1e-15);
            }
        }
        let h = 1e-6;
        for s in [0.0, 0.2, 0.5, 0.9] {
            let d = edge_grad_shape(s);
            let (p, m) = (edge_shape(s + h), edge_shape(s - h));
            for a in 0..3 {
                assert!(((p[a] - m[a]) / (2.0 * h) - d[a]).abs() < 1e-8);
            }
        }
    }

    fn sample_points() -> Vec<[f64; 2]> {
        let mut pts = REFERENCE_NODES.to_vec();
        pts.extend(TriangleRule::degree(6).points);
        pts.push([0.1, 0.7]);
        pts
    }

    /// Isoparametric completeness: on a curved element the P2 space contains every field
    /// that is linear in the physical coordinates (x itself is interpolated), with exact
    /// physical gradients. A physical quadratic is *not* in the space of a curved element
    /// (x² is quartic in ξ there); quadratics are checked on straight-sided elements and as
    /// fields quadratic in ξ below.
    #[test]
    fn linear_physical_fields_exact_on_curved_element() {
        checks::linear_fields_exact::<Tri6, 2, 6>(&curved(), &sample_points(), 0.7, [-1.3, 2.1]);
    }

    #[test]
    fn quadratic_fields_exact_on_straight_element() {
        let v = [[0.2, -0.1], [1.7, 0.4], [0.5, 1.3]];
        let x = checks::straight_triangle(v);
        let f = |p: [f64; 2]| {
            1.0 + p[0] - 2.0 * p[1] + 3.0 * p[0] * p[0] - p[0] * p[1] + 0.5 * p[1] * p[1]
        };
        let grad = |p: [f64; 2]| [1.0 + 6.0 * p[0] - p[1], -2.0 - p[0] + p[1]];
        let nodal = x.map(f);
        for xi in sample_points() {
            let (p, _, val, g) = checks::interpolant::<Tri6, 2, 6>(&x, &nodal, xi);
            let ge = grad(p);
            assert!((val - f(p)).abs() < 1e-12);
            assert!((g[0] - ge[0]).abs() < 1e-11 && (g[1] - ge[1]).abs() < 1e-11);
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
        let nodal = REFERENCE_NODES.map(q);
        for xi in sample_points() {
            let (_, jac, val, g) = checks::interpolant::<Tri6, 2, 6>(&x, &nodal, xi);
            assert!((val - q(xi)).abs() < 1e-13);
            let d = dq(xi);
            let inv_t = jac.try_inverse().expect("regular Jacobian").transpose();
            let expect = [
                inv_t[(0, 0)] * d[0] + inv_t[(0, 1)] * d[1],
                inv_t[(1, 0)] * d[0] + inv_t[(1, 1)] * d[1],
            ];
            assert!((g[0] - expect[0]).abs() < 1e-12 && (g[1] - expect[1]).abs() < 1e-12);
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
        let tab = crate::fem::EdgeRule::degree(20).subdivided(3);
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
