//! The geometry of a drawing, from a run's files only: the deformed cell as polygons with
//! curved P2 edges, the outlines of the active regions carried by the deformation, and
//! the profiles of the substrate and of the fibronectin layer. No drawing here.

use nalgebra::Vector2;

use crate::fem::Domain;
use crate::fem::tri6::{EDGES, edge_shape};
use crate::fem::{Lagrange, Tri6};
use crate::physics::{ActiveStrain, PillarFoot, Substrate};
use crate::run_files::MeshFile;

/// A point \[µm\].
pub type Pt = [f64; 2];

/// Straight pieces per curved element edge when tracing polygons.
pub const EDGE_PIECES: usize = 4;

/// Sub-divisions per element side when contouring an active-region indicator.
const CONTOUR_DIVISIONS: usize = 6;

/// Sub-divisions per boundary edge when clipping it to an active region.
const EDGE_CLIP_PIECES: usize = 16;

/// Level of an indicator χ ∈ [0, 1] taken as the region's boundary.
pub const ACTIVE_LEVEL: f64 = 0.5;

/// Current node positions x = X + u. `u` must have one entry per node.
pub fn deformed_nodes(mesh: &MeshFile, u: &[[f64; 2]]) -> Vec<Pt> {
    mesh.nodes
        .iter()
        .zip(u)
        .map(|(p, d)| [p[0] + d[0], p[1] + d[1]])
        .collect()
}

/// The quadratic edge through `x` = (vertex, mid-node, vertex) at s ∈ [0, 1].
pub fn edge_point(x: &[Pt; 3], s: f64) -> Pt {
    let n = edge_shape(s);
    [
        n[0] * x[0][0] + n[1] * x[1][0] + n[2] * x[2][0],
        n[0] * x[0][1] + n[1] * x[1][1] + n[2] * x[2][1],
    ]
}

/// The quadratic edge `x` as `pieces + 1` points from its first to its last vertex.
pub fn edge_polyline(x: &[Pt; 3], pieces: usize) -> Vec<Pt> {
    let pieces = pieces.max(1);
    (0..=pieces)
        .map(|k| edge_point(x, k as f64 / pieces as f64))
        .collect()
}

/// The boundary of a P2 element with node positions `x` (local order of
/// [`crate::fem::tri6`]) as a closed polygon, counter-clockwise in the reference element,
/// each side traced with `pieces` straight pieces (first point not repeated).
pub fn element_polygon(x: &[Pt; 6], pieces: usize) -> Vec<Pt> {
    let mut out = Vec::with_capacity(3 * pieces);
    for e in EDGES {
        let line = edge_polyline(&[x[e[0]], x[e[1]], x[e[2]]], pieces);
        out.extend_from_slice(&line[..line.len() - 1]);
    }
    out
}

/// The point of a P2 element with node positions `x` at reference coordinates ξ.
pub fn element_point(x: &[Pt; 6], xi: [f64; 2]) -> Pt {
    let n = Tri6::shape(xi);
    let mut p = [0.0; 2];
    for a in 0..6 {
        p[0] += n[a] * x[a][0];
        p[1] += n[a] * x[a][1];
    }
    p
}

/// Which active-strain region a curve outlines.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ActiveRegion {
    /// Perinuclear actin cap ("push"), in the cytoplasm.
    Pac,
    /// Bottom fibres ("pull"), in the cytoplasm and membrane.
    Bottom,
}

impl ActiveRegion {
    /// The region's indicator χ at reference point `p`, without the domain restriction.
    fn chi(self, a: &ActiveStrain, p: Pt) -> f64 {
        let v = Vector2::new(p[0], p[1]);
        match self {
            ActiveRegion::Pac => a.chi_pac(&v),
            ActiveRegion::Bottom => a.chi_bottom(&v),
        }
    }

    /// Whether the region may extend into elements of `d` (MODEL.md §6).
    pub(crate) fn allowed(self, d: Domain) -> bool {
        match self {
            ActiveRegion::Pac => d == Domain::Cytoplasm,
            ActiveRegion::Bottom => d != Domain::Nucleus,
        }
    }

