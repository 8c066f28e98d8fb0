//! Quadrature rules: Gauss–Legendre on [0, 1], rules on the reference triangle
//! (0,0), (1,0), (0,1) and on the reference tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1),
//! their sub-divided versions, and 1-D rules on an element edge.
//!
//! Every rule here has positive weights and points strictly inside its domain. Rules are
//! generated (Newton iterations on Legendre polynomials or on moment equations), not
//! copied from tables; the tests check exactness on every monomial of the claimed degree.

use nalgebra::{Matrix4, SMatrix, SVector, Vector4};

/// Gauss–Legendre nodes and weights on [0, 1] with `n` points, exact for polynomials of
/// degree ≤ 2n − 1. The weights sum to 1.
///
/// The nodes are the roots of the Legendre polynomial Pₙ, found by Newton's method from
/// the asymptotic guess cos(π(i − ¼)/(n + ½)) on [−1, 1], then mapped by x ↦ (x + 1)/2;
/// the weight of a root x is 2/((1 − x²) Pₙ′(x)²), halved for [0, 1].
/// `n = 0` gives empty vectors (an integral of zero).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut points = vec![0.0; n];
    let mut weights = vec![0.0; n];
    // Roots come in ± pairs: compute the m = ⌈n/2⌉ non-negative ones.
    let m = n.div_ceil(2);
    for i in 0..m {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut dp = 1.0;
        for _ in 0..100 {
            let (p, d) = legendre_and_derivative(n, x);
            dp = d;
            let dx = p / d;
            x -= dx;
            if dx.abs() <= 1e-16 * x.abs().max(1.0) {
                let (_, d) = legendre_and_derivative(n, x);
                dp = d;
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * dp * dp);
        // Store on [0, 1]: the root +x and its mirror −x.
        points[i] = 0.5 * (1.0 - x);
        points[n - 1 - i] = 0.5 * (1.0 + x);
        weights[i] = 0.5 * w;
        weights[n - 1 - i] = 0.5 * w;
    }
    if n % 2 == 1 {
        // The middle root is exactly 0 on [−1, 1].
        points[m - 1] = 0.5;
    }
    (points, weights)
}

