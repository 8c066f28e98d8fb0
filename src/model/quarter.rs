//! What only the 3-D cell reports (MODEL.md §7, §10): the contact radius along the
//! meridian in the plane z = 0 (the 2-D scene's measure), the contact area in both frames
//! (whole cell: four quarters or eight eighths) and its equivalent radius, the penetration
//! depth, and its records for the output files.
//!
//! The records are always of the quarter x ≥ 0, z ≥ 0: an eighth cell (0 ≤ z ≤ x) is
//! unfolded by its diagonal mirror x ↔ z ([`Unfold`]), so that every reader of the files
//! (figures, VTU, movies) sees the same quarter whichever wedge was computed.

use nalgebra::{Vector2, Vector3};

use super::QuarterCell;
use super::observables::{QuarterMeshFile, QuarterObservables, QuarterSnapshot};
use super::observe::add_band_lengths;
use crate::fem::tet10::{FLIP, face_map};
use crate::fem::{TetMesh, TriangleRule, Wedge};
use crate::physics::Substrate;

/// Sub-triangle levels of the rule sampling each P2 surface face for the contact area.
const FACE_LEVELS: u32 = 3;

impl QuarterCell {
    /// The 3-D quantities in state `y`.
    pub fn observe_quarter(&self, y: &[f64]) -> QuarterObservables {
        let (a, a_ref) = self.contact_areas(y);
        let penetration_depth = match self.params.substrate {
            Substrate::Pillars(p) => {
                let pb = self.mesh.points.nucleus_bottom;
                let y_pb = self.mesh.nodes[pb][1] + self.dofs.node_u(y, pb)[1];
                (p.y_top - y_pb).max(0.0)
            }
            Substrate::Flat { .. } => 0.0,
        };
        QuarterObservables {
            contact_area: a,
            contact_area_ref: a_ref,
            contact_radius_equiv: (a / std::f64::consts::PI).sqrt(),
            penetration_depth,
        }
    }

    /// Length of the meridian (the outer boundary in the plane z = c_z) in contact, i.e.
    /// whose current position lies within ε_ct of the substrate, along the deformed and
    /// the reference curve: `(deformed, reference)` \[µm\], as the half-plane models'
    /// contact radius. The points of that plane stay in it (u_z = 0 there).
    pub fn meridian_contact_lengths(&self, y: &[f64]) -> (f64, f64) {
        let eps = self.params.contact.eps;
        let cz = 0.0;
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
        let cz = 0.0;
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
    /// reference sphere, whole cell (4 × the quarter, 8 × the eighth) \[µm²\]: each P2 face
    /// sampled by a
    /// degree-2 rule on 4^`FACE_LEVELS` sub-triangles, a point counting with its area
    /// element where its current position is within the band.
    pub fn contact_areas(&self, y: &[f64]) -> (f64, f64) {
        let eps = self.params.contact.eps;
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
        let copies = self.mesh.params.wedge.copies();
        (copies * a, copies * a_ref)
    }

    /// The state at time `t` as the output writers take it (`t` within the integrator's
    /// last step while the exposures are deferred).
    pub fn snapshot(
        &self,
        t: f64,
        y: &[f64],
        yp: &[f64],
    ) -> Result<QuarterSnapshot, super::history::OutsideHistory> {
        let per_el = self.element_strain_and_jacobian(y);
        let unfold = Unfold::new(&self.mesh);
        Ok(QuarterSnapshot {
            t,
            u: unfold.vectors(
                (0..self.mesh.nodes.len()).map(|i| self.dofs.node_u(y, i)),
                [0.0; 3],
            ),
            v: unfold.vectors(
                (0..self.mesh.nodes.len()).map(|i| self.dofs.node_velocity(y, yp, i)),
                [0.0; 3],
            ),
            mu_as: unfold.nodal(self.nodal_mu_as(t, y)?),
            element_strain: unfold.elemental(per_el.iter().map(|p| p.0).collect()),
            element_jacobian: unfold.elemental(per_el.iter().map(|p| p.1).collect()),
        })
    }

    /// What `mesh3.json` records of this model, with the scene's phase end times.
    pub fn mesh_file(&self, phase_times: [f64; 4]) -> QuarterMeshFile {
        let p = &self.params;
        let unfold = Unfold::new(&self.mesh);
        QuarterMeshFile {
            nodes: unfold.vectors(self.mesh.nodes.iter().copied(), self.mesh.params.center),
            elements: unfold.elements(&self.mesh.elements),
            domains: unfold.elemental(self.mesh.domains.clone()),
            outer_faces: unfold.faces(&self.mesh.outer_faces),
            substrate: self.substrate,
            active: p.active,
            contact_eps: p.contact.eps,
            layer_thickness: p.adhesion.map(|a| a.e_f),
            center: [p.center[0], p.center[1], 0.0],
            phase_times,
        }
    }
}

/// The quarter cell from the eighth 0 ≤ z ≤ x and its mirror image under x ↔ z (the
/// diagonal plane's nodes shared), as the records give it; nothing to do for the quarter.
/// Mirror node `i` is `mirror[i]`: `i` itself on the diagonal, else a new node after the
/// eighth's. Mirrored tetrahedra and faces are reversed to keep their orientation.
struct Unfold {
    /// Per node of the eighth, its mirror image's index (empty: the mesh is a quarter).
    mirror: Vec<usize>,
    /// The eighth's nodes off the diagonal, in order (the new nodes).
    off: Vec<usize>,
}

impl Unfold {
    fn new(mesh: &TetMesh) -> Self {
        if mesh.params.wedge != Wedge::Eighth {
            return Self {
                mirror: Vec::new(),
                off: Vec::new(),
            };
        }
        // The nodes their own images: those on the diagonal plane, and on the axis (the
        // eighth's nodes with x = c_x).
        let n = mesh.nodes.len();
        let mut on_plane = vec![false; n];
        for &i in mesh.symmetry_diagonal.iter().chain(&mesh.symmetry_x) {
            on_plane[i] = true;
        }
        let mut mirror = vec![0; n];
        let mut off = Vec::new();
        for i in 0..n {
            if on_plane[i] {
                mirror[i] = i;
            } else {
                mirror[i] = n + off.len();
                off.push(i);
            }
        }
        Self { mirror, off }
    }

