//! What a scene reports (MODEL.md §7), computed from a state y alone, for every model.
//!
//! In the axisymmetric model (MODEL.md §10) the integrals are per radian (the elements'
//! quadrature weights carry r): the strain means are volume means (weight r dA) of the
//! 3-D ‖E‖, hoop strain included, the weight and the contact force are per radian, and
//! the contact radius is the length of the meridian contour in contact, as in 2-D.

use nalgebra::{SMatrix, SVector, Vector2};

use super::dofs::NONE;
use super::element::ElementOf;
use super::kinematics::{NodalOf, det};
use super::observables::Observables;
use super::{CellOf, Shape, deformation};
use crate::fem::tri6::edge_shape;
use crate::fem::{CellMesh, Domain, ElementTabulation};
use crate::physics::{KinematicModel, Surface, contact_force};

/// Sub-segments per boundary edge when measuring the contact length.
const EDGE_SAMPLES: usize = 64;

/// Reference-area integrals of ‖E‖_F and reference areas per domain (nucleus,
/// cytoplasm, membrane), from [`super::CellOf::mean_strain_norms`]; in the axisymmetric
/// model reference volumes per radian (∫ r dA) and the integrals with that weight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainNorms {
    /// ∫ ‖E‖_F dA over each domain \[µm²\] (axisymmetric: ∫ ‖E‖_F r dA \[µm³\]).
    pub integral: [f64; 3],
    /// Reference area of each domain \[µm²\] (half cell; axisymmetric: ∫ r dA \[µm³\], the
    /// volume per radian).
    pub area: [f64; 3],
}

/// `F₃₃` at standard point `q` of `el` with nodal displacements `ue`: the hoop stretch
/// `1 + u_r/r` in the axisymmetric model (its hoop table), 1 otherwise.
fn hoop_stretch<const D: usize, const N: usize>(
    el: &ElementOf<D, N>,
    q: usize,
    ue: &NodalOf<D, N>,
) -> f64 {
    match el.hoop.get(q) {
        Some(h) => 1.0 + (0..N).map(|a| h[a] * ue[a][0]).sum::<f64>(),
        None => 1.0,
    }
}

/// ‖E‖_F of `E = ½(C − I)` for `F ⊕ f33`: the block of `F` and the hoop entry
/// `½(f33² − 1)` (0 where `f33 = 1`).
fn strain_norm<const D: usize>(f: &SMatrix<f64, D, D>, f33: f64) -> f64 {
    let e = (f.transpose() * f - SMatrix::<f64, D, D>::identity()) * 0.5;
    let e33 = 0.5 * (f33 * f33 - 1.0);
    (e.norm_squared() + e33 * e33).sqrt()
}

impl StrainNorms {
    fn index(d: Domain) -> usize {
        match d {
            Domain::Nucleus => 0,
            Domain::Cytoplasm => 1,
            Domain::Membrane => 2,
        }
    }

    /// Reference-area mean of ‖E‖_F over the union of `domains`: the integrals summed
    /// over the areas summed (the paper's cytoplasm is `[Cytoplasm, Membrane]`).
    pub fn mean(&self, domains: &[Domain]) -> f64 {
        let (mut i, mut a) = (0.0, 0.0);
        for &d in domains {
            i += self.integral[Self::index(d)];
            a += self.area[Self::index(d)];
        }
        i / a
    }
}

/// Adds to `total` the length of the part of one P2 edge whose current position `x` has
/// `depth(x) > 0`, measured along the current curve and along the reference curve:
/// `[deformed, reference]`. The edge's parameter s ∈ [0, 1] is cut into `EDGE_SAMPLES` equal
/// steps; each step counts with the fraction of it where the depth, interpolated
/// linearly between its ends, is positive, times its chord in the current frame and in
/// the reference frame. The fraction is that of the same material sub-segment in both
/// frames, so a rigid motion gives equal lengths and a uniform stretch λ along a straight
/// edge gives deformed = λ × reference.
pub fn add_band_lengths(
    reference: &[Vector2<f64>; 3],
    current: &[Vector2<f64>; 3],
    depth: impl Fn(&Vector2<f64>) -> f64,
    total: &mut [f64; 2],
) {
    let along = |xs: &[Vector2<f64>; 3], s: f64| {
        let n = edge_shape(s);
        xs[0] * n[0] + xs[1] * n[1] + xs[2] * n[2]
    };
    let mut x0 = along(current, 0.0);
    let mut p0 = along(reference, 0.0);
    let mut d0 = depth(&x0);
    for k in 1..=EDGE_SAMPLES {
        let s = k as f64 / EDGE_SAMPLES as f64;
        let x1 = along(current, s);
        let p1 = along(reference, s);
        let d1 = depth(&x1);
        let frac = if d0 > 0.0 && d1 > 0.0 {
            1.0
        } else if d0 <= 0.0 && d1 <= 0.0 {
            0.0
        } else {
            d0.max(d1) / (d0 - d1).abs()
        };
        total[0] += frac * (x1 - x0).norm();
        total[1] += frac * (p1 - p0).norm();
        x0 = x1;
        p0 = p1;
        d0 = d1;
    }
}