/// Legendre polynomial Pₙ(x) and its derivative, by the three-term recurrence
/// (k + 1) P_{k+1} = (2k + 1) x P_k − k P_{k−1}, and Pₙ′ = n (x Pₙ − P_{n−1}) / (x² − 1).
fn legendre_and_derivative(n: usize, x: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = x;
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 1..n {
        let k = k as f64;
        let p2 = ((2.0 * k + 1.0) * x * p1 - k * p0) / (k + 1.0);
        p0 = p1;
        p1 = p2;
    }
    let d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

/// A quadrature rule ∫ f ≈ Σ_q w_q f(p_q) on a reference domain whose points are `P`:
/// [`TriangleRule`], [`TetRule`], [`EdgeRule`].
#[derive(Debug, Clone, PartialEq)]
pub struct Rule<P> {
    /// Points p_q in reference coordinates, all strictly inside the domain.
    pub points: Vec<P>,
    /// Weights w_q > 0, summing to the domain's measure.
    pub weights: Vec<f64>,
}

impl<P> Rule<P> {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True if the rule has no points.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// A rule's refinement: the rule applied on each sub-domain of a number of regular
/// refinements (e.g. [`TriangleRule::subdivided`]).
pub type Subdivision<P> = fn(&Rule<P>, u32) -> Rule<P>;

/// A quadrature rule on the reference triangle with vertices (0,0), (1,0), (0,1):
/// ∫_T̂ f dξ ≈ Σ_q w_q f(ξ_q), points ξ_q = (ξ, η); the weights sum to the triangle's
/// area ½.
pub type TriangleRule = Rule<[f64; 2]>;

impl TriangleRule {
    /// A rule exact for every polynomial of total degree ≤ `d`.
    ///
    /// | d | rule | points |
    /// |---|---|---|
    /// | 0, 1 | centroid | 1 |
    /// | 2 | symmetric, at barycentric (⅔, ⅙, ⅙) and permutations | 3 |
    /// | 3, 4 | symmetric, two 3-point orbits (a, a, 1 − 2a); coefficients solved from the moment equations by Newton | 6 |
    /// | 5 | Radon's 7-point rule, closed form with √15 | 7 |
    /// | ≥ 6 | collapsed (Duffy) Gauss–Legendre product, ⌈(d + 2)/2⌉ × ⌈(d + 1)/2⌉ | e.g. 36 for d = 10 |
    ///
    /// The collapsed rule maps the unit square onto the triangle by (u, v) ↦ (u, v(1 − u))
    /// with Jacobian (1 − u); the extra factor raises the degree in u by one, hence one more
    /// Gauss point in that direction.
    pub fn degree(d: usize) -> Self {
        match d {
            0 | 1 => Self {
                points: vec![[1.0 / 3.0, 1.0 / 3.0]],
                weights: vec![0.5],
            },
            2 => Self::from_orbits(&[], &[(1.0 / 6.0, 1.0 / 6.0)]),
            3 | 4 => {
                // Solved once per process.
                static ORBITS: std::sync::OnceLock<[f64; 4]> = std::sync::OnceLock::new();
                let [a1, a2, w1, w2] = *ORBITS.get_or_init(degree4_orbits);
                Self::from_orbits(&[], &[(a1, w1), (a2, w2)])
            }
            5 => {
                let s = 15f64.sqrt();
                let a1 = (6.0 - s) / 21.0;
                let a2 = (6.0 + s) / 21.0;
                // Area-normalised weights 9/40, (155 ∓ √15)/1200, times the area ½.
                let w1 = (155.0 - s) / 2400.0;
                let w2 = (155.0 + s) / 2400.0;
                Self::from_orbits(&[9.0 / 80.0], &[(a1, w1), (a2, w2)])
            }
            _ => Self::collapsed_gauss(d.div_ceil(2) + 1, (d + 1).div_ceil(2)),
        }
    }

    /// Builds a fully symmetric rule from a centroid weight (if any) and orbits
    /// S₂₁(a) = {(a, a, 1 − 2a) and its permutations}, each orbit point with weight w.
    fn from_orbits(centroid: &[f64], orbits: &[(f64, f64)]) -> Self {
        let mut points = Vec::new();
        let mut weights = Vec::new();
        for &w in centroid {
            points.push([1.0 / 3.0, 1.0 / 3.0]);
            weights.push(w);
        }
        for &(a, w) in orbits {
            let b = 1.0 - 2.0 * a;
            // Barycentric (λ₀, λ₁, λ₂) with ξ = λ₁, η = λ₂.
            for p in [[a, a], [b, a], [a, b]] {
                points.push(p);
                weights.push(w);
            }
        }
        Self { points, weights }
    }

    /// The collapsed (conical-product) Gauss rule with `nu` points in u and `nv` in v:
    /// ξ = u, η = v(1 − u), weight w_u w_v (1 − u). Exact for degree ≤ min(2nu − 2, 2nv − 1).
    pub fn collapsed_gauss(nu: usize, nv: usize) -> Self {
        let (pu, wu) = gauss_legendre(nu);
        let (pv, wv) = gauss_legendre(nv);
        let mut points = Vec::with_capacity(nu * nv);
        let mut weights = Vec::with_capacity(nu * nv);
        for (u, a) in pu.iter().zip(&wu) {
            for (v, b) in pv.iter().zip(&wv) {
                points.push([*u, v * (1.0 - u)]);
                weights.push(a * b * (1.0 - u));
            }
        }
        Self { points, weights }
    }

    /// This rule applied on each of the 4^`levels` congruent sub-triangles obtained by
    /// halving every edge `levels` times (m = 2^levels sub-intervals per edge): m(m+1)/2
    /// "upright" and m(m−1)/2 "inverted" triangles, each of area 1/(2m²). Same degree of
    /// exactness, with points spread over the whole element: use it where an integrand is
    /// only piecewise smooth, e.g. a thin contact band crossing an element (MODEL.md §9).
    pub fn subdivided(&self, levels: u32) -> Self {
        let m = 1usize << levels;
        let h = 1.0 / m as f64;
        let scale = h * h;
        let mut points = Vec::with_capacity(self.len() * m * m);
        let mut weights = Vec::with_capacity(self.len() * m * m);
        let mut push = |o: [f64; 2], e1: [f64; 2], e2: [f64; 2]| {
            for (p, w) in self.points.iter().zip(&self.weights) {
                points.push([
                    o[0] + p[0] * e1[0] + p[1] * e2[0],
                    o[1] + p[0] * e1[1] + p[1] * e2[1],
                ]);
                weights.push(w * scale);
            }
        };
        for j in 0..m {
            for i in 0..m - j {
                let (x, y) = (i as f64 * h, j as f64 * h);
                push([x, y], [h, 0.0], [0.0, h]);
                if i + j + 1 < m {
                    // Inverted triangle with its right angle at (x + h, y + h).
                    push([x + h, y + h], [-h, 0.0], [0.0, -h]);
                }
            }
        }
        Self { points, weights }
    }
}

/// Orbit parameters (a₁, a₂) and point weights (w₁, w₂) of the 6-point symmetric degree-4
/// rule, solved from the moment equations.
///
/// Every symmetric polynomial of degree ≤ 4 in the barycentric coordinates λᵢ is a
/// combination of the power sums p_k = Σᵢ λᵢᵏ, k = 0, 2, 3, 4 (p₀ = 3, p₁ = 1). On an orbit
/// S₂₁(a) = {(a, a, 1 − 2a) and permutations}, p_k takes the single value
/// p_k(a) = 2aᵏ + (1 − 2a)ᵏ, and ∫_T̂ λ₁ᵏ = k!/(k + 2)!, so the rule is exact to degree 4 iff
///
///   3 w₁ p_k(a₁) + 3 w₂ p_k(a₂) = 3 k!/(k + 2)!,  i.e.  w₁ p_k(a₁) + w₂ p_k(a₂) = 1/((k + 1)(k + 2)),
///
/// for k = 0, 2, 3, 4. Newton from a rough guess converges in a few steps.
fn degree4_orbits() -> [f64; 4] {
    // Unknowns z = (a₁, a₂, w₁, w₂).
    let mut z = Vector4::new(0.45, 0.09, 0.11, 0.055);
    let pk = |a: f64, k: i32| 2.0 * a.powi(k) + (1.0 - 2.0 * a).powi(k);
    let dpk = |a: f64, k: i32| {
        if k == 0 {
            0.0
        } else {
            2.0 * f64::from(k) * (a.powi(k - 1) - (1.0 - 2.0 * a).powi(k - 1))
        }
    };
    for _ in 0..50 {
        let mut r = Vector4::zeros();
        let mut jac = Matrix4::zeros();
        for (row, k) in [0, 2, 3, 4].into_iter().enumerate() {
            r[row] = z[2] * pk(z[0], k) + z[3] * pk(z[1], k) - 1.0 / f64::from((k + 1) * (k + 2));
            jac[(row, 0)] = z[2] * dpk(z[0], k);
            jac[(row, 1)] = z[3] * dpk(z[1], k);
            jac[(row, 2)] = pk(z[0], k);
            jac[(row, 3)] = pk(z[1], k);
        }
        let Some(dz) = jac.lu().solve(&r) else {
            break;
        };
        z -= dz;
        if dz.amax() < 1e-16 {
            break;
        }
    }
    [z[0], z[1], z[2], z[3]]
}

/// A quadrature rule on the unit interval [0, 1] for integrals along an element edge
/// parametrised by s ∈ [0, 1] from its first to its last vertex; the weights sum to 1.
pub type EdgeRule = Rule<f64>;

impl EdgeRule {
    /// Gauss–Legendre rule exact for polynomials of degree ≤ `d` (⌈(d + 1)/2⌉ points, at
    /// least one).
    pub fn degree(d: usize) -> Self {
        let (points, weights) = gauss_legendre((d + 1).div_ceil(2).max(1));
        Self { points, weights }
    }

    /// This rule applied on each of 2^`levels` equal sub-intervals.
    pub fn subdivided(&self, levels: u32) -> Self {
        let m = 1usize << levels;
        let h = 1.0 / m as f64;
        let mut points = Vec::with_capacity(self.len() * m);
        let mut weights = Vec::with_capacity(self.len() * m);
        for i in 0..m {
            for (p, w) in self.points.iter().zip(&self.weights) {
                points.push((i as f64 + p) * h);
                weights.push(w * h);
            }
        }
        Self { points, weights }
    }
}

/// A quadrature rule on the reference tetrahedron with vertices (0,0,0), (1,0,0), (0,1,0),
/// (0,0,1): ∫_T̂ f dξ ≈ Σ_q w_q f(ξ_q), points ξ_q = (ξ, η, ζ); the weights sum to the
/// tetrahedron's volume ⅙.
pub type TetRule = Rule<[f64; 3]>;

impl TetRule {
    /// A rule exact for every polynomial of total degree ≤ `d`.
    ///
    /// | d | rule | points |
    /// |---|---|---|
    /// | 0, 1 | centroid | 1 |
    /// | 2 | symmetric, one 4-point orbit (a, a, a, 1 − 3a), a = (5 − √5)/20, weights 1/24 | 4 |
    /// | 3, 4, 5 | symmetric, two 4-point orbits (a, a, a, 1 − 3a) and the 6-point orbit (b, b, ½ − b, ½ − b); the six parameters solved from the moment equations by Newton | 14 |
    /// | ≥ 6 | collapsed (Stroud conical / Duffy) Gauss–Legendre product, ⌈(d + 3)/2⌉ × ⌈(d + 2)/2⌉ × ⌈(d + 1)/2⌉ | e.g. 80 for d = 6 |
    ///
    /// All weights are positive and all points strictly inside (the degree-3 and degree-4
    /// cases use the degree-5 rule: the symmetric positive-weight rules of degree 3 need as
    /// many points). The collapsed rule maps the unit cube onto the tetrahedron by
    /// (u, v, w) ↦ (u, v(1 − u), w(1 − u)(1 − v)), with Jacobian (1 − u)²(1 − v): the extra
    /// factors raise the degree in u by two and in v by one, hence the extra Gauss points
    /// in those directions.
    pub fn degree(d: usize) -> Self {
        match d {
            0 | 1 => Self {
                points: vec![[0.25, 0.25, 0.25]],
                weights: vec![1.0 / 6.0],
            },
            2 => {
                let a = (5.0 - 5f64.sqrt()) / 20.0;
                Self::from_orbits(&[(a, 1.0 / 24.0)], &[])
            }
            3..=5 => {
                // Solved once per process.
                static ORBITS: std::sync::OnceLock<[f64; 6]> = std::sync::OnceLock::new();
                let [a1, a2, b, w1, w2, w3] = *ORBITS.get_or_init(tet_degree5_orbits);
                Self::from_orbits(&[(a1, w1), (a2, w2)], &[(b, w3)])
            }
            _ => Self::collapsed_gauss(
                (d + 3).div_ceil(2),
                (d + 2).div_ceil(2),
                (d + 1).div_ceil(2),
            ),
        }
    }

    /// Builds a fully symmetric rule from orbits S₃₁(a) = {(a, a, a, 1 − 3a) and its 4
    /// permutations} and S₂₂(b) = {(b, b, ½ − b, ½ − b) and its 6 permutations} of the
    /// barycentric coordinates (λ₀, λ₁, λ₂, λ₃), ξ = (λ₁, λ₂, λ₃); every orbit point has its
    /// orbit's weight w.
    fn from_orbits(s31: &[(f64, f64)], s22: &[(f64, f64)]) -> Self {
        let mut points = Vec::new();
        let mut weights = Vec::new();
        for &(a, w) in s31 {
            for k in 0..4 {
                let mut l = [a; 4];
                l[k] = 1.0 - 3.0 * a;
                points.push([l[1], l[2], l[3]]);
                weights.push(w);
            }
        }
        for &(b, w) in s22 {
            let c = 0.5 - b;
            for (i, j) in [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)] {
                let mut l = [c; 4];
                l[i] = b;
                l[j] = b;
                points.push([l[1], l[2], l[3]]);
                weights.push(w);
            }
        }
        Self { points, weights }
    }

    /// The collapsed (conical-product) Gauss rule with `nu`, `nv`, `nw` points in u, v, w:
    /// ξ = u, η = v(1 − u), ζ = w(1 − u)(1 − v), weight w_u w_v w_w (1 − u)²(1 − v). Exact
    /// for total degree ≤ min(2nu − 3, 2nv − 2, 2nw − 1).
    pub fn collapsed_gauss(nu: usize, nv: usize, nw: usize) -> Self {
        let (pu, wu) = gauss_legendre(nu);
        let (pv, wv) = gauss_legendre(nv);
        let (pw, ww) = gauss_legendre(nw);
        let mut points = Vec::with_capacity(nu * nv * nw);
        let mut weights = Vec::with_capacity(nu * nv * nw);
        for (u, a) in pu.iter().zip(&wu) {
            for (v, b) in pv.iter().zip(&wv) {
                for (w, c) in pw.iter().zip(&ww) {
                    points.push([*u, v * (1.0 - u), w * (1.0 - u) * (1.0 - v)]);
                    weights.push(a * b * c * (1.0 - u) * (1.0 - u) * (1.0 - v));
                }
            }
        }
        Self { points, weights }
    }

    /// This rule applied on each of the 8^`levels` sub-tetrahedra of `levels` regular
    /// refinements (Bey's: each tetrahedron is cut by its edge midpoints into the 4 corner
    /// tetrahedra and the inner octahedron, split along the diagonal between the midpoints
    /// of edges 0–2 and 1–3 into 4 more). All 8 children have ⅛ of the parent's volume, so
    /// every weight is scaled by 8^−`levels`. Same degree of exactness, with points spread
    /// over the whole element: use it where an integrand is only piecewise smooth, e.g. a
    /// thin contact band crossing an element (MODEL.md §9).
    pub fn subdivided(&self, levels: u32) -> Self {
        let mut tets: Vec<[[f64; 3]; 4]> = vec![[
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]];
        for _ in 0..levels {
            tets = tets.iter().flat_map(bey_children).collect();
        }
        let scale = 0.125f64.powi(levels as i32);
        let mut points = Vec::with_capacity(self.len() * tets.len());
        let mut weights = Vec::with_capacity(self.len() * tets.len());
        for t in &tets {
            for (p, w) in self.points.iter().zip(&self.weights) {
                let mut x = t[0];
                for (k, v) in t[1..].iter().enumerate() {
                    for i in 0..3 {
                        x[i] += p[k] * (v[i] - t[0][i]);
                    }
                }
                points.push(x);
                weights.push(w * scale);
            }
        }
        Self { points, weights }
    }
}

/// The 8 children of tetrahedron `t` in Bey's regular refinement: the corner tetrahedra
/// and the octahedron split along the diagonal x₀₂–x₁₃ (xᵢⱼ the midpoint of edge i–j).
fn bey_children(t: &[[f64; 3]; 4]) -> [[[f64; 3]; 4]; 8] {
    let m = |i: usize, j: usize| -> [f64; 3] { std::array::from_fn(|k| 0.5 * (t[i][k] + t[j][k])) };
    let (x01, x02, x03, x12, x13, x23) = (m(0, 1), m(0, 2), m(0, 3), m(1, 2), m(1, 3), m(2, 3));
    [
        [t[0], x01, x02, x03],
        [x01, t[1], x12, x13],
        [x02, x12, t[2], x23],
        [x03, x13, x23, t[3]],
        [x01, x02, x03, x13],
        [x01, x02, x12, x13],
        [x02, x03, x13, x23],
        [x02, x12, x13, x23],
    ]
}

/// Orbit parameters (a₁, a₂, b) and point weights (w₁, w₂, w₃) of the 14-point symmetric
/// degree-5 rule on the tetrahedron, solved from the moment equations.
///
/// Every symmetric polynomial of degree ≤ 5 in the barycentric coordinates λ₀ … λ₃
/// (Σλᵢ = 1) is a combination of 1, p₂, p₃, p₄, p₂², p₂p₃ with the power sums
/// p_k = Σᵢ λᵢᵏ (the invariants e₂^α e₃^β e₄^γ of degree 2α + 3β + 4γ ≤ 5 are six). With
/// ∫_T̂ λ^α = α!/(|α| + 3)! (multi-index notation),
///
///   ∫ p_k = 4 k!/(k + 3)!,  ∫ p_i p_j = [4 (i + j)! + 12 i! j!]/(i + j + 3)!,
///
/// and on the orbits p_k(S₃₁(a)) = 3aᵏ + (1 − 3a)ᵏ, p_k(S₂₂(b)) = 2bᵏ + 2(½ − b)ᵏ, the
/// rule is exact to degree 5 iff 4w₁ f(a₁) + 4w₂ f(a₂) + 6w₃ f(b) = ∫ f for the six f.
/// Newton from a two-digit guess converges in a few steps to the solution with all
/// weights positive and all points inside (a₁ ≈ 0.0927, a₂ ≈ 0.3109, b ≈ 0.0455).
fn tet_degree5_orbits() -> [f64; 6] {
    let fact = |n: u32| (1..=n).map(f64::from).product::<f64>();
    // The six moment functions of (p₂, p₃, p₄) and their exact integrals.
    let exact_p = |k: u32| 4.0 * fact(k) / fact(k + 3);
    let exact_pp =
        |i: u32, j: u32| (4.0 * fact(i + j) + 12.0 * fact(i) * fact(j)) / fact(i + j + 3);
    let exact = [
        1.0 / 6.0,
        exact_p(2),
        exact_p(3),
        exact_p(4),
        exact_pp(2, 2),
        exact_pp(2, 3),
    ];
    // f and df/dt from p_k(t) and dp_k/dt, k = 2, 3, 4.
    let moments = |p: [f64; 3], dp: [f64; 3]| -> ([f64; 6], [f64; 6]) {
        let [p2, p3, p4] = p;
        let [d2, d3, d4] = dp;
        (
            [1.0, p2, p3, p4, p2 * p2, p2 * p3],
            [0.0, d2, d3, d4, 2.0 * p2 * d2, d2 * p3 + p2 * d3],
        )
    };
    let s31 = |a: f64| {
        let c = 1.0 - 3.0 * a;
        let p = [2, 3, 4].map(|k: i32| 3.0 * a.powi(k) + c.powi(k));
        let dp = [2, 3, 4].map(|k: i32| 3.0 * f64::from(k) * (a.powi(k - 1) - c.powi(k - 1)));
        moments(p, dp)
    };
    let s22 = |b: f64| {
        let c = 0.5 - b;
        let p = [2, 3, 4].map(|k: i32| 2.0 * b.powi(k) + 2.0 * c.powi(k));
        let dp = [2, 3, 4].map(|k: i32| 2.0 * f64::from(k) * (b.powi(k - 1) - c.powi(k - 1)));
        moments(p, dp)
    };
    // Unknowns z = (a₁, a₂, b, w₁, w₂, w₃).
    let mut z = SVector::<f64, 6>::from([0.09, 0.31, 0.045, 0.012, 0.019, 0.007]);
    for _ in 0..50 {
        let (f1, df1) = s31(z[0]);
        let (f2, df2) = s31(z[1]);
        let (g, dg) = s22(z[2]);
        let mut r = SVector::<f64, 6>::zeros();
        let mut jac = SMatrix::<f64, 6, 6>::zeros();
        for k in 0..6 {
            r[k] = 4.0 * z[3] * f1[k] + 4.0 * z[4] * f2[k] + 6.0 * z[5] * g[k] - exact[k];
            jac[(k, 0)] = 4.0 * z[3] * df1[k];
            jac[(k, 1)] = 4.0 * z[4] * df2[k];
            jac[(k, 2)] = 6.0 * z[5] * dg[k];
            jac[(k, 3)] = 4.0 * f1[k];
            jac[(k, 4)] = 4.0 * f2[k];
            jac[(k, 5)] = 6.0 * g[k];
        }
        let Some(dz) = jac.lu().solve(&r) else {
            break;
        };
        z -= dz;
        if dz.amax() < 1e-16 {
            break;
        }
    }
    [z[0], z[1], z[2], z[3], z[4], z[5]]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Relative error of `rule` on the monomial ∏ ξᵢ^aᵢ, whose integral over the reference
    /// simplex is ∏ aᵢ! / (Σ aᵢ + D)!.
    fn monomial_error<const D: usize>(rule: &Rule<[f64; D]>, a: [u32; D]) -> f64 {
        let f = |n: u32| (1..=n).map(f64::from).product::<f64>();
        let exact = a.iter().map(|&k| f(k)).product::<f64>() / f(a.iter().sum::<u32>() + D as u32);
        let q: f64 = rule
            .points
            .iter()
            .zip(&rule.weights)
            .map(|(p, w)| w * (0..D).map(|i| p[i].powi(a[i] as i32)).product::<f64>())
            .sum();
        (q - exact).abs() / exact
    }

    /// Largest relative error over all monomials of total degree exactly `d`.
    fn max_error_at_degree<const D: usize>(rule: &Rule<[f64; D]>, d: u32) -> f64 {
        let mut worst: f64 = 0.0;
        // The exponents of the first D − 1 coordinates as the digits of k in base d + 1.
        for k in 0..(d + 1).pow(D as u32 - 1) {
            let mut a = [0u32; D];
            let mut rest = k;
            for ai in a.iter_mut().take(D - 1) {
                *ai = rest % (d + 1);
                rest /= d + 1;
            }
            let first: u32 = a.iter().sum();
            if first <= d {
                a[D - 1] = d - first;
                worst = worst.max(monomial_error(rule, a));
            }
        }
        worst
    }

    /// Positive weights summing to the simplex's measure 1/D!, all points strictly inside.
    fn assert_positive_inside<const D: usize>(rule: &Rule<[f64; D]>) {
        assert!(!rule.is_empty());
        assert_eq!(rule.points.len(), rule.weights.len());
        for (p, w) in rule.points.iter().zip(&rule.weights) {
            assert!(*w > 0.0, "non-positive weight {w}");
            assert!(
                p.iter().all(|x| *x > 0.0) && p.iter().sum::<f64>() < 1.0,
                "point {p:?} not strictly inside"
            );
        }
        let s: f64 = rule.weights.iter().sum();
        let measure = 1.0 / (1..=D).map(|k| k as f64).product::<f64>();
        assert!((s - measure).abs() < 1e-14, "weights sum {s}");
    }

    /// The rules `degree(d)` for d ≤ `max` are exact to degree d and positive inside.
    fn rules_exact_to_claimed_degree<const D: usize>(
        degree: fn(usize) -> Rule<[f64; D]>,
        max: usize,
    ) {
        for d in 0..=max {
            let rule = degree(d);
            assert_positive_inside(&rule);
            for k in 0..=d as u32 {
                let e = max_error_at_degree(&rule, k);
                assert!(e < 1e-13, "degree {d} rule, monomials of degree {k}: {e}");
            }
        }
    }

    /// Each rule `degree(d)` of `sharp` = (d, s) is exact to degree s and no further: some
    /// monomial of degree s + 1 is not integrated.
    fn rules_fail_above<const D: usize>(
        degree: fn(usize) -> Rule<[f64; D]>,
        sharp: &[(usize, u32)],
    ) {
        for &(d, s) in sharp {
            let e = max_error_at_degree(&degree(d), s + 1);
            assert!(
                e > 1e-11,
                "degree {d} rule integrates degree {} exactly ({e:e})",
                s + 1
            );
        }
    }

    /// The rules `degree(d)` subdivided `levels` times keep their degree and stay inside,
    /// with (2^D)^levels times the points, for each (d, levels) of `cases`.
    fn subdivided_rules_exact_and_inside<const D: usize>(
        degree: fn(usize) -> Rule<[f64; D]>,
        subdivided: Subdivision<[f64; D]>,
        cases: &[(usize, u32)],
    ) {
        for &(d, levels) in cases {
            let base = degree(d);
            let rule = subdivided(&base, levels);
            assert_eq!(rule.len(), base.len() * (1usize << D).pow(levels));
            assert_positive_inside(&rule);
            for k in 0..=d as u32 {
                let e = max_error_at_degree(&rule, k);
                assert!(e < 1e-13, "d={d} levels={levels} k={k}: {e}");
            }
            assert!(max_error_at_degree(&rule, d as u32 + 2) > 1e-10);
        }
        let base = degree(5);
        assert_eq!(subdivided(&base, 0), base);
    }

    /// The error of `rule` on the kinked f = |ξ − a| whose integral is `exact`.
    fn kink_error<const D: usize>(rule: &Rule<[f64; D]>, a: f64, exact: f64) -> f64 {
        let q: f64 = rule
            .points
            .iter()
            .zip(&rule.weights)
            .map(|(p, w)| w * (p[0] - a).abs())
            .sum();
        (q - exact).abs()
    }

    #[test]
    fn gauss_legendre_exact_to_2n_minus_1_and_not_beyond() {
        for n in 1..=20usize {
            let (x, w) = gauss_legendre(n);
            assert_eq!(x.len(), n);
            for k in 0..2 * n {
                let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                let e = 1.0 / (k as f64 + 1.0);
                assert!((q - e).abs() < 1e-14, "n={n} k={k}: {q} vs {e}");
            }
            // Degree 2n is not integrated exactly: the error of x^{2n} is the Gauss remainder
            // (n!)⁴ / ((2n + 1) ((2n)!)²) on [0, 1]; check it wherever it exceeds round-off.
            let k = 2 * n as i32;
            let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k)).sum();
            let fact = |m: usize| (1..=m).map(|i| i as f64).product::<f64>();
            let remainder = fact(n).powi(4) / ((2 * n + 1) as f64 * fact(2 * n).powi(2));
            if remainder > 1e-12 {
                let err = 1.0 / (k as f64 + 1.0) - q;
                assert!(
                    (err - remainder).abs() < 1e-6 * remainder + 1e-15,
                    "n={n}: error {err:e}, expected {remainder:e}"
                );
            }
            for (xi, wi) in x.iter().zip(&w) {
                assert!(*xi > 0.0 && *xi < 1.0 && *wi > 0.0);
            }
            for i in 1..n {
                assert!(x[i] > x[i - 1], "nodes not increasing");
            }
        }
        assert!(gauss_legendre(0).0.is_empty());
    }

    #[test]
    fn triangle_rules_exact_to_claimed_degree() {
        rules_exact_to_claimed_degree(TriangleRule::degree, 20);
    }

    #[test]
    fn low_order_rules_have_the_cheap_point_counts() {
        assert_eq!(TriangleRule::degree(1).len(), 1);
        assert_eq!(TriangleRule::degree(2).len(), 3);
        assert_eq!(TriangleRule::degree(4).len(), 6);
        assert_eq!(TriangleRule::degree(5).len(), 7);
        assert_eq!(TriangleRule::degree(10).len(), 36);
    }

    #[test]
    fn rules_fail_one_degree_above() {
        // (d = 3 uses the degree-4 rule, so its sharp degree is 4.)
        let sharp = [
            (1, 1),
            (2, 2),
            (3, 4),
            (4, 4),
            (5, 5),
            (6, 6),
            (10, 10),
            (15, 15),
        ];
        rules_fail_above(TriangleRule::degree, &sharp);
    }

    #[test]
    fn degree4_coefficients_match_the_published_values() {
        // Dunavant (1985), degree 4, area-normalised weights 0.223381589678011 and
        // 0.109951743655322 at a = 0.445948490915965 and 0.091576213509771.
        let [a1, a2, w1, w2] = degree4_orbits();
        assert!((a1 - 0.445948490915965).abs() < 1e-14);
        assert!((a2 - 0.091576213509771).abs() < 1e-14);
        assert!((2.0 * w1 - 0.223381589678011).abs() < 1e-14);
        assert!((2.0 * w2 - 0.109951743655322).abs() < 1e-14);
    }

    #[test]
    fn triangle_subdivided_rules_exact_and_inside() {
        let cases = [(2, 1), (4, 2), (5, 3), (10, 2)];
        subdivided_rules_exact_and_inside(TriangleRule::degree, TriangleRule::subdivided, &cases);
    }

    #[test]
    fn subdivided_rule_integrates_a_kink_better() {
        // f = |ξ − 0.3| has a kink; sub-division must converge to ∫ = known value.
        // ∫_T̂ |ξ − a| = ∫_0^1 |ξ − a| (1 − ξ) dξ.
        let a: f64 = 0.3;
        let exact = {
            // ∫_0^a (a − ξ)(1 − ξ) + ∫_a^1 (ξ − a)(1 − ξ)
            let f1 = a * a / 2.0 - a * a * a / 6.0;
            let b = 1.0 - a;
            let f2 = b * b * b / 6.0;
            f1 + f2
        };
        let err = |r: &TriangleRule| kink_error(r, a, exact);
        let base = TriangleRule::degree(4);
        let e0 = err(&base);
        let e3 = err(&base.subdivided(3));
        assert!(e3 < e0 / 20.0, "{e0} → {e3}");
    }

    #[test]
    fn edge_rules_exact() {
        for d in 0..=15usize {
            for levels in [0u32, 2] {
                let r = EdgeRule::degree(d).subdivided(levels);
                let s: f64 = r.weights.iter().sum();
                assert!((s - 1.0).abs() < 1e-14);
                for k in 0..=d {
                    let q: f64 = r
                        .points
                        .iter()
                        .zip(&r.weights)
                        .map(|(x, w)| w * x.powi(k as i32))
                        .sum();
                    assert!((q - 1.0 / (k as f64 + 1.0)).abs() < 1e-14, "d={d} k={k}");
                }
            }
        }
    }

    #[test]
    fn tet_rules_exact_to_claimed_degree() {
        rules_exact_to_claimed_degree(TetRule::degree, 14);
    }

    #[test]
    fn tet_rules_have_the_expected_point_counts() {
        assert_eq!(TetRule::degree(1).len(), 1);
        assert_eq!(TetRule::degree(2).len(), 4);
        for d in 3..=5 {
            assert_eq!(TetRule::degree(d).len(), 14);
        }
        assert_eq!(TetRule::degree(6).len(), 5 * 4 * 4);
        assert_eq!(TetRule::degree(7).len(), 5 * 5 * 4);
    }

    #[test]
    fn tet_rules_fail_one_degree_above() {
        // (d = 3, 4 use the degree-5 rule, so their sharp degree is 5.)
        let sharp = [
            (1, 1),
            (2, 2),
            (3, 5),
            (4, 5),
            (5, 5),
            (6, 6),
            (7, 7),
            (10, 10),
            (13, 13),
        ];
        rules_fail_above(TetRule::degree, &sharp);
    }

    /// The Newton solution is the known positive 14-point rule (two S₃₁ orbits and one S₂₂
    /// orbit): inside, positive, and equal to the published digits (exactness itself is
    /// checked on every monomial above).
    #[test]
    fn tet_degree5_orbits_are_a_converged_positive_solution() {
        let [a1, a2, b, w1, w2, w3] = tet_degree5_orbits();
        // Inside: 0 < a < ⅓ on S₃₁, 0 < b < ½ on S₂₂.
        assert!(a1 > 0.0 && a1 < 1.0 / 3.0 && a2 > 0.0 && a2 < 1.0 / 3.0);
        assert!(b > 0.0 && b < 0.5);
        assert!(w1 > 0.0 && w2 > 0.0 && w3 > 0.0);
        assert!((a1 - 0.0927).abs() < 1e-4 && (a2 - 0.3109).abs() < 1e-4);
        assert!((b - 0.0455).abs() < 1e-4);
        assert!((4.0 * (w1 + w2) + 6.0 * w3 - 1.0 / 6.0).abs() < 1e-16);
        // The tabulated values of this rule (e.g. Walkington 2000; volume-normalised
        // weights): a = 0.0927352503108912, 0.3108859192633006, b = 0.0455037041256496,
        // 6w = 0.0734930431163620, 0.1126879257180159, 0.0425460207770815.
        assert!((a1 - 0.0927352503108912).abs() < 1e-14);
        assert!((a2 - 0.3108859192633006).abs() < 1e-14);
        assert!((b - 0.0455037041256496).abs() < 1e-14);
        assert!((6.0 * w1 - 0.0734930431163620).abs() < 1e-14);
        assert!((6.0 * w2 - 0.1126879257180159).abs() < 1e-14);
        assert!((6.0 * w3 - 0.0425460207770815).abs() < 1e-14);
    }

    #[test]
    fn tet_subdivided_rules_exact_and_inside() {
        let cases = [(1, 1), (2, 1), (5, 1), (5, 2), (6, 1), (2, 3)];
        subdivided_rules_exact_and_inside(TetRule::degree, TetRule::subdivided, &cases);
    }

    /// Bey's children tile the parent: equal volumes ⅛ of it, and together they integrate
    /// a kinked function better than the unrefined rule.
    #[test]
    fn tet_subdivision_tiles_and_integrates_a_kink_better() {
        let t = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        for c in bey_children(&t) {
            let e = |k: usize| std::array::from_fn::<f64, 3, _>(|i| c[k][i] - c[0][i]);
            let (u, v, w) = (e(1), e(2), e(3));
            let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                + u[2] * (v[0] * w[1] - v[1] * w[0]);
            assert!((det.abs() - 0.125).abs() < 1e-15, "child volume {det}");
        }
        // f = |ξ − a|: ∫_T̂ |ξ − a| = ∫_0^1 |ξ − a| (1 − ξ)²/2 dξ.
        let a: f64 = 0.3;
        let exact = {
            let f1 = a * a * (a * a - 4.0 * a + 6.0) / 24.0; // ∫_0^a (a − ξ)(1 − ξ)²/2
            let b = 1.0 - a;
            f1 + b * b * b * b / 24.0 // ∫_a^1 (ξ − a)(1 − ξ)²/2 with s = 1 − ξ
        };
        let err = |r: &TetRule| kink_error(r, a, exact);
        let base = TetRule::degree(5);
        let (e0, e2) = (err(&base), err(&base.subdivided(2)));
        assert!(e2 < e0 / 10.0, "{e0} → {e2}");
    }
}
