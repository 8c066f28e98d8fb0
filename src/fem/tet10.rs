//! Ten-node quadratic tetrahedron (P2), isoparametric, and the six-node surface triangle
//! in 3-D.
//!
//! Reference tetrahedron T̂ = {(ξ, η, ζ): ξ, η, ζ ≥ 0, ξ + η + ζ ≤ 1}, barycentric
//! coordinates λ₀ = 1 − ξ − η − ζ, λ₁ = ξ, λ₂ = η, λ₃ = ζ. Local nodes in gmsh's order for
//! its element type 11: the vertices 0 … 3 at (0,0,0), (1,0,0), (0,1,0), (0,0,1), then the
//! mid-edge nodes 4 = mid(0,1), 5 = mid(1,2), 6 = mid(0,2), 7 = mid(0,3), 8 = mid(2,3),
//! 9 = mid(1,3) ([`TET_EDGES`]), at the midpoints of those edges in T̂.
//!
//! Shape functions Nᵢ = λᵢ(2λᵢ − 1) at the vertices and N = 4λᵢλⱼ at the mid-node of edge
//! i–j. The element map is x(ξ) = Σ Nₐ(ξ) xₐ: where a mid-node is not its edge's midpoint
//! (on a sphere), the edge is a parabola through its three nodes and the faces are curved.
//! A tetrahedron is positively oriented when (x₁ − x₀) × (x₂ − x₀) · (x₃ − x₀) > 0, which
//! is what gmsh writes; then det J > 0 wherever the map is regular.
//!
//! Faces are six-node triangles in the order of [`super::tri6`] (gmsh type 9: vertices, then
//! mid(0,1), mid(1,2), mid(2,0)); [`TET_FACES`] lists them outward-oriented, face k opposite
//! vertex k. On a surface triangle embedded in 3-D, [`face_map`] gives the point and the
//! area-weighted normal ∂x/∂ξ × ∂x/∂η: ∫_S f dA = ∫_T̂ f |n| dξ and ∫_S f n dA = ∫_T̂ f n dξ.
//!
//! Element geometry at quadrature points is a [`TetGeometry`] = [`GeometryOf<3, 10>`], the
//! 3-D twin of the triangle's [`super::tri6::ElementGeometry`].

use super::element::{GeometryOf, JacobianError, Lagrange, Tabulation};
pub use super::element::{jacobian, physical_gradients};
use super::quadrature::TetRule;
use super::tri6::Tri6;

/// Reference coordinates (ξ, η, ζ) of the ten local nodes.
pub const REFERENCE_NODES: [[f64; 3]; 10] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.5, 0.0, 0.0],
    [0.5, 0.5, 0.0],
    [0.0, 0.5, 0.0],
    [0.0, 0.0, 0.5],
    [0.0, 0.5, 0.5],
    [0.5, 0.0, 0.5],
];

/// The vertex pairs of the six edges; edge k carries local node 4 + k (gmsh's order).
pub const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [0, 2], [0, 3], [2, 3], [1, 3]];

/// The four faces as six-node triangles (vertices, then mid(0,1), mid(1,2), mid(2,0) of the
/// face), face k opposite vertex k, each ordered so that its normal ∂x/∂ξ × ∂x/∂η
/// ([`face_map`]) points out of a positively oriented tetrahedron.
pub const TET_FACES: [[usize; 6]; 4] = [
    [1, 2, 3, 5, 8, 9],
    [0, 3, 2, 7, 8, 6],
    [0, 1, 3, 4, 9, 7],
    [0, 2, 1, 6, 5, 4],
];

/// Local permutation that reverses a tetrahedron's orientation: vertices 1 and 2 swapped,
/// with their mid-nodes (new node a is old node `FLIP[a]`).
pub const FLIP: [usize; 10] = [0, 2, 1, 3, 6, 5, 4, 7, 9, 8];

/// Geometry of one ten-node tetrahedron at the points of a [`TetTabulation`]: points,
/// det J · w and physical gradients.
pub type TetGeometry = GeometryOf<3, 10>;

/// The ten-node tetrahedron, as a [`Lagrange`] element.
#[derive(Debug, Clone, Copy)]
pub struct Tet10;

/// Errors of the tetrahedron's geometry.
pub type TetError = JacobianError<3>;

impl Lagrange<3, 10> for Tet10 {
    const EDGES: &'static [[usize; 2]] = &TET_EDGES;
    const RULE: fn(usize) -> TetRule = TetRule::degree;
    const SUBDIVIDED: fn(&TetRule, u32) -> TetRule = TetRule::subdivided;
}

/// The map of a six-node triangle embedded in 3-D (node order of [`super::tri6`]) at
/// reference point ξ = (ξ, η) of the reference triangle: the point x(ξ) and the
/// area-weighted normal ∂x/∂ξ × ∂x/∂η (its length is the area element: dA = |n| dξ dη).
#[inline]
pub fn face_map(x: &[[f64; 3]; 6], xi: [f64; 2]) -> ([f64; 3], [f64; 3]) {
    let n = Tri6::shape(xi);
    let g = Tri6::grad_shape(xi);
    let mut p = [0.0; 3];
    let mut t = [[0.0; 3]; 2];
    for a in 0..6 {
        for i in 0..3 {
            p[i] += n[a] * x[a][i];
            t[0][i] += g[a][0] * x[a][i];
            t[1][i] += g[a][1] * x[a][i];
        }
    }
    let [u, v] = t;
    let normal = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    (p, normal)
}

