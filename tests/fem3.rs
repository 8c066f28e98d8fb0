//! The 3-D P2 pieces (MODEL.md §10): the gmsh-meshed quarter cell (volumes and their
//! convergence, the patch test, symmetry sets, named points, outer faces, determinism and
//! the cache, refusals) and the extruded slab (volumes, conformity, the 2-D space inside
//! the 3-D one). The element and quadrature tests are unit tests of `fem::tet10` and
//! `fem::quadrature`.

use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

use cellsim::case::Case;
use cellsim::fem::element::Lagrange;
use cellsim::fem::mesh::quarter_cell::Generated;
use cellsim::fem::tet10::{self as tet, TET_FACES};
use cellsim::fem::tri6::{self as p2, Tri6};
use cellsim::fem::{
    CellMesh, Domain, EdgeRule, Mesh, MeshError, TetMesh, TetMeshParams, TetRule, TetTabulation,
    TriangleRule, Wedge,
};
use cellsim::scene::terms;

/// The cache root of these tests (under the target directory, kept across runs).
fn cache() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("fem3-cache")
}

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("fem3-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn generate(p: &TetMeshParams) -> Generated {
    TetMesh::generate_with(p, Path::new("gmsh"), &cache()).unwrap_or_else(|e| panic!("{p:?}: {e}"))
}

fn params(refine: f64) -> TetMeshParams {
    TetMeshParams {
        refine,
        wedge: Wedge::Quarter,
        ..cellsim::scene::terms::tet_mesh_params(&cellsim::case::Case::reference())
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// Volumes of the balls r_n, r_cp, r_c (of the wedge) from a mesh: nucleus, nucleus +
/// cytoplasm, everything. Each has one curved boundary.
fn ball_volumes(m: &TetMesh) -> [f64; 3] {
    let n = m.volume(Some(Domain::Nucleus));
    let c = m.volume(Some(Domain::Cytoplasm));
    [n, n + c, m.volume(None)]
}

/// P2 geometry error: the volumes of the meshed quarter balls against π r³/3, at refine 1
/// and 2 of the default sizes. The error must be small and fall at least like h³ (a factor
/// 8 from refine 1 to 2; measured ≈ 15, i.e. ≈ h⁴).
#[test]
fn curved_tetrahedra_give_the_quarter_ball_volumes_with_high_order_convergence() {
    let m1 = generate(&params(1.0)).mesh;
    let m2 = generate(&params(2.0)).mesh;
    let p = &m1.params;
    let exact = [p.r_n, p.r_cp, p.r_c].map(|r| PI * r * r * r / 3.0);
    let (v1, v2) = (ball_volumes(&m1), ball_volumes(&m2));
    for k in 0..3 {
        let e1 = (v1[k] - exact[k]) / exact[k];
        let e2 = (v2[k] - exact[k]) / exact[k];
        println!(
            "ball {k}: relative volume error {e1:.3e} (refine 1) → {e2:.3e} (refine 2), ratio {:.1}",
            e1 / e2
        );
        assert!(e1.abs() < 1e-4, "ball {k}: {e1:e}");
        assert!(e1.abs() / e2.abs() > 8.0, "ball {k}: {e1:e} → {e2:e}");
    }
    // The straight-sided (vertex) tetrahedra alone miss far more: the curved P2 geometry is
    // what makes the volume this accurate.
    let straight: f64 = m1
        .elements
        .iter()
        .map(|el| {
            let x = [0, 1, 2, 3].map(|k| m1.nodes[el[k]]);
            let (a, b, c) = (sub(x[1], x[0]), sub(x[2], x[0]), sub(x[3], x[0]));
            (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0]))
                / 6.0
        })
        .sum();
    let e_straight = (straight - exact[2]) / exact[2];
    let e_p2 = (v1[2] - exact[2]) / exact[2];
    println!("whole cell: straight tetrahedra {e_straight:.3e}, P2 {e_p2:.3e}");
    assert!(e_straight.abs() > 50.0 * e_p2.abs());
}

