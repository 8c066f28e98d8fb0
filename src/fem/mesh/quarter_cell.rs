//! The P2 tetrahedral mesh of the quarter cell (MODEL.md §10), and the 2-D half cell
//! extruded into a one-layer slab.
//!
//! # The quarter cell
//!
//! The domain is x ≥ c_x, z ≥ c_z of three concentric balls about c: the nucleus (r ≤ r_n),
//! the cytoplasm (r_n ≤ r ≤ r_cp) and the membrane shell (r_cp ≤ r ≤ r_c); y is vertical.
//! The symmetry planes x = c_x and z = c_z carry u_x = 0 and u_z = 0, the sphere r = r_c is
//! the cell surface (contact, adhesion).
//!
//! **The mesher is gmsh** (Debian package `gmsh`, 4.8 and later), run headless on a
//! geometry written here ([`TetMeshParams::geo`]):
//!
//! 1. OpenCASCADE balls r_n, r_cp, r_c about c, each intersected with the box x ≥ c_x,
//!    z ≥ c_z; the two shells as differences; `BooleanFragments` of the three volumes and
//!    the centre point, so that the volumes are conforming and c is a mesh vertex. The
//!    balls are first rotated by 3π/4 about the vertical axis, which puts the poles and the
//!    seam of OpenCASCADE's sphere parametrisation outside the quarter: each sphere is then
//!    one smooth face without a degenerate edge. Every point where a sphere meets the
//!    vertical axis through c (the cell and nucleus bottom and top) is a geometric vertex,
//!    and the centre is embedded by the fragments: the named points are mesh vertices.
//! 2. Physical volumes `nucleus`, `cytoplasm`, `membrane`, physical surface `outer` (the
//!    sphere r_c).
//! 3. The size field is the 2-D grading law ([`MeshParams::size_at`]): linear in y from
//!    h_bottom at the cell bottom c_y − r_c to h_nucleus at the nucleus bottom c_y − r_n,
//!    constant above, divided by `refine`; a `MathEval` field, the clamp written with
//!    `abs`. With `h_surface`, a second `MathEval` field, the surface cap of
//!    [`MeshParams::surface_cap`], and a `Min` field of the two as the background field
//!    (without it the file is as before, so cached meshes keep their keys). Sizes from
//!    points, curvature and boundary extension are off.
//! 4. `Mesh.Algorithm3D = 10` (HXT): the default Delaunay leaves slivers in the 0.25 µm
//!    membrane shell that gmsh cannot repair (min γ 0.01). Second order with the mid-edge
//!    nodes on the curved surfaces (`Mesh.ElementOrder = 2`, `SecondOrderLinear = 0`).
//! 5. gmsh runs single-threaded (`-nt 1`). That is not enough for a reproducible mesh:
//!    gmsh 4.8's HXT result also depends on heap addresses (pointer-keyed containers decide
//!    between the many equivalent Delaunay choices among points on a sphere), so two plain
//!    runs differ. gmsh therefore runs under `setarch -R` (util-linux: address-space
//!    randomisation off), in a fresh working directory with a fixed-length name in the
//!    system temporary directory, on `cell.geo` → `cell.msh`, with the environment reduced
//!    to `HOME` (that directory), `LC_ALL=C`, `PATH=/usr/bin:/bin` (and `LD_LIBRARY_PATH`
//!    if set). Every string gmsh allocates before meshing then has the same length, and the
//!    same .geo gives the same file byte for byte, whatever the cache directory and across
//!    processes (tested). Without a working `setarch` gmsh runs directly; its meshes may
//!    then differ from run to run, and the cache serves the first one.
//!
//! **Cache.** The mesh file is kept under `$CELLSIM_CACHE`, else `$XDG_CACHE_HOME/cellsim`,
//! else `$HOME/.cache/cellsim` (else the system temporary directory), in `mesh3d/<key>.msh`
//! beside the `<key>.geo` it was made from, the key being FNV-1a 64 of the .geo text, the
//! command line and `gmsh --version`'s output. A new mesh is copied beside its final name,
//! read and checked there, and renamed, so an interrupted run leaves no half file under the
//! final name (a mesh failing the checks stays under its temporary name, which the error
//! gives); a cached file is read instead of running gmsh. Processes sharing one cache (a
//! Slurm array on a shared file system, say) may mesh the same geometry at once: each
//! writes under a name of its own (host, process, counter) and the renames, to the same
//! bytes, replace one another whole, so a reader finds no file or a whole one (tested with
//! several processes on one cold cache).
//!
//! **Reading** ([`TetMesh::read_gmsh`], in [`crate::fem::gmsh`]): 10-node tetrahedra (gmsh
//! type 11) in the three physical volumes and 6-node triangles (type 9) in `outer`; the
//! nodes the tetrahedra use are renumbered compactly in file order. The completion checks
//! what the model relies on: every vertex inside the ball r_c and on the side of the
//! interfaces its domain says (so a mesh of another cell is refused), edges with one
//! mid-node each, faces shared by at most two tetrahedra, outer faces on r = r_c that are
//! faces of the mesh (oriented outward), the named points, and det J > 0 at the nodes and
//! at the points of every [`TetRule::degree`] with d ≤ 6 (the rules an assembly uses),
//! naming the element otherwise. Nodes within 1e-9 · r_c of a symmetry plane are moved onto
//! it exactly.
//!
//! # The slab
//!
//! [`TetMesh::extruded`] turns the 2-D half-cell mesh into one layer of thickness t in z:
//! each P2 triangle × [0, t] is a prism split into three P2 tetrahedra. The quadrilateral
//! faces are split by the diagonal from the smallest global vertex number (Dompierre et al.'s
//! rule), so neighbouring prisms agree and no prism gets the one impossible choice of
//! diagonals. The nodes are the 2-D nodes at z = 0, t/2 and t: the vertical edges' mid-nodes
//! are the vertices at t/2, the face diagonals' mid-nodes the 2-D mid-nodes at t/2, and the
//! triangles' own mid-nodes are reused on both faces. The P2 map of each tetrahedron then
//! *is* the extrusion of the curved 2-D element (the extrusion map is quadratic in the
//! tetrahedron's coordinates), so volumes are areas × t exactly and every field of the 2-D
//! P2 space, constant in z, lies in the 3-D space. This is the slab check of MODEL.md §10:
//! fixing u_z on **every** node (not only on `symmetry_z`) makes the 3-D model plane strain.

use std::collections::HashMap;
use std::f64::consts::PI;
use std::fmt;
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::OnceLock;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::super::element::{CellMesh, extremes};
use super::super::quadrature::{TetRule, TriangleRule};
use super::super::tet10::{self, FLIP, REFERENCE_NODES, TET_EDGES, TET_FACES, TetTabulation};
use super::super::tri6::EDGES;
use super::{Domain, MIN_ANGLE_DEG, Mesh, MeshError, MeshParams, NamedPoints};

/// Largest number of tetrahedra [`TetMesh::generate`] accepts to build (estimated from the
/// sizes before meshing, [`TetMeshParams::estimated_tets`]), so that a typo in a case file
/// fails fast instead of running gmsh for hours.
pub const MAX_TETS: f64 = 2.0e6;

/// Thinnest layer (r_n, r_cp − r_n, r_c − r_cp) accepted, µm: OpenCASCADE works with an
/// absolute tolerance of 1e-7.
pub const MIN_LAYER: f64 = 1e-3;

/// Tetrahedra per h³ of volume inside the ball r_cp in gmsh's HXT meshes with the graded
/// size field (measured 4.3–5.6 on the default cell, h_bottom/h_nucleus 0.3/1.0 to
/// 0.6/1.8, refine 1 to 2; it falls slowly with refinement).
const TETS_PER_H3: f64 = 5.0;

/// Tetrahedra per h² · min(h, t) of volume in the membrane shell of thickness t (measured
/// 6.8–7.6 on the same meshes).
const SHELL_TETS_PER_H2T: f64 = 7.4;

/// The gmsh command line after the .geo file (before `-o <file>`); part of the cache key.
const GMSH_ARGS: [&str; 6] = ["-3", "-nt", "1", "-format", "msh41", "-v"];
/// gmsh's verbosity (the argument of `-v`): errors, warnings and information.
const GMSH_VERBOSITY: &str = "4";