    /// Whether the scene has this region.
    pub(crate) fn present(self, a: &ActiveStrain) -> bool {
        match self {
            ActiveRegion::Pac => a.pac.is_some(),
            ActiveRegion::Bottom => a.bottom.is_some(),
        }
    }
}

/// The deformed half cell, ready to draw; in 3-D, a section of it
/// ([`super::cell3d_views::SectionShape`]).
#[derive(Debug, Clone, Default)]
pub struct CellShape {
    /// Each element's domain and deformed boundary polygon.
    pub elements: Vec<(Domain, Vec<Pt>)>,
    /// The deformed outer boundary, one polyline per edge.
    pub outer: Vec<Vec<Pt>>,
    /// The deformed nucleus and membrane interfaces, one polyline per edge.
    pub interfaces: Vec<Vec<Pt>>,
    /// Outline of the PAC region (segments), carried by the deformation.
    pub pac: Vec<[Pt; 2]>,
    /// Outline of the bottom region (segments), carried by the deformation.
    pub bottom: Vec<[Pt; 2]>,
    /// Current positions of the nucleus top p_t, the centre c and the nucleus bottom p_b.
    pub markers: Vec<Pt>,
}

/// Linear zero crossing between values `a` at `p` and `b` at `q` (`a`, `b` of opposite
/// signs or one zero).
fn crossing(p: [f64; 2], a: f64, q: [f64; 2], b: f64) -> [f64; 2] {
    let w = if a == b { 0.5 } else { a / (a - b) };
    [p[0] + w * (q[0] - p[0]), p[1] + w * (q[1] - p[1])]
}

impl CellShape {
    /// The cell of `mesh` displaced by `u` (one entry per node). Active regions are
    /// outlined by the level χ = [`ACTIVE_LEVEL`] of their indicators, contoured in each
    /// element's reference coordinates and mapped through the deformed P2 element, plus
    /// the parts of the domain interfaces and outer boundary that bound them.
    pub fn new(mesh: &MeshFile, u: &[[f64; 2]]) -> Self {
        let x = deformed_nodes(mesh, u);
        let nodes6 = |el: &[usize; 6], pos: &[Pt]| -> [Pt; 6] { el.map(|i| pos[i]) };
        let elements = mesh
            .elements
            .iter()
            .zip(&mesh.domains)
            .map(|(el, &d)| (d, element_polygon(&nodes6(el, &x), EDGE_PIECES)))
            .collect();
        let edge_lines = |edges: &[[usize; 3]]| -> Vec<Vec<Pt>> {
            edges
                .iter()
                .map(|e| edge_polyline(&e.map(|i| x[i]), EDGE_PIECES))
                .collect()
        };
        let outer = edge_lines(&mesh.outer_edges);
        let mut interfaces = edge_lines(&mesh.nucleus_edges);
        interfaces.extend(edge_lines(&mesh.membrane_inner_edges));

        let mut shape = CellShape {
            elements,
            outer,
            interfaces,
            markers: Self::markers(mesh, &x),
            ..Default::default()
        };
        if let Some(a) = &mesh.active {
            for region in [ActiveRegion::Pac, ActiveRegion::Bottom] {
                if !region.present(a) {
                    continue;
                }
                let segs = Self::active_outline(mesh, &x, a, region);
                match region {
                    ActiveRegion::Pac => shape.pac = segs,
                    ActiveRegion::Bottom => shape.bottom = segs,
                }
            }
        }
        shape
    }

