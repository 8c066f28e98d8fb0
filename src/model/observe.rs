//! What a scene reports (MODEL.md §7), computed from a state y alone.

use nalgebra::{Matrix2, Vector2};

use super::dofs::NONE;
use super::{CellModel, deformation};
use crate::fem::Domain;
use crate::fem::p2::edge_shape;
use crate::physics::contact_force;
use crate::record::Observables;

/// Sub-segments per boundary edge when measuring the contact length.
const EDGE_SAMPLES: usize = 64;

impl CellModel {
    /// Current position of node `i` in state `y`.
    pub fn position(&self, y: &[f64], i: usize) -> Vector2<f64> {
        let u = self.dofs.node_u(y, i);
        Vector2::new(self.mesh.nodes[i][0] + u[0], self.mesh.nodes[i][1] + u[1])
    }

    /// All observables at time `t` in state `y`.
    pub fn observe(&self, t: f64, y: &[f64]) -> Observables {
        let pts = self.mesh.points;
        let uy = |i: usize| self.dofs.node_u(y, i)[1];
        let (sn, sc) = self.mean_strain_norms(y);
        Observables {
            t,
            contact_radius: self.contact_length(y),
            uy_top: uy(pts.nucleus_top),
            uy_centre: uy(pts.centre),
            uy_bottom: uy(pts.nucleus_bottom),
            strain_nucleus: sn,
            strain_cytoplasm: sc,
        }
    }

    /// Deformed length of the outer boundary where the depth exceeds −ε_ct, i.e. within
    /// ε_ct of the substrate: each P2 boundary edge is sampled in [`EDGE_SAMPLES`] chords and
    /// the in-band part of each chord found by linear interpolation of the depth.
    pub fn contact_length(&self, y: &[f64]) -> f64 {
        let eps = self.params.contact.eps;
        let mut total = 0.0;
        for edge in &self.mesh.outer_edges {
            let xs = edge.map(|i| self.position(y, i));
            let at = |s: f64| {
                let n = edge_shape(s);
                xs[0] * n[0] + xs[1] * n[1] + xs[2] * n[2]
            };
            let mut x0 = at(0.0);
            let mut d0 = self.params.substrate.eval(&x0).0 + eps;
            for k in 1..=EDGE_SAMPLES {
                let x1 = at(k as f64 / EDGE_SAMPLES as f64);
                let d1 = self.params.substrate.eval(&x1).0 + eps;
                let len = (x1 - x0).norm();
                let frac = if d0 > 0.0 && d1 > 0.0 {
                    1.0
                } else if d0 <= 0.0 && d1 <= 0.0 {
                    0.0
                } else {
                    d0.max(d1) / (d0 - d1).abs()
                };
                total += frac * len;
                x0 = x1;
                d0 = d1;
            }
        }
        total
    }

    /// Reference-area means of the Frobenius norm of E = ½(FᵀF − I) over the nucleus and
    /// over the cytoplasm (plane strain: E₃₃ = 0).
    pub fn mean_strain_norms(&self, y: &[f64]) -> (f64, f64) {
        let mut acc = [[0.0f64; 2]; 2]; // [domain][sum, area]
        for el in &self.elements {
            let k = match el.domain {
                Domain::Nucleus => 0,
                Domain::Cytoplasm => 1,
                Domain::Membrane => continue,
            };
            let ue = self.element_displacements(el, y);
            for q in 0..el.geo.jxw.len() {
                let f = deformation(&ue, &el.geo.grads[q]);
                let e = (f.transpose() * f - Matrix2::identity()) * 0.5;
                acc[k][0] += el.geo.jxw[q] * e.norm();
                acc[k][1] += el.geo.jxw[q];
            }
        }
        (acc[0][0] / acc[0][1], acc[1][0] / acc[1][1])
    }

    /// Per-element mean ‖E‖_F and mean det F (reference-area averages), for output.
    pub fn element_strain_and_jacobian(&self, y: &[f64]) -> Vec<(f64, f64)> {
        self.elements
            .iter()
            .map(|el| {
                let ue = self.element_displacements(el, y);
                let (mut se, mut sj, mut a) = (0.0, 0.0, 0.0);
                for q in 0..el.geo.jxw.len() {
                    let f = deformation(&ue, &el.geo.grads[q]);
                    let e = (f.transpose() * f - Matrix2::identity()) * 0.5;
                    se += el.geo.jxw[q] * e.norm();
                    sj += el.geo.jxw[q] * f.determinant();
                    a += el.geo.jxw[q];
                }
                (se / a, sj / a)
            })
            .collect()
    }

    /// Total contact force on the half cell [pN/µm] (per unit thickness), integrated with
    /// the contact rule over every element.
    pub fn contact_force_total(&self, y: &[f64]) -> Vector2<f64> {
        let p = &self.params;
        let mut total = Vector2::zeros();
        for el in &self.elements {
            let ue = self.element_displacements(el, y);
            for q in 0..el.cgeo.jxw.len() {
                let nv = &self.ctab.values[q];
                let f = deformation(&ue, &el.cgeo.grads[q]);
                let mut x = Vector2::new(el.cgeo.x[q][0], el.cgeo.x[q][1]);
                for a in 0..6 {
                    x.x += nv[a] * ue[a][0];
                    x.y += nv[a] * ue[a][1];
                }
                total +=
                    contact_force(&p.substrate, &p.contact, &x, f.determinant()) * el.cgeo.jxw[q];
            }
        }
        total
    }

    /// Weight of the half cell at full gravity [pN/µm]: g ∫ ρ dV.
    pub fn weight(&self) -> f64 {
        self.elements
            .iter()
            .map(|el| el.mass.iter().flatten().sum::<f64>())
            .sum::<f64>()
            * self.params.gravity
    }

    fn element_displacements(&self, el: &super::Element, y: &[f64]) -> [[f64; 2]; 6] {
        let mut ue = [[0.0; 2]; 6];
        for a in 0..6 {
            for k in 0..2 {
                let d = self.dofs.u[el.nodes[a]][k];
                if d != NONE {
                    ue[a][k] = y[d];
                }
            }
        }
        ue
    }
}