/// Shape values and reference gradients tabulated at the points of a tetrahedron rule.
pub type TetTabulation = Tabulation<Tet10, 3, 10>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The local mid-node of the edge between local vertices `i` and `j` (i ≠ j, both < 4).
    fn edge_node(i: usize, j: usize) -> Option<usize> {
        TET_EDGES
            .iter()
            .position(|e| (e[0] == i && e[1] == j) || (e[0] == j && e[1] == i))
            .map(|k| 4 + k)
    }
    use crate::fem::element::checks;

    /// A curved element: an irregular tetrahedron with some mid-nodes moved off their
    /// edges' midpoints (as on a sphere).
    fn curved() -> [[f64; 3]; 10] {
        let v = [
            [0.1, -0.2, 0.0],
            [2.0, 0.2, 0.3],
            [0.3, 1.5, -0.1],
            [0.4, 0.5, 1.7],
        ];
        let mut x = [[0.0; 3]; 10];
        x[..4].copy_from_slice(&v);
        for (k, e) in TET_EDGES.iter().enumerate() {
            x[4 + k] = std::array::from_fn(|i| 0.5 * (v[e[0]][i] + v[e[1]][i]));
        }
        // Bulge edge 1–2 outward, pull edge 0–1 inward a little, lift edge 2–3.
        x[5][0] += 0.12;
        x[5][1] += 0.1;
        x[4][1] += 0.06;
        x[8][2] += 0.08;
        x
    }

    #[test]
    fn shape_functions_and_map() {
        let points = sample_points();
        checks::shape_functions_and_map::<Tet10, 3, 10>(&REFERENCE_NODES, &curved(), &points);
        checks::unfolded_test_is_sufficient::<Tet10, 3, 10>(&curved(), &points);
    }

    fn sample_points() -> Vec<[f64; 3]> {
        let mut pts = REFERENCE_NODES.to_vec();
        pts.extend(TetRule::degree(5).points);
        pts.push([0.1, 0.7, 0.05]);
        pts.push([0.2, 0.1, 0.6]);
        pts
    }

    #[test]
    fn edges_faces_and_flip_are_consistent() {
        for (k, e) in TET_EDGES.iter().enumerate() {
            let m = REFERENCE_NODES[4 + k];
            for i in 0..3 {
                let mid = 0.5 * (REFERENCE_NODES[e[0]][i] + REFERENCE_NODES[e[1]][i]);
                assert_eq!(m[i], mid);
            }
            assert_eq!(edge_node(e[1], e[0]), Some(4 + k));
        }
        assert_eq!(edge_node(2, 2), None);
        for (k, f) in TET_FACES.iter().enumerate() {
            assert!(
                !f[..3].contains(&k),
                "face {k} contains its opposite vertex"
            );
            for s in 0..3 {
                assert_eq!(edge_node(f[s], f[(s + 1) % 3]), Some(f[3 + s]));
            }
        }
        // The flipped reference element has det J = −1 and flipping twice is the identity.
        let flipped: [[f64; 3]; 10] = std::array::from_fn(|a| REFERENCE_NODES[FLIP[a]]);
        let (_, _, det) = Tet10::map(&flipped, [0.2, 0.3, 0.1]);
        assert!((det + 1.0).abs() < 1e-15);
        for a in 0..10 {
            assert_eq!(FLIP[FLIP[a]], a);
        }
        // The flipped node list is a valid node list: mid-node k of the flipped element is
        // the midpoint of its flipped edge.
        for (k, e) in TET_EDGES.iter().enumerate() {
            for i in 0..3 {
                assert_eq!(
                    flipped[4 + k][i],
                    0.5 * (flipped[e[0]][i] + flipped[e[1]][i])
                );
            }
        }
    }

    /// Every quadratic in ξ is reproduced: Σ Nₐ p(Xₐ) = p, with the gradient too.
    #[test]
    fn quadratics_are_reproduced() {
        // The ten monomials 1, ξ, η, ζ, ξ², η², ζ², ξη, ξζ, ηζ, one at a time and combined.
        let monomials: [fn([f64; 3]) -> f64; 10] = [
            |_| 1.0,
            |s| s[0],
            |s| s[1],
            |s| s[2],
            |s| s[0] * s[0],
            |s| s[1] * s[1],
            |s| s[2] * s[2],
            |s| s[0] * s[1],
            |s| s[0] * s[2],
            |s| s[1] * s[2],
        ];
        let h = 1e-6;
        for p in monomials {
            let nodal: Vec<f64> = REFERENCE_NODES.iter().map(|s| p(*s)).collect();
            for xi in sample_points() {
                let n = Tet10::shape(xi);
                let v: f64 = (0..10).map(|a| n[a] * nodal[a]).sum();
                assert!((v - p(xi)).abs() < 1e-14);
                let g = Tet10::grad_shape(xi);
                for j in 0..3 {
                    let gv: f64 = (0..10).map(|a| g[a][j] * nodal[a]).sum();
                    let (mut xp, mut xm) = (xi, xi);
                    xp[j] += h;
                    xm[j] -= h;
                    let fd = (p(xp) - p(xm)) / (2.0 * h);
                    assert!((gv - fd).abs() < 1e-8);
                }
            }
        }
    }

    /// On a curved element the physical gradients are those of the chain rule: J⁻ᵀ ∇_ξ, and
    /// fields linear in the physical coordinates have exact values and gradients.
    #[test]
    fn physical_gradients_invert_the_jacobian_and_linear_fields_are_exact() {
        let x = curved();
        for xi in sample_points() {
            let (_, jac, det) = Tet10::map(&x, xi);
            let rg = Tet10::grad_shape(xi);
            let g = physical_gradients(&jac, det, &rg);
            let inv_t = jac.try_inverse().expect("regular").transpose();
            for a in 0..10 {
                for i in 0..3 {
                    let e: f64 = (0..3).map(|j| inv_t[(i, j)] * rg[a][j]).sum();
                    assert!((g[a][i] - e).abs() < 1e-12);
                }
            }
        }
        let points = sample_points();
        checks::linear_fields_exact::<Tet10, 3, 10>(&x, &points, 0.7, [-1.3, 2.1, -0.4]);
    }

    /// The tabulated geometry integrates the volume of the curved element as the
    /// divergence theorem gives it from the faces: V = ⅓ ∮ x · n dA (the faces of
    /// [`TET_FACES`], outward), and the outward face vectors close: ∮ n dA = 0.
    #[test]
    fn volume_of_curved_element_from_its_faces_and_closed_surface() {
        let x = curved();
        let tab = TetTabulation::new(&TetRule::degree(6));
        let geo = tab.geometry(&x).expect("valid element");
        let vol: f64 = geo.jxw.iter().sum();
        let rule = crate::fem::TriangleRule::degree(8);
        let mut flux = 0.0;
        let mut total = [0.0; 3];
        for f in TET_FACES {
            let xf: [[f64; 3]; 6] = std::array::from_fn(|k| x[f[k]]);
            for (p, w) in rule.points.iter().zip(&rule.weights) {
                let (pt, n) = face_map(&xf, *p);
                flux += w * (pt[0] * n[0] + pt[1] * n[1] + pt[2] * n[2]) / 3.0;
                for i in 0..3 {
                    total[i] += w * n[i];
                }
            }
        }
        assert!((vol - flux).abs() < 1e-14, "{vol} vs {flux}");
        assert!(total.iter().all(|t| t.abs() < 1e-14), "{total:?}");
        // The straight reference element: volume ⅙, faces' normals outward.
        let tab1 = TetTabulation::new(&TetRule::degree(1));
        let g = tab1.geometry(&REFERENCE_NODES).expect("reference");
        assert!((g.jxw[0] - 1.0 / 6.0).abs() < 1e-16);
        let centroid = [0.25; 3];
        for f in TET_FACES {
            let xf: [[f64; 3]; 6] = std::array::from_fn(|k| REFERENCE_NODES[f[k]]);
            let (p, n) = face_map(&xf, [1.0 / 3.0, 1.0 / 3.0]);
            let out: f64 = (0..3).map(|i| (p[i] - centroid[i]) * n[i]).sum();
            assert!(out > 0.0);
        }
        // An inverted element is refused.
        let bad: [[f64; 3]; 10] = std::array::from_fn(|a| x[FLIP[a]]);
        assert!(matches!(
            tab.geometry(&bad),
            Err(TetError::NonPositiveJacobian { .. })
        ));
    }

    #[test]
    fn face_map_area_of_a_flat_triangle_and_a_parabolic_patch() {
        // Flat right triangle with legs 2 and 3 in the plane z = 1: area 3, normal +z.
        let v = [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 3.0, 1.0]];
        let x = checks::straight_triangle(v);
        let rule = crate::fem::TriangleRule::degree(2);
        let mut area = 0.0;
        for (p, w) in rule.points.iter().zip(&rule.weights) {
            let (_, n) = face_map(&x, *p);
            assert!(n[0].abs() < 1e-15 && n[1].abs() < 1e-15 && n[2] > 0.0);
            area += w * n[2];
        }
        assert!((area - 3.0).abs() < 1e-14);
        // A mid-node lifted by δ: the projected area is unchanged, and the graph
        // z = 1 + 4δ ξ(1 − ξ − η)… keeps ∫ n_z = projected area (the z-component of the
        // area vector of any surface over the same boundary).
        let mut y = x;
        y[3][2] += 0.3;
        let nz: f64 = rule
            .points
            .iter()
            .zip(&rule.weights)
            .map(|(p, w)| w * face_map(&y, *p).1[2])
            .sum();
        assert!((nz - 3.0).abs() < 1e-14);
    }
}
