//! The figures of the 3-D quarter cell (MODEL.md §10) — sections through its axis and the
//! shaded surface view — drawn from a [`QuarterMeshFile`] and a [`QuarterSnapshot`] only,
//! in the colours and styles of the 2-D figures ([`super::draw`]).
//!
//! **Sections** ([`section_figure`]): the deformed cell cut by a vertical plane through its
//! axis, mirrored to both sides as the 2-D shape figures are — nucleus red, cytoplasm
//! orange, membrane green, the element outlines in darker shades, the domain interfaces
//! dark grey and the cell's outline black; the PAC (blue) and bottom (purple) active
//! regions outlined where χ of the reference point is ½, carried by the deformation; the
//! substrate's section grey under its surface line, the fibronectin layer yellow, the
//! gravity arrow; equal scales on both axes. Two planes ([`Section`]):
//! - `z = 0`, a symmetry plane of the quarter: the mesh's boundary faces lying in it, each
//!   six-node triangle traced along its curved sides. This is the section the 2-D model
//!   computes, so the two can be set side by side;
//! - `x = z`, the diagonal: across the gaps between four pillars on the default lattice,
//!   where the 2-D model has no counterpart. Every tetrahedron is cut by the reference
//!   plane X = Z: its reference tetrahedron is divided into [`CUT_DIVISIONS`]³ sub-tetrahedra,
//!   X − Z (a quadratic of the reference coordinates) is evaluated at their vertices and each
//!   is cut by marching tetrahedra; the cut polygons' points are mapped to the deformed
//!   configuration by the P2 interpolation of u. Drawn in the plane's coordinates, the
//!   horizontal one (x + z)/√2 (the axis says so) and y. The deformed points leave the plane
//!   where the deformation is not symmetric about it (the gap lattice): the figure shows
//!   their projection onto it.
//!
//! Horizontal coordinates are measured from the cell's vertical axis (x = c_x, z = c_z;
//! c_x = c_z = 0 in every case cellsim builds), and the substrate's section is the surface
//! height ([`LatticeSubstrate::surface_height`]) along the section line: pillars stand on
//! their floor with their full width (the undercut below a superellipsoid's rounded foot,
//! which the model leaves open, is drawn filled).
//!
//! **Surface view** ([`surface_figure`]): the whole deformed cell (the quarter's outer faces
//! mirrored about x = 0 and z = 0) standing on the substrate — the floor and the pillars of
//! the lattice around the cell, or the flat plane — seen from above at an angle
//! ([`Camera::DEFAULT`]: elevation 30°, azimuth 35°), orthographic. It shows what no section
//! does: how the cell nests between the four pillars, or sags into the gap between two. A
//! renderer of its own: each curved six-node face subdivided into small flat triangles with
//! the exact normals of the P2 surface at their corners, the pillars as superellipsoid
//! caps on prisms, rasterised with a depth buffer at twice the resolution and averaged
//! down (smooth outlines), Lambert shading with one light, the picture blitted into a
//! plotters bitmap that adds the title, the legend or colour bar and the axes. Coloured by
//! domain (the outer surface is the membrane: its green, shaded) or by the mean ‖E‖ of the
//! element under each face ([`Coloring`]) with a colour bar; the strain is largest where
//! the cell touches the substrate, which no view from above shows, so the strain figure
//! has a second panel: the cell alone from 60° below ([`Camera::below`]), shaded at half
//! strength so that the colours can be read against the bar.
//!
//! **Accuracy.** The sections of the reference cell through its centre are the disks of
//! the three balls to 1e-4 of their areas (the P2 spheres and the chords that trace them;
//! `tests/output3.rs`).
//!
//! What it may import of [`super`]: [`super::draw`] (the primitives and the plane drawing
//! it shares with the 2-D shapes), [`super::geometry`], [`super::time_plots`] (the time
//! plots of [`plot_quarter_run`]) and [`super::vtu`] (the snapshot's check), and the error
//! types and [`super::draw_png`] of [`super`]; [`super::figures`] and [`super::movie`]
//! import it. Its public items are also reachable at their former paths,
//! `output::cell3d_views::…`.

use std::collections::{HashMap, HashSet};
use std::f64::consts::{FRAC_1_SQRT_2, PI};
use std::path::{Path, PathBuf};

use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::draw::{
    FONT, GravityMark, MEMBRANE, PlaneDrawing, SHAPE_SIZE, SUBSTRATE, ShapeScale,
    ShapeStyleOptions, check_displacements, draw_in_plane, phase_title,
};
use super::geometry::{
    ACTIVE_LEVEL, ActiveRegion, Backdrop, Bounds, CellShape, Pt, contour, element_polygon,
    intervals,
};
use super::vtu::VtuMesh;
use super::{DrawError, OutputError, draw_png};
use crate::fem::{Domain, Lagrange, Tet10, Tri6, tet10 as tet, tri6 as p2};
use crate::physics::{ActiveStrain, LatticeSubstrate, Substrate, smooth_step};
use crate::run_files::read::QuarterRunData;
use crate::run_files::{QuarterMeshFile, QuarterSnapshot, RunData};

/// Pixel size of the section and surface figures (as the 2-D shape figures).
pub const FIGURE_SIZE: (u32, u32) = SHAPE_SIZE;

/// Straight pieces per curved side of a face in the section z = 0.
pub const SECTION_EDGE_PIECES: usize = 8;

/// Divisions per edge of a tetrahedron's reference element cut by the plane x = z (its
/// CUT_DIVISIONS³ sub-tetrahedra are cut one by one).
pub const CUT_DIVISIONS: usize = 6;

/// Divisions per side of a face of the section z = 0 when contouring an active region.
const CONTOUR_DIVISIONS: usize = 6;

/// Pieces per boundary edge of the section z = 0 when clipping it to an active region.
const EDGE_CLIP_PIECES: usize = 16;

/// Step of the contour of the fibronectin layer's edge \[µm\].
const LAYER_STEP: f64 = 0.05;

/// Divisions per side of a curved outer face in the surface view.
pub const SURFACE_DIVISIONS: usize = 4;

/// Supersampling factor of the surface view (per axis).
const SUPERSAMPLE: usize = 2;

/// Fill colour of the floor in the surface view (the pillars are [`SUBSTRATE`]).
pub const FLOOR: RGBColor = RGBColor(200, 200, 200);

/// Shading of the surface view: a surface's colour times AMBIENT + KEY cos(key light) +
/// FILL cos(fill light from the viewer), each cosine clamped at 0.
const AMBIENT: f64 = 0.32;
const KEY: f64 = 0.5;
const FILL: f64 = 0.3;

/// The vertical plane through the cell's axis a section figure cuts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Section {
    /// The symmetry plane z = 0 (the 2-D model's plane).
    Z0,
    /// The diagonal plane x = z.
    Diagonal,
}

impl Section {
    /// Both planes.
    pub const ALL: [Section; 2] = [Section::Z0, Section::Diagonal];

    /// The horizontal coordinate in the plane of the point `p`, from the axis through `c`:
    /// x − c_x (z = 0) or ((x − c_x) + (z − c_z))/√2 (x = z).
    pub fn horizontal(self, p: [f64; 3], c: [f64; 3]) -> f64 {
        match self {
            Section::Z0 => p[0] - c[0],
            Section::Diagonal => FRAC_1_SQRT_2 * ((p[0] - c[0]) + (p[2] - c[2])),
        }
    }

    /// The plane coordinates (horizontal, y) of `p`.
    pub fn to_plane(self, p: [f64; 3], c: [f64; 3]) -> Pt {
        [self.horizontal(p, c), p[1]]
    }

    /// The horizontal point (x, z) of the section line at horizontal coordinate `h`.
    pub fn line_point(self, h: f64, c: [f64; 3]) -> (f64, f64) {
        match self {
            Section::Z0 => (c[0] + h, c[2]),
            Section::Diagonal => (c[0] + FRAC_1_SQRT_2 * h, c[2] + FRAC_1_SQRT_2 * h),
        }
    }

    /// The plane's equation, for titles.
    pub fn name(self) -> &'static str {
        match self {
            Section::Z0 => "z = 0",
            Section::Diagonal => "x = z",
        }
    }

    /// A short tag for file names: `z0` or `diagonal`.
    pub fn tag(self) -> &'static str {
        match self {
            Section::Z0 => "z0",
            Section::Diagonal => "diagonal",
        }
    }

    /// The label of the horizontal axis.
    pub fn axis_label(self) -> &'static str {
        match self {
            Section::Z0 => "x (µm), in the plane z = 0",
            Section::Diagonal => "(x + z)/√2 (µm), in the plane x = z",
        }
    }
}

/// A point of a section: where it is in the reference configuration and where it is drawn.
#[derive(Debug, Clone, Copy)]
struct SPt {
    /// Reference position \[µm\].
    x: [f64; 3],
    /// Deformed position in the plane's coordinates \[µm\].
    p: Pt,
}