impl<S: Shape<D, N, E>, const D: usize, const N: usize, const E: usize> CellOf<S, D, N, E> {
    /// All observables at time `t` in state `y` (the contact radius: [`Shape::contact_lengths`]).
    pub fn observe(&self, t: f64, y: &[f64]) -> Observables {
        let pts = self.mesh.points();
        let uy = |i: usize| self.dofs.node_u(y, i)[1];
        let strain = self.mean_strain_norms(y);
        let (contact, contact_ref) = S::contact_lengths(self, y);
        Observables {
            t,
            contact_radius: contact,
            uy_top: uy(pts.nucleus_top),
            uy_centre: uy(pts.centre),
            uy_bottom: uy(pts.nucleus_bottom),
            strain_nucleus: strain.mean(&[Domain::Nucleus]),
            strain_cytoplasm: strain.mean(&[Domain::Cytoplasm, Domain::Membrane]),
            contact_radius_ref: contact_ref,
            strain_membrane: strain.mean(&[Domain::Membrane]),
            uy_nucleus_max: self.nucleus_lowest_uy(y),
        }
    }

    /// Reference integrals of the Frobenius norm of E = ½(FᵀF − I) per domain (plane
    /// strain: E₃₃ = 0; axisymmetric: with the hoop strain E₃₃ = ½(λ_θ² − 1), weighted by r,
    /// volumes per radian; 3-D: the quarter's volumes), and the domains' reference sizes.
    pub fn mean_strain_norms(&self, y: &[f64]) -> StrainNorms {
        let mut s = StrainNorms {
            integral: [0.0; 3],
            area: [0.0; 3],
        };
        for el in &self.elements {
            let k = StrainNorms::index(el.domain);
            let ue = self.element_displacements(el, y);
            for q in 0..el.geo.jxw.len() {
                let f = deformation(&ue, &el.geo.grads[q]);
                s.integral[k] += el.geo.jxw[q] * strain_norm(&f, hoop_stretch(el, q, &ue));
                s.area[k] += el.geo.jxw[q];
            }
        }
        s
    }

    /// The largest ‖E‖_F = ‖½(FᵀF − I)‖ over the quadrature points of the elements of
    /// `domain` (with the hoop strain where axisymmetric), as [`Self::mean_strain_norms`]
    /// evaluates it; 0 for a domain without elements.
    pub fn largest_strain_norm(&self, y: &[f64], domain: Domain) -> f64 {
        let mut largest = 0.0f64;
        for el in self.elements.iter().filter(|el| el.domain == domain) {
            let ue = self.element_displacements(el, y);
            for q in 0..el.geo.jxw.len() {
                let f = deformation(&ue, &el.geo.grads[q]);
                largest = largest.max(strain_norm(&f, hoop_stretch(el, q, &ue)));
            }
        }
        largest
    }

    /// The elements whose map is not positive at some point of the band rule (denser than
    /// the solid rule, whose points the law keeps positive): P2 elements folded inside
    /// between their solid points (docs/MODEL.md §5, J₊). Their number, the smallest det F
    /// at the band points of the elements not shown unfolded by the sufficient test
    /// (`ElementTabulation::unfolded_throughout`), and where it is (element, point,
    /// centroid of the element's nodes); a mesh with none folded has `folded == 0`.
    pub fn folded_elements(&self, y: &[f64]) -> Folded {
        let mut out = Folded {
            folded: 0,
            smallest: None,
            element: 0,
            point: 0,
            domain: Domain::Cytoplasm,
            x: Vec::new(),
        };
        let nodes = self.mesh.nodes();
        for (e, el) in self.elements.iter().enumerate() {
            let ue = self.element_displacements(el, y);
            // Most elements are shown unfolded by the cheap sufficient test; only the
            // others are looked at point by point (an output's check cost a sixth of the
            // flat gravity phase at refine 2 when every element was).
            let xr: [[f64; D]; N] = el.nodes.map(|i| nodes[i]);
            let x = std::array::from_fn(|a| std::array::from_fn(|k| xr[a][k] + ue[a][k]));
            if <S::Mesh as CellMesh<D, N>>::Tab::unfolded_throughout(&xr, &x) {
                continue;
            }
            let mut el_min = f64::INFINITY;
            for q in 0..el.cgeo.jxw.len() {
                let j = det(&deformation(&ue, &el.cgeo.grads[q]));
                if j < el_min {
                    el_min = j;
                    if out.smallest.is_none_or(|s| j < s) {
                        (out.smallest, out.element, out.point) = (Some(j), e, q);
                    }
                }
            }
            out.folded += usize::from(el_min <= 0.0);
        }
        out.domain = self.mesh.domains()[out.element];
        out.x = self.element_centroid(y, out.element).to_vec();
        out
    }