    /// Nodal vectors: the mirror images have their x and z measured from `about` swapped
    /// (positions about the centre; displacements and velocities about 0).
    fn vectors(&self, v: impl Iterator<Item = [f64; 3]>, about: [f64; 3]) -> Vec<[f64; 3]> {
        let mut v: Vec<[f64; 3]> = v.collect();
        let [a, _, b] = about;
        let images: Vec<[f64; 3]> = self
            .off
            .iter()
            .map(|&i| [a + v[i][2] - b, v[i][1], b + v[i][0] - a])
            .collect();
        v.extend(images);
        v
    }

    /// Nodal scalars: the mirror images carry the same values.
    fn nodal<T: Clone>(&self, mut v: Vec<T>) -> Vec<T> {
        let images: Vec<T> = self.off.iter().map(|&i| v[i].clone()).collect();
        v.extend(images);
        v
    }

    /// Per-element values: each element's image after all the elements.
    fn elemental<T: Clone>(&self, mut v: Vec<T>) -> Vec<T> {
        if !self.mirror.is_empty() {
            v.extend_from_within(..);
        }
        v
    }

    /// The tetrahedra and their reversed mirror images.
    fn elements(&self, elements: &[[usize; 10]]) -> Vec<[usize; 10]> {
        let mut out = elements.to_vec();
        if !self.mirror.is_empty() {
            out.extend(elements.iter().map(|el| FLIP.map(|k| self.mirror[el[k]])));
        }
        out
    }

    /// The outer faces and their reversed mirror images (vertices 0, 2, 1; mid-nodes
    /// (0, 2), (2, 1), (1, 0)).
    fn faces(&self, faces: &[[usize; 6]]) -> Vec<[usize; 6]> {
        let mut out = faces.to_vec();
        if !self.mirror.is_empty() {
            out.extend(
                faces
                    .iter()
                    .map(|f| [0, 2, 1, 5, 4, 3].map(|k| self.mirror[f[k]])),
            );
        }
        out
    }
}