/// Which interface a section's interface line lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Interface {
    /// Nucleus | cytoplasm.
    Nucleus,
    /// Cytoplasm | membrane.
    Membrane,
}

impl Interface {
    fn between(a: Domain, b: Domain) -> Self {
        if a == Domain::Nucleus || b == Domain::Nucleus {
            Interface::Nucleus
        } else {
            Interface::Membrane
        }
    }
}

/// The indicator χ of `region` at reference point `x` of a cell centred at height `c_z`,
/// without the domain restriction (the 3-D counterpart of the 2-D one in
/// [`super::geometry`]).
fn chi_revolved(region: ActiveRegion, a: &ActiveStrain, x: [f64; 3], c_z: f64) -> f64 {
    let v = Vector3::from(x);
    match region {
        ActiveRegion::Pac => a.chi_pac_revolved(&v, c_z),
        ActiveRegion::Bottom => a.chi_bottom_revolved(&v, c_z),
    }
}

/// The deformed cell cut by a [`Section`] plane, ready to draw: everything in the plane's
/// coordinates (horizontal, y) \[µm\].
#[derive(Debug, Clone)]
pub struct SectionShape {
    /// The plane.
    pub plane: Section,
    /// The cell in the plane: its filled pieces (`elements`: the faces in the plane z = 0,
    /// curved sides traced; the cut polygons of the sub-tetrahedra in the plane x = z),
    /// outline, interfaces, active-region outlines and the markers p_t, c, p_b.
    pub cell: CellShape,
    /// The elements' outlines in the plane (closed polylines for z = 0, segments for x = z),
    /// with the element's domain.
    pub mesh_lines: Vec<(Domain, Vec<Pt>)>,
}

/// The four faces of every tetrahedron by their sorted vertex triples: (element, local face).
type FaceMap = HashMap<[usize; 3], Vec<(usize, usize)>>;

/// The key of a face in a [`FaceMap`]: its vertices sorted.
fn face_key(mut v: [usize; 3]) -> [usize; 3] {
    v.sort_unstable();
    v
}

fn face_map(mesh: &QuarterMeshFile) -> FaceMap {
    let mut map: FaceMap = HashMap::with_capacity(2 * mesh.elements.len());
    for (e, el) in mesh.elements.iter().enumerate() {
        for (k, f) in tet::TET_FACES.iter().enumerate() {
            map.entry(face_key([el[f[0]], el[f[1]], el[f[2]]]))
                .or_default()
                .push((e, k));
        }
    }
    map
}

fn outer_set(mesh: &QuarterMeshFile) -> HashSet<[usize; 3]> {
    mesh.outer_faces
        .iter()
        .map(|f| face_key([f[0], f[1], f[2]]))
        .collect()
}

/// The point of a P2 element (a six-node face or a ten-node tetrahedron) whose node values
/// are `v`, at the local point where its shape functions are `n`.
fn p2_point<const N: usize, const D: usize>(n: [f64; N], v: &[[f64; D]; N]) -> [f64; D] {
    let mut out = [0.0; D];
    for a in 0..N {
        for k in 0..D {
            out[k] += n[a] * v[a][k];
        }
    }
    out
}

fn lerp(a: &SPt, b: &SPt, w: f64) -> SPt {
    let l = |p: f64, q: f64| p + w * (q - p);
    SPt {
        x: [l(a.x[0], b.x[0]), l(a.x[1], b.x[1]), l(a.x[2], b.x[2])],
        p: [l(a.p[0], b.p[0]), l(a.p[1], b.p[1])],
    }
}

/// Shoelace area of a polygon (absolute).
pub fn polygon_area(poly: &[Pt]) -> f64 {
    let n = poly.len();
    let mut s = 0.0;
    for i in 0..n {
        let (p, q) = (poly[i], poly[(i + 1) % n]);
        s += p[0] * q[1] - q[0] * p[1];
    }
    0.5 * s.abs()
}

/// What the section builders collect before the active outlines are traced.
#[derive(Default)]
struct Collected {
    fills: Vec<(Domain, Vec<Pt>)>,
    mesh_lines: Vec<(Domain, Vec<Pt>)>,
    outer: Vec<Vec<SPt>>,
    interfaces: Vec<(Interface, Vec<SPt>)>,
    /// Small polygons (with reference points) on which the active indicators are contoured.
    pieces: Vec<(Domain, Vec<SPt>)>,
}

/// The section z = 0: the boundary faces of the mesh in the plane z = c_z.
fn collect_z0(mesh: &QuarterMeshFile, pos: &[Pt]) -> Collected {
    let c = mesh.center;
    let r = cell_radius(mesh);
    let tol = 1e-9 * r.max(1.0);
    let outer_edges: HashSet<[usize; 2]> = mesh
        .outer_faces
        .iter()
        .flat_map(|f| p2::EDGES.map(|e| sorted2([f[e[0]], f[e[2]]])))
        .collect();
    let mut faces: Vec<(Domain, [usize; 6])> = Vec::new();
    for (el, &d) in mesh.elements.iter().zip(&mesh.domains) {
        for f in tet::TET_FACES {
            let nodes = f.map(|a| el[a]);
            if nodes
                .iter()
                .all(|&i| (mesh.nodes[i][2] - c[2]).abs() <= tol)
            {
                faces.push((d, nodes));
            }
        }
    }
    let mut out = Collected::default();
    let mut edges: HashMap<[usize; 2], Vec<(usize, usize)>> = HashMap::new();
    for (k, (d, f)) in faces.iter().enumerate() {
        let xd: [Pt; 6] = f.map(|i| pos[i]);
        let poly = element_polygon(&xd, SECTION_EDGE_PIECES);
        let mut closed = poly.clone();
        closed.push(poly[0]);
        out.fills.push((*d, poly));
        out.mesh_lines.push((*d, closed));
        for (j, e) in p2::EDGES.iter().enumerate() {
            edges
                .entry(sorted2([f[e[0]], f[e[2]]]))
                .or_default()
                .push((k, j));
        }
        // Sub-triangles for the active contours.
        let xr: [[f64; 3]; 6] = f.map(|i| mesh.nodes[i]);
        let n = CONTOUR_DIVISIONS;
        let at = |i: usize, j: usize| {
            let xi = [i as f64 / n as f64, j as f64 / n as f64];
            let shape = Tri6::shape(xi);
            SPt {
                x: p2_point(shape, &xr),
                p: p2_point(shape, &xd),
            }
        };
        for i in 0..n {
            for j in 0..n - i {
                out.pieces
                    .push((*d, vec![at(i, j), at(i + 1, j), at(i, j + 1)]));
                if i + j + 1 < n {
                    out.pieces
                        .push((*d, vec![at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]));
                }
            }
        }
    }
    let line = |k: usize, j: usize| -> Vec<SPt> {
        let f = &faces[k].1;
        let e = p2::EDGES[j];
        let xr: [[f64; 3]; 3] = e.map(|a| mesh.nodes[f[a]]);
        let xd: [Pt; 3] = e.map(|a| pos[f[a]]);
        (0..=EDGE_CLIP_PIECES)
            .map(|m| {
                let s = m as f64 / EDGE_CLIP_PIECES as f64;
                let n = p2::edge_shape(s);
                let mut x = [0.0; 3];
                let mut p = [0.0; 2];
                for a in 0..3 {
                    for q in 0..3 {
                        x[q] += n[a] * xr[a][q];
                    }
                    for q in 0..2 {
                        p[q] += n[a] * xd[a][q];
                    }
                }
                SPt { x, p }
            })
            .collect()
    };
    let mut keys: Vec<&[usize; 2]> = edges.keys().collect();
    keys.sort_unstable();
    for key in keys {
        let users = &edges[key];
        match users[..] {
            [(k, j)] if outer_edges.contains(key) => out.outer.push(line(k, j)),
            [(k, j), (k2, _)] if faces[k].0 != faces[k2].0 => out
                .interfaces
                .push((Interface::between(faces[k].0, faces[k2].0), line(k, j))),
            _ => {}
        }
    }
    out
}

fn sorted2(v: [usize; 2]) -> [usize; 2] {
    if v[0] <= v[1] { v } else { [v[1], v[0]] }
}