/// The isoparametric patch test: a linear field u(X) = A X + b interpolated at the nodes
/// has Σₐ uₐ ⊗ ∇Nₐ = A at every quadrature point of every element, across the material
/// interfaces too (they are conforming: interface nodes belong to both sides).
#[test]
fn linear_fields_have_exact_gradients_everywhere() {
    let m = generate(&params(1.0)).mesh;
    let a = [[0.3, -1.2, 0.7], [2.0, 0.1, -0.4], [-0.6, 0.9, 1.5]];
    let b = [0.2, -0.1, 0.05];
    let u: Vec<[f64; 3]> = m
        .nodes
        .iter()
        .map(|x| std::array::from_fn(|i| b[i] + (0..3).map(|j| a[i][j] * x[j]).sum::<f64>()))
        .collect();
    let tab = TetTabulation::new(&TetRule::degree(5));
    let mut worst: f64 = 0.0;
    for e in 0..m.n_elements() {
        let geo = tab
            .geometry(&m.element_coords(e))
            .unwrap_or_else(|err| panic!("element {e}: {err}"));
        let el = m.elements[e];
        for q in 0..tab.len() {
            for i in 0..3 {
                for j in 0..3 {
                    let g: f64 = (0..10).map(|k| u[el[k]][i] * geo.grads[q][k][j]).sum();
                    worst = worst.max((g - a[i][j]).abs());
                }
            }
            // The interpolated value is the field at the mapped point.
            let x = geo.x[q];
            for i in 0..3 {
                let v: f64 = (0..10).map(|k| u[el[k]][i] * tab.values[q][k]).sum();
                let exact = b[i] + (0..3).map(|j| a[i][j] * x[j]).sum::<f64>();
                assert!((v - exact).abs() < 1e-12, "element {e}");
            }
        }
    }
    println!("patch test: largest gradient error {worst:.2e}");
    assert!(worst < 1e-11, "{worst:e}");
    // Interface nodes are shared by the domains on both sides.
    let nuc = m.nodes_of_domain(Domain::Nucleus);
    let cyt = m.nodes_of_domain(Domain::Cytoplasm);
    let mem = m.nodes_of_domain(Domain::Membrane);
    let c = m.params.center;
    let r = |n: usize| norm(sub(m.nodes[n], c));
    let on = |n: usize, radius: f64| (r(n) - radius).abs() < 1e-9 * radius;
    let (mut n_nuc, mut n_mem) = (0, 0);
    for n in 0..m.n_nodes() {
        if on(n, m.params.r_n) {
            assert!(nuc[n] && cyt[n] && !mem[n], "node {n} on r_n");
            n_nuc += 1;
        }
        if on(n, m.params.r_cp) {
            assert!(cyt[n] && mem[n] && !nuc[n], "node {n} on r_cp");
            n_mem += 1;
        }
    }
    assert!(n_nuc > 50 && n_mem > 100, "{n_nuc} {n_mem}");
}

/// The default mesh: counts, quality, the symmetry sets, the named points, the outer faces,
/// the domains.
#[test]
fn default_mesh_is_complete_and_of_good_quality() {
    let m = generate(&params(1.0)).mesh;
    let q = m.quality();
    println!("{q}");
    assert!((7_000..=14_000).contains(&q.tets), "{q}");
    assert!(q.min_radius_ratio > 0.1, "{q}");
    assert!(q.min_dihedral_deg > 8.0, "{q}");
    assert!(q.min_jacobian_ratio > 0.3, "{q}");
    assert!(q.elements_through_membrane >= 1, "{q}");
    assert!(q.domain_tets.iter().all(|&n| n > 100), "{q}");
    assert_eq!(q.domain_tets.iter().sum::<usize>(), q.tets);
    assert_eq!(
        q.displacement_unknowns,
        3 * q.nodes - m.symmetry_x.len() - m.symmetry_z.len()
    );
    let est = m.params.estimated_tets();
    assert!(
        (est / q.tets as f64 - 1.0).abs() < 0.25,
        "estimate {est} vs {}",
        q.tets
    );

    let p = &m.params;
    let c = p.center;
    // Symmetry sets: exactly the nodes on the planes, and no node is near a plane without
    // being on it.
    for (set, k) in [(&m.symmetry_x, 0), (&m.symmetry_z, 2)] {
        let mut expect: Vec<usize> = (0..m.n_nodes())
            .filter(|&n| m.nodes[n][k] == c[k])
            .collect();
        expect.sort_unstable();
        assert_eq!(set, &expect);
        for n in 0..m.n_nodes() {
            let d = m.nodes[n][k] - c[k];
            assert!(
                d == 0.0 || d > 1e-3,
                "node {n} at distance {d} from plane {k}"
            );
        }
    }
    // The axis nodes are in both sets.
    let axis = m
        .symmetry_x
        .iter()
        .filter(|n| m.symmetry_z.contains(n))
        .count();
    assert!(axis >= 10, "{axis} nodes on the axis");
    // Named points: exact positions, tetrahedron vertices.
    let pts = m.points;
    for (n, y) in [
        (pts.centre, c[1]),
        (pts.nucleus_top, c[1] + p.r_n),
        (pts.nucleus_bottom, c[1] - p.r_n),
        (pts.cell_bottom, c[1] - p.r_c),
        (pts.cell_top, c[1] + p.r_c),
    ] {
        assert_eq!(m.nodes[n], [c[0], y, c[2]]);
        assert!(m.elements.iter().any(|el| el[..4].contains(&n)));
    }
    // Outer faces: on the sphere, outward, covering a quarter of it.
    let rule = TriangleRule::degree(6);
    let mut area = 0.0;
    for f in &m.outer_faces {
        let x = m.face_coords(f);
        for v in x {
            assert!((norm(sub(v, c)) - p.r_c).abs() < 1e-9 * p.r_c);
        }
        for (xi, w) in rule.points.iter().zip(&rule.weights) {
            let (pt, n) = tet::face_map(&x, *xi);
            let d = sub(pt, c);
            let cos = (n[0] * d[0] + n[1] * d[1] + n[2] * d[2]) / (norm(n) * norm(d));
            assert!(cos > 0.99, "outer face normal off the radius: cos {cos}");
            area += w * norm(n);
        }
    }
    let exact = PI * p.r_c * p.r_c;
    println!(
        "outer faces: {}, area error {:.2e}",
        m.outer_faces.len(),
        area / exact - 1.0
    );
    assert!((area / exact - 1.0).abs() < 1e-5);
    // Every boundary face is an outer face or lies on a symmetry plane.
    let outer: std::collections::HashSet<[usize; 3]> = m
        .outer_faces
        .iter()
        .map(|f| {
            let mut k = [f[0], f[1], f[2]];
            k.sort_unstable();
            k
        })
        .collect();
    let mut n_boundary = 0;
    for f in boundary_faces(&m) {
        n_boundary += 1;
        let mut k = [f[0], f[1], f[2]];
        k.sort_unstable();
        let on_plane = |i: usize| f.iter().all(|&n| m.nodes[n][i] == c[i]);
        assert!(
            outer.contains(&k) || on_plane(0) || on_plane(2),
            "stray boundary face {f:?}"
        );
    }
    assert!(n_boundary > m.outer_faces.len());
    // Domains by radius.
    for (el, d) in m.elements.iter().zip(&m.domains) {
        let rs = [0, 1, 2, 3].map(|k| norm(sub(m.nodes[el[k]], c)));
        let tol = 1e-9;
        let ok = rs.iter().all(|&r| match d {
            Domain::Nucleus => r <= p.r_n + tol,
            Domain::Cytoplasm => r >= p.r_n - tol && r <= p.r_cp + tol,
            Domain::Membrane => r >= p.r_cp - tol && r <= p.r_c + tol,
        });
        assert!(ok, "{d} element with vertex radii {rs:?}");
    }
    assert!(m.check_jacobians().is_ok());
}

