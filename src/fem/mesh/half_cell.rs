//! The P2 mesh of the reference half cell (MODEL.md §2).
//!
//! The half disk x ≥ 0 of radius r_c about the centre c is split into three conforming
//! sub-domains by the circles r_n (nucleus) and r_cp (inner face of the membrane). Element
//! edges follow both circles and the outer boundary; the P2 mid-nodes of edges on the three
//! circles lie on the circle (curved isoparametric edges), all other mid-nodes are edge
//! midpoints.
//!
//! # How the mesh is built
//!
//! Only the vertices' *placement* is done here; the triangulation and its quality
//! refinement are spade's constrained Delaunay triangulation and Ruppert-style refinement.
//!
//! 1. **Size function** (the grading law): h(y) = [h_b + (h_n − h_b) s(y)] / refine with
//!    s(y) = clamp((y − y_cb)/(y_nb − y_cb), 0, 1), linear in height from the cell bottom
//!    y_cb = c_y − r_c (size h_b) to the nucleus bottom y_nb = c_y − r_n (size h_n), and
//!    h_n above. The default grades 0.3 µm → 1 µm over 5 µm, a ratio of 0.14 per µm.
//! 2. **Membrane**: L = max(1, round(refine)) layers of concentric rings between r_cp and
//!    r_c. Vertices on neighbouring rings are staggered (half a spacing apart), so each
//!    layer is a zig-zag band of isosceles triangles. The tangential spacing is
//!    min(h, 2 t/L) for the membrane thickness t = r_c − r_cp: the band's triangles then
//!    have base angles ≥ 45°, and the membrane is at least one element thick; with a
//!    surface cap (`h_surface`, [`MeshParams::surface_cap`]) at most that cap. (For
//!    refine < 1 the membrane keeps this spacing: it cannot coarsen without skinny
//!    elements, so a coarse mesh has more than ¼ of the default's elements.)
//! 3. **Nucleus circle** and **symmetry line** x = c_x: vertices spaced by h along the
//!    curve (equidistributing ∫ ds/h), at least 8 segments per half circle (arcs ≤ 22.5°,
//!    so coarse curved elements stay valid). Every ring's ends and the named points are
//!    vertices; near a ring's end the spacing on x = c_x shrinks to that ring's end
//!    segment (size min(h, l_end + ½|y − y_end|)), so the right-angled corners there keep
//!    good angles.
//! 4. **Interior**: a triangular lattice graded in y (rows √3/2 · h apart, spacing h
//!    along a row, alternate rows shifted by h/2), keeping only points at least 0.6 h from
//!    the circles and from x = c_x so that no lattice point encroaches a boundary segment.
//! 5. spade builds the constrained Delaunay triangulation (circles and x = c_x as
//!    constraint edges) and refines it to the angle limit `min_angle_deg` ([`MIN_ANGLE_DEG`] = 28°),
//!    never splitting a constraint edge — so every vertex on a circle stays exactly on it.
//!    The achieved minimum angle is ≥ 26.9° for the default cell at refine 0.5, 1, 2.
//! 6. Elements are classified by the side of the circle polygons their centroid lies on,
//!    mid-nodes are added (on the circle for circle edges), and every element's
//!    isoparametric Jacobian is checked positive *everywhere* on the element (its exact
//!    minimum over the triangle, det J being a quadratic in ξ).
//!
//! Node numbering: vertices first (those on x = c_x, then the rings inside out, then the
//! lattice, then spade's Steiner points), mid-nodes after them in order of first use.
//! Generation is deterministic and takes a few milliseconds.

use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI};
use std::fmt;
use std::path::Path;

use serde::Serialize;
use spade::{
    AngleLimit, ConstrainedDelaunayTriangulation, Point2, RefinementParameters, Triangulation,
};

use super::super::element::{CellMesh, Lagrange, extremes};
use super::super::quadrature::TriangleRule;
use super::super::tri6::{self, EDGES, P2Tabulation, REFERENCE_NODES, Tri6};
use super::{Domain, MeshError, NamedPoints};

/// Geometry and mesh-size parameters of the half cell (µm). A case's are built by
/// [`crate::scene::terms::mesh_params`], which holds the defaults (the paper's cell and
/// mesh, MODEL.md §2, §9).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshParams {
    /// Cell centre c; the symmetry line is x = c_x.
    pub center: [f64; 2],
    /// Nucleus radius r_n.
    pub r_n: f64,
    /// Inner radius of the membrane r_cp.
    pub r_cp: f64,
    /// Cell radius r_c.
    pub r_c: f64,
    /// Element size at the cell bottom (before `refine`).
    pub h_bottom: f64,
    /// Element size in the nucleus and above (before `refine`).
    pub h_nucleus: f64,
    /// Refinement factor: every size is divided by it (2 halves all sizes, ≈ 4× the
    /// elements).
    pub refine: f64,
    /// Largest size at the cell surface below the centre (before `refine`), if any
    /// ([`MeshParams::surface_cap`]).
    pub h_surface: Option<f64>,
    /// Angle limit (degrees) of the Delaunay refinement, in (0, 33]
    /// ([`MIN_ANGLE_DEG`] unless a test asks otherwise).
    pub min_angle_deg: f64,
}

/// How fast the surface cap ([`MeshParams::surface_cap`]) grows inward from r_cp and
/// upward from the centre's height (µm of size per µm).
pub const SURFACE_GRADING: f64 = 0.5;

/// The generator's angle limit for the Delaunay refinement (degrees): the largest that
/// terminates reliably with the graded sizes.
pub const MIN_ANGLE_DEG: f64 = 28.0;

/// Largest number of elements [`Mesh::generate`] accepts to build (estimated from the
/// sizes before meshing), so that a typo in a case file fails fast instead of exhausting
/// memory.
pub const MAX_ELEMENTS: f64 = 4.0e6;

/// Minimum distance of an interior lattice point from a circle or the symmetry line, in
/// units of the local size h (see the module documentation, step 4).
const LATTICE_CLEARANCE: f64 = 0.6;

/// Fewest segments on a half circle: arcs of at most π/8 (22.5°) keep the curved P2
/// elements of very coarse meshes valid (the mid-node's offset from the chord is
/// r(1 − cos(φ/2)) ≈ chord · φ/8, under 5 % of the chord).
const MIN_CIRCLE_SEGMENTS: usize = 8;

/// Largest tangential spacing in the membrane, in units of the layer thickness.
const MEMBRANE_ASPECT: f64 = 2.0;

impl MeshParams {
    /// Checks every field; the error names the field and the rule it breaks.
    pub fn validate(&self) -> Result<(), MeshError> {
        super::check_cell(&self.center, self)?;
        if !(self.min_angle_deg > 0.0 && self.min_angle_deg <= 33.0) {
            return super::invalid(
                "min_angle_deg",
                self.min_angle_deg,
                "must lie in (0, 33] (larger limits need not terminate)",
            );
        }
        let far = self.center[0].abs().max(self.center[1].abs());
        let h_min = self.h_bottom.min(self.h_nucleus) / self.refine;
        super::check_scale(h_min, far, self.estimated_elements(), MAX_ELEMENTS)
    }

    /// Estimated number of elements of the mesh these parameters give, computed from the
    /// sizes without meshing: ≈ 2.3 elements per h² of area at the finest size
    /// min(h_bottom, h_nucleus) / refine, plus the membrane band. [`MeshParams::validate`]
    /// refuses more than [`MAX_ELEMENTS`]. Meaningful for radii and sizes that pass the
    /// other checks of `validate` (finite, positive, r_cp < r_c).
    pub fn estimated_elements(&self) -> f64 {
        let h_min = self.h_bottom.min(self.h_nucleus) / self.refine;
        let area = 0.5 * PI * self.r_c * self.r_c;
        let layers = self.membrane_layers() as f64;
        let l_m = h_min.min(MEMBRANE_ASPECT * (self.r_c - self.r_cp) / layers);
        2.3 * area / (h_min * h_min) + 2.0 * layers * PI * self.r_c / l_m
    }

    /// Expected number of elements of the mesh, from the sizes without meshing: 2.44
    /// triangles per h(y)² of area inside r_cp and 3.07 per h(y) of the half circle r_c
    /// in each membrane layer, integrated over the grading law [`MeshParams::size_at`]
    /// (midpoint rule). Within 6 % of the generator's counts on the paper's cell at
    /// refine 1 to 8 and h_bottom 0.05 to 0.3 µm (an overestimate by 2× at refine 0.5).
    /// [`MeshParams::estimated_elements`] is the generator's upper bound instead.
    pub fn expected_elements(&self) -> f64 {
        const N: usize = 2000;
        let [_, cy] = self.center;
        let (rc, rcp) = (self.r_c, self.r_cp);
        let dy = 2.0 * rcp / N as f64;
        let inside: f64 = (0..N)
            .map(|k| {
                let y = cy - rcp + (k as f64 + 0.5) * dy;
                let half_width = (rcp * rcp - (y - cy) * (y - cy)).max(0.0).sqrt();
                half_width / self.size_at(y).powi(2) * dy
            })
            .sum();
        let dth = PI / N as f64;
        let rim: f64 = (0..N)
            .map(|k| {
                let th = -0.5 * PI + (k as f64 + 0.5) * dth;
                rc * dth / self.size_at(cy + rc * th.sin())
            })
            .sum();
        2.44 * inside + 3.07 * rim * self.membrane_layers() as f64
    }