    /// p_t, c, p_b: the reference nodes on the symmetry line nearest to c ± (0, r_n) and
    /// c, with r_n the largest distance of a nucleus node from c.
    fn markers(mesh: &MeshFile, x: &[Pt]) -> Vec<Pt> {
        let c = mesh.center;
        let dist = |p: &Pt| ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2)).sqrt();
        let r_n = mesh
            .elements
            .iter()
            .zip(&mesh.domains)
            .filter(|(_, d)| **d == Domain::Nucleus)
            .flat_map(|(el, _)| el.iter().map(|&i| dist(&mesh.nodes[i])))
            .fold(0.0f64, f64::max);
        let nearest = |target: Pt| -> Option<Pt> {
            let mut best: Option<(f64, usize)> = None;
            for (i, p) in mesh.nodes.iter().enumerate() {
                let d = (p[0] - target[0]).powi(2) + (p[1] - target[1]).powi(2);
                if best.is_none_or(|(b, _)| d < b) {
                    best = Some((d, i));
                }
            }
            best.map(|(_, i)| x[i])
        };
        [[c[0], c[1] + r_n], c, [c[0], c[1] - r_n]]
            .into_iter()
            .filter_map(nearest)
            .collect()
    }

    fn active_outline(
        mesh: &MeshFile,
        x: &[Pt],
        a: &ActiveStrain,
        region: ActiveRegion,
    ) -> Vec<[Pt; 2]> {
        let mut segs = Vec::new();
        let n = CONTOUR_DIVISIONS;
        // 1. The level set χ = ACTIVE_LEVEL inside the elements the region may occupy.
        for (el, &d) in mesh.elements.iter().zip(&mesh.domains) {
            if !region.allowed(d) {
                continue;
            }
            let xr: [Pt; 6] = el.map(|i| mesh.nodes[i]);
            let xd: [Pt; 6] = el.map(|i| x[i]);
            let xi = |i: usize, j: usize| [i as f64 / n as f64, j as f64 / n as f64];
            let val = |p: [f64; 2]| region.chi(a, element_point(&xr, p)) - ACTIVE_LEVEL;
            for i in 0..n {
                for j in 0..n - i {
                    let mut tris = vec![[xi(i, j), xi(i + 1, j), xi(i, j + 1)]];
                    if i + j + 1 < n {
                        tris.push([xi(i + 1, j), xi(i + 1, j + 1), xi(i, j + 1)]);
                    }
                    for t in tris {
                        let v = t.map(val);
                        let mut cut = Vec::with_capacity(2);
                        for (p, q) in [(0, 1), (1, 2), (2, 0)] {
                            if (v[p] >= 0.0) != (v[q] >= 0.0) {
                                cut.push(crossing(t[p], v[p], t[q], v[q]));
                            }
                        }
                        if let [p, q] = cut[..] {
                            segs.push([element_point(&xd, p), element_point(&xd, q)]);
                        }
                    }
                }
            }
        }
        // 2. The parts of the bounding interfaces and outer boundary where χ ≥ level.
        let bounding: Vec<&[usize; 3]> = match region {
            ActiveRegion::Pac => mesh
                .nucleus_edges
                .iter()
                .chain(&mesh.membrane_inner_edges)
                .collect(),
            ActiveRegion::Bottom => mesh.nucleus_edges.iter().chain(&mesh.outer_edges).collect(),
        };
        for e in bounding {
            let er: [Pt; 3] = e.map(|i| mesh.nodes[i]);
            let ed: [Pt; 3] = e.map(|i| x[i]);
            let m = EDGE_CLIP_PIECES;
            let val = |s: f64| region.chi(a, edge_point(&er, s)) - ACTIVE_LEVEL;
            for k in 0..m {
                let (s0, s1) = (k as f64 / m as f64, (k + 1) as f64 / m as f64);
                let (v0, v1) = (val(s0), val(s1));
                let (a0, a1) = match (v0 >= 0.0, v1 >= 0.0) {
                    (true, true) => (s0, s1),
                    (false, false) => continue,
                    (true, false) => (s0, crossing([s0, 0.0], v0, [s1, 0.0], v1)[0]),
                    (false, true) => (crossing([s0, 0.0], v0, [s1, 0.0], v1)[0], s1),
                };
                segs.push([edge_point(&ed, a0), edge_point(&ed, a1)]);
            }
        }
        segs
    }

    /// The full cell: this half and its mirror image about x = 0.
    pub fn mirrored(&self) -> Self {
        let m = |p: &Pt| [-p[0], p[1]];
        let line = |l: &Vec<Pt>| l.iter().map(m).collect::<Vec<Pt>>();
        let seg = |s: &[Pt; 2]| [m(&s[0]), m(&s[1])];
        let mut out = self.clone();
        out.elements
            .extend(self.elements.iter().map(|(d, p)| (*d, line(p))));
        out.outer.extend(self.outer.iter().map(line));
        out.interfaces.extend(self.interfaces.iter().map(line));
        out.pac.extend(self.pac.iter().map(seg));
        out.bottom.extend(self.bottom.iter().map(seg));
        out
    }

    /// Bounding box (x_min, x_max, y_min, y_max) of the cell \[µm\].
    pub fn bounds(&self) -> Bounds {
        let mut b = Bounds::empty();
        for (_, poly) in &self.elements {
            for p in poly {
                b.include(*p);
            }
        }
        b
    }
}