/// The names in a mesh cache directory, sorted, after checking that they are one `.geo`
/// and one `.msh` (nothing temporary left).
fn only_geo_and_msh(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .filter_map(|d| d.ok())
        .map(|d| d.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names.len(), 2, "{names:?}");
    assert!(
        names[0].ends_with(".geo") && names[1].ends_with(".msh"),
        "{names:?}"
    );
    names
}

/// The same parameters give the same file, byte for byte, from two independent gmsh runs;
/// a second call on the same cache does not run gmsh and gives the same mesh.
#[test]
fn meshing_is_deterministic_and_cached() {
    let p = TetMeshParams {
        refine: 0.8,
        ..cellsim::scene::terms::tet_mesh_params(&cellsim::case::Case::reference())
    };
    let (ra, rb) = (scratch("det-a"), scratch("det-b"));
    let a = TetMesh::generate_with(&p, Path::new("gmsh"), &ra).expect("first");
    let b = TetMesh::generate_with(&p, Path::new("gmsh"), &rb).expect("second");
    assert!(!a.from_cache && !b.from_cache);
    assert_ne!(a.file, b.file);
    assert_eq!(a.file.file_name(), b.file.file_name());
    let (ta, tb) = (
        std::fs::read(&a.file).expect("a"),
        std::fs::read(&b.file).expect("b"),
    );
    assert!(ta == tb, "two gmsh runs differ");
    // And the same as the file in the shared cache, made by whichever test process first
    // asked for it.
    let shared = generate(&p);
    assert!(
        std::fs::read(&shared.file).expect("shared") == ta,
        "differs from the shared cache"
    );
    // Only the mesh and its geometry are left in the cache directory.
    only_geo_and_msh(&ra.join("mesh3d"));
    // From the cache.
    let t = Instant::now();
    let c = TetMesh::generate_with(&p, Path::new("gmsh"), &ra).expect("cached");
    let dt = t.elapsed().as_secs_f64();
    println!(
        "gmsh {:.2} s; from the cache {dt:.2} s ({} tetrahedra)",
        a.gmsh_seconds,
        c.mesh.n_elements()
    );
    assert!(c.from_cache && c.gmsh_seconds == 0.0);
    assert_eq!(c.file, a.file);
    assert_eq!(c.mesh.nodes, a.mesh.nodes);
    assert_eq!(c.mesh.elements, a.mesh.elements);
    // Another size is another key.
    let q = TetMeshParams {
        h_bottom: 0.31,
        ..p.clone()
    };
    assert_ne!(q.geo(), p.geo());
    let _ = std::fs::remove_dir_all(&ra);
    let _ = std::fs::remove_dir_all(&rb);
}

/// Other cells mesh too: an off-origin centre with a thick membrane and a uniform size, and
/// an inverted grading with the cell bottom at y = 0. Symmetry planes, named points and
/// volumes follow the parameters.
#[test]
fn other_cells_mesh_with_their_planes_points_and_volumes() {
    let cases = [
        TetMeshParams {
            center: [1.5, -2.0, 0.7],
            wedge: Wedge::Eighth,
            r_n: 3.0,
            r_cp: 6.0,
            r_c: 7.0,
            h_bottom: 0.6,
            h_nucleus: 0.6,
            refine: 1.0,
            h_surface: None,
        },
        TetMeshParams {
            center: [0.0, 10.0, 0.0],
            h_bottom: 1.0,
            h_nucleus: 0.5,
            ..cellsim::scene::terms::tet_mesh_params(&cellsim::case::Case::reference())
        },
    ];
    for p in cases {
        let m = generate(&p).mesh;
        let q = m.quality();
        println!("{p:?}\n{q}");
        let c = p.center;
        assert!(m.symmetry_x.iter().all(|&n| m.nodes[n][0] == c[0]));
        assert!(m.symmetry_z.iter().all(|&n| m.nodes[n][2] == c[2]));
        assert!(m.nodes.iter().all(|x| x[0] >= c[0] && x[2] >= c[2]));
        assert_eq!(m.nodes[m.points.cell_bottom], [c[0], c[1] - p.r_c, c[2]]);
        assert_eq!(m.nodes[m.points.nucleus_top], [c[0], c[1] + p.r_n, c[2]]);
        for k in 0..3 {
            let e = q.volumes[k] / q.exact_volumes[k] - 1.0;
            assert!(e.abs() < 1e-3, "domain {k}: {e:e}");
        }
        assert!(
            q.min_radius_ratio > 0.05 && q.min_jacobian_ratio > 0.2,
            "{q}"
        );
    }
}