/// Which part of the balls is meshed: a wedge about the vertical axis through c, bounded
/// by mirror planes of the problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Wedge {
    /// The quarter x ≥ c_x, z ≥ c_z: mirror planes x = c_x (u_x = 0) and z = c_z (u_z = 0).
    #[default]
    Quarter,
    /// The eighth 0 ≤ z − c_z ≤ x − c_x: mirror planes z = c_z (u_z = 0) and the diagonal
    /// x − c_x = z − c_z (u · (1, 0, −1) = 0: u_z = u_x there), for a problem that is
    /// also symmetric under x − c_x ↔ z − c_z (a flat substrate, the four-pillar lattice).
    Eighth,
}

impl Wedge {
    /// The wedge's opening angle about the vertical axis (radians).
    pub fn angle(self) -> f64 {
        match self {
            Wedge::Quarter => 0.5 * PI,
            Wedge::Eighth => 0.25 * PI,
        }
    }

    /// How many copies of the wedge make the whole cell.
    pub fn copies(self) -> f64 {
        2.0 * PI / self.angle()
    }
}

/// Geometry and mesh-size parameters of the 3-D cell's wedge (µm).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TetMeshParams {
    /// Cell centre c; the symmetry planes pass through it (see [`Wedge`]), y is vertical.
    pub center: [f64; 3],
    /// The part of the cell that is meshed.
    pub wedge: Wedge,
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
    /// Refinement factor: every size is divided by it (2 halves all sizes, ≈ 8× the
    /// tetrahedra).
    pub refine: f64,
    /// Largest size at the cell surface below the centre (before `refine`), if any: the
    /// 2-D [`MeshParams::surface_cap`], a second gmsh field.
    pub h_surface: Option<f64>,
}

impl TetMeshParams {
    /// The quarter cell whose section z = `c_z` has the 2-D parameters `p` (centre
    /// (p.center, c_z), same radii and sizes; the 2-D angle limit is not used).
    pub fn from_section(p: &MeshParams, c_z: f64) -> Self {
        Self {
            center: [p.center[0], p.center[1], c_z],
            wedge: Wedge::Quarter,
            r_n: p.r_n,
            r_cp: p.r_cp,
            r_c: p.r_c,
            h_bottom: p.h_bottom,
            h_nucleus: p.h_nucleus,
            refine: p.refine,
            h_surface: p.h_surface,
        }
    }

    /// Checks every field; the error names the field and the rule it breaks.
    pub fn validate(&self) -> Result<(), MeshError> {
        super::check_cell(&self.center, &self.section())?;
        let bad = super::invalid;
        let layer_rule = "layers thinner than 1e-3 µm are below the geometry kernel's tolerance";
        if self.r_n < MIN_LAYER {
            return bad("r_n", self.r_n, layer_rule);
        }
        if self.r_cp - self.r_n < MIN_LAYER {
            return bad("r_cp", self.r_cp, layer_rule);
        }
        if self.r_c - self.r_cp < MIN_LAYER {
            return bad("r_c", self.r_c, layer_rule);
        }
        let far = self.center.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let h_min = self.h_bottom.min(self.h_nucleus) / self.refine;
        super::check_scale(h_min, far, self.estimated_tets(), MAX_TETS)
    }

    /// The 2-D parameters of the section z = c_z (the half cell of the plane-strain and
    /// axisymmetric models), with the 2-D generator's angle limit.
    pub fn section(&self) -> MeshParams {
        MeshParams {
            center: [self.center[0], self.center[1]],
            r_n: self.r_n,
            r_cp: self.r_cp,
            r_c: self.r_c,
            h_bottom: self.h_bottom,
            h_nucleus: self.h_nucleus,
            refine: self.refine,
            h_surface: self.h_surface,
            min_angle_deg: MIN_ANGLE_DEG,
        }
    }

    /// Target element size h(y) at height y: the 2-D grading law [`MeshParams::size_at`].
    pub fn size_at(&self, y: f64) -> f64 {
        self.section().size_at(y)
    }

    /// Estimated number of tetrahedra, from the sizes without meshing (within ±15 % of
    /// gmsh's counts on the default cell): 5 · ∫ dV / h(y)³ over the wedge of the
    /// ball r_cp plus 7.4 · ∫ dV / (h² min(h, t)) over the membrane shell
    /// of thickness t = r_c − r_cp (a shell thinner than h still needs one layer of
    /// elements), by the midpoint rule in y on the wedge's circular-sector cross-sections.
    /// [`TetMeshParams::validate`] refuses more than [`MAX_TETS`]. Meaningful for
    /// parameters that pass the other checks of `validate`.
    pub fn estimated_tets(&self) -> f64 {
        const N: usize = 2000;
        // Radial points of the midpoint rule inside r_cp where the surface cap may act.
        const NR: usize = 40;
        let (cy, rc, rcp) = (self.center[1], self.r_c, self.r_cp);
        let t = rc - rcp;
        let dy = 2.0 * rc / N as f64;
        let opening = 0.5 * self.wedge.angle();
        let sector = |r: f64, y: f64| opening * (r * r - (y - cy) * (y - cy)).max(0.0);
        let section = self.section();
        let mut acc = 0.0;
        for k in 0..N {
            let y = cy - rc + (k as f64 + 0.5) * dy;
            let h = self.size_at(y);
            let inner = if self.h_surface.is_some() {
                // Rings of the disc r ≤ r_cp at this height, each at its own capped size.
                let dz = (y - cy).abs();
                let rho = (rcp * rcp - dz * dz).max(0.0).sqrt();
                let dr = rho / NR as f64;
                (0..NR)
                    .map(|j| {
                        let p = (j as f64 + 0.5) * dr;
                        let hr = section.size_near(p.hypot(dz), y);
                        2.0 * opening * p * dr / (hr * hr * hr)
                    })
                    .sum::<f64>()
            } else {
                sector(rcp, y) / (h * h * h)
            };
            let hs = section.size_near(rc, y);
            let shell = sector(rc, y) - sector(rcp, y);
            acc += TETS_PER_H3 * inner + SHELL_TETS_PER_H2T * shell / (hs * hs * hs.min(t));
        }
        acc * dy
    }