    /// Target element size h(y) at height y (µm), the grading law of the module
    /// documentation: linear from h_bottom at the cell bottom to h_nucleus at the nucleus
    /// bottom, constant above, all divided by `refine`.
    pub fn size_at(&self, y: f64) -> f64 {
        let y_cb = self.center[1] - self.r_c;
        let y_nb = self.center[1] - self.r_n;
        let s = ((y - y_cb) / (y_nb - y_cb)).clamp(0.0, 1.0);
        (self.h_bottom + (self.h_nucleus - self.h_bottom) * s) / self.refine
    }

    /// The surface cap on the size at a point at distance `r` from the centre c and height
    /// `y` (µm), if `h_surface` is set: (h_surface + ½ max(0, r_cp − r) + ½ max(0, y − c_y))
    /// / refine. The size there is the smaller of this and [`MeshParams::size_at`]: at most
    /// h_surface on the cell's lower half from r_cp outward, growing back to the grading
    /// law half a µm per µm inward and above the centre.
    pub fn surface_cap(&self, r: f64, y: f64) -> Option<f64> {
        let h = self.h_surface?;
        let inward = (self.r_cp - r).max(0.0);
        let up = (y - self.center[1]).max(0.0);
        Some((h + SURFACE_GRADING * (inward + up)) / self.refine)
    }

    /// The element size at a point at distance `r` from the centre and height `y`: the
    /// grading law, capped near the surface ([`MeshParams::surface_cap`]).
    pub fn size_near(&self, r: f64, y: f64) -> f64 {
        let h = self.size_at(y);
        self.surface_cap(r, y).map_or(h, |c| c.min(h))
    }

    /// Number of element layers through the membrane: max(1, round(refine)).
    pub fn membrane_layers(&self) -> usize {
        // refine is validated finite and positive; the cap keeps the cast meaningful.
        (self.refine.round().clamp(1.0, 1.0e6)) as usize
    }
}

/// A P2 triangle mesh of the half cell.
///
/// Nodes `0..n_vertices` are element vertices, the rest mid-side nodes. Element node order
/// is that of [`crate::fem::tri6`]: vertices counter-clockwise, then mid(0,1), mid(1,2), mid(2,0).
#[derive(Debug, Clone, Serialize)]
pub struct Mesh {
    /// The parameters the mesh was built from.
    pub params: MeshParams,
    /// Node coordinates (reference configuration, µm).
    pub nodes: Vec<[f64; 2]>,
    /// Number of vertex nodes; they come first in `nodes`.
    pub n_vertices: usize,
    /// Element connectivity, six nodes each.
    pub elements: Vec<[usize; 6]>,
    /// Domain of each element.
    pub domains: Vec<Domain>,
    /// Boundary edges on r = r_c as (vertex, mid, vertex), ordered along the boundary from
    /// the cell bottom counter-clockwise (through x > 0) to the cell top; consecutive
    /// edges share their end vertices.
    pub outer_edges: Vec<[usize; 3]>,
    /// Edges on the nucleus circle r = r_n, ordered likewise (bottom to top).
    pub nucleus_edges: Vec<[usize; 3]>,
    /// Edges on the membrane's inner circle r = r_cp, ordered likewise.
    pub membrane_inner_edges: Vec<[usize; 3]>,
    /// Nodes on the symmetry line x = c_x (coordinate exactly c_x), sorted by y.
    pub symmetry_nodes: Vec<usize>,
    /// Reference points for output.
    pub points: NamedPoints,
}

/// Steps 6 and 7 of [`Mesh::generate`]: the domain of each triangle (by its centroid
/// against the nucleus and cytoplasm rings), the mid-nodes (on the circle for the curved
/// rings' chords), and the edges along the three circles.
fn quadratic_elements(
    prm: &MeshParams,
    rings: &[Ring],
    mut verts: Vec<[f64; 2]>,
    tris: &[[usize; 3]],
) -> Result<MeshParts, MeshError> {
    let c = prm.center;
    // 6. Domains.
    let (nuc_ring, cp_ring) = (&rings[0], &rings[1]);
    let mut domains = Vec::with_capacity(tris.len());
    for t in tris {
        let p = [
            (verts[t[0]][0] + verts[t[1]][0] + verts[t[2]][0]) / 3.0,
            (verts[t[0]][1] + verts[t[1]][1] + verts[t[2]][1]) / 3.0,
        ];
        let d = if nuc_ring.contains(&verts, c, p) {
            Domain::Nucleus
        } else if cp_ring.contains(&verts, c, p) {
            Domain::Cytoplasm
        } else {
            Domain::Membrane
        };
        domains.push(d);
    }

    // 7. Mid-nodes.
    let n_vertices = verts.len();
    let mut curved: HashMap<(usize, usize), (f64, f64)> = HashMap::new();
    for ring in rings.iter().filter(|r| r.curved) {
        for i in 1..ring.vertices.len() {
            let (a, bb) = (ring.vertices[i - 1], ring.vertices[i]);
            let phi = 0.5 * (ring.angles[i - 1] + ring.angles[i]);
            curved.insert((a.min(bb), a.max(bb)), (ring.radius, phi));
        }
    }
    let mut mid_of: HashMap<(usize, usize), usize> = HashMap::new();
    let mut elements = Vec::with_capacity(tris.len());
    for t in tris {
        let mut el = [t[0], t[1], t[2], 0, 0, 0];
        for (k, e) in EDGES.iter().enumerate() {
            let (a, bb) = (el[e[0]], el[e[2]]);
            let key = (a.min(bb), a.max(bb));
            let id = *mid_of.entry(key).or_insert_with(|| {
                let p = match curved.get(&key) {
                    Some(&(r, phi)) => [c[0] + r * phi.cos(), c[1] + r * phi.sin()],
                    None => [
                        0.5 * (verts[a][0] + verts[bb][0]),
                        0.5 * (verts[a][1] + verts[bb][1]),
                    ],
                };
                verts.push(p);
                verts.len() - 1
            });
            el[3 + k] = id;
        }
        elements.push(el);
    }
    let nodes = verts;

    let ring_edges = |ring: &Ring| -> Vec<[usize; 3]> {
        ring.vertices
            .windows(2)
            .map(|w| {
                let key = (w[0].min(w[1]), w[0].max(w[1]));
                [w[0], mid_of.get(&key).copied().unwrap_or(usize::MAX), w[1]]
            })
            .collect()
    };
    let outer_edges = ring_edges(&rings[rings.len() - 1]);
    let nucleus_edges = ring_edges(&rings[0]);
    let membrane_inner_edges = ring_edges(&rings[1]);
    for (name, edges) in [
        ("outer", &outer_edges),
        ("nucleus", &nucleus_edges),
        ("membrane inner", &membrane_inner_edges),
    ] {
        if let Some(e) = edges.iter().find(|e| e[1] == usize::MAX) {
            return Err(MeshError::Inconsistent(format!(
                "{name} circle edge {:?}–{:?} is not an element edge",
                nodes[e[0]], nodes[e[2]]
            )));
        }
    }
    let circles = [outer_edges, nucleus_edges, membrane_inner_edges];
    Ok(MeshParts::new(
        prm, nodes, n_vertices, elements, domains, circles,
    ))
}

/// What a mesh builder makes; [`Mesh::assemble`] adds the rest.
pub(crate) struct MeshParts {
    params: MeshParams,
    nodes: Vec<[f64; 2]>,
    n_vertices: usize,
    elements: Vec<[usize; 6]>,
    domains: Vec<Domain>,
    /// Edges on the outer, nucleus and membrane-inner circles, in that order.
    circles: [Vec<[usize; 3]>; 3],
}

impl MeshParts {
    pub(crate) fn new(
        params: &MeshParams,
        nodes: Vec<[f64; 2]>,
        n_vertices: usize,
        elements: Vec<[usize; 6]>,
        domains: Vec<Domain>,
        circles: [Vec<[usize; 3]>; 3],
    ) -> Self {
        MeshParts {
            params: params.clone(),
            nodes,
            n_vertices,
            elements,
            domains,
            circles,
        }
    }
}

/// Size and shape statistics of a mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshQuality {
    /// Number of elements.
    pub elements: usize,
    /// Number of nodes (vertices and mid-nodes).
    pub nodes: usize,
    /// Number of vertices.
    pub vertices: usize,
    /// Displacement unknowns before boundary conditions, 2 · nodes.
    pub displacement_dofs: usize,
    /// Elements in the nucleus.
    pub nucleus_elements: usize,
    /// Elements in the cytoplasm.
    pub cytoplasm_elements: usize,
    /// Elements in the membrane.
    pub membrane_elements: usize,
    /// Smallest interior angle of the straight-sided triangles (degrees).
    pub min_angle_deg: f64,
    /// Largest interior angle of the straight-sided triangles (degrees).
    pub max_angle_deg: f64,
    /// Shortest vertex-to-vertex edge.
    pub min_edge: f64,
    /// Longest vertex-to-vertex edge.
    pub max_edge: f64,
    /// Mean edge length of the elements touching the lowest 0.5 µm of the cell.
    pub mean_edge_bottom: f64,
    /// Mean edge length of the nucleus elements.
    pub mean_edge_nucleus: f64,
    /// Minimum over 720 radial lines of the number of distinct membrane elements the line
    /// crosses between r_cp and r_c.
    pub elements_through_membrane: usize,
    /// Smallest ratio min det J / max det J over one element (1 for affine elements).
    pub min_jacobian_ratio: f64,
}