/// An axis-aligned box \[µm\].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Smallest x.
    pub x_min: f64,
    /// Largest x.
    pub x_max: f64,
    /// Smallest y.
    pub y_min: f64,
    /// Largest y.
    pub y_max: f64,
}

impl Bounds {
    /// The empty box (includes nothing).
    pub fn empty() -> Self {
        Bounds {
            x_min: f64::INFINITY,
            x_max: f64::NEG_INFINITY,
            y_min: f64::INFINITY,
            y_max: f64::NEG_INFINITY,
        }
    }

    /// Grows the box to include `p` (non-finite points are ignored).
    pub fn include(&mut self, p: Pt) {
        if p[0].is_finite() && p[1].is_finite() {
            self.x_min = self.x_min.min(p[0]);
            self.x_max = self.x_max.max(p[0]);
            self.y_min = self.y_min.min(p[1]);
            self.y_max = self.y_max.max(p[1]);
        }
    }

    /// The smallest box holding both.
    pub fn union(self, o: Bounds) -> Bounds {
        Bounds {
            x_min: self.x_min.min(o.x_min),
            x_max: self.x_max.max(o.x_max),
            y_min: self.y_min.min(o.y_min),
            y_max: self.y_max.max(o.y_max),
        }
    }

    /// Whether the box holds at least one point.
    pub fn is_empty(&self) -> bool {
        !(self.x_min <= self.x_max && self.y_min <= self.y_max)
    }

    /// The view of drawings of the full cell that this box holds: made symmetric about
    /// x = 0, extended down to `floor` (the substrate's, [`substrate_floor`]), with a
    /// margin of 1.5 µm on every side.
    pub fn around_axis(self, floor: f64) -> Bounds {
        let half = self.x_max.abs().max(self.x_min.abs()) + 1.5;
        Bounds {
            x_min: -half,
            x_max: half,
            y_min: self.y_min.min(floor) - 1.5,
            y_max: self.y_max + 1.5,
        }
    }
}

/// Step of the vertical scans and of the contouring grid \[µm\].
const SCAN_STEP: f64 = 0.05;

/// Points per pillar outline in [`Backdrop`].
const OUTLINE_POINTS: usize = 400;

/// A rectangle (x_a, x_b, y_lo, y_hi) \[µm\].
pub type Rect = [f64; 4];

/// The intervals of `[y0, y1]` where `f(y) ≥ 0`, found by a downward scan in steps of
/// [`SCAN_STEP`] with each sign change bisected to 1e-9 µm.
pub(crate) fn intervals(f: impl Fn(f64) -> f64, y0: f64, y1: f64) -> Vec<[f64; 2]> {
    let bisect = |mut inside: f64, mut outside: f64| {
        for _ in 0..40 {
            let mid = 0.5 * (inside + outside);
            if f(mid) >= 0.0 {
                inside = mid;
            } else {
                outside = mid;
            }
        }
        0.5 * (inside + outside)
    };
    let mut out = Vec::new();
    let mut y = y1;
    let mut top = (f(y) >= 0.0).then_some(y1);
    while y > y0 {
        let next = (y - SCAN_STEP).max(y0);
        let (a, b) = (f(y) >= 0.0, f(next) >= 0.0);
        match (a, b) {
            (false, true) => top = Some(bisect(next, y)),
            (true, false) => {
                if let Some(t) = top.take() {
                    out.push([bisect(y, next), t]);
                }
            }
            _ => {}
        }
        y = next;
    }
    if let Some(t) = top {
        out.push([y0, t]);
    }
    out
}