    /// The gmsh geometry (.geo) of the quarter cell described in the module documentation.
    /// Numbers are written in Rust's shortest round-trip form, so the text (and the cache
    /// key) is a function of the parameters alone.
    pub fn geo(&self) -> String {
        let [cx, cy, cz] = self.center;
        let (rn, rcp, rc) = (self.r_n, self.r_cp, self.r_c);
        let list = |v: &[f64]| {
            v.iter()
                .map(|v| format!("{v:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let centre = list(&self.center);
        // The thinnest layer bounds the tolerance of the bounding boxes that pick the
        // planar faces (their boxes are exact to 1e-7).
        let e = 1e-3 * rn.min(rcp - rn).min(rc - rcp);
        let (x0, y0, z0) = (cx - e, cy - rc - e, cz - e);
        let (x1, y1, z1) = (cx + rc + e, cy + rc + e, cz + rc + e);
        let mut s = String::new();
        let mut line = |l: String| {
            s.push_str(&l);
            s.push('\n');
        };
        line(
            match self.wedge {
                Wedge::Quarter => "// cellsim: the quarter cell x >= c_x, z >= c_z (MODEL.md §10).",
                Wedge::Eighth => {
                    "// cellsim: the eighth cell 0 <= z - c_z <= x - c_x (MODEL.md §10)."
                }
            }
            .into(),
        );
        line("SetFactory(\"OpenCASCADE\");".into());
        line("Geometry.OCCBooleanPreserveNumbering = 1;".into());
        line("General.NumThreads = 1;".into());
        for (tag, r) in [(1, rn), (2, rcp), (3, rc)] {
            line(format!("Sphere({tag}) = {{{centre}, {}}};", list(&[r])));
        }
        let rotate = |angle: &str, volumes: &str| {
            format!("Rotate {{{{0, 1, 0}}, {{{centre}}}, {angle}}} {{ Volume{{{volumes}}}; }}")
        };
        line(rotate("3 * Pi / 4", "1, 2, 3"));
        // The quarter box x ≥ c_x, z ≥ c_z (around the whole ball in y).
        let corner = list(&[cx, cy - 2.0 * rc, cz, 2.0 * rc, 4.0 * rc, 2.0 * rc]);
        let intersection = |tag: i32, a: i32, b: i32| {
            format!(
                "BooleanIntersection({tag}) = {{ Volume{{{a}}}; Delete; }}{{ Volume{{{b}}}; Delete; }};"
            )
        };
        for tag in 4..=6 {
            line(format!("Box({tag}) = {{{corner}}};"));
        }
        // The eighth: each box cut by the same box turned by π/4 about the vertical axis
        // (14–16 = 4–6 ∩ 7–9, the wedge 0 ≤ z − c_z ≤ x − c_x).
        let cut = if self.wedge == Wedge::Eighth {
            for tag in 7..=9 {
                line(format!("Box({tag}) = {{{corner}}};"));
            }
            line(rotate("Pi / 4", "7, 8, 9"));
            for tag in 4..=6 {
                line(intersection(tag + 10, tag, tag + 3));
            }
            10
        } else {
            0
        };
        for (ball, tag) in [(1, 11), (2, 12), (3, 13)] {
            line(intersection(tag, ball, ball + 3 + cut));
        }
        line("BooleanDifference(23) = { Volume{13}; Delete; }{ Volume{12}; };".into());
        line("BooleanDifference(22) = { Volume{12}; Delete; }{ Volume{11}; };".into());
        line(format!("Point(1000) = {{{centre}}};"));
        line("BooleanFragments{ Volume{11, 22, 23}; Delete; }{ Point{1000}; Delete; }".into());
        // The faces on the mirror plane x = c_x, or on the diagonal plane: the only faces
        // of the membrane inside the box c_x ≤ x, c_z ≤ z ≤ r_c/√2 (the sphere and the
        // face on z = c_z reach x = c_x + r_c).
        let (sx_x1, sx_z1) = match self.wedge {
            Wedge::Quarter => (cx + e, z1),
            Wedge::Eighth => {
                let d = rc * std::f64::consts::FRAC_1_SQRT_2;
                (cx + d + e, cz + d + e)
            }
        };
        for (name, corners) in [
            ("sx", [x0, y0, z0, sx_x1, y1, sx_z1]),
            ("sz", [x0, y0, z0, x1, y1, cz + e]),
        ] {
            line(format!(
                "{name}() = Surface In BoundingBox{{{}}};",
                list(&corners)
            ));
        }
        for text in [
            "outer() = Abs(Boundary{ Volume{23}; });",
            "outer() -= Abs(Boundary{ Volume{22}; });",
            "outer() -= sx();",
            "outer() -= sz();",
            "Physical Volume(\"nucleus\") = {11};",
            "Physical Volume(\"cytoplasm\") = {22};",
            "Physical Volume(\"membrane\") = {23};",
            "Physical Surface(\"outer\") = {outer()};",
            "Field[1] = MathEval;",
        ] {
            line(text.into());
        }
        line(format!("Field[1].F = \"{}\";", self.size_law()));
        match self.surface_law() {
            Some(law) => {
                line("Field[2] = MathEval;".into());
                line(format!("Field[2].F = \"{law}\";"));
                line("Field[3] = Min;".into());
                line("Field[3].FieldsList = {1, 2};".into());
                line("Background Field = 3;".into());
            }
            None => line("Background Field = 1;".into()),
        }
        for opt in [
            "Mesh.MeshSizeExtendFromBoundary = 0",
            "Mesh.MeshSizeFromPoints = 0",
            "Mesh.MeshSizeFromCurvature = 0",
            "Mesh.Algorithm3D = 10",
            "Mesh.MaxNumThreads3D = 1",
            "Mesh.ElementOrder = 2",
            "Mesh.SecondOrderLinear = 0",
            "Mesh.Binary = 0",
            "Mesh.SaveAll = 0",
            "Mesh.SaveParametric = 0",
        ] {
            line(format!("{opt};"));
        }
        s
    }

    /// The surface cap [`MeshParams::surface_cap`] as a gmsh MathEval expression (none
    /// without `h_surface`): (h_s + ½ max(0, r_cp − r) + ½ max(0, y − c_y)) / refine, with
    /// max(0, a) = (a + |a|)/2 and r the distance from c.
    fn surface_law(&self) -> Option<String> {
        let h = self.h_surface?;
        let f = |v: f64| format!("{v:?}");
        let [cx, cy, cz] = self.center;
        let d = |axis: &str, c: f64| format!("({axis} {})", signed(-c));
        let (dx, dy, dz) = (d("x", cx), d("y", cy), d("z", cz));
        let r = format!("sqrt({dx} * {dx} + {dy} * {dy} + {dz} * {dz})");
        let inward = format!("({} - {r})", f(self.r_cp));
        let k = f(super::half_cell::SURFACE_GRADING);
        Some(format!(
            "({} + {k} * ({inward} + abs({inward})) / 2 + {k} * ({dy} + abs({dy})) / 2) / {}",
            f(h),
            f(self.refine)
        ))
    }

    /// The size law as a gmsh MathEval expression: h = (h_b + (h_n − h_b) clamp(t, 0, 1)) /
    /// refine with t = (y − y_cb)/(y_nb − y_cb); clamp(t, 0, 1) = (|t| − |t − 1| + 1)/2.
    /// mathex has no unary minus after an operator: signs are folded into the operators.
    fn size_law(&self) -> String {
        let f = |v: f64| format!("{v:?}");
        let y_cb = self.center[1] - self.r_c;
        let t = format!("((y {}) / {})", signed(-y_cb), f(self.r_c - self.r_n));
        format!(
            "({} {} * (abs({t}) - abs({t} - 1) + 1) / 2) / {}",
            f(self.h_bottom),
            signed(self.h_nucleus - self.h_bottom),
            f(self.refine)
        )
    }
}

/// `v` as a signed term of a gmsh MathEval expression, `+ v` or `- |v|` (mathex has no
/// unary minus after an operator: signs are folded into the operators).
fn signed(v: f64) -> String {
    if v < 0.0 {
        format!("- {:?}", -v)
    } else {
        // abs: −0.0 would print as "-0.0".
        format!("+ {:?}", v.abs())
    }
}

/// A P2 tetrahedral mesh of the quarter cell (or of the extruded slab,
/// [`TetMesh::extruded`]).
///
/// Element node order is that of [`crate::fem::tet10`] (gmsh's type 11); every element is
/// positively oriented.
#[derive(Debug, Clone, Serialize)]
pub struct TetMesh {
    /// The parameters the mesh was built from.
    pub params: TetMeshParams,
    /// Node coordinates (reference configuration, µm).
    pub nodes: Vec<[f64; 3]>,
    /// Element connectivity, ten nodes each.
    pub elements: Vec<[usize; 10]>,
    /// Domain of each element.
    pub domains: Vec<Domain>,
    /// The six-node boundary triangles on the cell surface r = r_c (for the slab: on the
    /// cylinder over the 2-D outer boundary), oriented outward ([`crate::fem::tet10::face_map`]'s
    /// normal points out of the cell).
    pub outer_faces: Vec<[usize; 6]>,
    /// Nodes with x exactly c_x, ascending: u_x = 0 there (the mirror plane x = c_x of
    /// the quarter; in the eighth the vertical axis through c).
    pub symmetry_x: Vec<usize>,
    /// Nodes on the symmetry plane z = c_z (coordinate exactly c_z), ascending.
    pub symmetry_z: Vec<usize>,
    /// The eighth's nodes on the diagonal mirror plane x − c_x = z − c_z (exactly) off the
    /// axis, ascending: u_z = u_x there. Empty for the quarter and the slab.
    pub symmetry_diagonal: Vec<usize>,
    /// Reference points on the vertical axis through c (all mesh vertices; for the slab,
    /// those of the 2-D mesh on the face z = 0).
    pub points: NamedPoints,
}

/// A mesh made by [`TetMesh::generate_with`], with where it came from.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The mesh.
    pub mesh: TetMesh,
    /// The cached gmsh file it was read from.
    pub file: PathBuf,
    /// True if the file was in the cache (gmsh was not run).
    pub from_cache: bool,
    /// Wall time of the gmsh run (0 when cached), seconds.
    pub gmsh_seconds: f64,
}

/// Size and shape statistics of a 3-D mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TetMeshQuality {
    /// Number of tetrahedra.
    pub tets: usize,
    /// Number of nodes (vertices and mid-nodes).
    pub nodes: usize,
    /// Number of vertices.
    pub vertices: usize,
    /// Displacement unknowns: 3 · nodes minus one per node on each symmetry plane.
    pub displacement_unknowns: usize,
    /// Tetrahedra in the nucleus, cytoplasm and membrane.
    pub domain_tets: [usize; 3],
    /// Shortest vertex-to-vertex edge.
    pub min_edge: f64,
    /// Longest vertex-to-vertex edge.
    pub max_edge: f64,
    /// Smallest dihedral angle of the straight (vertex) tetrahedra, degrees.
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle of the straight tetrahedra, degrees.
    pub max_dihedral_deg: f64,
    /// Smallest radius ratio γ = 3 r_in / r_circ of the straight tetrahedra (1 for the
    /// regular one).
    pub min_radius_ratio: f64,
    /// Smallest ratio min det J / max det J over one element's check points (1 for
    /// straight elements; measures the curvature of the P2 elements).
    pub min_jacobian_ratio: f64,
    /// Minimum over vertical rays through the contact region below the centre (horizontal
    /// distances 0.5 to 3.5 µm from the axis) of the number of distinct membrane
    /// tetrahedra a ray crosses in the shell.
    pub elements_through_membrane: usize,
    /// Volume of the nucleus, cytoplasm and membrane (P2 geometry, exact integration).
    pub volumes: [f64; 3],
    /// The exact volumes of the three regions of the wedge.
    pub exact_volumes: [f64; 3],
    /// Area of the outer faces (P2 geometry).
    pub outer_area: f64,
    /// The exact area of the wedge's sphere (π r_c² for the quarter).
    pub exact_outer_area: f64,
}

impl fmt::Display for TetMeshQuality {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "tetrahedra {} (nucleus {}, cytoplasm {}, membrane {}); nodes {} ({} vertices); {} displacement unknowns",
            self.tets,
            self.domain_tets[0],
            self.domain_tets[1],
            self.domain_tets[2],
            self.nodes,
            self.vertices,
            self.displacement_unknowns
        )?;
        writeln!(
            f,
            "edges {:.3}–{:.3} µm; dihedral angles {:.1}°–{:.1}°; min radius ratio {:.3}; min det J ratio {:.3}; elements through membrane ≥ {}",
            self.min_edge,
            self.max_edge,
            self.min_dihedral_deg,
            self.max_dihedral_deg,
            self.min_radius_ratio,
            self.min_jacobian_ratio,
            self.elements_through_membrane
        )?;
        let rel = |a: f64, b: f64| (a - b) / b;
        write!(
            f,
            "volume error nucleus {:.2e}, cytoplasm {:.2e}, membrane {:.2e}; outer area error {:.2e}",
            rel(self.volumes[0], self.exact_volumes[0]),
            rel(self.volumes[1], self.exact_volumes[1]),
            rel(self.volumes[2], self.exact_volumes[2]),
            rel(self.outer_area, self.exact_outer_area)
        )
    }
}