    /// The smallest vertical displacement (the largest downward one, negative = down)
    /// over every node of the nucleus elements, vertices and mid-side nodes \[µm\].
    pub fn nucleus_lowest_uy(&self, y: &[f64]) -> f64 {
        self.elements
            .iter()
            .filter(|el| el.domain == Domain::Nucleus)
            .flat_map(|el| el.nodes)
            .map(|i| self.dofs.node_u(y, i)[1])
            .fold(f64::INFINITY, f64::min)
    }

    /// Per-element mean ‖E‖_F and mean det F (reference averages; axisymmetric: volume
    /// averages, hoop stretch included), for output.
    pub fn element_strain_and_jacobian(&self, y: &[f64]) -> Vec<(f64, f64)> {
        self.elements
            .iter()
            .map(|el| {
                let ue = self.element_displacements(el, y);
                let (mut se, mut sj, mut a) = (0.0, 0.0, 0.0);
                for q in 0..el.geo.jxw.len() {
                    let f = deformation(&ue, &el.geo.grads[q]);
                    let f33 = hoop_stretch(el, q, &ue);
                    se += el.geo.jxw[q] * strain_norm(&f, f33);
                    sj += el.geo.jxw[q] * det(&f) * f33;
                    a += el.geo.jxw[q];
                }
                (se / a, sj / a)
            })
            .collect()
    }

    /// Total contact force on the modelled part of the cell, integrated with the band rule
    /// over the elements in the band's reach (the others add exact zeros, as in the
    /// residual): half cell [pN/µm] per unit thickness; axisymmetric \[pN\] per radian (the
    /// whole cell's is 2π times it); quarter cell \[pN\].
    pub fn contact_force_total(&self, y: &[f64]) -> SVector<f64, D> {
        let axisymmetric = self.params.kinematics == KinematicModel::Axisymmetric;
        let p = &self.params;
        let values = self.ctab.values();
        let mut total = SVector::<f64, D>::zeros();
        for el in &self.elements {
            let ue = self.element_displacements(el, y);
            if !self.in_reach(el, &ue) {
                continue;
            }
            for q in 0..el.cgeo.jxw.len() {
                let nv = &values[q];
                let f = deformation(&ue, &el.cgeo.grads[q]);
                let mut x = SVector::<f64, D>::from(el.cgeo.x[q]);
                for a in 0..N {
                    for k in 0..D {
                        x[k] += nv[a] * ue[a][k];
                    }
                }
                // J = F₃₃ det F₂, F₃₃ = x_r/X_r axisymmetric.
                let f33 = if axisymmetric {
                    x[0] / el.cgeo.x[q][0]
                } else {
                    1.0
                };
                let surf = self.substrate.eval(&x);
                total += contact_force(&p.contact, surf, det(&f) * f33) * el.cgeo.jxw[q];
            }
        }
        total
    }

    /// Weight of the modelled part of the cell at full gravity: g ∫ ρ dV (half cell
    /// [pN/µm]; axisymmetric \[pN\] per radian, g ∫ ρ r dA; quarter cell \[pN\]).
    pub fn weight(&self) -> f64 {
        self.elements
            .iter()
            .map(|el| el.mass.iter().flatten().sum::<f64>())
            .sum::<f64>()
            * self.params.gravity
    }

    /// Reference size of domain `d` (all domains: `None`): area of the half cell \[µm²\],
    /// volume per radian (axisymmetric) or volume of the quarter cell \[µm³\].
    pub fn volume(&self, d: Option<Domain>) -> f64 {
        self.elements
            .iter()
            .filter(|el| d.is_none_or(|d| el.domain == d))
            .map(|el| el.geo.jxw.iter().sum::<f64>())
            .sum()
    }

    fn element_displacements(&self, el: &ElementOf<D, N>, y: &[f64]) -> NodalOf<D, N> {
        let mut ue = [[0.0; D]; N];
        for a in 0..N {
            for k in 0..D {
                let d = self.dofs.u[el.nodes[a]][k];
                if d != NONE {
                    ue[a][k] = y[d];
                }
            }
        }
        ue
    }
}