#[test]
fn gmsh_missing_and_bad_parameters_are_refused() {
    let root = scratch("missing");
    let e = TetMesh::generate_with(
        &cellsim::scene::terms::tet_mesh_params(&cellsim::case::Case::reference()),
        Path::new("/nonexistent/gmsh"),
        &root,
    )
    .expect_err("no gmsh");
    assert!(
        e.to_string()
            .contains("gmsh not found on PATH: install the Debian package `gmsh` (make deps does)"),
        "{e}"
    );
    let field_of = |p: TetMeshParams| match TetMesh::generate_with(&p, Path::new("gmsh"), &root) {
        Err(MeshError::InvalidParam { field, .. }) => field,
        other => panic!("expected InvalidParam, got {other:?}"),
    };
    let d = cellsim::scene::terms::tet_mesh_params(&cellsim::case::Case::reference());
    assert_eq!(
        field_of(TetMeshParams {
            r_cp: 5.0,
            ..d.clone()
        }),
        "r_cp"
    );
    assert_eq!(
        field_of(TetMeshParams {
            r_c: 9.0,
            ..d.clone()
        }),
        "r_c"
    );
    assert_eq!(
        field_of(TetMeshParams {
            r_c: 9.7505,
            ..d.clone()
        }),
        "r_c"
    );
    assert_eq!(
        field_of(TetMeshParams {
            r_n: -1.0,
            ..d.clone()
        }),
        "r_n"
    );
    assert_eq!(
        field_of(TetMeshParams {
            h_bottom: 0.0,
            ..d.clone()
        }),
        "h_bottom"
    );
    assert_eq!(
        field_of(TetMeshParams {
            h_nucleus: f64::NAN,
            ..d.clone()
        }),
        "h_nucleus"
    );
    assert_eq!(
        field_of(TetMeshParams {
            refine: f64::INFINITY,
            ..d.clone()
        }),
        "refine"
    );
    assert_eq!(
        field_of(TetMeshParams {
            center: [0.0, 0.0, f64::NAN],
            ..d.clone()
        }),
        "center[2]"
    );
    assert_eq!(
        field_of(TetMeshParams {
            center: [0.0, 1e12, 0.0],
            ..d.clone()
        }),
        "center"
    );
    assert!(matches!(
        TetMesh::generate_with(
            &TetMeshParams {
                refine: 20.0,
                ..d.clone()
            },
            Path::new("gmsh"),
            &root
        ),
        Err(MeshError::TooFine { .. })
    ));
    let msg = TetMesh::generate(&TetMeshParams { r_cp: 4.0, ..d })
        .expect_err("invalid")
        .to_string();
    assert!(msg.contains("r_cp") && msg.contains("r_n"), "{msg}");
    // Nothing was meshed.
    assert!(!root.join("mesh3d").exists());
}

/// The reader refuses broken files with the line, reorients inverted tetrahedra, names an
/// element with a non-positive Jacobian, and refuses a mesh of another cell.
#[test]
fn reading_checks_the_file_and_the_cell() {
    let g = generate(&params(0.6));
    let p = g.mesh.params.clone();
    let good = std::fs::read_to_string(&g.file).expect("mesh file");
    let path = "cell.msh";
    let m = TetMesh::parse_gmsh(&good, path, &p).expect("reads");
    assert_eq!(m.nodes, g.mesh.nodes);
    // Wrong version.
    let bad = good.replacen("4.1 0 8", "2.2 0 8", 1);
    assert!(matches!(
        TetMesh::parse_gmsh(&bad, path, &p),
        Err(MeshError::Format { line: 2, .. })
    ));
    // A missing group.
    let bad = good.replacen("\"membrane\"", "\"skin\"", 1);
    let e = TetMesh::parse_gmsh(&bad, path, &p).expect_err("no membrane");
    assert!(e.to_string().contains("membrane"), "{e}");
    let bad = good.replacen("\"outer\"", "\"surface\"", 1);
    let e = TetMesh::parse_gmsh(&bad, path, &p).expect_err("no outer");
    assert!(e.to_string().contains("outer"), "{e}");
    // A corrupt node coordinate: the message names its line.
    let lines: Vec<&str> = good.lines().collect();
    let end_nodes = lines.iter().position(|l| *l == "$EndNodes").expect("nodes");
    let mut broken = lines.clone();
    broken[end_nodes - 1] = "0.5 oops 0";
    match TetMesh::parse_gmsh(&broken.join("\n"), path, &p) {
        Err(MeshError::Format { line, message, .. }) => {
            assert_eq!(line, end_nodes, "{message}");
            assert!(message.contains("oops"));
        }
        other => panic!("expected a format error, got {other:?}"),
    }
    // The element blocks: find the first tetrahedron block and its first element.
    let start = lines
        .iter()
        .position(|l| *l == "$Elements")
        .expect("elements")
        + 2;
    let block = (start..lines.len())
        .find(|&i| {
            let f: Vec<&str> = lines[i].split_whitespace().collect();
            f.len() == 4 && f[0] == "3" && f[2] == "11"
        })
        .expect("a tetrahedron block");
    // Linear tetrahedra are refused.
    let mut linear = lines.clone();
    let f: Vec<&str> = lines[block].split_whitespace().collect();
    let relabelled = format!("{} {} 4 {}", f[0], f[1], f[3]);
    linear[block] = &relabelled;
    let e = TetMesh::parse_gmsh(&linear.join("\n"), path, &p).expect_err("linear");
    assert!(e.to_string().contains("10-node"), "{e}");
    // An element given with the opposite orientation is reoriented.
    let el: Vec<&str> = lines[block + 1].split_whitespace().collect();
    let flip = [0usize, 2, 1, 3, 6, 5, 4, 7, 9, 8];
    let flipped_line = std::iter::once(el[0].to_string())
        .chain(flip.iter().map(|&k| el[1 + k].to_string()))
        .collect::<Vec<_>>()
        .join(" ");
    let mut flipped = lines.clone();
    flipped[block + 1] = &flipped_line;
    let r = TetMesh::parse_gmsh(&flipped.join("\n"), path, &p).expect("reoriented");
    assert!(r.check_jacobians().is_ok());
    assert!((r.volume(None) - m.volume(None)).abs() < 1e-12 * m.volume(None));
    // A mid-node moved across its element: the element is named.
    let mut moved = m.clone();
    let el = moved.elements[5];
    moved.nodes[el[4]] = moved.nodes[el[3]];
    match moved.check_jacobians() {
        Err(MeshError::NonPositiveJacobian { element, det, .. }) => {
            assert!(
                moved.elements[element].contains(&el[4]),
                "element {element}"
            );
            assert!(det <= 0.0);
        }
        other => panic!("expected a Jacobian error, got {other:?}"),
    }
    // The file of another cell.
    let other = TetMeshParams {
        r_c: 10.5,
        ..p.clone()
    };
    let e = TetMesh::parse_gmsh(&good, path, &other).expect_err("another cell");
    println!("another cell: {e}");
    let other = TetMeshParams {
        r_n: 4.0,
        ..p.clone()
    };
    assert!(TetMesh::parse_gmsh(&good, path, &other).is_err());
    // A missing file.
    assert!(matches!(
        TetMesh::read_gmsh(Path::new("/nonexistent/cell.msh"), &p),
        Err(MeshError::Io { .. })
    ));
}