/// The cache directory root: `$CELLSIM_CACHE`, else `$XDG_CACHE_HOME/cellsim`, else
/// `$HOME/.cache/cellsim`, else `cellsim-cache` in the system temporary directory (empty
/// variables count as unset). 3-D meshes go to its subdirectory `mesh3d`.
pub fn cache_root() -> PathBuf {
    let var = |name: &str| std::env::var_os(name).filter(|v| !v.is_empty());
    if let Some(d) = var("CELLSIM_CACHE") {
        PathBuf::from(d)
    } else if let Some(d) = var("XDG_CACHE_HOME") {
        PathBuf::from(d).join("cellsim")
    } else if let Some(d) = var("HOME") {
        PathBuf::from(d).join(".cache").join("cellsim")
    } else {
        std::env::temp_dir().join("cellsim-cache")
    }
}

/// FNV-1a, 64 bits, over the concatenation of `parts`, each followed by a 0 byte (so that
/// moving text between parts changes the hash).
pub fn fnv1a64(parts: &[&[u8]]) -> u64 {
    const OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut h = OFFSET;
    for p in parts {
        for &b in p.iter().chain(std::iter::once(&0u8)) {
            h ^= u64::from(b);
            h = h.wrapping_mul(PRIME);
        }
    }
    h
}

/// `program --version`'s output (stdout then stderr; gmsh prints to stderr).
fn gmsh_version(program: &Path) -> Result<Vec<u8>, MeshError> {
    let out = Command::new(program)
        .arg("--version")
        .stdin(Stdio::null())
        .output()
        .map_err(|e| spawn_error(program, &e))?;
    if !out.status.success() {
        return Err(MeshError::GmshFailed {
            status: out.status.to_string(),
            input: "--version".into(),
            stderr: tail(&out.stderr, &out.stdout),
        });
    }
    let mut v = out.stdout;
    v.extend_from_slice(&out.stderr);
    Ok(v)
}

fn spawn_error(program: &Path, e: &std::io::Error) -> MeshError {
    if e.kind() == std::io::ErrorKind::NotFound {
        MeshError::GmshNotFound {
            program: program.display().to_string(),
        }
    } else {
        MeshError::GmshFailed {
            status: format!("could not start: {e}"),
            input: String::new(),
            stderr: String::new(),
        }
    }
}

/// The last lines of a failed run's error output (its standard output when that is empty),
/// joined by " | ".
fn tail(stderr: &[u8], stdout: &[u8]) -> String {
    const LINES: usize = 8;
    let text = if stderr.iter().any(|b| !b.is_ascii_whitespace()) {
        String::from_utf8_lossy(stderr)
    } else {
        String::from_utf8_lossy(stdout)
    };
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    lines[lines.len().saturating_sub(LINES)..].join(" | ")
}

/// A unique temporary name beside `path` (same directory, so a rename is atomic): the
/// host name, the process id and a counter, so that processes on several machines sharing
/// the directory never write to one file.
fn temp_beside(path: &Path) -> PathBuf {
    static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_default();
    let host: String = host
        .trim()
        .chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '-')
        .take(32)
        .collect();
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(format!(".tmp-{host}-{}-{n}", std::process::id()));
    path.with_file_name(name)
}

/// Writes `text` to `path` through a temporary file and a rename.
fn write_atomically(path: &Path, text: &str) -> Result<(), MeshError> {
    let werr = |source| MeshError::Write {
        path: path.display().to_string(),
        source,
    };
    let tmp = temp_beside(path);
    let mut file = std::fs::File::create(&tmp).map_err(werr)?;
    file.write_all(text.as_bytes()).map_err(werr)?;
    drop(file);
    std::fs::rename(&tmp, path).map_err(werr)
}

/// The absolute path of `program`: as given if it has a directory part (made absolute
/// against the current directory), else the first executable file of that name on `PATH`.
fn resolve_program(program: &Path) -> Result<PathBuf, MeshError> {
    let not_found = || MeshError::GmshNotFound {
        program: program.display().to_string(),
    };
    if program.components().count() > 1 || program.is_absolute() {
        return std::path::absolute(program).map_err(|_| not_found());
    }
    let path = std::env::var_os("PATH").ok_or_else(not_found)?;
    std::env::split_paths(&path)
        .map(|d| d.join(program))
        .find(|p| p.is_file())
        .ok_or_else(not_found)
}

/// `setarch` if it can run a program with address-space randomisation off (`setarch -R`),
/// checked once per process.
fn no_aslr_wrapper() -> Option<&'static Path> {
    static WRAPPER: OnceLock<Option<PathBuf>> = OnceLock::new();
    WRAPPER
        .get_or_init(|| {
            let setarch = resolve_program(Path::new("setarch")).ok()?;
            let ok = Command::new(&setarch)
                .args(["-R", "true"])
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status()
                .is_ok_and(|s| s.success());
            ok.then_some(setarch)
        })
        .as_deref()
}