/// The sub-tetrahedra of the reference tetrahedron divided `n` times per edge (n³ of
/// them), as indices into the lattice points (i, j, k)/n, i + j + k ≤ n, which are
/// returned with them.
fn subdivision(n: usize) -> (Vec<[usize; 3]>, Vec<[usize; 4]>) {
    let mut pts = Vec::new();
    let mut index = HashMap::new();
    for i in 0..=n {
        for j in 0..=n - i {
            for k in 0..=n - i - j {
                index.insert([i, j, k], pts.len());
                pts.push([i, j, k]);
            }
        }
    }
    let id = |p: [usize; 3]| index[&p];
    let add = |p: [usize; 3], d: [usize; 3]| [p[0] + d[0], p[1] + d[1], p[2] + d[2]];
    let (e1, e2, e3) = ([1, 0, 0], [0, 1, 0], [0, 0, 1]);
    let mut tets = Vec::new();
    for &p in &pts {
        let s = p[0] + p[1] + p[2];
        if s < n {
            tets.push([id(p), id(add(p, e1)), id(add(p, e2)), id(add(p, e3))]);
        }
        if s + 1 < n {
            // The octahedron between, split around its diagonal A–F.
            let a = id(add(p, e1));
            let f = id(add(p, [0, 1, 1]));
            let b = id(add(p, e2));
            let c = id(add(p, e3));
            let d = id(add(p, [1, 1, 0]));
            let e = id(add(p, [1, 0, 1]));
            tets.extend([[a, f, b, c], [a, f, c, e], [a, f, e, d], [a, f, d, b]]);
        }
        if s + 2 < n {
            tets.push([
                id(add(p, [1, 1, 0])),
                id(add(p, [1, 0, 1])),
                id(add(p, [0, 1, 1])),
                id(add(p, [1, 1, 1])),
            ]);
        }
    }
    (pts, tets)
}

/// The section x = z: every tetrahedron cut by the reference plane X − c_x = Z − c_z.
fn collect_diagonal(mesh: &QuarterMeshFile, pos: &[Pt]) -> Collected {
    let c = mesh.center;
    let n = CUT_DIVISIONS;
    let (lattice, subs) = subdivision(n);
    let xis: Vec<[f64; 3]> = lattice
        .iter()
        .map(|p| p.map(|v| v as f64 / n as f64))
        .collect();
    // Barycentric coordinates ×n: λ₀ … λ₃ of each lattice point.
    let bary: Vec<[usize; 4]> = lattice
        .iter()
        .map(|p| [n - p[0] - p[1] - p[2], p[0], p[1], p[2]])
        .collect();
    let shapes: Vec<[f64; 10]> = xis.iter().map(|&xi| Tet10::shape(xi)).collect();
    let faces = face_map(mesh);
    let outer = outer_set(mesh);
    let mut out = Collected::default();
    for (e, (el, &d)) in mesh.elements.iter().zip(&mesh.domains).enumerate() {
        let f: [f64; 10] = el.map(|i| {
            let p = mesh.nodes[i];
            (p[0] - c[0]) - (p[2] - c[2])
        });
        let vals: Vec<f64> = shapes
            .iter()
            .map(|n| n.iter().zip(&f).map(|(a, b)| a * b).sum())
            .collect();
        if vals.iter().all(|&v| v >= 0.0) || vals.iter().all(|&v| v < 0.0) {
            continue;
        }
        let xr: [[f64; 3]; 10] = el.map(|i| mesh.nodes[i]);
        let xd: [Pt; 10] = el.map(|i| pos[i]);
        // The point where the lattice edge a (≥ 0) – b (< 0) crosses zero.
        let cross = |a: usize, b: usize| -> SPt {
            let w = vals[a] / (vals[a] - vals[b]);
            let xi = [0, 1, 2].map(|k| xis[a][k] + w * (xis[b][k] - xis[a][k]));
            let shape = Tet10::shape(xi);
            SPt {
                x: p2_point(shape, &xr),
                p: p2_point(shape, &xd),
            }
        };
        // What the tetrahedron's face opposite vertex m is: outer, interface, inner.
        let classify = |m: usize| -> Option<(usize, Domain)> {
            let tf = tet::TET_FACES[m];
            let key = face_key([el[tf[0]], el[tf[1]], el[tf[2]]]);
            faces
                .get(&key)
                .and_then(|v| v.iter().find(|(e2, _)| *e2 != e))
                .map(|&(e2, _)| (e2, mesh.domains[e2]))
                .or_else(|| outer.contains(&key).then_some((usize::MAX, d)))
        };
        for sub in &subs {
            let pos_ix: Vec<usize> = sub.iter().copied().filter(|&a| vals[a] >= 0.0).collect();
            let neg_ix: Vec<usize> = sub.iter().copied().filter(|&a| vals[a] < 0.0).collect();
            // The polygon as (lattice edge) pairs in cyclic order.
            let ring: Vec<(usize, usize)> = match (pos_ix.len(), neg_ix.len()) {
                (1, 3) => neg_ix.iter().map(|&b| (pos_ix[0], b)).collect(),
                (3, 1) => pos_ix.iter().map(|&a| (a, neg_ix[0])).collect(),
                (2, 2) => {
                    let ([a, b], [p, q]) = ([pos_ix[0], pos_ix[1]], [neg_ix[0], neg_ix[1]]);
                    vec![(a, p), (a, q), (b, q), (b, p)]
                }
                _ => continue,
            };
            let pts: Vec<SPt> = ring.iter().map(|&(a, b)| cross(a, b)).collect();
            out.fills.push((d, pts.iter().map(|s| s.p).collect()));
            // Sides of the polygon that lie on a face of the tetrahedron.
            for k in 0..ring.len() {
                let (e1, e2) = (ring[k], ring[(k + 1) % ring.len()]);
                let mut verts = vec![e1.0, e1.1, e2.0, e2.1];
                verts.sort_unstable();
                verts.dedup();
                if verts.len() != 3 {
                    continue;
                }
                let Some(m) = (0..4).find(|&m| verts.iter().all(|&v| bary[v][m] == 0)) else {
                    continue;
                };
                let seg = vec![pts[k], pts[(k + 1) % pts.len()]];
                match classify(m) {
                    Some((usize::MAX, _)) => out.outer.push(seg),
                    Some((e2, d2)) if e < e2 => {
                        if d2 == d {
                            out.mesh_lines.push((d, vec![seg[0].p, seg[1].p]));
                        } else {
                            out.interfaces.push((Interface::between(d, d2), seg));
                        }
                    }
                    _ => {}
                }
            }
            out.pieces.push((d, pts));
        }
    }
    out
}

/// The largest distance of a node from the centre: the cell radius r_c.
fn cell_radius(mesh: &QuarterMeshFile) -> f64 {
    let c = mesh.center;
    mesh.nodes
        .iter()
        .map(|p| distance(*p, c))
        .fold(0.0f64, f64::max)
}

fn distance(p: [f64; 3], q: [f64; 3]) -> f64 {
    ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

/// Deformed node positions x = X + u.
fn deformed_positions(mesh: &QuarterMeshFile, u: &[[f64; 3]]) -> Vec<[f64; 3]> {
    mesh.nodes
        .iter()
        .zip(u)
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1], p[2] + d[2]])
        .collect()
}

/// Segments of the level χ = ½ inside the pieces the region may occupy, and the parts of
/// the bounding lines where χ ≥ ½.
fn active_outline(
    col: &Collected,
    a: &ActiveStrain,
    region: ActiveRegion,
    c_z: f64,
) -> Vec<[Pt; 2]> {
    let mut segs = Vec::new();
    for (d, piece) in &col.pieces {
        if !region.allowed(*d) {
            continue;
        }
        let v: Vec<f64> = piece
            .iter()
            .map(|s| chi_revolved(region, a, s.x, c_z) - ACTIVE_LEVEL)
            .collect();
        let mut cuts = Vec::with_capacity(4);
        for k in 0..piece.len() {
            let l = (k + 1) % piece.len();
            if (v[k] >= 0.0) != (v[l] >= 0.0) {
                let w = v[k] / (v[k] - v[l]);
                cuts.push(lerp(&piece[k], &piece[l], w).p);
            }
        }
        for pair in cuts.chunks_exact(2) {
            segs.push([pair[0], pair[1]]);
        }
    }
    let bounding: Vec<&Vec<SPt>> = match region {
        ActiveRegion::Pac => col.interfaces.iter().map(|(_, l)| l).collect(),
        ActiveRegion::Bottom => col
            .interfaces
            .iter()
            .filter(|(k, _)| *k == Interface::Nucleus)
            .map(|(_, l)| l)
            .chain(&col.outer)
            .collect(),
    };
    for line in bounding {
        for w in line.windows(2) {
            let (v0, v1) = (
                chi_revolved(region, a, w[0].x, c_z) - ACTIVE_LEVEL,
                chi_revolved(region, a, w[1].x, c_z) - ACTIVE_LEVEL,
            );
            let at = |s: f64| lerp(&w[0], &w[1], s).p;
            match (v0 >= 0.0, v1 >= 0.0) {
                (true, true) => segs.push([w[0].p, w[1].p]),
                (false, false) => {}
                (true, false) => segs.push([w[0].p, at(v0 / (v0 - v1))]),
                (false, true) => segs.push([at(v0 / (v0 - v1)), w[1].p]),
            }
        }
    }
    segs
}

