//! What the 3-D quarter cell reports (MODEL.md §7, §10), computed from a state y alone: the
//! 2-D scene's observables — the contact radius is the length of the meridian in the plane
//! z = 0 in contact, as in 2-D, the strain means are volume means of ‖E‖_F — and the 3-D
//! ones ([`Observables3`]): the contact area in both frames (whole cell, four quarters)
//! and its equivalent radius.

use nalgebra::{Matrix3, Vector2, Vector3};

use super::Cell3;
use crate::fem::Domain;
use crate::fem::TriangleRule;
use crate::fem::assembly::NONE;
use crate::fem::tet::face_map;
use crate::model::kinematics::deformation;
use crate::model::observe::{StrainNorms, add_band_lengths};
use crate::physics::Substrate;
use crate::physics::contact_force3;
use crate::record::{Mesh3File, Observables, Observables3, Snapshot3};

/// Sub-triangle levels of the rule sampling each P2 surface face for the contact area.
const FACE_LEVELS: u32 = 3;

impl Cell3 {
    /// The 2-D scene's observables at time `t` in state `y`.
    pub fn observe(&self, t: f64, y: &[f64]) -> Observables {
        let pts = self.mesh.points;
        let uy = |i: usize| self.dofs.node_u(y, i)[1];
        let strain = self.mean_strain_norms(y);
        let (contact, contact_ref) = self.meridian_contact_lengths(y);
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

    /// The 3-D quantities in state `y`.
    pub fn observe3(&self, y: &[f64]) -> Observables3 {
        let (a, a_ref) = self.contact_areas(y);
        let penetration_depth = match self.params.plane.substrate {
            Substrate::Pillars(p) => {
                let pb = self.mesh.points.nucleus_bottom;
                let y_pb = self.mesh.nodes[pb][1] + self.dofs.node_u(y, pb)[1];
                (p.y_top - y_pb).max(0.0)
            }
            Substrate::Flat { .. } => 0.0,
        };
        Observables3 {
            contact_area: a,
            contact_area_ref: a_ref,
            contact_radius_equiv: (a / std::f64::consts::PI).sqrt(),
            penetration_depth,
        }
    }

    /// Length of the meridian (the outer boundary in the plane z = c_z) in contact, i.e.
    /// whose current position lies within ε_ct of the substrate, along the deformed and
    /// the reference curve: `(deformed, reference)` [µm], as the half-plane models'
    /// contact radius. The points of that plane stay in it (u_z = 0 there).
    pub fn meridian_contact_lengths(&self, y: &[f64]) -> (f64, f64) {
        let eps = self.params.plane.contact.eps;
        let cz = self.params.center().z;
        let depth = |x: &Vector2<f64>| self.substrate.eval(&Vector3::new(x.x, x.y, cz)).0 + eps;
        let mut total = [0.0; 2];
        for edge in self.meridian_edges() {
            let reference =
                edge.map(|i| Vector2::new(self.mesh.nodes[i][0], self.mesh.nodes[i][1]));
            let current = edge.map(|i| {
                let x = self.position(y, i);
                Vector2::new(x.x, x.y)
            });
            add_band_lengths(&reference, &current, depth, &mut total);
        }
        (total[0], total[1])
    }

    /// The P2 edges (vertex, mid, vertex) of the outer faces that lie in the plane
    /// z = c_z.
    pub fn meridian_edges(&self) -> Vec<[usize; 3]> {
        let cz = self.params.center().z;
        let on = |i: usize| self.mesh.nodes[i][2] == cz;
        let mut edges = Vec::new();
        for f in &self.mesh.outer_faces {
            // Face node order: vertices 0, 1, 2, then mids (0,1), (1,2), (2,0).
            for (a, m, b) in [(0, 3, 1), (1, 4, 2), (2, 5, 0)] {
                if on(f[a]) && on(f[b]) && on(f[m]) {
                    edges.push([f[a], f[m], f[b]]);
                }
            }
        }
        edges
    }

    /// Area of the cell surface in contact (current depth > −ε_ct), deformed and on the
    /// reference sphere, whole cell (4 × the quarter) [µm²]: each P2 face sampled by a
    /// degree-2 rule on 4^[`FACE_LEVELS`] sub-triangles, a point counting with its area
    /// element where its current position is within the band.
    pub fn contact_areas(&self, y: &[f64]) -> (f64, f64) {
        let eps = self.params.plane.contact.eps;
        let rule = TriangleRule::degree(2).subdivided(FACE_LEVELS);
        let (mut a, mut a_ref) = (0.0, 0.0);
        for f in &self.mesh.outer_faces {
            let reference: [[f64; 3]; 6] = f.map(|i| self.mesh.nodes[i]);
            let current: [[f64; 3]; 6] = f.map(|i| {
                let x = self.position(y, i);
                [x.x, x.y, x.z]
            });
            for (xi, w) in rule.points.iter().zip(&rule.weights) {
                let (x, n) = face_map(&current, *xi);
                if self.substrate.eval(&Vector3::from(x)).0 + eps <= 0.0 {
                    continue;
                }
                let (_, n_ref) = face_map(&reference, *xi);
                a += w * Vector3::from(n).norm();
                a_ref += w * Vector3::from(n_ref).norm();
            }
        }
        (4.0 * a, 4.0 * a_ref)
    }

    /// Reference-volume integrals of ‖E‖_F per domain and the domains' volumes (quarter).
    pub fn mean_strain_norms(&self, y: &[f64]) -> StrainNorms {
        let mut s = StrainNorms {
            integral: [0.0; 3],
            area: [0.0; 3],
        };
        for el in &self.elements {
            let k = crate::model::ModelParams::domain_index(el.domain);
            let ue = self.element_displacements(&el.nodes, y);
            for q in 0..el.geo.jxw.len() {
                let f = deformation(&ue, &el.geo.grads[q]);
                let e = (f.transpose() * f - Matrix3::identity()) * 0.5;
                s.integral[k] += el.geo.jxw[q] * e.norm();
                s.area[k] += el.geo.jxw[q];
            }
        }
        s
    }

    /// Per-element reference-volume means of ‖E‖_F and of det F, for output.
    pub fn element_strain_and_jacobian(&self, y: &[f64]) -> Vec<(f64, f64)> {
        self.elements
            .iter()
            .map(|el| {
                let ue = self.element_displacements(&el.nodes, y);
                let (mut se, mut sj, mut v) = (0.0, 0.0, 0.0);
                for q in 0..el.geo.jxw.len() {
                    let f = deformation(&ue, &el.geo.grads[q]);
                    let e = (f.transpose() * f - Matrix3::identity()) * 0.5;
                    se += el.geo.jxw[q] * e.norm();
                    sj += el.geo.jxw[q] * f.determinant();
                    v += el.geo.jxw[q];
                }
                (se / v, sj / v)
            })
            .collect()
    }

    /// The state at time `t` as the output writers take it (`t` within the integrator's
    /// last step while the exposures are deferred).
    pub fn snapshot(&self, t: f64, y: &[f64], yp: &[f64]) -> Result<Snapshot3, String> {
        let per_el = self.element_strain_and_jacobian(y);
        Ok(Snapshot3 {
            t,
            u: (0..self.mesh.nodes.len())
                .map(|i| self.dofs.node_u(y, i))
                .collect(),
            v: (0..self.mesh.nodes.len())
                .map(|i| self.dofs.node_velocity(y, yp, i))
                .collect(),
            mu_as: self.nodal_mu_as(t, y)?,
            element_strain: per_el.iter().map(|p| p.0).collect(),
            element_jacobian: per_el.iter().map(|p| p.1).collect(),
        })
    }

    /// What `mesh3.json` records of this model, with the scene's phase end times.
    pub fn mesh_file(&self, phase_times: [f64; 4]) -> Mesh3File {
        let p = &self.params.plane;
        let c = self.params.center();
        Mesh3File {
            nodes: self.mesh.nodes.clone(),
            elements: self.mesh.elements.clone(),
            domains: self.mesh.domains.clone(),
            outer_faces: self.mesh.outer_faces.clone(),
            substrate: self.substrate,
            active: p.active,
            contact_eps: p.contact.eps,
            layer_thickness: p.adhesion.map(|a| a.e_f),
            center: [c.x, c.y, c.z],
            phase_times,
        }
    }

    /// The smallest vertical displacement over every node of the nucleus elements [µm].
    pub fn nucleus_lowest_uy(&self, y: &[f64]) -> f64 {
        self.elements
            .iter()
            .filter(|el| el.domain == Domain::Nucleus)
            .flat_map(|el| el.nodes)
            .map(|i| self.dofs.node_u(y, i)[1])
            .fold(f64::INFINITY, f64::min)
    }

    /// Total contact force on the quarter cell [pN], integrated with the band rule over
    /// the elements in the band's reach (the others add exact zeros).
    pub fn contact_force_total(&self, y: &[f64]) -> Vector3<f64> {
        let p = &self.params.plane;
        let mut total = Vector3::zeros();
        for el in &self.elements {
            let ue = self.element_displacements(&el.nodes, y);
            if !self.in_reach(el, &ue) {
                continue;
            }
            for q in 0..el.cgeo.jxw.len() {
                let nv = &self.ctab.values[q];
                let f = deformation(&ue, &el.cgeo.grads[q]);
                let mut x = Vector3::from(el.cgeo.x[q]);
                for a in 0..super::NODES {
                    for k in 0..3 {
                        x[k] += nv[a] * ue[a][k];
                    }
                }
                total += contact_force3(&self.substrate, &p.contact, &x, f.determinant())
                    * el.cgeo.jxw[q];
            }
        }
        total
    }

    /// Weight of the quarter cell at full gravity [pN]: g ∫ ρ dV.
    pub fn weight(&self) -> f64 {
        self.elements
            .iter()
            .map(|el| el.mass.iter().flatten().sum::<f64>())
            .sum::<f64>()
            * self.params.plane.gravity
    }

    /// Reference volume of the quarter cell's domain `d` (all domains: `None`) [µm³].
    pub fn volume(&self, d: Option<Domain>) -> f64 {
        self.elements
            .iter()
            .filter(|el| d.is_none_or(|d| el.domain == d))
            .map(|el| el.geo.jxw.iter().sum::<f64>())
            .sum()
    }

    pub(crate) fn element_displacements(
        &self,
        nodes: &[usize; super::NODES],
        y: &[f64],
    ) -> super::Nodal {
        let mut ue = [[0.0; 3]; super::NODES];
        for a in 0..super::NODES {
            for k in 0..3 {
                let d = self.dofs.u[nodes[a]][k];
                if d != NONE {
                    ue[a][k] = y[d];
                }
            }
        }
        ue
    }
}