fn mesh2(refine: f64) -> Mesh {
    let mut p = terms::mesh_params(&Case::reference());
    p.refine = refine;
    Mesh::generate(&p).expect("2-D mesh")
}

/// The slab: volumes are area × thickness, the mesh is conforming with every interior face
/// shared by two tetrahedra, det J > 0, the sets and points are those of the 2-D mesh.
#[test]
fn extruded_slab_is_conforming_with_exact_volumes() {
    let m2 = mesh2(1.0);
    let t = 0.7;
    let m = TetMesh::extruded(&m2, t);
    assert_eq!(m.n_elements(), 3 * m2.n_elements());
    assert_eq!(m.n_nodes(), 3 * m2.n_nodes());
    for d in Domain::ALL {
        let (v, a) = (m.volume(Some(d)), m2.area(Some(d)));
        assert!((v - a * t).abs() < 1e-13 * a * t, "{d}: {v} vs {}", a * t);
    }
    assert!(m.check_jacobians().is_ok());
    // Conformity: one mid-node per edge, every face used once or twice, and the faces
    // used once are exactly the slab's boundary.
    let boundary = m.check_conformity().expect("conforming");
    let mut uses: HashMap<[usize; 3], usize> = HashMap::new();
    for el in &m.elements {
        for f in TET_FACES {
            let mut k = [el[f[0]], el[f[1]], el[f[2]]];
            k.sort_unstable();
            *uses.entry(k).or_insert(0) += 1;
        }
    }
    let interior = uses.values().filter(|&&u| u == 2).count();
    assert_eq!(interior + boundary.len(), uses.len());
    let c = m.params.center;
    let r_c = m.params.r_c;
    let mut lateral = 0;
    for f in boundary.values() {
        let zs: Vec<f64> = f.iter().map(|&n| m.nodes[n][2]).collect();
        let on_z = |z: f64| zs.iter().all(|&v| v == z);
        let on_sym = f.iter().all(|&n| m.nodes[n][0] == c[0]);
        let on_cyl = f[..3]
            .iter()
            .all(|&n| ((m.nodes[n][0] - c[0]).hypot(m.nodes[n][1] - c[1]) - r_c).abs() < 1e-9);
        assert!(on_z(0.0) || on_z(t) || on_sym || on_cyl, "stray face {f:?}");
        if on_cyl && !on_z(0.0) && !on_z(t) {
            lateral += 1;
        }
    }
    // Two faces per outer edge on the cylinder, and they are the outer faces.
    assert_eq!(lateral, 2 * m2.outer_edges.len());
    assert_eq!(m.outer_faces.len(), lateral);
    for f in &m.outer_faces {
        let mut k = [f[0], f[1], f[2]];
        k.sort_unstable();
        assert!(boundary.contains_key(&k));
        let (p, n) = tet::face_map(&m.face_coords(f), [1.0 / 3.0, 1.0 / 3.0]);
        assert!(
            n[0] * (p[0] - c[0]) + n[1] * (p[1] - c[1]) > 0.0,
            "inward face"
        );
        assert!(n[2].abs() < 1e-12 * norm(n));
    }
    // The lateral area is the 2-D outer length × t.
    let er = EdgeRule::degree(20).subdivided(2);
    let length: f64 = m2
        .outer_edges
        .iter()
        .map(|e| {
            let x = [m2.nodes[e[0]], m2.nodes[e[1]], m2.nodes[e[2]]];
            (0..er.len())
                .map(|q| {
                    let (_, d) = p2::edge_map(&x, er.points[q]);
                    er.weights[q] * d[0].hypot(d[1])
                })
                .sum::<f64>()
        })
        .sum();
    let area = m.outer_area();
    assert!(
        (area - length * t).abs() < 1e-9 * area,
        "{area} vs {}",
        length * t
    );
    // Sets and points.
    let n2 = m2.n_nodes();
    assert_eq!(m.symmetry_z, (0..n2).collect::<Vec<_>>());
    let mut sx: Vec<usize> = (0..3)
        .flat_map(|l| m2.symmetry_nodes.iter().map(move |&i| l * n2 + i))
        .collect();
    sx.sort_unstable();
    assert_eq!(m.symmetry_x, sx);
    assert_eq!(m.points, m2.points);
    assert_eq!(m.nodes[m.points.cell_bottom], [0.0, -1.5, 0.0]);
    // Each prism's three tetrahedra have its triangle's domain.
    for (k, d) in m2.domains.iter().enumerate() {
        assert!(m.domains[3 * k..3 * k + 3].iter().all(|x| x == d));
    }
    let q = m.quality();
    println!(
        "slab t = {t}: {} tetrahedra, {} nodes, min radius ratio {:.3}",
        q.tets, q.nodes, q.min_radius_ratio
    );
}