impl SectionShape {
    /// The quarter cell of `mesh` displaced by `u` (one entry per node), cut by `plane`:
    /// the half section (horizontal coordinate ≥ 0); [`Self::mirrored`] gives the whole.
    pub fn new(mesh: &QuarterMeshFile, u: &[[f64; 3]], plane: Section) -> Self {
        let c = mesh.center;
        let x = deformed_positions(mesh, u);
        let pos: Vec<Pt> = x.iter().map(|p| plane.to_plane(*p, c)).collect();
        let col = match plane {
            Section::Z0 => collect_z0(mesh, &pos),
            Section::Diagonal => collect_diagonal(mesh, &pos),
        };
        let (mut pac, mut bottom) = (Vec::new(), Vec::new());
        if let Some(a) = &mesh.active {
            if ActiveRegion::Pac.present(a) {
                pac = active_outline(&col, a, ActiveRegion::Pac, c[2]);
            }
            if ActiveRegion::Bottom.present(a) {
                bottom = active_outline(&col, a, ActiveRegion::Bottom, c[2]);
            }
        }
        let plain = |l: &Vec<SPt>| l.iter().map(|s| s.p).collect::<Vec<Pt>>();
        SectionShape {
            plane,
            cell: CellShape {
                elements: col.fills,
                outer: col.outer.iter().map(plain).collect(),
                interfaces: col.interfaces.iter().map(|(_, l)| plain(l)).collect(),
                pac,
                bottom,
                markers: markers(mesh, &x, plane),
            },
            mesh_lines: col.mesh_lines,
        }
    }

    /// The whole section: this half and its mirror image about the cell's axis.
    pub fn mirrored(&self) -> Self {
        let m = |p: &Pt| [-p[0], p[1]];
        let mut mesh_lines = self.mesh_lines.clone();
        mesh_lines.extend(
            self.mesh_lines
                .iter()
                .map(|(d, l)| (*d, l.iter().map(m).collect())),
        );
        SectionShape {
            plane: self.plane,
            cell: self.cell.mirrored(),
            mesh_lines,
        }
    }

    /// The area of the filled pieces of domain `d` \[µm²\].
    pub fn area(&self, d: Domain) -> f64 {
        self.cell
            .elements
            .iter()
            .filter(|(dd, _)| *dd == d)
            .map(|(_, p)| polygon_area(p))
            .sum()
    }

    /// Bounding box of the filled pieces.
    pub fn bounds(&self) -> Bounds {
        self.cell.bounds()
    }
}

/// p_t, c, p_b: the nodes nearest to c ± (0, r_n, 0) and c, r_n the largest distance of a
/// nucleus node from c; their deformed positions in the plane.
fn markers(mesh: &QuarterMeshFile, x: &[[f64; 3]], plane: Section) -> Vec<Pt> {
    let c = mesh.center;
    let r_n = mesh
        .elements
        .iter()
        .zip(&mesh.domains)
        .filter(|(_, d)| **d == Domain::Nucleus)
        .flat_map(|(el, _)| el.iter().map(|&i| distance(mesh.nodes[i], c)))
        .fold(0.0f64, f64::max);
    let nearest = |target: [f64; 3]| -> Option<Pt> {
        (0..mesh.nodes.len())
            .min_by(|&i, &j| {
                distance(mesh.nodes[i], target).total_cmp(&distance(mesh.nodes[j], target))
            })
            .map(|i| plane.to_plane(x[i], c))
    };
    [[c[0], c[1] + r_n, c[2]], c, [c[0], c[1] - r_n, c[2]]]
        .into_iter()
        .filter_map(nearest)
        .collect()
}

/// The substrate and the fibronectin layer in a section plane, over a view, ready to draw.
#[derive(Debug, Clone)]
pub struct SectionBackdrop {
    /// The plane.
    pub plane: Section,
    /// The drawing in the plane's coordinates (h, y), over the view (h0, h1, y0, y1) it
    /// was computed for: the substrate as column rectangles from the view's bottom to the
    /// surface height, the fibronectin layer `{d_sub ≥ −e_f}` and its upper edge, the
    /// substrate's surface line along the section (one polyline); no pillar feet.
    pub backdrop: Backdrop,
}

impl SectionBackdrop {
    /// The section of `sub` by `plane` through the axis of centre `c`, with the layer of
    /// thickness `e_f`, over the view `[h0, h1, y0, y1]` in `columns` strips.
    pub fn new(
        sub: &LatticeSubstrate,
        e_f: Option<f64>,
        plane: Section,
        c: [f64; 3],
        view: [f64; 4],
        columns: usize,
    ) -> Self {
        let [h0, h1, y0, y1] = view;
        let n = columns.max(2);
        let dh = (h1 - h0) / n as f64;
        let height = |h: f64| {
            let (x, z) = plane.line_point(h, c);
            sub.surface_height(x, z)
        };
        let depth = |h: f64, y: f64| {
            let (x, z) = plane.line_point(h, c);
            sub.eval(&Vector3::new(x, y, z)).0
        };
        let mut b = Backdrop {
            view,
            substrate: Vec::with_capacity(n),
            ..Default::default()
        };
        for k in 0..n {
            let (ha, hb) = (h0 + k as f64 * dh, h0 + (k + 1) as f64 * dh);
            let hm = 0.5 * (ha + hb);
            let top = height(hm).min(y1);
            if top > y0 {
                b.substrate.push([ha, hb, y0, top]);
            }
            if let Some(e) = e_f {
                for [lo, hi] in intervals(|y| depth(hm, y) + e, y0, y1) {
                    b.layer.push([ha, hb, lo, hi]);
                }
            }
        }
        b.surface = vec![
            (0..=n)
                .map(|k| {
                    let h = h0 + k as f64 * dh;
                    [h, height(h)]
                })
                .collect(),
        ];
        if let Some(e) = e_f {
            b.layer_edge = match sub.plane {
                Substrate::Flat { y_s } => vec![[[h0, y_s + e], [h1, y_s + e]]],
                Substrate::Pillars(_) => contour(|h, y| depth(h, y) + e, view, LAYER_STEP),
            };
        }
        SectionBackdrop { plane, backdrop: b }
    }
}

impl AsRef<Backdrop> for SectionBackdrop {
    fn as_ref(&self) -> &Backdrop {
        &self.backdrop
    }
}

/// The region a set of section drawings shares: the reference cell and the deformed
/// sections of `states` and the substrate below them, with a margin of 1.5 µm, symmetric
/// about the axis.
pub fn section_view(mesh: &QuarterMeshFile, states: &[&QuarterSnapshot], plane: Section) -> Bounds {
    let c = mesh.center;
    let r = cell_radius(mesh);
    let mut b = Bounds {
        x_min: -r,
        x_max: r,
        y_min: c[1] - r,
        y_max: c[1] + r,
    };
    for s in states {
        if s.u.len() == mesh.nodes.len() {
            b = b.union(SectionShape::new(mesh, &s.u, plane).mirrored().bounds());
        }
    }
    b.around_axis(super::geometry::substrate_floor(&mesh.substrate.plane))
}

/// Gravity at time `t` with the phase times of `mesh`: down, ramped in over [0, T_g0]. (The
/// mesh file does not record a gravity flip.)
pub fn gravity_at(mesh: &QuarterMeshFile, t: f64) -> GravityMark {
    GravityMark {
        factor: smooth_step(t, 0.0, mesh.phase_times[0]),
        note: "gravity".to_string(),
    }
}

/// Draws the deformed whole cell of `mesh` displaced by `u`, cut by `plane`, into `area`
/// over `view`, with equal aspect (the 3-D twin of [`super::shapes::draw_shape`]).
/// `backdrop` caches the substrate drawing between calls with the same view and plane
/// (pass `&mut None` for a single drawing).
pub fn draw_section<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    mesh: &QuarterMeshFile,
    u: &[[f64; 3]],
    plane: Section,
    view: Bounds,
    opts: &ShapeStyleOptions,
    backdrop: &mut Option<SectionBackdrop>,
) -> Result<ShapeScale, DrawError> {
    check_displacements(u, mesh.nodes.len())?;
    let shape = SectionShape::new(mesh, u, plane).mirrored();
    let cell = PlaneDrawing {
        x_label: plane.axis_label(),
        substrate_label: format!("substrate (section {})", plane.name()),
        layer: mesh.layer_thickness.is_some(),
        shape: &shape.cell,
        mesh_lines: Some(&shape.mesh_lines),
    };
    draw_in_plane(
        area,
        &cell,
        view,
        opts,
        backdrop,
        |cached, key, columns| match cached {
            Some(b) if b.backdrop.view == key && b.plane == plane => b,
            _ => SectionBackdrop::new(
                &mesh.substrate,
                mesh.layer_thickness,
                plane,
                mesh.center,
                key,
                columns,
            ),
        },
    )
}