/// The cached mesh file for `geo` made by `program` under `root`, running gmsh if it is not
/// there yet: (file, whether it was cached, gmsh's wall time, what `accept` returned for a
/// fresh file). `accept` reads and checks a fresh file before it goes into the cache. How
/// gmsh is run, and why, is step 5 of the module documentation.
pub(crate) fn mesh_file<T>(
    program: &Path,
    geo: &str,
    root: &Path,
    accept: impl FnOnce(&Path) -> Result<T, MeshError>,
) -> Result<(PathBuf, bool, f64, Option<T>), MeshError> {
    let version = gmsh_version(program)?;
    let program = resolve_program(program)?;
    let wrapper = no_aslr_wrapper();
    let args = format!(
        "{}{} {GMSH_VERBOSITY}",
        if wrapper.is_some() {
            "setarch -R; "
        } else {
            ""
        },
        GMSH_ARGS.join(" ")
    );
    let key = fnv1a64(&[geo.as_bytes(), args.as_bytes(), &version]);
    let dir = root.join("mesh3d");
    std::fs::create_dir_all(&dir).map_err(|source| MeshError::Write {
        path: dir.display().to_string(),
        source,
    })?;
    let file = dir.join(format!("{key:016x}.msh"));
    if file.is_file() {
        return Ok((file, true, 0.0, None));
    }
    let geo_path = dir.join(format!("{key:016x}.geo"));
    write_atomically(&geo_path, geo)?;
    // The working directory: fixed-length name, removed afterwards whatever happens.
    static COUNTER: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let work = std::env::temp_dir().join(format!(
        "cellsim-gmsh-{key:016x}-{:08x}-{n:08x}",
        std::process::id()
    ));
    struct Cleanup(PathBuf);
    impl Drop for Cleanup {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
    let _cleanup = Cleanup(work.clone());
    let werr = |path: &Path| {
        let path = path.display().to_string();
        move |source| MeshError::Write { path, source }
    };
    std::fs::create_dir_all(&work).map_err(werr(&work))?;
    std::fs::write(work.join("cell.geo"), geo).map_err(werr(&work.join("cell.geo")))?;
    let mut cmd = match wrapper {
        Some(setarch) => {
            let mut c = Command::new(setarch);
            c.arg("-R").arg(&program);
            c
        }
        None => Command::new(&program),
    };
    cmd.arg("cell.geo")
        .args(GMSH_ARGS)
        .arg(GMSH_VERBOSITY)
        .args(["-o", "cell.msh"])
        .current_dir(&work)
        .env_clear()
        .env("HOME", &work)
        .env("LC_ALL", "C")
        .env("PATH", "/usr/bin:/bin")
        .stdin(Stdio::null());
    if let Some(ld) = std::env::var_os("LD_LIBRARY_PATH") {
        cmd.env("LD_LIBRARY_PATH", ld);
    }
    let start = Instant::now();
    let out = cmd.output().map_err(|e| spawn_error(&program, &e))?;
    let seconds = start.elapsed().as_secs_f64();
    let made = work.join("cell.msh");
    let failed = |status: String| MeshError::GmshFailed {
        status,
        input: geo_path.display().to_string(),
        stderr: tail(&out.stderr, &out.stdout),
    };
    if !out.status.success() {
        return Err(failed(out.status.to_string()));
    }
    if !made.is_file() {
        return Err(failed("no mesh file written".into()));
    }
    // Into the cache: a copy beside the final name, checked, then renamed. A mesh that
    // fails the checks stays there under its temporary name (the error names it).
    let tmp = temp_beside(&file);
    std::fs::copy(&made, &tmp).map_err(werr(&tmp))?;
    let value = accept(&tmp)?;
    std::fs::rename(&tmp, &file).map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        MeshError::Write {
            path: file.display().to_string(),
            source,
        }
    })?;
    Ok((file, false, seconds, Some(value)))
}

/// The reference points at which det J is checked: the ten nodes and the points of every
/// [`TetRule::degree`] with d ≤ 6, with the shape gradients tabulated.
fn jacobian_check_points() -> &'static TetTabulation {
    static TAB: OnceLock<TetTabulation> = OnceLock::new();
    TAB.get_or_init(|| {
        let mut rule = TetRule {
            points: REFERENCE_NODES.to_vec(),
            weights: vec![0.0; 10],
        };
        for d in [1, 2, 5, 6] {
            let r = TetRule::degree(d);
            rule.points.extend(r.points);
            rule.weights.extend(r.weights);
        }
        TetTabulation::new(&rule)
    })
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: [f64; 3]) -> f64 {
    dot(a, a).sqrt()
}

/// Six times the signed volume of the straight tetrahedron (p₀, p₁, p₂, p₃).
fn six_volume(p: [[f64; 3]; 4]) -> f64 {
    dot(cross(sub(p[1], p[0]), sub(p[2], p[0])), sub(p[3], p[0]))
}

/// The 6-node face reversed: vertices 1 and 2 swapped, with the mid-nodes.
fn reverse_face(f: [usize; 6]) -> [usize; 6] {
    [f[0], f[2], f[1], f[5], f[4], f[3]]
}

/// Sorted vertex triple of a face: its key in face maps.
fn face_key(f: &[usize; 6]) -> [usize; 3] {
    let mut k = [f[0], f[1], f[2]];
    k.sort_unstable();
    k
}

/// How far a node read from a mesh file (its coordinates rounded there) may lie from a
/// circle or a named height and still count as on it: 10⁻⁶ r_c.
fn fit_tolerance(params: &TetMeshParams) -> f64 {
    1e-6 * params.r_c
}

/// Snaps the nodes within 10⁻⁹ r_c of a symmetry plane onto it (the symmetry sets are
/// those exactly on it): x = c_x and z = c_z for the quarter; z = c_z and the diagonal
/// x − c_x = z − c_z for the eighth (both: onto the axis). Refuses a node outside the wedge.
fn snap_to_symmetry_planes(params: &TetMeshParams, nodes: &mut [[f64; 3]]) -> Result<(), String> {
    let c = params.center;
    let snap = 1e-9 * params.r_c;
    for (i, p) in nodes.iter_mut().enumerate() {
        let outside =
            |p: &[f64; 3], wedge: &str| Err(format!("node {i} at {p:?} is outside the {wedge}"));
        match params.wedge {
            Wedge::Quarter => {
                for k in [0, 2] {
                    if (p[k] - c[k]).abs() <= snap {
                        p[k] = c[k];
                    } else if p[k] < c[k] {
                        return outside(p, "quarter x ≥ c_x, z ≥ c_z");
                    }
                }
            }
            Wedge::Eighth => {
                let (dx, dz) = (p[0] - c[0], p[2] - c[2]);
                let near_z = dz.abs() <= snap;
                // Distance to the diagonal plane: |dx − dz| / √2.
                let near_diagonal = (dx - dz).abs() <= snap * std::f64::consts::SQRT_2;
                if near_z {
                    p[2] = c[2];
                }
                if near_diagonal && near_z {
                    p[0] = c[0];
                } else if near_diagonal {
                    let m = 0.5 * (dx + dz);
                    p[0] = c[0] + m;
                    p[2] = c[2] + m;
                } else if dz < 0.0 || dx < dz {
                    return outside(p, "eighth 0 ≤ z − c_z ≤ x − c_x");
                }
            }
        }
    }
    Ok(())
}

/// Checks that every tetrahedron's vertices lie inside r_c and on its domain's side of
/// the interfaces r_n and r_cp (within the fit tolerance): the mesh fits the cell.
fn check_vertex_radii(
    params: &TetMeshParams,
    nodes: &[[f64; 3]],
    elements: &[[usize; 10]],
    domains: &[Domain],
) -> Result<(), String> {
    let tol = fit_tolerance(params);
    for (e, (el, d)) in elements.iter().zip(domains).enumerate() {
        for &n in &el[..4] {
            let r = norm(sub(nodes[n], params.center));
            let ok = r <= params.r_c + tol
                && match d {
                    Domain::Nucleus => r <= params.r_n + tol,
                    Domain::Cytoplasm => r >= params.r_n - tol && r <= params.r_cp + tol,
                    Domain::Membrane => r >= params.r_cp - tol,
                };
            if !ok {
                return Err(format!(
                    "{d} tetrahedron {e} has a vertex at r = {r} from the centre: the mesh does not fit the cell (r_n {}, r_cp {}, r_c {})",
                    params.r_n, params.r_cp, params.r_c
                ));
            }
        }
    }
    Ok(())
}

/// Reverses the tetrahedra of negative volume (vertices 1 and 2 swapped, with their
/// mid-nodes), so that every element is positively oriented.
fn orient_positively(nodes: &[[f64; 3]], elements: &mut [[usize; 10]]) {
    for el in elements.iter_mut() {
        if six_volume([0, 1, 2, 3].map(|k| nodes[el[k]])) < 0.0 {
            *el = FLIP.map(|k| el[k]);
        }
    }
}

/// Radius ratio γ = 3 r_in / r_circ and the six dihedral angles (radians) of the straight
/// tetrahedron p (any orientation).
fn tet_shape(p: [[f64; 3]; 4]) -> (f64, [f64; 6]) {
    let v = six_volume(p).abs() / 6.0;
    // Face k opposite vertex k, normals pointing away from vertex k.
    let mut normals = [[0.0; 3]; 4];
    let mut area = 0.0;
    for k in 0..4 {
        let f: Vec<[f64; 3]> = (0..4).filter(|&i| i != k).map(|i| p[i]).collect();
        let mut n = cross(sub(f[1], f[0]), sub(f[2], f[0]));
        if dot(n, sub(p[k], f[0])) > 0.0 {
            n = [-n[0], -n[1], -n[2]];
        }
        let l = norm(n);
        area += 0.5 * l;
        normals[k] = [n[0] / l, n[1] / l, n[2] / l];
    }
    let r_in = 3.0 * v / area;
    // Circumcentre o (relative to p₀): 2 (pᵢ − p₀) · o = |pᵢ − p₀|², i = 1, 2, 3.
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let det = dot(a, cross(b, c));
    let (la, lb, lc) = (dot(a, a), dot(b, b), dot(c, c));
    let bc = cross(b, c);
    let ca = cross(c, a);
    let ab = cross(a, b);
    let o: [f64; 3] = std::array::from_fn(|i| (la * bc[i] + lb * ca[i] + lc * ab[i]) / (2.0 * det));
    let r_circ = norm(o);
    // The dihedral angle at the edge shared by faces k and l is π − ∠(n_k, n_l).
    let mut dihedral = [0.0; 6];
    let mut i = 0;
    for k in 0..4 {
        for l in k + 1..4 {
            dihedral[i] = PI - dot(normals[k], normals[l]).clamp(-1.0, 1.0).acos();
            i += 1;
        }
    }
    (3.0 * r_in / r_circ, dihedral)
}