/// Every field of the 2-D P2 space, constant in z, is in the slab's space: interpolated at
/// the slab's nodes it has the 2-D value and in-plane gradient at every quadrature point,
/// and a zero z-derivative (what makes the slab with u_z = 0 plane strain).
#[test]
fn extruded_slab_contains_the_2d_space() {
    let m2 = mesh2(0.5);
    let t = 0.4;
    let m = TetMesh::extruded(&m2, t);
    let n2 = m2.n_nodes();
    // Arbitrary nodal values on the 2-D mesh.
    let f2: Vec<f64> = (0..n2)
        .map(|i| {
            let p = m2.nodes[i];
            (0.7 * p[0]).sin() + (0.3 * p[1]).cos() * p[0] + 0.01 * i as f64
        })
        .collect();
    let f3: Vec<f64> = (0..m.n_nodes()).map(|n| f2[n % n2]).collect();
    let tab = TetTabulation::new(&TetRule::degree(5));
    let mut worst: f64 = 0.0;
    for e in 0..m.n_elements() {
        let geo = tab.geometry(&m.element_coords(e)).expect("valid");
        let tri = e / 3;
        let x2 = m2.element_coords(tri);
        let el = m.elements[e];
        for q in 0..tab.len() {
            let pt = geo.x[q];
            // The 2-D reference point of (x, y), by Newton on the curved triangle.
            let mut xi = [1.0 / 3.0, 1.0 / 3.0];
            for _ in 0..30 {
                let (p, jac, _) = Tri6::map(&x2, xi);
                let r = nalgebra::Vector2::new(p[0] - pt[0], p[1] - pt[1]);
                let d = jac.lu().solve(&r).expect("regular");
                xi = [xi[0] - d[0], xi[1] - d[1]];
                if d.amax() < 1e-15 {
                    break;
                }
            }
            let (_, jac, det) = Tri6::map(&x2, xi);
            let g2 = p2::physical_gradients(&jac, det, &Tri6::grad_shape(xi));
            let n2v = Tri6::shape(xi);
            let tri_nodes = m2.elements[tri];
            let v2: f64 = (0..6).map(|a| n2v[a] * f2[tri_nodes[a]]).sum();
            let gx2: f64 = (0..6).map(|a| g2[a][0] * f2[tri_nodes[a]]).sum();
            let gy2: f64 = (0..6).map(|a| g2[a][1] * f2[tri_nodes[a]]).sum();
            let v3: f64 = (0..10).map(|a| tab.values[q][a] * f3[el[a]]).sum();
            let g3: [f64; 3] =
                std::array::from_fn(|i| (0..10).map(|a| geo.grads[q][a][i] * f3[el[a]]).sum());
            let scale = 1.0 + gx2.abs() + gy2.abs();
            worst = worst
                .max((v3 - v2).abs())
                .max((g3[0] - gx2).abs() / scale)
                .max((g3[1] - gy2).abs() / scale)
                .max(g3[2].abs() / scale);
        }
    }
    println!("slab against 2-D: largest difference {worst:.2e}");
    assert!(worst < 1e-10, "{worst:e}");
}

/// Measurements for the report: counts, unknowns, gmsh time and quality at refine 1, 1.5,
/// 2 of the default sizes (run with --nocapture).
#[test]
fn print_quality() {
    for refine in [1.0, 1.5, 2.0] {
        let p = params(refine);
        let root = scratch(&format!("print-{refine}"));
        let t = Instant::now();
        let g = TetMesh::generate_with(&p, Path::new("gmsh"), &root).expect("mesh");
        let total = t.elapsed().as_secs_f64();
        let q = g.mesh.quality();
        println!(
            "refine {refine}: gmsh {:.2} s, with reading and checks {total:.2} s, estimate {:.0}\n{q}",
            g.gmsh_seconds,
            p.estimated_tets(),
        );
        let _ = std::fs::remove_dir_all(&root);
    }
}