impl super::CellModel {
    /// Length of the part of the outer boundary in contact, i.e. whose current position
    /// lies within ε_ct of the substrate (depth > −ε_ct), measured along the deformed
    /// contour and along the reference contour: `(deformed, reference)` \[µm\]. Each P2
    /// boundary edge is sampled in `EDGE_SAMPLES` sub-segments of its parameter
    /// ([`add_band_lengths`]).
    pub fn contact_lengths(&self, y: &[f64]) -> (f64, f64) {
        let eps = self.params.contact.eps;
        let depth = |x: &Vector2<f64>| self.params.substrate.eval(x).0 + eps;
        let mut total = [0.0; 2];
        for edge in &self.mesh.outer_edges {
            let reference = edge.map(|i| Vector2::from(self.mesh.nodes[i]));
            let current = edge.map(|i| self.position(y, i));
            add_band_lengths(&reference, &current, depth, &mut total);
        }
        (total[0], total[1])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    /// A straight P2 edge from `a` to `b` (mid-node at the midpoint).
    fn straight(a: Vector2<f64>, b: Vector2<f64>) -> [Vector2<f64>; 3] {
        [a, (a + b) * 0.5, b]
    }

    fn lengths(
        reference: &[Vector2<f64>; 3],
        current: &[Vector2<f64>; 3],
        depth: impl Fn(&Vector2<f64>) -> f64,
    ) -> [f64; 2] {
        let mut t = [0.0; 2];
        add_band_lengths(reference, current, depth, &mut t);
        t
    }

    #[test]
    fn a_rigid_motion_gives_the_same_length_in_both_frames() {
        // A curved edge (mid-node off the chord), half of it below y = 0.3 after the motion.
        let reference = [v(0.0, 0.0), v(1.0, 0.4), v(2.0, 1.5)];
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let current = reference.map(|p| v(c * p.x - s * p.y + 4.0, s * p.x + c * p.y - 0.7));
        let [d, r] = lengths(&reference, &current, |x| 0.3 - x.y);
        assert!(
            d > 0.1 && r > 0.1,
            "part of the edge is in the band: {d}, {r}"
        );
        assert!((d - r).abs() < 1e-12 * r, "deformed {d}, reference {r}");
    }

    #[test]
    fn a_horizontal_stretch_multiplies_the_deformed_length_by_lambda() {
        // Reference: the segment X ∈ [0, 3] at Y = 1. Current: x = λX, y = Y − 1.05, in a
        // band whose depth 2 − x is linear, so the part in contact is exactly x < 2:
        // deformed length 2, reference length 2/λ.
        let lambda = 1.6;
        let reference = straight(v(0.0, 1.0), v(3.0, 1.0));
        let current = reference.map(|p| v(lambda * p.x, p.y - 1.05));
        let [d, r] = lengths(&reference, &current, |x| 2.0 - x.x);
        assert!((d - 2.0).abs() < 1e-12, "deformed {d}");
        assert!((r - 2.0 / lambda).abs() < 1e-12, "reference {r}");
        assert!((d - lambda * r).abs() < 1e-12);
        // Wholly in a flat band (depth > 0 everywhere): 3λ and 3.
        let [d, r] = lengths(&reference, &current, |x| 0.1 - x.y);
        assert!((d - 3.0 * lambda).abs() < 1e-12 && (r - 3.0).abs() < 1e-12);
        // Wholly out of it: nothing.
        assert_eq!(lengths(&reference, &current, |x| -1.0 - x.y), [0.0, 0.0]);
    }

    #[test]
    fn lengths_add_to_the_running_total() {
        let reference = straight(v(0.0, 0.0), v(1.0, 0.0));
        let mut t = [1.0, 2.0];
        add_band_lengths(&reference, &reference, |_| 1.0, &mut t);
        assert!((t[0] - 2.0).abs() < 1e-12 && (t[1] - 3.0).abs() < 1e-12);
    }

    #[test]
    fn means_over_unions_of_domains_weight_by_area() {
        let s = StrainNorms {
            integral: [2.0, 6.0, 1.0],
            area: [4.0, 10.0, 2.0],
        };
        assert_eq!(s.mean(&[Domain::Nucleus]), 0.5);
        assert_eq!(s.mean(&[Domain::Cytoplasm]), 0.6);
        assert_eq!(s.mean(&[Domain::Membrane]), 0.5);
        // (6 + 1)/(10 + 2), not the mean of the means (0.55).
        assert_eq!(s.mean(&[Domain::Cytoplasm, Domain::Membrane]), 7.0 / 12.0);
    }
}

/// Elements folded inside between the solid rule's points ([`CellOf::folded_elements`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Folded {
    /// How many elements have det F ≤ 0 at some point of the band rule.
    pub folded: usize,
    /// The smallest det F at a band point of the elements a sufficient test did not show
    /// unfolded throughout (`ElementTabulation::unfolded_throughout`); none when it
    /// showed every element.
    pub smallest: Option<f64>,
    /// Its element, the band point and the element's domain.
    pub element: usize,
    pub point: usize,
    pub domain: Domain,
    /// Centroid of that element's nodes \[µm\].
    pub x: Vec<f64>,
}