/// The deformed cell of `s` cut by `plane`, as a PNG of [`FIGURE_SIZE`] at `path` (see
/// [`draw_section`] and the module notes), with the legend, the element outlines and the
/// gravity arrow, over [`section_view`] of this state.
pub fn section_figure(
    path: &Path,
    mesh: &QuarterMeshFile,
    s: &QuarterSnapshot,
    plane: Section,
    title: &str,
) -> Result<(), OutputError> {
    mesh.check(s).map_err(|m| OutputError::draw(path, m))?;
    let view = section_view(mesh, &[s], plane);
    let opts = ShapeStyleOptions {
        title: title.to_string(),
        legend: true,
        font: 28,
        mesh_lines: true,
        gravity: Some(gravity_at(mesh, s.t)),
    };
    draw_png(path, FIGURE_SIZE, |root| {
        draw_section(root, mesh, &s.u, plane, view, &opts, &mut None).map(|_| ())
    })
}

// ---------------------------------------------------------------------------------------
// The surface view.

/// How the surface view colours the cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coloring {
    /// By domain: the outer surface is the membrane (green), shaded.
    Domain,
    /// By the mean ‖E‖ of the element under each face, with a colour bar.
    Strain,
}

/// Where the surface view is seen from: orthographic, looking at the cell from the
/// direction (cos el sin az, sin el, cos el cos az).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Angle of the line of sight above the horizontal [°].
    pub elevation_deg: f64,
    /// Angle of the line of sight about the vertical axis, from +z towards +x [°].
    pub azimuth_deg: f64,
}

impl Camera {
    /// From above at an angle: elevation 30°, azimuth 35°.
    pub const DEFAULT: Camera = Camera {
        elevation_deg: 30.0,
        azimuth_deg: 35.0,
    };

    /// The same azimuth, from 60° below the horizontal: the cell's underside, where it
    /// touches the substrate, nearly face on.
    pub fn below(&self) -> Camera {
        Camera {
            elevation_deg: -60.0,
            azimuth_deg: self.azimuth_deg,
        }
    }

    /// The screen's right and up directions and the direction towards the viewer (a
    /// right-handed orthonormal frame).
    pub fn basis(&self) -> [[f64; 3]; 3] {
        let (se, ce) = self.elevation_deg.to_radians().sin_cos();
        let (sa, ca) = self.azimuth_deg.to_radians().sin_cos();
        let right = [ca, 0.0, -sa];
        let up = [-se * sa, ce, -se * ca];
        let toward = [ce * sa, se, ce * ca];
        [right, up, toward]
    }

    /// The directions towards the lights: the key light from the upper left in front, the
    /// fill light from the viewer.
    fn lights(&self) -> [[f64; 3]; 2] {
        let [r, u, d] = self.basis();
        [
            normalize([0, 1, 2].map(|k| -0.45 * r[k] + 0.75 * u[k] + 0.5 * d[k])),
            d,
        ]
    }
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn normalize(a: [f64; 3]) -> [f64; 3] {
    let n = dot(a, a).sqrt();
    if n > 0.0 { a.map(|v| v / n) } else { a }
}

/// A point of a rendered surface and its unit normal.
#[derive(Debug, Clone, Copy)]
struct Vertex {
    p: [f64; 3],
    n: [f64; 3],
}

/// A flat triangle of a rendered surface, with its colour.
#[derive(Debug, Clone, Copy)]
struct Triangle {
    v: [Vertex; 3],
    color: [f64; 3],
}

fn rgb(c: RGBColor) -> [f64; 3] {
    [c.0 as f64, c.1 as f64, c.2 as f64]
}

/// The substrate's extent and the framing of a surface view.
#[derive(Debug, Clone, PartialEq)]
pub struct SurfaceFrame {
    /// The camera.
    pub camera: Camera,
    /// Half-widths of the floor drawn, in x and in z, about the cell's axis \[µm\].
    pub floor: [f64; 2],
    /// The box (right, up) in the camera's coordinates \[µm\] the picture shows.
    pub screen: Bounds,
    /// The box the view from below ([`Camera::below`], the cell alone) shows: the cell,
    /// with room for its contact to spread to 1.4 r_c.
    pub below: Bounds,
}

/// `b` grown by 3 % of its larger side on every side.
fn padded(b: Bounds) -> Bounds {
    let pad = 0.03 * (b.x_max - b.x_min).max(b.y_max - b.y_min);
    Bounds {
        x_min: b.x_min - pad,
        x_max: b.x_max + pad,
        y_min: b.y_min - pad,
        y_max: b.y_max + pad,
    }
}

/// Half-width of the floor in one horizontal direction: the first line midway between
/// pillar rows at least 1.5 r_c from the axis (so the pillars drawn are whole), or 1.6 r_c
/// on a flat substrate.
fn floor_half_width(p: Option<(f64, f64)>, c: f64, r: f64) -> f64 {
    match p {
        None => 1.6 * r,
        Some((first_axis, period)) => {
            // Mid-lines at first_axis + P/2 + kP.
            let base = first_axis + 0.5 * period - c;
            let k = ((1.5 * r - base) / period).ceil();
            base + k * period
        }
    }
}

impl SurfaceFrame {
    /// The frame showing the substrate around the cell of `mesh` and the cell of every state
    /// in `states` (the reference cell at least), seen by `camera`.
    pub fn new(mesh: &QuarterMeshFile, states: &[&QuarterSnapshot], camera: Camera) -> Self {
        let c = mesh.center;
        let r = cell_radius(mesh);
        let floor = match &mesh.substrate.plane {
            Substrate::Flat { .. } => [1.6 * r, 1.6 * r],
            Substrate::Pillars(p) => {
                let z0 = mesh.substrate.lattice.z_offset(p.period());
                [
                    floor_half_width(Some((p.first_center, p.period())), c[0], r),
                    floor_half_width(Some((z0, p.period())), c[2], r),
                ]
            }
        };
        let mut frame = SurfaceFrame {
            camera,
            floor,
            screen: Bounds::empty(),
            below: Bounds::empty(),
        };
        let deformed: Vec<Vec<[f64; 3]>> = states
            .iter()
            .filter(|s| s.u.len() == mesh.nodes.len())
            .map(|s| deformed_positions(mesh, &s.u))
            .collect();
        // The reference cell's silhouette and the deformed cells, seen by `cam`.
        let cell_box = |cam: Camera| {
            let [right, up, _] = cam.basis();
            let mut b = Bounds::empty();
            let mut add = |p: [f64; 3]| b.include([dot(p, right), dot(p, up)]);
            for k in 0..64 {
                let (dy, dx) = (2.0 * PI * k as f64 / 64.0).sin_cos();
                add([0, 1, 2].map(|i| c[i] + r * (dx * right[i] + dy * up[i])));
            }
            for x in &deformed {
                for &p in x {
                    for m in mirrors(c) {
                        add(m(p));
                    }
                }
            }
            (b, right, up)
        };
        let (mut b, right, up) = cell_box(camera);
        for t in substrate_triangles(mesh, &frame) {
            for v in t.v {
                b.include([dot(v.p, right), dot(v.p, up)]);
            }
        }
        frame.screen = padded(b);
        let (mut b, right, up) = cell_box(camera.below());
        for k in 0..64 {
            let (sz, sx) = (2.0 * PI * k as f64 / 64.0).sin_cos();
            let p = [c[0] + 1.4 * r * sx, c[1] - r, c[2] + 1.4 * r * sz];
            b.include([dot(p, right), dot(p, up)]);
        }
        frame.below = padded(b);
        frame
    }
}

/// The four mirror images about x = c_x and z = c_z (the identity first).
fn mirrors(c: [f64; 3]) -> [impl Fn([f64; 3]) -> [f64; 3]; 4] {
    [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)].map(|(sx, sz)| {
        move |p: [f64; 3]| [c[0] + sx * (p[0] - c[0]), p[1], c[2] + sz * (p[2] - c[2])]
    })
}