/// The eighth cell 0 ≤ z − c_z ≤ x − c_x: every node in the wedge, the symmetry sets exactly
/// the nodes on their planes (u_x = 0 only on the axis), half the quarter's volumes and
/// area to the P2 geometry's error, and about half its tetrahedra.
#[test]
fn the_eighth_mesh_is_half_the_quarter() {
    let quarter = generate(&params(1.0)).mesh;
    let m = generate(&TetMeshParams {
        wedge: Wedge::Eighth,
        ..params(1.0)
    })
    .mesh;
    let q = m.quality();
    println!("{q}");
    let ratio = q.tets as f64 / quarter.elements.len() as f64;
    assert!((0.4..0.6).contains(&ratio), "{ratio}");
    assert!(q.min_radius_ratio > 0.1 && q.min_dihedral_deg > 8.0, "{q}");
    assert!(q.elements_through_membrane >= 1, "{q}");
    for (v, e) in q.volumes.iter().zip(q.exact_volumes) {
        assert!((v / e - 1.0).abs() < 1e-3, "{q}");
    }
    assert!(
        (q.outer_area / q.exact_outer_area - 1.0).abs() < 1e-3,
        "{q}"
    );
    let half = |a: f64, b: f64| (a / (0.5 * b) - 1.0).abs() < 1e-9;
    assert!(half(q.exact_outer_area, quarter.quality().exact_outer_area));
    let est = m.params.estimated_tets();
    assert!(
        (est / q.tets as f64 - 1.0).abs() < 0.25,
        "estimate {est} vs {}",
        q.tets
    );
    let c = m.params.center;
    for n in 0..m.n_nodes() {
        let (x, z) = (m.nodes[n][0] - c[0], m.nodes[n][2] - c[2]);
        assert!(z >= 0.0 && x >= z, "node {n} outside the eighth");
        // No node near a plane without being on it.
        assert!(z == 0.0 || z > 1e-3, "node {n}: z {z}");
        assert!(x == z || x - z > 1e-3, "node {n}: x − z {}", x - z);
    }
    let on = |f: &dyn Fn(f64, f64) -> bool| -> Vec<usize> {
        (0..m.n_nodes())
            .filter(|&n| f(m.nodes[n][0] - c[0], m.nodes[n][2] - c[2]))
            .collect()
    };
    assert_eq!(m.symmetry_z, on(&|_, z| z == 0.0));
    assert_eq!(m.symmetry_x, on(&|x, z| x == 0.0 && z == 0.0));
    assert_eq!(m.symmetry_diagonal, on(&|x, z| x == z && x != 0.0));
    assert!(
        m.symmetry_x.len() >= 10,
        "{} nodes on the axis",
        m.symmetry_x.len()
    );
    assert!(m.symmetry_diagonal.len() > 100);
    assert_eq!(
        q.displacement_unknowns,
        3 * q.nodes - m.symmetry_x.len() - m.symmetry_z.len() - m.symmetry_diagonal.len()
    );
    // The named points on the axis, as in the quarter.
    for n in [
        m.points.centre,
        m.points.nucleus_bottom,
        m.points.cell_bottom,
    ] {
        assert!(m.symmetry_x.contains(&n));
    }
}

/// All boundary faces of `m` (used by one tetrahedron), outward, in element order.
fn boundary_faces(m: &TetMesh) -> Vec<[usize; 6]> {
    let key = |f: &[usize; 6]| {
        let mut k = [f[0], f[1], f[2]];
        k.sort_unstable();
        k
    };
    let mut count: HashMap<[usize; 3], usize> = HashMap::new();
    let faces = || {
        m.elements
            .iter()
            .flat_map(|el| TET_FACES.map(|lf| lf.map(|k| el[k])))
    };
    for f in faces() {
        *count.entry(key(&f)).or_insert(0) += 1;
    }
    faces().filter(|f| count[&key(f)] == 1).collect()
}