impl TetMesh {
    /// Generates the quarter-cell mesh with the gmsh on the PATH and the cache of
    /// [`cache_root`] (see the module documentation).
    pub fn generate(params: &TetMeshParams) -> Result<TetMesh, MeshError> {
        Self::generate_with(params, Path::new("gmsh"), &cache_root()).map(|g| g.mesh)
    }

    /// As [`TetMesh::generate`] with the gmsh executable `program` and the cache root
    /// `cache_root` (meshes go to its `mesh3d` subdirectory); also says whether the mesh
    /// came from the cache.
    pub fn generate_with(
        params: &TetMeshParams,
        program: &Path,
        cache_root: &Path,
    ) -> Result<Generated, MeshError> {
        params.validate()?;
        let geo = params.geo();
        let (file, from_cache, gmsh_seconds, fresh) =
            mesh_file(program, &geo, cache_root, |tmp| {
                Self::read_gmsh(tmp, params)
            })?;
        let mesh = match fresh {
            Some(m) => m,
            None => Self::read_gmsh(&file, params)?,
        };
        Ok(Generated {
            mesh,
            file,
            from_cache,
            gmsh_seconds,
        })
    }

    /// Completes a mesh read from a file (see the module documentation): checks against
    /// `params`, snapping onto the symmetry planes, orientation, conformity, outer faces,
    /// named points, Jacobians. `faces` are the outer triangles with their file lines.
    pub(crate) fn from_parts(
        params: &TetMeshParams,
        mut nodes: Vec<[f64; 3]>,
        mut elements: Vec<[usize; 10]>,
        domains: Vec<Domain>,
        faces: &[([usize; 6], usize)],
        path: &str,
    ) -> Result<TetMesh, MeshError> {
        let ferr = |line: usize, message: String| MeshError::Format {
            path: path.to_string(),
            line,
            message,
        };
        snap_to_symmetry_planes(params, &mut nodes).map_err(|m| ferr(0, m))?;
        check_vertex_radii(params, &nodes, &elements, &domains).map_err(|m| ferr(0, m))?;
        orient_positively(&nodes, &mut elements);
        let mut mesh = TetMesh {
            params: params.clone(),
            nodes,
            elements,
            domains,
            outer_faces: Vec::new(),
            symmetry_x: Vec::new(),
            symmetry_z: Vec::new(),
            symmetry_diagonal: Vec::new(),
            points: NamedPoints {
                centre: 0,
                nucleus_top: 0,
                nucleus_bottom: 0,
                cell_bottom: 0,
                cell_top: 0,
            },
        };
        let boundary = mesh.check_conformity().map_err(|m| ferr(0, m))?;
        mesh.outer_faces = mesh
            .outer_faces_of(&boundary, faces)
            .map_err(|(line, m)| ferr(line, m))?;
        mesh.set_symmetry_sets();
        mesh.points = mesh.snap_named_points().map_err(|m| ferr(0, m))?;
        mesh.check_jacobians()?;
        Ok(mesh)
    }

    /// The node sets on the symmetry planes (coordinates exactly c_x, c_z, and for the
    /// eighth x − c_x = z − c_z off the axis).
    fn set_symmetry_sets(&mut self) {
        let c = self.params.center;
        let on = |k: usize| -> Vec<usize> {
            (0..self.nodes.len())
                .filter(|&n| self.nodes[n][k] == c[k])
                .collect()
        };
        self.symmetry_x = on(0);
        self.symmetry_z = on(2);
        if self.params.wedge == Wedge::Eighth {
            self.symmetry_diagonal = (0..self.nodes.len())
                .filter(|&n| {
                    let p = self.nodes[n];
                    p[0] - c[0] == p[2] - c[2] && p[0] != c[0]
                })
                .collect();
        }
    }

    /// The outer faces from a file's outer triangles `faces` (with their file lines): each
    /// must be a boundary face of the tetrahedra (in `boundary`) with the same mid-nodes,
    /// on r = r_c; returned as the tetrahedra's faces, oriented outward. The error is the
    /// file line and what is wrong.
    fn outer_faces_of(
        &self,
        boundary: &HashMap<[usize; 3], [usize; 6]>,
        faces: &[([usize; 6], usize)],
    ) -> Result<Vec<[usize; 6]>, (usize, String)> {
        let (c, r_c) = (self.params.center, self.params.r_c);
        let tol = fit_tolerance(&self.params);
        let mut outer = Vec::with_capacity(faces.len());
        for (f, line) in faces {
            let Some(bf) = boundary.get(&face_key(f)) else {
                return Err((
                    *line,
                    "outer triangle is not a boundary face of the tetrahedra".into(),
                ));
            };
            // The tetrahedron's face, with its own mid-nodes, must be this triangle.
            let mut fm = [f[3], f[4], f[5]];
            let mut bm = [bf[3], bf[4], bf[5]];
            fm.sort_unstable();
            bm.sort_unstable();
            if fm != bm {
                return Err((
                    *line,
                    "outer triangle's mid-nodes are not those of the tetrahedron's face".into(),
                ));
            }
            for &v in &f[..6] {
                let r = norm(sub(self.nodes[v], c));
                if (r - r_c).abs() > tol {
                    return Err((
                        *line,
                        format!("outer triangle node at r = {r}, not on r_c = {r_c}"),
                    ));
                }
            }
            outer.push(*bf);
        }
        Ok(outer)
    }

    /// The named points: vertices on the axis x = c_x, z = c_z within the fit tolerance of
    /// the centre's and the circles' poles' heights, their heights snapped exactly.
    fn snap_named_points(&mut self) -> Result<NamedPoints, String> {
        let c = self.params.center;
        let (r_n, r_c) = (self.params.r_n, self.params.r_c);
        let tol = fit_tolerance(&self.params);
        let mut on_axis: Vec<usize> = self
            .elements
            .iter()
            .flat_map(|el| el[..4].iter().copied())
            .filter(|&n| self.nodes[n][0] == c[0] && self.nodes[n][2] == c[2])
            .collect();
        on_axis.sort_unstable();
        on_axis.dedup();
        let nodes = &mut self.nodes;
        let mut find = |y: f64, what: &str| {
            let found = on_axis
                .iter()
                .copied()
                .find(|&n| (nodes[n][1] - y).abs() <= tol);
            match found {
                Some(n) => {
                    nodes[n][1] = y;
                    Ok(n)
                }
                None => Err(format!(
                    "no vertex at the {what} (x = {}, y = {y}, z = {})",
                    c[0], c[2]
                )),
            }
        };
        Ok(NamedPoints {
            centre: find(c[1], "centre")?,
            nucleus_top: find(c[1] + r_n, "nucleus top")?,
            nucleus_bottom: find(c[1] - r_n, "nucleus bottom")?,
            cell_bottom: find(c[1] - r_c, "cell bottom")?,
            cell_top: find(c[1] + r_c, "cell top")?,
        })
    }

    /// Checks that every edge has one mid-node and every face belongs to one or two
    /// tetrahedra; returns the boundary faces (used once), outward, by their sorted vertex
    /// triple. The error says what is wrong.
    pub fn check_conformity(&self) -> Result<HashMap<[usize; 3], [usize; 6]>, String> {
        let mut mids: HashMap<(usize, usize), usize> = HashMap::new();
        for (e, el) in self.elements.iter().enumerate() {
            for (k, ed) in TET_EDGES.iter().enumerate() {
                let (a, b) = (el[ed[0]], el[ed[1]]);
                let m = *mids.entry((a.min(b), a.max(b))).or_insert(el[4 + k]);
                if m != el[4 + k] {
                    return Err(format!(
                        "edge {a}–{b} has two mid-nodes ({m} and {}, element {e})",
                        el[4 + k]
                    ));
                }
            }
        }
        let mut faces: HashMap<[usize; 3], (usize, [usize; 6])> = HashMap::new();
        for (e, el) in self.elements.iter().enumerate() {
            for lf in TET_FACES {
                let f = lf.map(|k| el[k]);
                let entry = faces.entry(face_key(&f)).or_insert((0, f));
                entry.0 += 1;
                if entry.0 > 2 {
                    return Err(format!(
                        "face {:?} belongs to more than two tetrahedra (element {e})",
                        face_key(&f)
                    ));
                }
            }
        }
        Ok(faces
            .into_iter()
            .filter(|(_, (n, _))| *n == 1)
            .map(|(k, (_, f))| (k, f))
            .collect())
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elements.len()
    }