/// The floor and the pillars within the frame's floor, as shaded-surface triangles.
fn substrate_triangles(mesh: &QuarterMeshFile, frame: &SurfaceFrame) -> Vec<Triangle> {
    let c = mesh.center;
    let [lx, lz] = frame.floor;
    let mut out = Vec::new();
    let up = [0.0, 1.0, 0.0];
    let quad = |out: &mut Vec<Triangle>, v: [Vertex; 4], color: [f64; 3]| {
        out.push(Triangle {
            v: [v[0], v[1], v[2]],
            color,
        });
        out.push(Triangle {
            v: [v[0], v[2], v[3]],
            color,
        });
    };
    let floor_y = super::geometry::substrate_floor(&mesh.substrate.plane);
    let corner = |sx: f64, sz: f64| Vertex {
        p: [c[0] + sx * lx, floor_y, c[2] + sz * lz],
        n: up,
    };
    quad(
        &mut out,
        [
            corner(-1.0, -1.0),
            corner(1.0, -1.0),
            corner(1.0, 1.0),
            corner(-1.0, 1.0),
        ],
        rgb(FLOOR),
    );
    let Substrate::Pillars(p) = &mesh.substrate.plane else {
        return out;
    };
    let (a, b, q) = (0.5 * p.width, 0.5 * p.height, p.q);
    let per = p.period();
    let z0 = mesh.substrate.lattice.z_offset(per);
    let axes = |first: f64, lo: f64, hi: f64| -> Vec<f64> {
        let k0 = ((lo + a - first) / per).ceil() as i64;
        let k1 = ((hi - a - first) / per).floor() as i64;
        (k0..=k1).map(|k| first + k as f64 * per).collect()
    };
    let f = |t: f64| t.signum() * t.abs().powf(2.0 / q);
    let g = |s: f64| s.signum() * s.abs().powf(q - 1.0);
    let (na, ne) = (96usize, 24usize);
    let color = rgb(SUBSTRATE);
    let y_mid = p.y_top - b;
    for &ax in &axes(p.first_center, c[0] - lx, c[0] + lx) {
        for &az in &axes(z0, c[2] - lz, c[2] + lz) {
            let cap = |i: usize, j: usize| {
                let om = 2.0 * PI * i as f64 / na as f64;
                let eta = 0.5 * PI * j as f64 / ne as f64;
                let (ce, se) = (eta.cos(), eta.sin());
                let (xt, zt, yt) = (a * f(ce) * f(om.cos()), a * f(ce) * f(om.sin()), b * f(se));
                let n = normalize([g(xt / a) / a, g(yt / b) / b, g(zt / a) / a]);
                Vertex {
                    p: [ax + xt, y_mid + yt, az + zt],
                    n,
                }
            };
            for i in 0..na {
                for j in 0..ne {
                    quad(
                        &mut out,
                        [cap(i, j), cap(i + 1, j), cap(i + 1, j + 1), cap(i, j + 1)],
                        color,
                    );
                }
                // The side below the equator, down to the floor.
                let (top0, top1) = (cap(i, 0), cap(i + 1, 0));
                let low = |v: Vertex| Vertex {
                    p: [v.p[0], p.y_top - p.height, v.p[2]],
                    n: v.n,
                };
                quad(&mut out, [low(top0), low(top1), top1, top0], color);
            }
        }
    }
    out
}

/// The membrane colour, or the colour of `value` on [0, `max`] (viridis).
fn strain_color(value: f64, max: f64) -> [f64; 3] {
    let c: RGBColor =
        ViridisRGB.get_color_normalized(value.clamp(0.0, max) as f32, 0.0, max as f32);
    rgb(c)
}

/// The whole deformed cell's outer surface: the quarter's outer faces subdivided and
/// mirrored four times, coloured by `coloring` (strain on [0, `strain_max`]).
fn cell_triangles(
    mesh: &QuarterMeshFile,
    s: &QuarterSnapshot,
    coloring: Coloring,
    strain_max: f64,
) -> Vec<Triangle> {
    let c = mesh.center;
    let x = deformed_positions(mesh, &s.u);
    let element_of: HashMap<[usize; 3], usize> = {
        let outer = outer_set(mesh);
        let mut m = HashMap::new();
        for (e, el) in mesh.elements.iter().enumerate() {
            for f in tet::TET_FACES {
                let key = face_key([el[f[0]], el[f[1]], el[f[2]]]);
                if outer.contains(&key) {
                    m.insert(key, e);
                }
            }
        }
        m
    };
    let n = SURFACE_DIVISIONS;
    let mut out = Vec::with_capacity(4 * mesh.outer_faces.len() * n * n);
    for f in &mesh.outer_faces {
        let color = match coloring {
            Coloring::Domain => rgb(MEMBRANE),
            Coloring::Strain => {
                let e = element_of.get(&face_key([f[0], f[1], f[2]]));
                let v = e.map_or(0.0, |&e| s.element_strain[e]);
                strain_color(v, strain_max)
            }
        };
        let xd: [[f64; 3]; 6] = f.map(|i| x[i]);
        let at = |i: usize, j: usize| {
            let (p, nrm) = tet::face_map(&xd, [i as f64 / n as f64, j as f64 / n as f64]);
            Vertex {
                p,
                n: normalize(nrm),
            }
        };
        let mut quarter = Vec::with_capacity(n * n);
        for i in 0..n {
            for j in 0..n - i {
                quarter.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
                if i + j + 1 < n {
                    quarter.push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
        }
        for (k, m) in mirrors(c).iter().enumerate() {
            let (sx, sz) = (
                if k % 2 == 1 { -1.0 } else { 1.0 },
                if k >= 2 { -1.0 } else { 1.0 },
            );
            for t in &quarter {
                out.push(Triangle {
                    v: t.map(|v| Vertex {
                        p: m(v.p),
                        n: [sx * v.n[0], v.n[1], sz * v.n[2]],
                    }),
                    color,
                });
            }
        }
    }
    out
}

/// A depth-buffered raster of shaded triangles.
struct Raster {
    w: usize,
    h: usize,
    rgb: Vec<[f32; 3]>,
    depth: Vec<f64>,
}

impl Raster {
    fn new(w: usize, h: usize) -> Self {
        Raster {
            w,
            h,
            rgb: vec![[255.0; 3]; w * h],
            depth: vec![f64::NEG_INFINITY; w * h],
        }
    }

    /// Draws `t` with its vertices at screen points `s` (x right, y down, depth towards
    /// the viewer), normals interpolated and shaded by the key and the fill light
    /// `light` (unit directions towards them); `strength` ∈ [0, 1] scales the shading
    /// (0: the flat colour).
    fn triangle(&mut self, s: [[f64; 3]; 3], t: &Triangle, light: [[f64; 3]; 2], strength: f64) {
        let area =
            (s[1][0] - s[0][0]) * (s[2][1] - s[0][1]) - (s[2][0] - s[0][0]) * (s[1][1] - s[0][1]);
        if area.abs() < 1e-12 {
            return;
        }
        // The pixels the triangle's bounding box covers along screen axis k (`len` of them).
        let pixels = |k: usize, len: usize| {
            let lo = s.iter().map(|p| p[k]).fold(f64::INFINITY, f64::min);
            let hi = s.iter().map(|p| p[k]).fold(f64::NEG_INFINITY, f64::max);
            (lo.floor().max(0.0) as usize)..(hi.ceil() as usize).min(len)
        };
        let (xs, ys) = (pixels(0, self.w), pixels(1, self.h));
        let edge = |a: [f64; 3], b: [f64; 3], x: f64, y: f64| {
            (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0])
        };
        for py in ys {
            for px in xs.clone() {
                let (x, y) = (px as f64 + 0.5, py as f64 + 0.5);
                let w0 = edge(s[1], s[2], x, y) / area;
                let w1 = edge(s[2], s[0], x, y) / area;
                let w2 = edge(s[0], s[1], x, y) / area;
                if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                    continue;
                }
                let z = w0 * s[0][2] + w1 * s[1][2] + w2 * s[2][2];
                let k = py * self.w + px;
                if z <= self.depth[k] {
                    continue;
                }
                self.depth[k] = z;
                let n = normalize(
                    [0, 1, 2].map(|i| w0 * t.v[0].n[i] + w1 * t.v[1].n[i] + w2 * t.v[2].n[i]),
                );
                let lit =
                    AMBIENT + KEY * dot(n, light[0]).max(0.0) + FILL * dot(n, light[1]).max(0.0);
                let shade = 1.0 - strength + strength * lit;
                self.rgb[k] = t.color.map(|c| (c * shade).clamp(0.0, 255.0) as f32);
            }
        }
    }

    /// The raster averaged over `f` × `f` blocks, as RGB bytes.
    fn downsample(&self, f: usize) -> (usize, usize, Vec<u8>) {
        let (w, h) = (self.w / f, self.h / f);
        let mut out = Vec::with_capacity(3 * w * h);
        for y in 0..h {
            for x in 0..w {
                let mut acc = [0.0f32; 3];
                for dy in 0..f {
                    for dx in 0..f {
                        let p = self.rgb[(f * y + dy) * self.w + f * x + dx];
                        for k in 0..3 {
                            acc[k] += p[k];
                        }
                    }
                }
                for a in acc {
                    out.push((a / (f * f) as f32).round().clamp(0.0, 255.0) as u8);
                }
            }
        }
        (w, h, out)
    }
}

/// The largest element mean ‖E‖ under the outer faces (at least 1e-3): the top of the
/// colour bar.
fn outer_strain_max(mesh: &QuarterMeshFile, s: &QuarterSnapshot) -> f64 {
    let outer = outer_set(mesh);
    mesh.elements
        .iter()
        .enumerate()
        .filter(|(_, el)| {
            tet::TET_FACES
                .iter()
                .any(|f| outer.contains(&face_key([el[f[0]], el[f[1]], el[f[2]]])))
        })
        .map(|(e, _)| s.element_strain[e])
        .filter(|v| v.is_finite())
        .fold(1e-3, f64::max)
}