/// The pieces of a polyline with x inside `[x0, x1]`, cut where it leaves.
fn clip_x(line: &[Pt], x0: f64, x1: f64) -> Vec<Vec<Pt>> {
    let inside = |p: &Pt| p[0] >= x0 && p[0] <= x1;
    let mut pieces = Vec::new();
    let mut cur: Vec<Pt> = Vec::new();
    for w in line.windows(2) {
        let (p, q) = (w[0], w[1]);
        let cut = |xc: f64| {
            let s = (xc - p[0]) / (q[0] - p[0]);
            [xc, p[1] + s * (q[1] - p[1])]
        };
        match (inside(&p), inside(&q)) {
            (true, true) => {
                if cur.is_empty() {
                    cur.push(p);
                }
                cur.push(q);
            }
            (true, false) => {
                if cur.is_empty() {
                    cur.push(p);
                }
                cur.push(cut(if q[0] > x1 { x1 } else { x0 }));
                pieces.push(std::mem::take(&mut cur));
            }
            (false, true) => {
                cur = vec![cut(if p[0] > x1 { x1 } else { x0 }), q];
            }
            (false, false) => {}
        }
    }
    if cur.len() > 1 {
        pieces.push(cur);
    }
    pieces
}

/// Segments of the zero level of `f` over the box, by marching squares on a grid of
/// spacing about `h` (linear interpolation on the cell edges; saddles split by the cell
/// centre's value).
pub(crate) fn contour(f: impl Fn(f64, f64) -> f64, b: [f64; 4], h: f64) -> Vec<[Pt; 2]> {
    let [x0, x1, y0, y1] = b;
    let nx = ((x1 - x0) / h).ceil().max(1.0) as usize;
    let ny = ((y1 - y0) / h).ceil().max(1.0) as usize;
    let (hx, hy) = ((x1 - x0) / nx as f64, (y1 - y0) / ny as f64);
    let pt = |i: usize, j: usize| [x0 + i as f64 * hx, y0 + j as f64 * hy];
    let vals: Vec<Vec<f64>> = (0..=nx)
        .map(|i| {
            (0..=ny)
                .map(|j| {
                    let p = pt(i, j);
                    f(p[0], p[1])
                })
                .collect()
        })
        .collect();
    let mut segs = Vec::new();
    for i in 0..nx {
        for j in 0..ny {
            // Corners counter-clockwise from the lower left.
            let c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let v = c.map(|(a, b)| vals[a][b]);
            let p = c.map(|(a, b)| pt(a, b));
            let mut cuts = Vec::with_capacity(4);
            for k in 0..4 {
                let l = (k + 1) % 4;
                if (v[k] >= 0.0) != (v[l] >= 0.0) {
                    cuts.push(crossing(p[k], v[k], p[l], v[l]));
                }
            }
            match cuts.len() {
                2 => segs.push([cuts[0], cuts[1]]),
                4 => {
                    let centre = 0.25 * (v[0] + v[1] + v[2] + v[3]);
                    // Cuts are on edges 0-1, 1-2, 2-3, 3-0; pair them so the centre's side
                    // stays connected.
                    if (centre >= 0.0) == (v[0] >= 0.0) {
                        segs.push([cuts[0], cuts[1]]);
                        segs.push([cuts[2], cuts[3]]);
                    } else {
                        segs.push([cuts[3], cuts[0]]);
                        segs.push([cuts[1], cuts[2]]);
                    }
                }
                _ => {}
            }
        }
    }
    segs
}