    /// Number of nodes.
    pub fn n_nodes(&self) -> usize {
        self.nodes.len()
    }

    /// Coordinates of the six nodes of a face.
    pub fn face_coords(&self, f: &[usize; 6]) -> [[f64; 3]; 6] {
        f.map(|n| self.nodes[n])
    }

    /// Displacement unknowns: 3 per node minus u_x on `symmetry_x` and u_z on
    /// `symmetry_z`.
    pub fn displacement_unknowns(&self) -> usize {
        3 * self.nodes.len()
            - self.symmetry_x.len()
            - self.symmetry_z.len()
            - self.symmetry_diagonal.len()
    }

    /// Volume of domain `d` (or of the whole mesh with `None`), integrating det J of the
    /// P2 maps exactly (det J is a cubic in ξ; the degree-3 rule is exact).
    pub fn volume(&self, d: Option<Domain>) -> f64 {
        let tab = TetTabulation::new(&TetRule::degree(3));
        let mut v = 0.0;
        for e in 0..self.elements.len() {
            if d.is_some_and(|d| d != self.domains[e]) {
                continue;
            }
            let x = self.element_coords(e);
            for q in 0..tab.len() {
                v += tet10::jacobian(&x, &tab.grads[q]).1 * tab.weights[q];
            }
        }
        v
    }

    /// Area of the outer faces (P2 geometry; the degree-10 triangle rule).
    pub fn outer_area(&self) -> f64 {
        let rule = TriangleRule::degree(10);
        let mut a = 0.0;
        for f in &self.outer_faces {
            let x = self.face_coords(f);
            for (p, w) in rule.points.iter().zip(&rule.weights) {
                a += w * norm(tet10::face_map(&x, *p).1);
            }
        }
        a
    }

    /// Minimum and maximum of det J over the check points of element `e` (its ten nodes and
    /// the points of every tetrahedron rule of degree ≤ 6), and where the minimum is.
    pub fn jacobian_range(&self, e: usize) -> (f64, f64, [f64; 3]) {
        let tab = jacobian_check_points();
        let x = self.element_coords(e);
        let det = |q: usize| tet10::jacobian(&x, &tab.grads[q]).1;
        let (min, max, q) = extremes(0..tab.len(), det);
        (min, max, tab.points[q])
    }

    /// Size and shape statistics.
    pub fn quality(&self) -> TetMeshQuality {
        let mut min_edge = f64::INFINITY;
        let mut max_edge: f64 = 0.0;
        let mut min_dih = f64::INFINITY;
        let mut max_dih: f64 = 0.0;
        let mut min_gamma = f64::INFINITY;
        let mut min_ratio = f64::INFINITY;
        let mut is_vertex = vec![false; self.nodes.len()];
        for (e, el) in self.elements.iter().enumerate() {
            let p = [0, 1, 2, 3].map(|k| self.nodes[el[k]]);
            for ed in TET_EDGES {
                let l = norm(sub(p[ed[0]], p[ed[1]]));
                min_edge = min_edge.min(l);
                max_edge = max_edge.max(l);
            }
            let (gamma, dih) = tet_shape(p);
            min_gamma = min_gamma.min(gamma);
            for a in dih {
                min_dih = min_dih.min(a);
                max_dih = max_dih.max(a);
            }
            let (jmin, jmax, _) = self.jacobian_range(e);
            min_ratio = min_ratio.min(jmin / jmax);
            for &n in &el[..4] {
                is_vertex[n] = true;
            }
        }
        let count = |d: Domain| self.domains.iter().filter(|&&x| x == d).count();
        let prm = &self.params;
        // The wedge's share of a ball and of a sphere.
        let share = 1.0 / prm.wedge.copies();
        let ball = |r: f64| share * 4.0 * PI * r * r * r / 3.0;
        TetMeshQuality {
            tets: self.elements.len(),
            nodes: self.nodes.len(),
            vertices: is_vertex.iter().filter(|&&v| v).count(),
            displacement_unknowns: self.displacement_unknowns(),
            domain_tets: Domain::ALL.map(count),
            min_edge,
            max_edge,
            min_dihedral_deg: min_dih.to_degrees(),
            max_dihedral_deg: max_dih.to_degrees(),
            min_radius_ratio: min_gamma,
            min_jacobian_ratio: min_ratio,
            elements_through_membrane: self.elements_through_membrane(),
            volumes: Domain::ALL.map(|d| self.volume(Some(d))),
            exact_volumes: [
                ball(prm.r_n),
                ball(prm.r_cp) - ball(prm.r_n),
                ball(prm.r_c) - ball(prm.r_cp),
            ],
            outer_area: self.outer_area(),
            exact_outer_area: share * 4.0 * PI * prm.r_c * prm.r_c,
        }
    }

    /// Minimum over 12 vertical rays below the centre (horizontal distance ρ = 0.5, 1.5,
    /// 2.5, 3.5 µm from the axis at azimuths 1/4, 1/2 and 3/4 of the wedge's angle from the
    /// x axis: π/8, π/4, 3π/8 in the quarter) of the number
    /// of distinct membrane tetrahedra (straight-sided) met by the ray where it crosses the
    /// shell r_cp ≤ r ≤ r_c, sampled at 64 heights. 0 if a ray misses the shell.
    pub fn elements_through_membrane(&self) -> usize {
        let prm = &self.params;
        let c = prm.center;
        let members: Vec<(usize, [[f64; 3]; 4])> = self
            .elements
            .iter()
            .enumerate()
            .filter(|(e, _)| self.domains[*e] == Domain::Membrane)
            .map(|(e, el)| (e, [0, 1, 2, 3].map(|k| self.nodes[el[k]])))
            .filter(|(_, p)| p.iter().any(|q| q[1] < c[1]))
            .collect();
        let mut best = usize::MAX;
        for rho in [0.5, 1.5, 2.5, 3.5] {
            if rho >= prm.r_cp {
                continue;
            }
            for phi in [0.25, 0.5, 0.75].map(|s| s * prm.wedge.angle()) {
                let (x, z) = (c[0] + rho * phi.cos(), c[2] + rho * phi.sin());
                let y_out = c[1] - (prm.r_c * prm.r_c - rho * rho).sqrt();
                let y_in = c[1] - (prm.r_cp * prm.r_cp - rho * rho).sqrt();
                let cands: Vec<&(usize, [[f64; 3]; 4])> = members
                    .iter()
                    .filter(|(_, p)| {
                        let lo = |i: usize| p.iter().map(|q| q[i]).fold(f64::INFINITY, f64::min);
                        let hi =
                            |i: usize| p.iter().map(|q| q[i]).fold(f64::NEG_INFINITY, f64::max);
                        lo(0) <= x && x <= hi(0) && lo(2) <= z && z <= hi(2)
                    })
                    .collect();
                let mut hit: Vec<usize> = Vec::new();
                for j in 0..64 {
                    let y = y_out + (j as f64 + 0.5) / 64.0 * (y_in - y_out);
                    for (e, p) in &cands {
                        if !hit.contains(e) && straight_contains(p, [x, y, z]) {
                            hit.push(*e);
                        }
                    }
                }
                best = best.min(hit.len());
            }
        }
        if best == usize::MAX { 0 } else { best }
    }