impl fmt::Display for MeshQuality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "elements {} (nucleus {}, cytoplasm {}, membrane {}); nodes {} ({} vertices); {} displacement dofs",
            self.elements,
            self.nucleus_elements,
            self.cytoplasm_elements,
            self.membrane_elements,
            self.nodes,
            self.vertices,
            self.displacement_dofs
        )?;
        writeln!(
            f,
            "angles {:.1}°–{:.1}°; edges {:.3}–{:.3} µm; mean edge at bottom {:.3} µm, in nucleus {:.3} µm",
            self.min_angle_deg,
            self.max_angle_deg,
            self.min_edge,
            self.max_edge,
            self.mean_edge_bottom,
            self.mean_edge_nucleus
        )?;
        write!(
            f,
            "elements through membrane ≥ {}; min det J ratio {:.3}",
            self.elements_through_membrane, self.min_jacobian_ratio
        )
    }
}

/// A circle of vertices used during generation: radius, whether it is one of the three
/// physical circles (curved mid-nodes), vertex indices and their angles, bottom to top.
struct Ring {
    radius: f64,
    curved: bool,
    vertices: Vec<usize>,
    angles: Vec<f64>,
}

impl Ring {
    /// True if the point p (angle φ ∈ [−π/2, π/2] about c) is on the centre side of this
    /// ring's polygon (chords between consecutive vertices, closed by x = c_x).
    fn contains(&self, verts: &[[f64; 2]], c: [f64; 2], p: [f64; 2]) -> bool {
        let phi = (p[1] - c[1]).atan2(p[0] - c[0]);
        // First index whose angle exceeds φ: the chord (i−1, i) spans φ.
        let i = self
            .angles
            .partition_point(|&a| a <= phi)
            .clamp(1, self.angles.len() - 1);
        let a = verts[self.vertices[i - 1]];
        let b = verts[self.vertices[i]];
        // The ring runs counter-clockwise about c: inside is to the left of a → b.
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0.0
    }
}

/// Positions s₀ = 0 < s₁ < … < s_m = `length` along a curve equidistributing ∫ ds / h(s),
/// with m = max(`min_segments`, round(∫ ds/h)).
fn graded_division(length: f64, h: impl Fn(f64) -> f64, min_segments: usize) -> Vec<f64> {
    const SAMPLES: usize = 4000;
    let ds = length / SAMPLES as f64;
    let mut cum = Vec::with_capacity(SAMPLES + 1);
    cum.push(0.0);
    let mut acc = 0.0;
    for k in 0..SAMPLES {
        let s0 = k as f64 * ds;
        // Simpson on each sub-interval.
        acc += ds / 6.0 * (1.0 / h(s0) + 4.0 / h(s0 + 0.5 * ds) + 1.0 / h(s0 + ds));
        cum.push(acc);
    }
    let m = (acc.round() as usize).max(min_segments);
    let mut out = Vec::with_capacity(m + 1);
    out.push(0.0);
    let mut k = 0;
    for i in 1..m {
        let target = acc * i as f64 / m as f64;
        while k + 1 < SAMPLES && cum[k + 1] < target {
            k += 1;
        }
        let t = (target - cum[k]) / (cum[k + 1] - cum[k]);
        out.push((k as f64 + t) * ds);
    }
    out.push(length);
    out
}

/// Constrained Delaunay triangulation of `input` with `constraints`, refined by spade to
/// the angle limit without splitting constraint edges. Returns all vertices (the input
/// ones first, in order, then the Steiner points) and the triangles (counter-clockwise).
/// A panic inside spade (it asserts on precision loss) is turned into an error.
#[allow(clippy::type_complexity)]
fn triangulate(
    input: &[[f64; 2]],
    constraints: &[[usize; 2]],
    min_angle_deg: f64,
) -> Result<(Vec<[f64; 2]>, Vec<[usize; 3]>), MeshError> {
    let run = || -> Result<(Vec<[f64; 2]>, Vec<[usize; 3]>), MeshError> {
        let pts: Vec<Point2<f64>> = input.iter().map(|p| Point2::new(p[0], p[1])).collect();
        let mut conflicts = 0usize;
        let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::try_bulk_load_cdt(
            pts,
            constraints.to_vec(),
            |_| conflicts += 1,
        )
        .map_err(|e| MeshError::Triangulation(e.to_string()))?;
        if conflicts > 0 || cdt.num_vertices() != input.len() {
            return Err(MeshError::Inconsistent(format!(
                "{conflicts} conflicting constraints, {} of {} vertices kept",
                cdt.num_vertices(),
                input.len()
            )));
        }
        // The half disk is convex, so every face of the triangulation is inside the cell.
        // (spade's `exclude_outer_faces` is not wanted: it decides inside/outside by the
        // parity of constraint loops crossed, which would drop the nested sub-domains.)
        let result = cdt.refine(
            RefinementParameters::<f64>::new()
                .with_angle_limit(AngleLimit::from_deg(min_angle_deg))
                .keep_constraint_edges(),
        );
        if !result.refinement_complete {
            return Err(MeshError::RefinementIncomplete {
                vertices: cdt.num_vertices(),
            });
        }
        let verts: Vec<[f64; 2]> = cdt
            .vertices()
            .map(|v| {
                let p = v.position();
                [p.x, p.y]
            })
            .collect();
        // spade keeps the input order; refinement appends Steiner points.
        if verts[..input.len()] != input[..] {
            return Err(MeshError::Inconsistent(
                "vertex order not preserved by the triangulation".into(),
            ));
        }
        let tris = cdt
            .inner_faces()
            .map(|f| f.vertices().map(|v| v.fix().index()))
            .collect();
        Ok((verts, tris))
    };
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(run)).unwrap_or_else(|payload| {
        let msg = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".into());
        Err(MeshError::Triangulation(format!("spade panicked: {msg}")))
    })
}

/// Builder state for the vertex set and the constraint edges.
struct Builder {
    verts: Vec<[f64; 2]>,
    constraints: Vec<[usize; 2]>,
}

impl Builder {
    fn add(&mut self, p: [f64; 2]) -> usize {
        self.verts.push(p);
        self.verts.len() - 1
    }
    fn chain(&mut self, ids: &[usize]) {
        for w in ids.windows(2) {
            self.constraints.push([w[0], w[1]]);
        }
    }
}

/// The ring radii, inside out: the nucleus r_n, then the `layers` + 1 membrane rings from
/// r_cp to r_c, `t_layer` apart; each with whether it is a physical circle (curved).
fn ring_radii(prm: &MeshParams, layers: usize, t_layer: f64) -> Vec<(f64, bool)> {
    let mut radii = vec![(prm.r_n, true)];
    for k in 0..=layers {
        let r = if k == layers {
            prm.r_c
        } else {
            prm.r_cp + k as f64 * t_layer
        };
        radii.push((r, k == 0 || k == layers));
    }
    radii
}

/// The vertex angles of each ring, bottom (−π/2) to top (π/2): the nucleus spaced by h
/// along its arc; the membrane rings spaced by min(h, MEMBRANE_ASPECT · t_layer) along
/// the mid-membrane circle, alternate rings staggered by half a spacing (module
/// documentation, step 2), the outer ring r_c on the unstaggered angles.
fn ring_angles(
    prm: &MeshParams,
    radii: &[(f64, bool)],
    layers: usize,
    t_layer: f64,
) -> Vec<Vec<f64>> {
    let c = prm.center;
    let h = |y: f64| prm.size_at(y);
    let arc_y = |r: f64, s: f64| c[1] + r * (s / r - FRAC_PI_2).sin();
    let to_angles =
        |r: f64, div: Vec<f64>| -> Vec<f64> { div.iter().map(|s| s / r - FRAC_PI_2).collect() };
    // Membrane base angles, from the spacing along the mid-membrane circle.
    let r_mid = 0.5 * (prm.r_cp + prm.r_c);
    let l_cap = MEMBRANE_ASPECT * t_layer;
    let base = to_angles(
        r_mid,
        graded_division(
            PI * r_mid,
            |s| prm.size_near(r_mid, arc_y(r_mid, s)).min(l_cap),
            MIN_CIRCLE_SEGMENTS,
        ),
    );
    let staggered = {
        let mut a = vec![-FRAC_PI_2];
        a.extend(base.windows(2).map(|w| 0.5 * (w[0] + w[1])));
        a.push(FRAC_PI_2);
        a
    };
    radii
        .iter()
        .enumerate()
        .map(|(k, &(r, _))| {
            if k == 0 {
                to_angles(
                    r,
                    graded_division(PI * r, |s| h(arc_y(r, s)), MIN_CIRCLE_SEGMENTS),
                )
            } else if (layers - (k - 1)) % 2 == 0 {
                base.clone()
            } else {
                staggered.clone()
            }
        })
        .collect()
}