/// Several processes meshing one geometry at once on one cold cache (Slurm array tasks on a
/// shared file system do this): every process gets the mesh, and the cache never holds a
/// half-written file under its final name. A watcher reads the final name over and over
/// (without pause) while they run; whatever it reads must be the whole file the processes
/// leave. (Writing the final name directly, without the rename, fails here: the watcher
/// reads the file while it is being copied.)
#[test]
fn several_processes_on_one_cold_cache_share_one_whole_mesh() {
    const N: usize = 4;
    let root = scratch("cold-cache");
    std::fs::create_dir_all(&root).expect("cache root");
    let case = "cases/fast/push-pull-3d-coarse.ron";
    // Started 0.2 s apart, so that later ones may find the cache being written.
    let children: Vec<_> = (0..N)
        .map(|k| {
            std::thread::sleep(std::time::Duration::from_millis(200 * u64::from(k > 0)));
            std::process::Command::new(env!("CARGO_BIN_EXE_cellsim"))
                .args(["mesh", case])
                .current_dir(env!("CARGO_MANIFEST_DIR"))
                .env("CELLSIM_CACHE", &root)
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .expect("start cellsim mesh")
        })
        .collect();
    // Watch the cache directory until every process has ended.
    let dir = root.join("mesh3d");
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let watcher = {
        let (dir, done) = (dir.clone(), done.clone());
        std::thread::spawn(move || {
            let mut seen: Vec<Vec<u8>> = Vec::new();
            let mut reads = 0usize;
            while !done.load(std::sync::atomic::Ordering::Relaxed) {
                for e in std::fs::read_dir(&dir).into_iter().flatten().flatten() {
                    let name = e.file_name().to_string_lossy().into_owned();
                    if name.ends_with(".msh") {
                        if let Ok(bytes) = std::fs::read(e.path()) {
                            reads += 1;
                            if !seen.contains(&bytes) {
                                seen.push(bytes);
                            }
                        }
                    }
                }
            }
            (seen, reads)
        })
    };
    let outputs: Vec<_> = children
        .into_iter()
        .map(|c| c.wait_with_output().expect("wait"))
        .collect();
    done.store(true, std::sync::atomic::Ordering::Relaxed);
    let (seen, reads) = watcher.join().expect("watcher");
    let mut made = 0;
    for o in &outputs {
        let (stdout, stderr) = (
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr),
        );
        assert!(o.status.success(), "{stdout}\n{stderr}");
        made += usize::from(stdout.contains("made by gmsh"));
    }
    // The same report (the same mesh) in every process; the file line aside.
    let report = |o: &std::process::Output| {
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| !l.starts_with("mesh file "))
            .collect::<Vec<_>>()
            .join("\n")
    };
    for o in &outputs[1..] {
        assert_eq!(report(o), report(&outputs[0]));
    }
    // One mesh and its geometry, nothing temporary left.
    let names = only_geo_and_msh(&dir);
    // Whole: ending as the file left (the same bytes where gmsh runs without address
    // randomization, as here; otherwise another run's whole mesh).
    let whole = std::fs::read(dir.join(&names[1])).expect("mesh");
    let text = String::from_utf8_lossy(&whole);
    let last = text.trim_end().lines().last().expect("a line").to_string();
    assert!(last.starts_with("$End"), "{last}");
    for s in &seen {
        let t = String::from_utf8_lossy(s);
        assert!(
            t.trim_end().ends_with(&last) && s.len() * 10 > whole.len() * 9,
            "a partial mesh file was read ({} of {} bytes)",
            s.len(),
            whole.len()
        );
    }
    println!(
        "{N} processes on a cold cache: {made} ran gmsh, the watcher read the final name \
         {reads} times, always whole"
    );
    assert!(made >= 1, "nobody ran gmsh on a cold cache");
    // A later process reads it from the cache.
    let again = std::process::Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args(["mesh", case])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("CELLSIM_CACHE", &root)
        .output()
        .expect("cellsim mesh");
    assert!(String::from_utf8_lossy(&again.stdout).contains("(from the cache)"));
    assert_eq!(report(&again), report(&outputs[0]));
    let _ = std::fs::remove_dir_all(&root);
}

/// `mesh.h_surface`: the eighth cell's outer surface below the centre gets edges no
/// longer than the cap allows (gmsh's sizes are targets: within 1.5× of them), the rest of
/// the mesh keeps the grading law, the count is estimated before meshing, and without the
/// option the geometry file (and so every cached mesh's key) is what it was.
#[test]
fn a_surface_cap_refines_the_lower_surface_only() {
    let base = TetMeshParams {
        wedge: Wedge::Eighth,
        ..params(1.0)
    };
    let geo = base.geo();
    assert!(geo.contains("Background Field = 1;") && !geo.contains("Field[2]"));
    let capped_params = TetMeshParams {
        h_surface: Some(0.6),
        ..base.clone()
    };
    let geo = capped_params.geo();
    assert!(geo.contains("Field[3] = Min;") && geo.contains("Background Field = 3;"));
    let plain = generate(&base).mesh;
    let capped = generate(&capped_params).mesh;
    let c = base.center;
    // The longest vertex-to-vertex edge of the outer faces whose midpoint lies in the
    // height band `ys` and whose ends are both on the surface.
    let longest = |m: &TetMesh, ys: std::ops::Range<f64>| -> f64 {
        let mut l: f64 = 0.0;
        for f in &m.outer_faces {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                let (p, q) = (m.nodes[f[a]], m.nodes[f[b]]);
                if ys.contains(&(0.5 * (p[1] + q[1]) - c[1])) {
                    l = l.max(norm(sub(p, q)));
                }
            }
        }
        l
    };
    // From the nucleus bottom (where the grading law reaches h_nucleus = 1) to 2 µm below
    // the centre: the cap is 0.6 there, the law 1.0.
    let band = -5.0..-2.0;
    let (l_plain, l_capped) = (longest(&plain, band.clone()), longest(&capped, band));
    assert!(l_plain > 1.0, "{l_plain}");
    assert!(l_capped < 1.5 * 0.6, "{l_capped}");
    // Near the top the cap (0.6 + 0.5 × 9) is far above the law: same sizes.
    let top = 8.0..10.0;
    let (t_plain, t_capped) = (longest(&plain, top.clone()), longest(&capped, top));
    assert!(
        (t_capped / t_plain - 1.0).abs() < 0.3,
        "{t_plain} {t_capped}"
    );
    let (n_plain, n_capped) = (plain.elements.len() as f64, capped.elements.len() as f64);
    assert!(n_capped > 1.1 * n_plain, "{n_plain} {n_capped}");
    for (m, p) in [(&plain, &base), (&capped, &capped_params)] {
        let est = p.estimated_tets();
        let n = m.elements.len() as f64;
        assert!((est / n - 1.0).abs() < 0.25, "estimate {est} vs {n}");
    }
    // The cap's estimate grows as its mesh does.
    let grows = capped_params.estimated_tets() / base.estimated_tets();
    assert!((grows / (n_capped / n_plain) - 1.0).abs() < 0.15, "{grows}");
}