/// The substrate and the fibronectin layer over a view, ready to draw.
#[derive(Debug, Clone, Default)]
pub struct Backdrop {
    /// The view (x0, x1, y0, y1) it was computed for \[µm\].
    pub view: [f64; 4],
    /// The fibronectin layer `{d_sub ≥ −e_f}` as thin column rectangles.
    pub layer: Vec<Rect>,
    /// The substrate `{d_sub ≥ 0}` as thin column rectangles.
    pub substrate: Vec<Rect>,
    /// The rounded pillars' feet ([`PillarFoot::Rounded`]; none for straight ones): in each
    /// column within a pillar's width, from the floor up to the pillar's mid-height (where
    /// its side is vertical). Drawn under [`Backdrop::substrate`], it fills the undercuts
    /// below the superellipse's rounded lower corners, so the pillars stand on their
    /// floor; the model's substrate leaves those undercuts open (MODEL.md §5), and the
    /// fibronectin layer fills them there.
    pub foot: Vec<Rect>,
    /// The layer's upper edge `d_sub = −e_f` (segments).
    pub layer_edge: Vec<[Pt; 2]>,
    /// The substrate's surface, exact (polylines, clipped to the view).
    pub surface: Vec<Vec<Pt>>,
}

impl Backdrop {
    /// The substrate `sub` and, with `e_f`, its fibronectin layer (MODEL.md §5) over the
    /// view `[x0, x1, y0, y1]`, filled by `columns` vertical strips (one per pixel gives
    /// an exact picture: undercuts by the pillars' rounded feet stay open).
    pub fn new(sub: &Substrate, e_f: Option<f64>, view: [f64; 4], columns: usize) -> Self {
        let [x0, x1, y0, y1] = view;
        let mut b = Backdrop {
            view,
            ..Default::default()
        };
        match sub {
            Substrate::Flat { y_s } => {
                b.substrate.push([x0, x1, y0, y_s.min(y1)]);
                b.surface.push(vec![[x0, *y_s], [x1, *y_s]]);
                if let Some(e) = e_f {
                    b.layer.push([x0, x1, y0, (y_s + e).min(y1)]);
                    b.layer_edge.push([[x0, y_s + e], [x1, y_s + e]]);
                }
            }
            Substrate::Pillars(p) => {
                let n = columns.max(2);
                let dx = (x1 - x0) / n as f64;
                let depth = |x: f64, y: f64| sub.eval(&Vector2::new(x, y)).0;
                let floor = p.y_top - p.height;
                let mid = (p.y_top - 0.5 * p.height).min(y1);
                for k in 0..n {
                    let (xa, xb) = (x0 + k as f64 * dx, x0 + (k + 1) as f64 * dx);
                    let xm = 0.5 * (xa + xb);
                    // Within the pillar's width, as the substrate strips: by the centre.
                    let within = (xm - p.nearest_axis(xm)).abs() < 0.5 * p.width;
                    if within && p.foot == PillarFoot::Rounded && mid > floor.max(y0) {
                        b.foot.push([xa, xb, floor.max(y0), mid]);
                    }
                    for [lo, hi] in intervals(|y| depth(xm, y), y0, y1) {
                        b.substrate.push([xa, xb, lo, hi]);
                    }
                    if let Some(e) = e_f {
                        for [lo, hi] in intervals(|y| depth(xm, y) + e, y0, y1) {
                            b.layer.push([xa, xb, lo, hi]);
                        }
                    }
                }
                let outline = sub.outline(x0, x1, OUTLINE_POINTS);
                b.surface = clip_x(&outline, x0, x1);
                if let Some(e) = e_f {
                    b.layer_edge = contour(|x, y| depth(x, y) + e, view, SCAN_STEP);
                }
            }
        }
        b
    }
}

impl AsRef<Backdrop> for Backdrop {
    fn as_ref(&self) -> &Backdrop {
        self
    }
}

/// The lowest height any drawing of `sub` needs \[µm\]: the floor for pillars, the surface
/// for a flat substrate.
pub fn substrate_floor(sub: &Substrate) -> f64 {
    match sub {
        Substrate::Flat { y_s } => *y_s,
        Substrate::Pillars(p) => p.y_top - p.height,
    }
}