/// The key vertices on the symmetry line x = c_x: their heights, ascending, and their
/// vertex indices.
struct Keys {
    ys: Vec<f64>,
    ids: Vec<usize>,
}

impl Keys {
    /// The key vertex at height exactly `y`.
    fn of(&self, y: f64) -> Result<usize, MeshError> {
        self.ys
            .iter()
            .position(|&k| k == y)
            .map(|i| self.ids[i])
            .ok_or_else(|| MeshError::Inconsistent(format!("no key vertex at y = {y}")))
    }
}

/// Adds the vertices of the symmetry line x = c_x and its constraint edges, and returns
/// its key vertices (each ring's ends and the centre). Between keys the line is graded
/// with size min(h(y), l_k + ½|y − y_k|) over the ring ends y_k, l_k being the length of
/// the ring's segment there: a ring segment meets x = 0 at a right angle, and a much
/// longer segment along x = 0 would leave a skinny corner triangle that the refinement
/// cannot fix without splitting a constraint.
fn symmetry_line(
    b: &mut Builder,
    prm: &MeshParams,
    radii: &[(f64, bool)],
    ring_angles: &[Vec<f64>],
) -> Keys {
    let c = prm.center;
    let mut ends: Vec<(f64, f64)> = Vec::new();
    for (&(r, _), ang) in radii.iter().zip(ring_angles) {
        let n = ang.len();
        ends.push((c[1] - r, r * (ang[1] - ang[0])));
        ends.push((c[1] + r, r * (ang[n - 1] - ang[n - 2])));
    }
    let h_sym = |y: f64| {
        ends.iter()
            .map(|&(yk, lk)| lk + 0.5 * (y - yk).abs())
            .fold(prm.size_at(y), f64::min)
    };
    let mut keys: Vec<f64> = ends.iter().map(|e| e.0).collect();
    keys.push(c[1]);
    keys.sort_by(f64::total_cmp);
    let mut sym_ids = Vec::new();
    let mut key_id: Vec<usize> = Vec::with_capacity(keys.len());
    for (i, &y) in keys.iter().enumerate() {
        if i > 0 {
            let y0 = keys[i - 1];
            let div = graded_division(y - y0, |s| h_sym(y0 + s), 1);
            for s in &div[1..div.len() - 1] {
                sym_ids.push(b.add([c[0], y0 + s]));
            }
        }
        let id = b.add([c[0], y]);
        sym_ids.push(id);
        key_id.push(id);
    }
    b.chain(&sym_ids);
    Keys {
        ys: keys,
        ids: key_id,
    }
}

/// Adds each ring's vertices about the centre `c` at its `angles` and its constraint
/// edges; the ring's ends are the key vertices on x = c_x.
fn ring_vertices(
    b: &mut Builder,
    c: [f64; 2],
    radii: &[(f64, bool)],
    ring_angles: Vec<Vec<f64>>,
    keys: &Keys,
) -> Result<Vec<Ring>, MeshError> {
    let mut rings: Vec<Ring> = Vec::new();
    for (&(r, curved), angles) in radii.iter().zip(ring_angles) {
        let n = angles.len();
        let mut ids = Vec::with_capacity(n);
        ids.push(keys.of(c[1] - r)?);
        for &a in &angles[1..n - 1] {
            ids.push(b.add([c[0] + r * a.cos(), c[1] + r * a.sin()]));
        }
        ids.push(keys.of(c[1] + r)?);
        b.chain(&ids);
        rings.push(Ring {
            radius: r,
            curved,
            vertices: ids,
            angles,
        });
    }
    Ok(rings)
}

/// Adds the interior lattice inside r_cp (module documentation, step 4): rows √3/2 · h
/// apart, spacing h along a row, alternate rows shifted by h/2, keeping the points at
/// least LATTICE_CLEARANCE · h from x = c_x and from the circles r_n and r_cp.
fn interior_lattice(b: &mut Builder, prm: &MeshParams) {
    let c = prm.center;
    let h = |y: f64| prm.size_at(y);
    let interfaces = [prm.r_n, prm.r_cp];
    let mut y = c[1] - prm.r_cp;
    let mut row = 0usize;
    while y < c[1] + prm.r_cp {
        let hy = h(y);
        let mut x = if row % 2 == 0 { hy } else { 0.5 * hy };
        while x < prm.r_cp {
            let r = x.hypot(y - c[1]);
            let clear = x >= LATTICE_CLEARANCE * hy
                && r < prm.r_cp
                && interfaces
                    .iter()
                    .all(|&ri| (r - ri).abs() >= LATTICE_CLEARANCE * hy);
            if clear {
                b.add([c[0] + x, y]);
            }
            x += hy;
        }
        y += 0.5 * 3f64.sqrt() * h(y + 0.25 * 3f64.sqrt() * hy);
        row += 1;
    }
}

impl Mesh {
    /// Generates the mesh described in the module documentation.
    pub fn generate(params: &MeshParams) -> Result<Mesh, MeshError> {
        params.validate()?;
        let layers = params.membrane_layers();
        let t_layer = (params.r_c - params.r_cp) / layers as f64;
        let mut b = Builder {
            verts: Vec::new(),
            constraints: Vec::new(),
        };
        let radii = ring_radii(params, layers, t_layer);
        // 1. Ring angles, bottom (−π/2) to top (π/2).
        let ring_angles = ring_angles(params, &radii, layers, t_layer);
        // 2. Symmetry line, with the rings' ends and the centre as key vertices.
        let keys = symmetry_line(&mut b, params, &radii, &ring_angles);
        // 3. Ring vertices; the ends are the key vertices on x = 0.
        let rings = ring_vertices(&mut b, params.center, &radii, ring_angles, &keys)?;
        // 4. Interior lattice, rows graded in y.
        interior_lattice(&mut b, params);
        // 5. Constrained Delaunay triangulation and refinement.
        let (verts, tris) = triangulate(&b.verts, &b.constraints, params.min_angle_deg)?;
        // 6.–7. Domains, mid-nodes and the circles' edges.
        let parts = quadratic_elements(params, &rings, verts, &tris)?;
        Mesh::assemble(parts, |_, y, _| keys.of(y))
    }