/// Options of [`draw_surface`].
#[derive(Debug, Clone)]
pub struct SurfaceStyleOptions {
    /// Title above the drawing.
    pub title: String,
    /// How the cell is coloured.
    pub coloring: Coloring,
    /// Font size of the title (other texts scale with it).
    pub font: u32,
    /// Draw the legend (domain colouring), the axes and the caption.
    pub legend: bool,
}

/// Shading strength of the strain colouring: half, so that the colours stay readable
/// against the colour bar.
const STRAIN_SHADING: f64 = 0.5;

/// `tris` seen by `camera` over the box `screen` (equal scales, centred) in a picture of
/// `pw` × `ph` pixels, as RGB bytes, white where nothing is.
fn render(
    tris: &[Triangle],
    camera: Camera,
    screen: Bounds,
    (pw, ph): (usize, usize),
    strength: f64,
) -> Vec<u8> {
    let f = SUPERSAMPLE;
    let sb = screen;
    let scale = (pw as f64 / (sb.x_max - sb.x_min)).min(ph as f64 / (sb.y_max - sb.y_min));
    let (ox, oy) = (
        0.5 * (pw as f64 - scale * (sb.x_max - sb.x_min)),
        0.5 * (ph as f64 - scale * (sb.y_max - sb.y_min)),
    );
    let [right, up, toward] = camera.basis();
    let to_screen = |p: [f64; 3]| -> [f64; 3] {
        [
            f as f64 * (ox + scale * (dot(p, right) - sb.x_min)),
            f as f64 * (oy + scale * (sb.y_max - dot(p, up))),
            dot(p, toward),
        ]
    };
    let mut raster = Raster::new(f * pw, f * ph);
    let light = camera.lights();
    for t in tris {
        raster.triangle(t.v.map(|v| to_screen(v.p)), t, light, strength);
    }
    raster.downsample(f).2
}

/// What one panel of a surface view shows and how.
struct Panel<'a> {
    /// The camera.
    camera: Camera,
    /// The box of the camera's plane shown.
    screen: Bounds,
    /// Shading strength (see [`Raster::triangle`]).
    strength: f64,
    /// Text in the upper left corner.
    label: Option<&'a str>,
}

/// One panel of a surface view: the picture of `tris` as `panel` says, with the axes (x,
/// y, z as the camera sees them) in its lower left corner if `axes`.
fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    tris: &[Triangle],
    panel: &Panel,
    axes: bool,
    fs: f64,
) -> Result<(), DrawError> {
    let Panel {
        camera,
        screen,
        strength,
        label,
    } = *panel;
    let (pw, ph) = area.dim_in_pixel();
    if pw < 8 || ph < 8 {
        return Err(DrawError("drawing area too small".into()));
    }
    let bytes = render(tris, camera, screen, (pw as usize, ph as usize), strength);
    let image = BitMapElement::<(i32, i32)>::with_owned_buffer((0, 0), (pw, ph), bytes)
        .ok_or_else(|| DrawError("the rendered picture has the wrong size".into()))?;
    area.draw(&image)?;
    if axes {
        let [right, up, _] = camera.basis();
        let origin = ((2.4 * fs) as i32, ph as i32 - (2.6 * fs) as i32);
        let len = 1.6 * fs;
        for (k, name) in ["x", "y", "z"].iter().enumerate() {
            let mut unit = [0.0; 3];
            unit[k] = 1.0;
            let (dx, dy) = (dot(unit, right) * len, -dot(unit, up) * len);
            let tip = (origin.0 + dx as i32, origin.1 + dy as i32);
            area.draw(&PathElement::new(vec![origin, tip], BLACK.stroke_width(2)))?;
            area.draw(&Text::new(
                name.to_string(),
                (
                    origin.0 + (1.25 * dx) as i32 - (0.2 * fs) as i32,
                    origin.1 + (1.25 * dy) as i32 - (0.35 * fs) as i32,
                ),
                scaled_text(0.6, fs),
            ))?;
        }
    }
    if let Some(l) = label {
        area.draw(&Text::new(
            l.to_string(),
            ((0.6 * fs) as i32, (0.4 * fs) as i32),
            scaled_text(0.65, fs),
        ))?;
    }
    Ok(())
}

/// Draws the surface view of the deformed whole cell of `s` on its substrate into `area`,
/// framed by `frame` (see the module notes). Coloured by strain, a second panel shows the
/// cell from below ([`Camera::below`], the substrate not drawn), where the contact is.
pub fn draw_surface<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    mesh: &QuarterMeshFile,
    s: &QuarterSnapshot,
    frame: &SurfaceFrame,
    opts: &SurfaceStyleOptions,
) -> Result<(), DrawError> {
    mesh.check(s)?;
    let fs = opts.font as f64;
    let areas = SurfaceAreas::new(area, opts, fs)?;
    let strain_max = outer_strain_max(mesh, s);
    let cell = cell_triangles(mesh, s, opts.coloring, strain_max);
    let mut all = substrate_triangles(mesh, frame);
    all.extend_from_slice(&cell);
    draw_surface_panels(&areas, &all, &cell, frame, opts, fs)?;
    if opts.legend {
        draw_surface_caption(&areas.caption, frame.camera, opts.coloring, fs)?;
    }
    if opts.legend && opts.coloring == Coloring::Domain {
        let pillars = matches!(mesh.substrate.plane, Substrate::Pillars(_));
        draw_surface_legend(&areas.pic, areas.pw, pillars, fs)?;
    }
    if opts.coloring == Coloring::Strain {
        draw_strain_bar(&areas.bar, strain_max, fs)?;
    }
    Ok(())
}

/// A text style of `size` × the font size `fs` in [`FONT`].
fn scaled_text(size: f64, fs: f64) -> TextStyle<'static> {
    TextStyle::from((FONT, (size * fs) as i32).into_font())
}

/// The parts of a surface view's drawing area under its title.
struct SurfaceAreas<DB: DrawingBackend> {
    /// The picture: one panel, or two side by side.
    pic: DrawingArea<DB, Shift>,
    /// The strip right of the picture holding the colour bar (empty when coloured by
    /// domain).
    bar: DrawingArea<DB, Shift>,
    /// The strip under the picture holding the caption (empty without the legend).
    caption: DrawingArea<DB, Shift>,
    /// Width of the picture \[px\].
    pw: u32,
}

impl<DB: DrawingBackend> SurfaceAreas<DB> {
    /// `area` under the title of `opts`, divided as its colouring and legend ask (sizes
    /// scaled by the font size `fs`).
    fn new(
        area: &DrawingArea<DB, Shift>,
        opts: &SurfaceStyleOptions,
        fs: f64,
    ) -> Result<Self, DrawError> {
        let area = area.titled(&opts.title, (FONT, opts.font as i32))?;
        let (aw, ah) = area.dim_in_pixel();
        let bar_w = match opts.coloring {
            Coloring::Strain => (5.5 * fs) as u32,
            Coloring::Domain => 0,
        };
        let pw = aw.saturating_sub(bar_w);
        let (pic, bar) = area.split_horizontally(pw);
        let caption_h = if opts.legend { (1.4 * fs) as u32 } else { 0 };
        let (pic, caption) = pic.split_vertically(ah.saturating_sub(caption_h));
        Ok(SurfaceAreas {
            pic,
            bar,
            caption,
            pw,
        })
    }
}

/// The panels of a surface view in `areas.pic`: coloured by domain, `all` (substrate and
/// cell) seen by the frame's camera; coloured by strain, `all` from above beside `cell`
/// alone from below, both shaded at [`STRAIN_SHADING`].
fn draw_surface_panels<DB: DrawingBackend>(
    areas: &SurfaceAreas<DB>,
    all: &[Triangle],
    cell: &[Triangle],
    frame: &SurfaceFrame,
    opts: &SurfaceStyleOptions,
    fs: f64,
) -> Result<(), DrawError> {
    let cam = frame.camera;
    match opts.coloring {
        Coloring::Domain => {
            let panel = Panel {
                camera: cam,
                screen: frame.screen,
                strength: 1.0,
                label: None,
            };
            draw_panel(&areas.pic, all, &panel, opts.legend, fs)?;
        }
        Coloring::Strain => {
            let (left, right) = areas.pic.split_horizontally(areas.pw / 2);
            let above = Panel {
                camera: cam,
                screen: frame.screen,
                strength: STRAIN_SHADING,
                label: Some("from above"),
            };
            draw_panel(&left, all, &above, opts.legend, fs)?;
            let below = Panel {
                camera: cam.below(),
                screen: frame.below,
                strength: STRAIN_SHADING,
                label: Some("from below (substrate not drawn)"),
            };
            draw_panel(&right, cell, &below, opts.legend, fs)?;
        }
    }
    Ok(())
}