    /// The 2-D half-cell mesh extruded one layer of thickness `thickness` in z
    /// (0 ≤ z ≤ thickness), each prism split into three P2 tetrahedra (see the module
    /// documentation). Nodes: the 2-D nodes at z = 0 (same indices as in `mesh`, so its
    /// [`NamedPoints`] carry over), then at z = thickness/2, then at z = thickness
    /// (node l · n + i is 2-D node i in layer l). Tetrahedra 3k, 3k + 1, 3k + 2 fill the
    /// prism over triangle k and have its domain.
    /// `symmetry_z` is the face z = 0 and `outer_faces` the cylinder over the 2-D outer
    /// edges. For the slab check of MODEL.md §10 (plane strain) fix u_z on **every** node.
    ///
    /// # Panics
    /// If `thickness` is not finite and positive.
    pub fn extruded(mesh: &Mesh, thickness: f64) -> TetMesh {
        assert!(
            thickness.is_finite() && thickness > 0.0,
            "slab thickness must be finite and > 0, got {thickness}"
        );
        let n2 = mesh.nodes.len();
        let mut nodes = Vec::with_capacity(3 * n2);
        for z in [0.0, 0.5 * thickness, thickness] {
            nodes.extend(mesh.nodes.iter().map(|p| [p[0], p[1], z]));
        }
        let mut mid2: HashMap<(usize, usize), usize> = HashMap::new();
        for el in &mesh.elements {
            for ed in EDGES {
                let (a, b) = (el[ed[0]], el[ed[2]]);
                mid2.insert((a.min(b), a.max(b)), el[ed[1]]);
            }
        }
        // A slab vertex is (2-D vertex, layer 0 or 2); node(i, l) = l n₂ + i.
        let node = |(i, l): (usize, usize)| l * n2 + i;
        let mid = |(i, li): (usize, usize), (j, lj): (usize, usize)| {
            if i == j {
                n2 + i
            } else {
                (li + lj) / 2 * n2 + mid2[&(i.min(j), i.max(j))]
            }
        };
        let p10 = |v: [(usize, usize); 4]| -> [usize; 10] {
            let mut el = [0usize; 10];
            for k in 0..4 {
                el[k] = node(v[k]);
            }
            for (k, ed) in TET_EDGES.iter().enumerate() {
                el[4 + k] = mid(v[ed[0]], v[ed[1]]);
            }
            el
        };
        let mut elements = Vec::with_capacity(3 * mesh.elements.len());
        let mut domains = Vec::with_capacity(3 * mesh.elements.len());
        for (el, d) in mesh.elements.iter().zip(&mesh.domains) {
            // Rotate so that a is the smallest vertex; the triangle stays counter-clockwise.
            let k = (0..3).min_by_key(|&k| el[k]).unwrap_or(0);
            let (a, b, c) = (el[k], el[(k + 1) % 3], el[(k + 2) % 3]);
            let (ba, bb, bc) = ((a, 0), (b, 0), (c, 0));
            let (ta, tb, tc) = ((a, 2), (b, 2), (c, 2));
            // Diagonals a–B and a–C on the faces through a; on face b c C B the diagonal
            // starts at the smaller of b, c.
            let tets = if b < c {
                [[ba, bb, bc, tc], [ba, bb, tc, tb], [ba, tb, tc, ta]]
            } else {
                [[ba, bb, bc, tb], [ba, bc, tc, tb], [ba, tb, tc, ta]]
            };
            for mut v in tets {
                if six_volume(v.map(|q| nodes[node(q)])) < 0.0 {
                    v.swap(1, 2);
                }
                elements.push(p10(v));
                domains.push(*d);
            }
        }
        let c2 = mesh.params.center;
        let mut outer_faces = Vec::with_capacity(2 * mesh.outer_edges.len());
        for e in &mesh.outer_edges {
            let (p, q) = (e[0].min(e[2]), e[0].max(e[2]));
            for tri in [[(p, 0), (q, 0), (q, 2)], [(p, 0), (q, 2), (p, 2)]] {
                let mut f = [0usize; 6];
                for s in 0..3 {
                    f[s] = node(tri[s]);
                    f[3 + s] = mid(tri[s], tri[(s + 1) % 3]);
                }
                let x: [[f64; 3]; 6] = f.map(|n| nodes[n]);
                let (pt, n) = tet10::face_map(&x, [1.0 / 3.0, 1.0 / 3.0]);
                if n[0] * (pt[0] - c2[0]) + n[1] * (pt[1] - c2[1]) < 0.0 {
                    f = reverse_face(f);
                }
                outer_faces.push(f);
            }
        }
        let mut out = TetMesh {
            params: TetMeshParams::from_section(&mesh.params, 0.0),
            nodes,
            elements,
            domains,
            outer_faces,
            symmetry_x: Vec::new(),
            symmetry_z: Vec::new(),
            symmetry_diagonal: Vec::new(),
            points: mesh.points,
        };
        out.set_symmetry_sets();
        out
    }
}

/// True if p lies in the straight tetrahedron q (either orientation; boundary included).
fn straight_contains(q: &[[f64; 3]; 4], p: [f64; 3]) -> bool {
    let s = six_volume(*q).signum();
    (0..4).all(|k| {
        let mut t = *q;
        t[k] = p;
        s * six_volume(t) >= -1e-12 * six_volume(*q).abs()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scratch directory in the system temporary directory, emptied first.
    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("cellsim-mesh3-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        d
    }

    #[test]
    fn fnv1a64_matches_the_reference_values() {
        // FNV-1a 64 of "" and "a" (the published test vectors), here with the 0 byte that
        // ends each part: "" + 0 and "a" + 0.
        let h = |bytes: &[u8]| {
            let mut h: u64 = 0xcbf2_9ce4_8422_2325;
            for &b in bytes {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x100_0000_01b3);
            }
            h
        };
        assert_eq!(h(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(h(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(h(b"foobar"), 0x8594_4171_f739_67e8);
        assert_eq!(fnv1a64(&[b"a"]), h(b"a\0"));
        assert_eq!(fnv1a64(&[b"ab", b"c"]), h(b"ab\0c\0"));
        assert_ne!(fnv1a64(&[b"ab", b"c"]), fnv1a64(&[b"a", b"bc"]));
    }

    #[test]
    fn missing_gmsh_is_reported_with_the_package_name() {
        let root = scratch("missing");
        let e = TetMesh::generate_with(
            &crate::fem::reference::tet_mesh_params(),
            Path::new("/nonexistent/bin/gmsh"),
            &root,
        )
        .expect_err("no gmsh there");
        assert!(matches!(e, MeshError::GmshNotFound { .. }), "{e:?}");
        let msg = e.to_string();
        assert!(
            msg.contains(
                "gmsh not found on PATH: install the Debian package `gmsh` (make deps does)"
            ),
            "{msg}"
        );
        assert!(!root.join("mesh3d").exists());
    }

    /// gmsh failing on a broken geometry: its error lines are in the message, and no file
    /// is left in the cache.
    #[test]
    fn gmsh_failure_reports_its_error_output() {
        let root = scratch("failure");
        let geo = "SetFactory(\"OpenCASCADE\");\nSphere(1) = {0, 0, 0, 1;\n";
        let e = mesh_file(Path::new("gmsh"), geo, &root, |_| Ok(())).expect_err("syntax error");
        match &e {
            MeshError::GmshFailed { stderr, .. } => {
                assert!(stderr.contains("rror"), "{stderr}")
            }
            other => panic!("expected GmshFailed, got {other:?}"),
        }
        let left: Vec<_> = std::fs::read_dir(root.join("mesh3d"))
            .expect("cache dir")
            .filter_map(|d| d.ok())
            .map(|d| d.file_name().to_string_lossy().into_owned())
            .filter(|n| n.contains(".msh"))
            .collect();
        assert!(left.is_empty(), "{left:?}");
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn shape_measures_of_known_tetrahedra() {
        // Regular tetrahedron: γ = 1, all dihedral angles acos(1/3).
        let s = 1.0 / 2f64.sqrt();
        let reg = [
            [1.0, 0.0, -s],
            [-1.0, 0.0, -s],
            [0.0, 1.0, s],
            [0.0, -1.0, s],
        ];
        let (g, d) = tet_shape(reg);
        assert!((g - 1.0).abs() < 1e-14, "{g}");
        for a in d {
            assert!((a - (1.0f64 / 3.0).acos()).abs() < 1e-14);
        }
        // The reference tetrahedron: three right dihedral angles at the origin, three of
        // atan(√2) = 54.74°; γ = 3 r_in/r_circ with r_in = 1/(3 + √3), r_circ = √3/2.
        let (g, d) = tet_shape([[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
        let expect = 3.0 / (3.0 + 3f64.sqrt()) / (3f64.sqrt() / 2.0);
        assert!((g - expect).abs() < 1e-14);
        let mut d = d.map(f64::to_degrees);
        d.sort_by(f64::total_cmp);
        for a in &d[..3] {
            assert!((a - 2f64.sqrt().atan().to_degrees()).abs() < 1e-12, "{a}");
        }
        for a in &d[3..] {
            assert!((a - 90.0).abs() < 1e-12);
        }
        assert!(straight_contains(
            &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [0.2, 0.2, 0.2]
        ));
        assert!(!straight_contains(
            &[[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            [0.5, 0.5, 0.2]
        ));
    }
}