    /// Completes a mesh from the parts a builder (the generator, the gmsh reader) made:
    /// the symmetry nodes (coordinate exactly c_x, sorted by y), the named points found by
    /// `vertex_at(nodes, y, name)` on the symmetry line, and a check of every element's
    /// Jacobian.
    pub(crate) fn assemble(
        parts: MeshParts,
        vertex_at: impl Fn(&[[f64; 2]], f64, &str) -> Result<usize, MeshError>,
    ) -> Result<Mesh, MeshError> {
        let MeshParts {
            params,
            nodes,
            n_vertices,
            elements,
            domains,
            circles: [outer_edges, nucleus_edges, membrane_inner_edges],
        } = parts;
        let c = params.center;
        let mut symmetry_nodes: Vec<usize> =
            (0..nodes.len()).filter(|&i| nodes[i][0] == c[0]).collect();
        symmetry_nodes.sort_by(|&a, &b| nodes[a][1].total_cmp(&nodes[b][1]));
        let at = |y: f64, name: &str| vertex_at(&nodes, y, name);
        let points = NamedPoints {
            centre: at(c[1], "centre")?,
            nucleus_top: at(c[1] + params.r_n, "nucleus top")?,
            nucleus_bottom: at(c[1] - params.r_n, "nucleus bottom")?,
            cell_bottom: at(c[1] - params.r_c, "cell bottom")?,
            cell_top: at(c[1] + params.r_c, "cell top")?,
        };
        let mesh = Mesh {
            params,
            nodes,
            n_vertices,
            elements,
            domains,
            outer_edges,
            nucleus_edges,
            membrane_inner_edges,
            symmetry_nodes,
            points,
        };
        mesh.check_jacobians()?;
        Ok(mesh)
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elements.len()
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Area of domain `d` (or of the whole mesh with `None`), integrating det J of the
    /// isoparametric maps exactly (det J is quadratic in ξ; a degree-2 rule is exact).
    pub fn area(&self, d: Option<Domain>) -> f64 {
        let tab = P2Tabulation::new(&TriangleRule::degree(2));
        let mut a = 0.0;
        for e in 0..self.elements.len() {
            if d.is_some_and(|d| d != self.domains[e]) {
                continue;
            }
            let x = self.element_coords(e);
            for q in 0..tab.len() {
                let (_, det) = tri6::jacobian(&x, &tab.grads[q]);
                a += det * tab.weights[q];
            }
        }
        a
    }

    /// Exact minimum and maximum of det J over element `e`, and where the minimum is.
    ///
    /// det J is a quadratic polynomial in ξ, so its P2 interpolant from the six nodal
    /// values is exact; the minimum over the triangle is at a vertex, at a critical point
    /// of an edge restriction, or at the interior critical point.
    pub fn jacobian_range(&self, e: usize) -> (f64, f64, [f64; 2]) {
        let x = self.element_coords(e);
        let vals: [f64; 6] =
            std::array::from_fn(|a| tri6::jacobian(&x, &Tri6::grad_shape(REFERENCE_NODES[a])).1);
        let q = |xi: [f64; 2]| {
            let n = Tri6::shape(xi);
            (0..6).map(|a| n[a] * vals[a]).sum::<f64>()
        };
        let mut cands: Vec<[f64; 2]> = REFERENCE_NODES.to_vec();
        // Edges: f(s) along v_i + s (v_j − v_i) is quadratic; vertex-mid-vertex values give
        // f(s) = f0 (1−s)(1−2s) + 4 fm s(1−s) + f1 s(2s−1); f'(s) = 0 at
        // s* = (3f0 − 4fm + f1) / (4(f0 − 2fm + f1)).
        for ed in EDGES {
            let (f0, fm, f1) = (vals[ed[0]], vals[ed[1]], vals[ed[2]]);
            let den = 4.0 * (f0 - 2.0 * fm + f1);
            if den.abs() > 0.0 {
                let s = (3.0 * f0 - 4.0 * fm + f1) / den;
                if s > 0.0 && s < 1.0 {
                    let (a, b) = (REFERENCE_NODES[ed[0]], REFERENCE_NODES[ed[2]]);
                    cands.push([a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])]);
                }
            }
        }
        // Interior: q = c0 + c1 ξ + c2 η + c3 ξ² + c4 ξη + c5 η², fitted from the values.
        let f = |i: usize| vals[i];
        // With λ-based nodal values: c1 = −3f0 − f1 + 4f3, c2 = −3f0 − f2 + 4f5,
        // c3 = 2f0 + 2f1 − 4f3, c5 = 2f0 + 2f2 − 4f5, c4 = 4(f0 − f3 + f4 − f5).
        let c1 = -3.0 * f(0) - f(1) + 4.0 * f(3);
        let c2 = -3.0 * f(0) - f(2) + 4.0 * f(5);
        let c3 = 2.0 * f(0) + 2.0 * f(1) - 4.0 * f(3);
        let c5 = 2.0 * f(0) + 2.0 * f(2) - 4.0 * f(5);
        let c4 = 4.0 * (f(0) - f(3) + f(4) - f(5));
        // ∇q = 0: [2c3 c4; c4 2c5] ξ = −(c1, c2).
        let det = 4.0 * c3 * c5 - c4 * c4;
        if det.abs() > 1e-300 {
            let xi = (-c1 * 2.0 * c5 + c4 * c2) / det;
            let eta = (-2.0 * c3 * c2 + c4 * c1) / det;
            if xi > 0.0 && eta > 0.0 && xi + eta < 1.0 {
                cands.push([xi, eta]);
            }
        }
        extremes(cands, q)
    }

    /// Size and shape statistics.
    pub fn quality(&self) -> MeshQuality {
        let mut min_angle = f64::INFINITY;
        let mut max_angle: f64 = 0.0;
        let mut min_edge = f64::INFINITY;
        let mut max_edge: f64 = 0.0;
        let (mut sum_b, mut n_b, mut sum_n, mut n_n) = (0.0, 0usize, 0.0, 0usize);
        let mut min_ratio = f64::INFINITY;
        let y_low = self.params.center[1] - self.params.r_c + 0.5;
        for (e, el) in self.elements.iter().enumerate() {
            let p = [self.nodes[el[0]], self.nodes[el[1]], self.nodes[el[2]]];
            let len = |i: usize, j: usize| (p[j][0] - p[i][0]).hypot(p[j][1] - p[i][1]);
            let l = [len(1, 2), len(2, 0), len(0, 1)];
            for k in 0..3 {
                let (a, b, c) = (l[k], l[(k + 1) % 3], l[(k + 2) % 3]);
                let cos = ((b * b + c * c - a * a) / (2.0 * b * c)).clamp(-1.0, 1.0);
                let ang = cos.acos().to_degrees();
                min_angle = min_angle.min(ang);
                max_angle = max_angle.max(ang);
                min_edge = min_edge.min(a);
                max_edge = max_edge.max(a);
            }
            let s: f64 = l.iter().sum();
            if p.iter().any(|q| q[1] < y_low) {
                sum_b += s;
                n_b += 3;
            }
            if self.domains[e] == Domain::Nucleus {
                sum_n += s;
                n_n += 3;
            }
            let (jmin, jmax, _) = self.jacobian_range(e);
            min_ratio = min_ratio.min(jmin / jmax);
        }
        let count = |d: Domain| self.domains.iter().filter(|&&x| x == d).count();
        MeshQuality {
            elements: self.elements.len(),
            nodes: self.nodes.len(),
            vertices: self.n_vertices,
            displacement_dofs: 2 * self.nodes.len(),
            nucleus_elements: count(Domain::Nucleus),
            cytoplasm_elements: count(Domain::Cytoplasm),
            membrane_elements: count(Domain::Membrane),
            min_angle_deg: min_angle,
            max_angle_deg: max_angle,
            min_edge,
            max_edge,
            mean_edge_bottom: sum_b / n_b.max(1) as f64,
            mean_edge_nucleus: sum_n / n_n.max(1) as f64,
            elements_through_membrane: self.elements_through_membrane(720),
            min_jacobian_ratio: min_ratio,
        }
    }

    /// Minimum over `rays` radial lines (at angles evenly spaced in (−π/2, π/2)) of the
    /// number of distinct membrane elements (straight-sided) met by the line between r_cp
    /// and r_c, sampled at 64 radii.
    pub fn elements_through_membrane(&self, rays: usize) -> usize {
        let c = self.params.center;
        let (r0, r1) = (self.params.r_cp, self.params.r_c);
        let members: Vec<(usize, f64, f64)> = self
            .elements
            .iter()
            .enumerate()
            .filter(|(e, _)| self.domains[*e] == Domain::Membrane)
            .map(|(e, el)| {
                let angs = [0, 1, 2].map(|k| {
                    let p = self.nodes[el[k]];
                    (p[1] - c[1]).atan2(p[0] - c[0])
                });
                let lo = angs.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = angs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                (e, lo, hi)
            })
            .collect();
        let mut best = usize::MAX;
        for k in 0..rays {
            let phi = -FRAC_PI_2 + (k as f64 + 0.5) * PI / rays as f64;
            let cands: Vec<usize> = members
                .iter()
                .filter(|(_, lo, hi)| *lo <= phi && phi <= *hi)
                .map(|m| m.0)
                .collect();
            let mut hit: Vec<usize> = Vec::new();
            for j in 0..64 {
                let r = r0 + (j as f64 + 0.5) / 64.0 * (r1 - r0);
                let p = [c[0] + r * phi.cos(), c[1] + r * phi.sin()];
                for &e in &cands {
                    if self.straight_contains(e, p) && !hit.contains(&e) {
                        hit.push(e);
                    }
                }
            }
            best = best.min(hit.len());
        }
        if best == usize::MAX { 0 } else { best }
    }

    /// True if p lies in the straight-sided triangle of element e's vertices.
    fn straight_contains(&self, e: usize, p: [f64; 2]) -> bool {
        let el = &self.elements[e];
        let (a, b, c) = (self.nodes[el[0]], self.nodes[el[1]], self.nodes[el[2]]);
        let cross = |u: [f64; 2], v: [f64; 2], w: [f64; 2]| {
            (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0])
        };
        cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
    }

    /// Writes the mesh as an SVG drawing (straight vertex edges, elements coloured by
    /// domain, circle mid-nodes as dots) for a quick look.
    pub fn write_svg(&self, path: &Path) -> Result<(), MeshError> {
        let c = self.params.center;
        let r = self.params.r_c;
        let scale = 40.0;
        let w = (r + 0.5) * scale;
        let hgt = (2.0 * r + 1.0) * scale;
        let tx = |p: [f64; 2]| {
            (
                (p[0] - c[0] + 0.25) * scale,
                (c[1] + r + 0.5 - p[1]) * scale,
            )
        };
        let mut s = format!(
            "<svg xmlns='http://www.w3.org/2000/svg' width='{w:.0}' height='{hgt:.0}'>\n<rect width='100%' height='100%' fill='white'/>\n"
        );
        for (el, d) in self.elements.iter().zip(&self.domains) {
            let fill = match d {
                Domain::Nucleus => "#f4c7a1",
                Domain::Cytoplasm => "#bfe0f2",
                Domain::Membrane => "#b5e3b0",
            };
            let pts: Vec<String> = [0, 3, 1, 4, 2, 5]
                .iter()
                .map(|&k| {
                    let (x, y) = tx(self.nodes[el[k]]);
                    format!("{x:.2},{y:.2}")
                })
                .collect();
            s.push_str(&format!(
                "<polygon points='{}' fill='{fill}' stroke='black' stroke-width='0.6'/>\n",
                pts.join(" ")
            ));
        }
        s.push_str("</svg>\n");
        std::fs::write(path, s).map_err(|source| MeshError::Write {
            path: path.display().to_string(),
            source,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(refine: f64) -> Mesh {
        Mesh::generate(&params(refine)).expect("mesh generation")
    }

    fn params(refine: f64) -> MeshParams {
        MeshParams {
            refine,
            ..crate::fem::reference::mesh_params()
        }
    }

    fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
        (p[0] - q[0]).hypot(p[1] - q[1])
    }

    /// Area of the half disk of radius r minus the P2 approximation's deficit on each
    /// circle edge: the circular segment (r²/2)(φ − sin φ) minus the parabolic one,
    /// (2/3) · chord · sagitta, chord 2r sin(φ/2), sagitta r(1 − cos(φ/2)), since the
    /// mid-node is on the arc at the mid angle (see p2 tests for the parabola's area).
    fn p2_half_disk_area(m: &Mesh, edges: &[[usize; 3]], r: f64) -> f64 {
        let c = m.params.center;
        let ang = |n: usize| (m.nodes[n][1] - c[1]).atan2(m.nodes[n][0] - c[0]);
        let mut a = 0.5 * PI * r * r;
        for e in edges {
            let phi = ang(e[2]) - ang(e[0]);
            assert!(phi > 0.0, "circle edges must run counter-clockwise");
            let circ = 0.5 * r * r * (phi - phi.sin());
            let para = 2.0 / 3.0 * (2.0 * r * (0.5 * phi).sin()) * (r * (1.0 - (0.5 * phi).cos()));
            a -= circ - para;
        }
        a
    }

    /// Domain areas against the exact P2 geometry (to round-off) and against the true
    /// circles. The P2 deficit per edge of angle φ is r²φ⁵/960 to leading order, so the
    /// relative error of a half disk is ≈ φ⁴/480: with φ ≤ 0.2 (1 µm on r_n = 5) that is
    /// ≤ 3.4e-6, and the bound 1e-5 holds at refine = 1.
    #[test]
    fn domain_areas() {
        for refine in [0.5, 1.0, 2.0] {
            let m = mesh(refine);
            let p = &m.params;
            let an = p2_half_disk_area(&m, &m.nucleus_edges, p.r_n);
            let acp = p2_half_disk_area(&m, &m.membrane_inner_edges, p.r_cp);
            let ac = p2_half_disk_area(&m, &m.outer_edges, p.r_c);
            let expect = [
                (Some(Domain::Nucleus), an),
                (Some(Domain::Cytoplasm), acp - an),
                (Some(Domain::Membrane), ac - acp),
                (None, ac),
            ];
            for (d, e) in expect {
                let a = m.area(d);
                assert!(
                    (a - e).abs() < 1e-12 * e,
                    "refine {refine} {d:?}: {a} vs exact P2 geometry {e}"
                );
            }
            if refine >= 1.0 {
                let half = |r: f64| 0.5 * PI * r * r;
                let truth = [
                    (Some(Domain::Nucleus), half(p.r_n)),
                    (Some(Domain::Cytoplasm), half(p.r_cp) - half(p.r_n)),
                    (Some(Domain::Membrane), half(p.r_c) - half(p.r_cp)),
                    (None, half(p.r_c)),
                ];
                for (d, t) in truth {
                    let a = m.area(d);
                    assert!(
                        (a - t).abs() < 1e-5 * t,
                        "refine {refine} {d:?}: {a} vs {t}"
                    );
                }
            }
        }
    }

    #[test]
    fn circle_nodes_lie_on_their_circles_and_other_mid_nodes_are_midpoints() {
        let m = mesh(1.0);
        let p = &m.params;
        let c = p.center;
        let mut on_circle = std::collections::HashSet::new();
        for (edges, r) in [
            (&m.nucleus_edges, p.r_n),
            (&m.membrane_inner_edges, p.r_cp),
            (&m.outer_edges, p.r_c),
        ] {
            assert!(edges.len() >= 4);
            for e in edges.iter() {
                for &n in e {
                    assert!(
                        (dist(m.nodes[n], c) - r).abs() < 1e-12 * r,
                        "node {n} off r = {r}"
                    );
                }
                on_circle.insert(e[1]);
                // The mid-node sits at the mid angle, not at the chord midpoint.
                let chord_mid = [
                    0.5 * (m.nodes[e[0]][0] + m.nodes[e[2]][0]),
                    0.5 * (m.nodes[e[0]][1] + m.nodes[e[2]][1]),
                ];
                assert!(dist(m.nodes[e[1]], chord_mid) > 1e-6);
                assert!(
                    (dist(m.nodes[e[1]], m.nodes[e[0]]) - dist(m.nodes[e[1]], m.nodes[e[2]])).abs()
                        < 1e-12
                );
            }
        }
        for el in &m.elements {
            for ed in EDGES {
                if on_circle.contains(&el[ed[1]]) {
                    continue;
                }
                let (a, b) = (m.nodes[el[ed[0]]], m.nodes[el[ed[2]]]);
                let mid = m.nodes[el[ed[1]]];
                assert_eq!(mid, [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]);
            }
        }
    }

    #[test]
    fn named_points_and_symmetry_nodes() {
        let m = mesh(1.0);
        let at = |n: usize| m.nodes[n];
        let np = m.points;
        assert_eq!(at(np.centre), [0.0, 8.5]);
        assert_eq!(at(np.nucleus_top), [0.0, 13.5]);
        assert_eq!(at(np.nucleus_bottom), [0.0, 3.5]);
        assert_eq!(at(np.cell_bottom), [0.0, -1.5]);
        assert_eq!(at(np.cell_top), [0.0, 18.5]);
        for n in [
            np.centre,
            np.nucleus_top,
            np.nucleus_bottom,
            np.cell_bottom,
            np.cell_top,
        ] {
            assert!(n < m.n_vertices, "named point {n} is not a vertex");
        }
        // Symmetry nodes: exactly the nodes with x = 0, sorted by y, from bottom to top;
        // no node strays to small negative or tiny positive x.
        let expect: Vec<usize> = (0..m.n_nodes()).filter(|&n| at(n)[0] == 0.0).collect();
        assert_eq!(m.symmetry_nodes.len(), expect.len());
        for w in m.symmetry_nodes.windows(2) {
            assert!(at(w[0])[1] < at(w[1])[1]);
        }
        assert_eq!(m.symmetry_nodes[0], np.cell_bottom);
        assert_eq!(*m.symmetry_nodes.last().unwrap(), np.cell_top);
        for (n, p) in m.nodes.iter().enumerate() {
            assert!(p[0] == 0.0 || p[0] > 1e-6, "node {n} at x = {}", p[0]);
        }
        // Vertices and mid-nodes alternate along x = 0 (every symmetry edge has its mid-node there).
        for (i, &n) in m.symmetry_nodes.iter().enumerate() {
            assert_eq!(n < m.n_vertices, i % 2 == 0);
        }
    }

    /// Each interior edge is shared by exactly two elements, traversed in opposite
    /// directions, with one mid-node; each boundary edge lies on x = 0 or is an outer
    /// edge; the outer edges chain from the cell bottom to the cell top; no two nodes
    /// coincide; every node is used.
    #[test]
    fn conformity() {
        for refine in [0.5, 1.0, 2.0] {
            let m = mesh(refine);
            #[allow(clippy::type_complexity)]
            let mut edges: HashMap<(usize, usize), Vec<(usize, usize, usize)>> = HashMap::new();
            for (e, el) in m.elements.iter().enumerate() {
                for ed in EDGES {
                    let (a, b) = (el[ed[0]], el[ed[2]]);
                    edges
                        .entry((a.min(b), a.max(b)))
                        .or_default()
                        .push((e, a, el[ed[1]]));
                }
            }
            let outer: std::collections::HashSet<(usize, usize)> = m
                .outer_edges
                .iter()
                .map(|e| (e[0].min(e[2]), e[0].max(e[2])))
                .collect();
            let mut n_boundary_outer = 0;
            for (key, uses) in &edges {
                match uses.len() {
                    2 => {
                        assert_ne!(uses[0].1, uses[1].1, "edge {key:?}: same direction twice");
                        assert_eq!(uses[0].2, uses[1].2, "edge {key:?}: two mid-nodes");
                    }
                    1 => {
                        let on_axis = m.nodes[key.0][0] == 0.0 && m.nodes[key.1][0] == 0.0;
                        let on_outer = outer.contains(key);
                        assert!(
                            on_axis ^ on_outer,
                            "boundary edge {key:?} on neither boundary"
                        );
                        n_boundary_outer += usize::from(on_outer);
                        if on_outer {
                            let e = m
                                .outer_edges
                                .iter()
                                .find(|e| (e[0].min(e[2]), e[0].max(e[2])) == *key);
                            assert_eq!(e.map(|e| e[1]), Some(uses[0].2));
                        }
                    }
                    k => panic!("edge {key:?} used {k} times"),
                }
            }
            assert_eq!(n_boundary_outer, m.outer_edges.len());
            assert_eq!(m.outer_edges[0][0], m.points.cell_bottom);
            // The outer boundary's nodes bottom to top: vertex, mid-node, vertex, …
            let mut ob = vec![m.outer_edges[0][0]];
            ob.extend(m.outer_edges.iter().flat_map(|e| [e[1], e[2]]));
            assert_eq!(ob.len(), 2 * m.outer_edges.len() + 1);
            assert_eq!(
                (ob[0], ob[ob.len() - 1]),
                (m.points.cell_bottom, m.points.cell_top)
            );
            assert_eq!(m.outer_edges.last().unwrap()[2], m.points.cell_top);
            for w in m.outer_edges.windows(2) {
                assert_eq!(w[0][2], w[1][0]);
            }
            // Outer edges run counter-clockwise about the centre (angles increase).
            let c = m.params.center;
            let ang = |n: usize| (m.nodes[n][1] - c[1]).atan2(m.nodes[n][0] - c[0]);
            for e in &m.outer_edges {
                assert!(ang(e[2]) > ang(e[0]));
            }
            // Euler: V − E + F = 1 for a triangulated disk.
            assert_eq!(m.n_vertices + m.elements.len(), edges.len() + 1);
            assert_eq!(m.n_nodes(), m.n_vertices + edges.len());
            let mut used = vec![false; m.n_nodes()];
            for el in &m.elements {
                for &n in el {
                    used[n] = true;
                }
                for k in 0..3 {
                    assert!(el[k] < m.n_vertices && el[k + 3] >= m.n_vertices);
                }
            }
            assert!(used.iter().all(|&u| u));
            let mut sorted: Vec<[f64; 2]> = m.nodes.clone();
            sorted.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
            for w in sorted.windows(2) {
                assert!(w[0] != w[1], "duplicate node at {:?}", w[0]);
            }
        }
    }

    #[test]
    fn elements_counter_clockwise_with_positive_jacobian() {
        for refine in [0.5, 1.0, 2.0] {
            let m = mesh(refine);
            for e in 0..m.n_elements() {
                let x = m.element_coords(e);
                let a2 = (x[1][0] - x[0][0]) * (x[2][1] - x[0][1])
                    - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
                assert!(a2 > 0.0, "element {e} clockwise");
                let (min, max, _) = m.jacobian_range(e);
                assert!(min > 0.0 && max >= min);
            }
            assert!(m.check_jacobians().is_ok());
            assert!(m.quality().min_jacobian_ratio > 0.5);
        }
    }

    /// The exact minimum of det J agrees with dense sampling, and a corrupted element is
    /// reported by index.
    #[test]
    fn jacobian_minimum_is_exact_and_bad_elements_are_named() {
        let mut m = mesh(1.0);
        // Bend some curved elements strongly so the minimum moves inside.
        let samples = TriangleRule::degree(20).subdivided(2).points;
        for e in [0, 7, 100] {
            let el = m.elements[e];
            let a = m.nodes[el[0]];
            let b = m.nodes[el[1]];
            m.nodes[el[3]] = [
                0.5 * (a[0] + b[0]) + 0.3 * (b[1] - a[1]),
                0.5 * (a[1] + b[1]) - 0.3 * (b[0] - a[0]),
            ];
            let (min, _, at) = m.jacobian_range(e);
            let x = m.element_coords(e);
            let sampled = samples
                .iter()
                .chain(REFERENCE_NODES.iter())
                .map(|&xi| Tri6::map(&x, xi).2)
                .fold(f64::INFINITY, f64::min);
            assert!(
                sampled >= min - 1e-12,
                "sampled {sampled} below exact {min}"
            );
            assert!(
                sampled - min < 1e-3 * sampled.abs().max(1e-3),
                "{sampled} vs {min}"
            );
            assert!((Tri6::map(&x, at).2 - min).abs() < 1e-12);
        }
        // Pull the mid-node of element 42 across its opposite vertex.
        let el = m.elements[42];
        m.nodes[el[3]] = m.nodes[el[2]];
        m.nodes[el[3]][0] += 0.1 * (m.nodes[el[2]][0] - m.nodes[el[0]][0]);
        m.nodes[el[3]][1] += 0.1 * (m.nodes[el[2]][1] - m.nodes[el[0]][1]);
        match m.check_jacobians() {
            Err(MeshError::NonPositiveJacobian { element, det, .. }) => {
                assert!(element == 42 || m.elements[element].contains(&el[3]));
                assert!(det <= 0.0);
            }
            other => panic!("expected a Jacobian error, got {other:?}"),
        }
    }

    #[test]
    fn angles_membrane_thickness_and_domains() {
        for refine in [0.5, 1.0, 2.0] {
            let m = mesh(refine);
            let q = m.quality();
            // spade refines to 28°; only corners between constraint edges are exempt, and
            // the vertex placement keeps those above 25°.
            assert!(
                q.min_angle_deg >= 25.0,
                "refine {refine}: {}",
                q.min_angle_deg
            );
            let layers = m.params.membrane_layers();
            assert!(
                q.elements_through_membrane >= layers.max(1),
                "refine {refine}: {q}"
            );
            // Domain membership by vertex radius: membrane elements only touch r ≥ r_cp,
            // nucleus elements only r ≤ r_n, cytoplasm elements r_n ≤ r ≤ r_cp.
            let c = m.params.center;
            let tol = 1e-9;
            for (el, d) in m.elements.iter().zip(&m.domains) {
                for &n in &el[..3] {
                    let r = dist(m.nodes[n], c);
                    let ok = match d {
                        Domain::Nucleus => r <= m.params.r_n + tol,
                        Domain::Cytoplasm => r >= m.params.r_n - tol && r <= m.params.r_cp + tol,
                        Domain::Membrane => r >= m.params.r_cp - tol,
                    };
                    assert!(ok, "{d} element has a vertex at r = {r}");
                }
            }
            // Interface nodes belong to both neighbouring domains.
            let nuc = m.nodes_of_domain(Domain::Nucleus);
            let cyt = m.nodes_of_domain(Domain::Cytoplasm);
            let mem = m.nodes_of_domain(Domain::Membrane);
            for e in &m.nucleus_edges {
                assert!(e.iter().all(|&n| nuc[n] && cyt[n] && !mem[n]));
            }
            for e in &m.membrane_inner_edges {
                assert!(e.iter().all(|&n| cyt[n] && mem[n] && !nuc[n]));
            }
            assert_eq!(m.elements_of(Domain::Membrane).len(), q.membrane_elements);
        }
    }

    /// The default mesh lands near the paper's (≈ 630 P2 triangles, ≈ 2 700 displacement
    /// unknowns), is graded from ≈ 0.3 µm at the bottom to ≈ 1 µm in the nucleus, and
    /// refine = 2 gives about four times the elements.
    #[test]
    fn counts_grading_and_refinement() {
        let m1 = mesh(1.0);
        let q1 = m1.quality();
        assert!((550..=710).contains(&q1.elements), "{q1}");
        assert!((2400..=3000).contains(&q1.displacement_dofs), "{q1}");
        assert!(q1.mean_edge_bottom < 0.4, "{q1}");
        assert!((0.85..=1.2).contains(&q1.mean_edge_nucleus), "{q1}");
        // Every edge within a factor of the local target size. Membrane edges are capped
        // by the thickness and the mesh grades down to them over about 2 h_nucleus, so the
        // lower bound applies only away from the membrane.
        let c = m1.params.center;
        let far = m1.params.r_cp - 2.0 * m1.params.h_nucleus;
        for el in &m1.elements {
            for ed in EDGES {
                let (a, b) = (m1.nodes[el[ed[0]]], m1.nodes[el[ed[2]]]);
                let l = dist(a, b);
                let h = m1.params.size_at(0.5 * (a[1] + b[1]));
                assert!(l < 1.8 * h, "edge {l} vs h {h} at {a:?} {b:?}");
                if dist(a, c) < far && dist(b, c) < far {
                    assert!(l > 0.5 * h, "edge {l} vs h {h} at {a:?} {b:?}");
                }
            }
        }
        let q2 = mesh(2.0).quality();
        let ratio = q2.elements as f64 / q1.elements as f64;
        assert!((3.6..=4.4).contains(&ratio), "ratio {ratio}");
        assert!((q2.mean_edge_nucleus / q1.mean_edge_nucleus - 0.5).abs() < 0.05);
    }

    #[test]
    fn generation_is_deterministic_and_general() {
        let a = mesh(1.0);
        let b = mesh(1.0);
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.elements, b.elements);
        // Another cell: off-origin centre, thicker membrane, uniform size.
        let p = MeshParams {
            center: [1.5, -2.0],
            r_n: 3.0,
            r_cp: 6.0,
            r_c: 7.0,
            h_bottom: 0.5,
            h_nucleus: 0.5,
            refine: 1.0,
            h_surface: None,
            min_angle_deg: 25.0,
        };
        let m = Mesh::generate(&p).expect("mesh");
        assert!(m.symmetry_nodes.iter().all(|&n| m.nodes[n][0] == 1.5));
        assert_eq!(m.nodes[m.points.cell_top], [1.5, 5.0]);
        let a = m.area(None);
        let t = 0.5 * PI * 49.0;
        assert!((a - t).abs() < 1e-4 * t, "{a} vs {t}");
        assert!(m.quality().min_angle_deg >= 23.0);
    }

    /// Unusual but valid parameters mesh without error, with positive Jacobians, exact
    /// P2 areas and sane angles (a thin band between nucleus and membrane limits the
    /// angles, so the bound here is 15°).
    #[test]
    fn unusual_parameters_give_valid_meshes() {
        let d = crate::fem::reference::mesh_params();
        let cases = [
            MeshParams {
                refine: 0.1,
                ..d.clone()
            },
            MeshParams {
                refine: 1.5,
                ..d.clone()
            },
            MeshParams {
                refine: 3.0,
                ..d.clone()
            },
            MeshParams {
                min_angle_deg: 5.0,
                ..d.clone()
            },
            MeshParams {
                min_angle_deg: 33.0,
                ..d.clone()
            },
            MeshParams {
                h_bottom: 1.0,
                h_nucleus: 0.3,
                ..d.clone()
            },
            MeshParams {
                h_bottom: 5.0,
                h_nucleus: 20.0,
                ..d.clone()
            },
            MeshParams {
                r_cp: 6.0,
                ..d.clone()
            },
            MeshParams {
                r_n: 9.5,
                ..d.clone()
            },
            MeshParams {
                r_n: 0.5,
                ..d.clone()
            },
            MeshParams {
                center: [0.0, 1.0e4],
                ..d.clone()
            },
            MeshParams {
                center: [0.0, 0.0],
                r_n: 5e-3,
                r_cp: 9.75e-3,
                r_c: 1e-2,
                h_bottom: 3e-4,
                h_nucleus: 1e-3,
                ..d.clone()
            },
        ];
        for p in cases {
            let m = Mesh::generate(&p).unwrap_or_else(|e| panic!("{p:?}: {e}"));
            assert!(m.check_jacobians().is_ok());
            let q = m.quality();
            assert!(q.min_angle_deg > 15.0, "{p:?}: {q}");
            assert!(q.elements_through_membrane >= 1, "{p:?}: {q}");
            let t = 0.5 * PI * p.r_c * p.r_c;
            let a = m.area(None);
            assert!((a - t).abs() < 1e-3 * t, "{p:?}: area {a} vs {t}");
            for n in m.symmetry_nodes {
                assert_eq!(m.nodes[n][0], p.center[0]);
            }
        }
    }

    #[test]
    fn invalid_parameters_are_refused_with_the_field_named() {
        let field_of = |p: MeshParams| match Mesh::generate(&p) {
            Err(MeshError::InvalidParam { field, .. }) => field,
            other => panic!("expected InvalidParam, got {other:?}"),
        };
        let d = crate::fem::reference::mesh_params();
        assert_eq!(
            field_of(MeshParams {
                r_cp: 5.0,
                ..d.clone()
            }),
            "r_cp"
        );
        assert_eq!(
            field_of(MeshParams {
                r_c: 9.0,
                ..d.clone()
            }),
            "r_c"
        );
        assert_eq!(
            field_of(MeshParams {
                r_n: -1.0,
                ..d.clone()
            }),
            "r_n"
        );
        assert_eq!(
            field_of(MeshParams {
                h_surface: Some(0.0),
                ..d.clone()
            }),
            "h_surface"
        );
        assert_eq!(
            field_of(MeshParams {
                h_bottom: 0.0,
                ..d.clone()
            }),
            "h_bottom"
        );
        assert_eq!(
            field_of(MeshParams {
                h_nucleus: f64::NAN,
                ..d.clone()
            }),
            "h_nucleus"
        );
        assert_eq!(
            field_of(MeshParams {
                refine: 0.0,
                ..d.clone()
            }),
            "refine"
        );
        assert_eq!(
            field_of(MeshParams {
                refine: f64::INFINITY,
                ..d.clone()
            }),
            "refine"
        );
        assert_eq!(
            field_of(MeshParams {
                min_angle_deg: 40.0,
                ..d.clone()
            }),
            "min_angle_deg"
        );
        assert_eq!(
            field_of(MeshParams {
                center: [f64::NAN, 0.0],
                ..d.clone()
            }),
            "center[0]"
        );
        assert!(matches!(
            Mesh::generate(&MeshParams {
                refine: 1000.0,
                ..d.clone()
            }),
            Err(MeshError::TooFine { .. })
        ));
        let msg = Mesh::generate(&MeshParams { r_cp: 4.0, ..d })
            .expect_err("invalid")
            .to_string();
        assert!(msg.contains("r_cp") && msg.contains("r_n"), "{msg}");
    }

    /// The surface cap: below the centre the outer ring's edges are no longer than the cap
    /// (0.2 µm, under the membrane's own limit of 0.5); above the centre, where the cap has
    /// grown past that limit, the ring's spacing is the default one.
    #[test]
    fn a_surface_cap_shortens_the_lower_outer_edges() {
        let plain = mesh(1.0);
        let capped = Mesh::generate(&MeshParams {
            h_surface: Some(0.2),
            ..params(1.0)
        })
        .expect("mesh generation");
        let c = plain.params.center;
        let edges = |m: &Mesh, below: bool| -> Vec<f64> {
            m.outer_edges
                .iter()
                .filter(|e| (m.nodes[e[1]][1] < c[1] - 0.5) == below)
                .map(|e| dist(m.nodes[e[0]], m.nodes[e[2]]))
                .collect()
        };
        let max = |v: Vec<f64>| v.into_iter().fold(0.0, f64::max);
        let (p_low, c_low) = (max(edges(&plain, true)), max(edges(&capped, true)));
        assert!(p_low > 0.3, "{p_low}");
        assert!(c_low <= 0.2 * 1.05, "{c_low}");
        assert!(capped.n_elements() > plain.n_elements());
        // Where the cap exceeds the membrane's limit (above c_y + 0.6 µm) the spacing is the
        // membrane's limit again (the division equidistributes over the whole half circle,
        // so the points there shift, but the longest edge stays within 5 %).
        let high = |m: &Mesh| -> Vec<f64> {
            let mut v: Vec<f64> = m
                .outer_edges
                .iter()
                .filter(|e| m.nodes[e[1]][1] > c[1] + 2.0)
                .map(|e| dist(m.nodes[e[0]], m.nodes[e[2]]))
                .collect();
            v.sort_by(f64::total_cmp);
            v
        };
        let (h_plain, h_capped) = (max(high(&plain)), max(high(&capped)));
        assert!(
            (h_capped / h_plain - 1.0).abs() < 0.05,
            "{h_plain} {h_capped}"
        );
        assert_eq!(
            params(1.0).surface_cap(9.0, c[1] + 1.0),
            None,
            "no cap without h_surface"
        );
        let p = MeshParams {
            h_surface: Some(0.2),
            refine: 2.0,
            ..params(1.0)
        };
        // (0.2 + 0.5 × 0.75 + 0.5 × 1) / 2 at 0.75 µm inside r_cp and 1 µm above c.
        let cap = p.surface_cap(p.r_cp - 0.75, c[1] + 1.0).unwrap();
        assert!((cap - 0.5375).abs() < 1e-12, "{cap}");
        // At the bottom the cap (0.1) is below the law (0.157); 5 µm above the centre the
        // law (0.5) below the cap (1.35).
        assert_eq!(p.size_near(p.r_c, c[1] - 9.9), 0.1);
        assert_eq!(p.size_near(p.r_c, c[1] + 5.0), p.size_at(c[1] + 5.0));
    }

    #[test]
    fn print_quality() {
        for r in [0.5, 1.0, 2.0] {
            let t = std::time::Instant::now();
            let m = mesh(r);
            let dt = t.elapsed();
            println!(
                "refine {r}: generated in {:.1} ms\n{}",
                dt.as_secs_f64() * 1e3,
                m.quality()
            );
            if std::env::var("CELLSIM_MESH_PNG").is_ok() {
                draw_png(&m, &format!("/tmp/mesh_{r}.png"), None);
                draw_png(
                    &m,
                    &format!("/tmp/mesh_{r}_bottom.png"),
                    Some([0.0, 5.0, -1.6, 3.0]),
                );
            }
        }
    }

    /// Debug picture of a mesh (set CELLSIM_MESH_PNG to write them).
    fn draw_png(m: &Mesh, path: &str, window: Option<[f64; 4]>) {
        use plotters::prelude::*;
        let [x0, x1, y0, y1] = window.unwrap_or([-0.3, 10.3, -1.8, 18.8]);
        let px = 1000u32;
        let py = (px as f64 * (y1 - y0) / (x1 - x0)) as u32;
        let root = BitMapBackend::new(path, (px, py)).into_drawing_area();
        root.fill(&WHITE).unwrap();
        let tx = |p: [f64; 2]| {
            (
                ((p[0] - x0) / (x1 - x0) * px as f64) as i32,
                ((y1 - p[1]) / (y1 - y0) * py as f64) as i32,
            )
        };
        for (el, d) in m.elements.iter().zip(&m.domains) {
            let fill = match d {
                Domain::Nucleus => RGBColor(244, 199, 161),
                Domain::Cytoplasm => RGBColor(191, 224, 242),
                Domain::Membrane => RGBColor(181, 227, 176),
            };
            // Curved outline: sample each quadratic edge.
            let mut pts = Vec::new();
            for e in EDGES {
                let xe = [m.nodes[el[e[0]]], m.nodes[el[e[1]]], m.nodes[el[e[2]]]];
                for k in 0..8 {
                    pts.push(tx(tri6::edge_map(&xe, k as f64 / 8.0).0));
                }
            }
            root.draw(&Polygon::new(pts.clone(), fill.filled()))
                .unwrap();
            pts.push(pts[0]);
            root.draw(&PathElement::new(pts, BLACK.stroke_width(1)))
                .unwrap();
        }
        root.present().unwrap();
    }
}