/// The caption of a surface view in `caption`: what it shows and where `cam` sees it from
/// (and from below too when coloured by strain).
fn draw_surface_caption<DB: DrawingBackend>(
    caption: &DrawingArea<DB, Shift>,
    cam: Camera,
    coloring: Coloring,
    fs: f64,
) -> Result<(), DrawError> {
    let seen = match coloring {
        Coloring::Domain => format!(
            "seen from elevation {}°, azimuth {}°",
            cam.elevation_deg, cam.azimuth_deg
        ),
        Coloring::Strain => format!(
            "seen from elevation {}° (left) and {}° (right), azimuth {}°",
            cam.elevation_deg,
            cam.below().elevation_deg,
            cam.azimuth_deg
        ),
    };
    caption
        .draw(&Text::new(
            format!("The whole cell: the quarter cell mirrored about x = 0 and z = 0; {seen}."),
            ((0.6 * fs) as i32, (0.3 * fs) as i32),
            scaled_text(0.5, fs),
        ))
        .map_err(DrawError::from)
}

/// The legend of the domain colouring in the upper right corner of `pic` (`pw` wide): the
/// membrane, the pillars if there are `pillars`, and the floor.
fn draw_surface_legend<DB: DrawingBackend>(
    pic: &DrawingArea<DB, Shift>,
    pw: u32,
    pillars: bool,
    fs: f64,
) -> Result<(), DrawError> {
    let entries: Vec<(RGBColor, &str)> = [
        (MEMBRANE, "membrane (the cell's outer surface)"),
        (SUBSTRATE, "pillars"),
        (FLOOR, "substrate floor"),
    ]
    .into_iter()
    .filter(|(c, _)| *c != SUBSTRATE || pillars)
    .collect();
    let style = scaled_text(0.55, fs);
    let sz = (0.55 * fs) as i32;
    let line = (0.9 * fs) as i32;
    let mut text_w = 0;
    for (_, name) in &entries {
        text_w = text_w.max(pic.estimate_text_size(name, &style)?.0 as i32);
    }
    let box_w = 2 * sz + 24 + text_w;
    let x1 = pw as i32 - (0.4 * fs) as i32;
    let x0 = x1 - box_w;
    let y0 = (0.4 * fs) as i32;
    let box_h = line * entries.len() as i32 + (0.4 * fs) as i32;
    pic.draw(&Rectangle::new(
        [(x0, y0), (x1, y0 + box_h)],
        WHITE.mix(0.9).filled(),
    ))?;
    pic.draw(&Rectangle::new([(x0, y0), (x1, y0 + box_h)], BLACK))?;
    for (k, (c, name)) in entries.iter().enumerate() {
        let y = y0 + (0.3 * fs) as i32 + k as i32 * line;
        pic.draw(&Rectangle::new(
            [(x0 + 8, y + 2), (x0 + 8 + 2 * sz, y + 2 + sz)],
            c.filled(),
        ))?;
        pic.draw(&Text::new(
            name.to_string(),
            (x0 + 2 * sz + 16, y),
            style.clone(),
        ))?;
    }
    Ok(())
}

/// The colour bar of the strain colouring in `bar`: viridis from 0 to `strain_max`, in
/// 200 steps, on a labelled axis.
fn draw_strain_bar<DB: DrawingBackend>(
    bar: &DrawingArea<DB, Shift>,
    strain_max: f64,
    fs: f64,
) -> Result<(), DrawError> {
    let mut chart = ChartBuilder::on(bar)
        .margin_top((1.0 * fs) as u32)
        .margin_bottom((1.0 * fs) as u32)
        .margin_right((0.4 * fs) as u32)
        .y_label_area_size((3.2 * fs) as u32)
        .build_cartesian_2d(0.0..1.0, 0.0..strain_max)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .y_desc("element mean ‖E‖")
        .axis_desc_style((FONT, (0.6 * fs) as i32))
        .label_style((FONT, (0.5 * fs) as i32))
        .draw()?;
    let steps = 200;
    chart.draw_series((0..steps).map(|k| {
        let (v0, v1) = (
            strain_max * k as f64 / steps as f64,
            strain_max * (k + 1) as f64 / steps as f64,
        );
        let c: RGBColor =
            ViridisRGB.get_color_normalized((0.5 * (v0 + v1)) as f32, 0.0, strain_max as f32);
        Rectangle::new([(0.0, v0), (1.0, v1)], c.filled())
    }))?;
    Ok(())
}

/// The surface view of the deformed whole cell of `s` on its substrate, coloured by
/// `coloring`, as a PNG of [`FIGURE_SIZE`] at `path` (see the module notes).
pub fn surface_figure(
    path: &Path,
    mesh: &QuarterMeshFile,
    s: &QuarterSnapshot,
    coloring: Coloring,
    title: &str,
) -> Result<(), OutputError> {
    mesh.check(s).map_err(|m| OutputError::draw(path, m))?;
    let frame = SurfaceFrame::new(mesh, &[s], Camera::DEFAULT);
    let opts = SurfaceStyleOptions {
        title: title.to_string(),
        coloring,
        font: 28,
        legend: true,
    };
    draw_png(path, FIGURE_SIZE, |root| {
        draw_surface(root, mesh, s, &frame, &opts)
    })
}

/// A 3-D run's own figures into `out` (besides the time plots of its 2-D columns, which
/// [`super::figures::plot_run`] draws): `contact-3d.png`, the contact radius along the
/// section z = 0 against √(A/π) of the contact area (equal for a round patch, apart where
/// the pillars break it); `penetration.png` on pillars; for each state file
/// `shape-<phase>-z0.png` and `shape-<phase>-diagonal.png` ([`section_figure`]),
/// `surface-<phase>.png` and `surface-<phase>-strain.png` ([`surface_figure`]).
pub fn plot_quarter_run(
    run: &RunData,
    r3: &QuarterRunData,
    out: &Path,
) -> Result<Vec<PathBuf>, OutputError> {
    use super::draw::{Curve, PALETTE, Stroke};
    use super::time_plots::{TimePlot, after_active_name, points, time_figure};
    let mut written = Vec::new();
    let t3: Vec<(f64, &crate::run_files::QuarterObservables)> =
        run.series.iter().map(|o| o.t).zip(&r3.series).collect();
    let plot = |title: String, y_desc: &str, curves: Vec<Curve>| TimePlot {
        title,
        y_desc: y_desc.into(),
        curves,
        marks: vec![],
        links: vec![],
        notes: vec![],
        from_zero: true,
        phase_times: run.mesh.phase_times,
        after_active: after_active_name(Some(run)),
        t_max: run.t_end(),
        legend: SeriesLabelPosition::UpperLeft,
    };
    let p = out.join("contact-3d.png");
    time_figure(
        &p,
        &plot(
            format!("{}: contact radius in 3-D", run.name),
            "contact radius (µm)",
            vec![
                Curve {
                    label: "along the section z = 0".into(),
                    points: points(&run.series, |o| o.contact_radius),
                    color: PALETTE[0],
                    stroke: Stroke::Solid,
                },
                Curve {
                    label: "√(A/π) of the contact area A".into(),
                    points: t3
                        .iter()
                        .map(|(t, o)| (*t, o.contact_radius_equiv))
                        .collect(),
                    color: PALETTE[1],
                    stroke: Stroke::Dashed,
                },
            ],
        ),
    )?;
    written.push(p);
    if matches!(r3.mesh.substrate.plane, Substrate::Pillars(_)) {
        let p = out.join("penetration.png");
        time_figure(
            &p,
            &plot(
                format!("{}: nucleus bottom below the pillar tops", run.name),
                "penetration depth (µm)",
                vec![Curve {
                    label: "max(0, y_top − y(p_b))".into(),
                    points: t3.iter().map(|(t, o)| (*t, o.penetration_depth)).collect(),
                    color: PALETTE[0],
                    stroke: Stroke::Solid,
                }],
            ),
        )?;
        written.push(p);
    }
    for s in &r3.states {
        let title = format!(
            "{}, {} (t = {} s)",
            run.name,
            phase_title(&s.phase),
            s.state.t
        );
        for (plane, name) in [(Section::Z0, "z0"), (Section::Diagonal, "diagonal")] {
            let p = out.join(format!("shape-{}-{name}.png", s.phase));
            section_figure(&p, &r3.mesh, &s.state, plane, &title)?;
            written.push(p);
        }
        for (coloring, name) in [(Coloring::Domain, ""), (Coloring::Strain, "-strain")] {
            let p = out.join(format!("surface-{}{name}.png", s.phase));
            surface_figure(&p, &r3.mesh, &s.state, coloring, &title)?;
            written.push(p);
        }
    }
    Ok(written)
}
