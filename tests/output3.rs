//! The 3-D cell's outputs (`output::vtu`, `cell3d_views`, `movie`) on the default quarter
//! mesh: the ParaView file read back, the sections' areas against the balls', every figure
//! and the GIF.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use cellsim::case::{self, Case};
use cellsim::fem::element::Lagrange;
use cellsim::fem::tet10::Tet10;
use cellsim::fem::{Domain, TetMesh, TetRule};
use cellsim::physics::{Lattice, LatticeSubstrate, Substrate};
use cellsim::render::cell3d_views::{
    self, Coloring, FIGURE_SIZE, Section, SectionShape, section_figure, surface_figure,
};
use cellsim::render::figures::ShapeStyleOptions;
use cellsim::render::movie::{FRAME_SIZE, MAX_FRAMES, MovieView, QuarterMovie};
use cellsim::render::vtu::{
    GMSH_OF_VTK, QUADRATIC_TETRA, QuarterVtuSeries, read_vtu_grid, write_vtu,
};
use cellsim::run_files::{QuarterMeshFile, QuarterSnapshot};
use cellsim::scene;
use plotters::prelude::*;

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("output3-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("create scratch dir");
    d
}

/// The default quarter mesh
/// (`cellsim::scene::terms::tet_mesh_params(&cellsim::case::Case::reference())`), meshed
/// once.
fn mesh() -> &'static TetMesh {
    static MESH: OnceLock<TetMesh> = OnceLock::new();
    MESH.get_or_init(|| {
        TetMesh::generate(&cellsim::scene::terms::tet_mesh_params(
            &cellsim::case::Case::reference(),
        ))
        .expect("the default mesh")
    })
}

/// The mesh file of the default mesh over MODEL.md's pillars on `lattice` (tops placed
/// for the 0.5 µm gap in 3-D), with both active regions and the fibronectin layer.
fn mesh_file(lattice: Lattice) -> QuarterMeshFile {
    let m = mesh();
    let mut c = Case::reference_active();
    c.substrate = case::Substrate::pillars();
    let mut p = scene::model_params(&c, "pillars-3d", false).expect("a valid case");
    if let Substrate::Pillars(pl) = &mut p.substrate {
        let c3 = [p.center[0], p.center[1], 0.0];
        pl.y_top = pl
            .y_top_for_gap_on_lattice(0.5, lattice, c3, 10.0)
            .expect("placed");
    }
    QuarterMeshFile {
        nodes: m.nodes.clone(),
        elements: m.elements.clone(),
        domains: m.domains.clone(),
        outer_faces: m.outer_faces.clone(),
        substrate: LatticeSubstrate {
            plane: p.substrate,
            lattice,
        },
        active: p.active,
        contact_eps: p.contact.eps,
        layer_thickness: p.adhesion.map(|a| a.e_f),
        center: [p.center[0], p.center[1], 0.0],
        phase_times: [10_000.0, 40_000.0, 50_000.0, 50_000.0],
    }
}

/// A smooth deformation keeping the symmetry planes (u_x = 0 on x = 0, u_z = 0 on z = 0),
/// scaled by `w`: the cell sinks and its bottom spreads; made-up element values.
fn snapshot(mesh: &QuarterMeshFile, w: f64, t: f64) -> QuarterSnapshot {
    let c = mesh.center;
    let u: Vec<[f64; 3]> = mesh
        .nodes
        .iter()
        .map(|x| {
            let low = (-(x[1] - c[1] + 10.0).powi(2) / 18.0).exp();
            [
                w * 0.08 * low * (x[0] - c[0]),
                -w * (0.5 + 0.8 * low),
                w * 0.08 * low * (x[2] - c[2]),
            ]
        })
        .collect();
    let n = u.len();
    let ne = mesh.elements.len();
    QuarterSnapshot {
        t,
        v: u.iter().map(|d| d.map(|v| 1e-3 * v)).collect(),
        mu_as: (0..n).map(|i| (i % 3 == 0).then_some(i as f64)).collect(),
        element_strain: (0..ne).map(|e| w * 0.3 * (e % 7) as f64 / 7.0).collect(),
        element_jacobian: (0..ne).map(|e| 1.0 - 0.01 * (e % 5) as f64).collect(),
        u,
    }
}

/// VTK's quadratic tetrahedron: shape functions in VTK's node order (vertices, then the
/// mid-nodes of (0,1), (1,2), (2,0), (0,3), (1,3), (2,3)) and their gradients, written out
/// from VTK's definition, independently of `fem::tet10`.
const VTK_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]];

fn vtk_volume(x: &[[f64; 3]]) -> (f64, f64) {
    let rule = TetRule::degree(4);
    let (mut vol, mut min_det) = (0.0, f64::INFINITY);
    for (xi, w) in rule.points.iter().zip(&rule.weights) {
        let l = [1.0 - xi[0] - xi[1] - xi[2], xi[0], xi[1], xi[2]];
        // ∂λ/∂ξ
        let dl = [
            [-1.0, -1.0, -1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let mut grads = [[0.0; 3]; 10];
        for i in 0..4 {
            for k in 0..3 {
                grads[i][k] = (4.0 * l[i] - 1.0) * dl[i][k];
            }
        }
        for (e, [i, j]) in VTK_EDGES.iter().enumerate() {
            for k in 0..3 {
                grads[4 + e][k] = 4.0 * (dl[*i][k] * l[*j] + l[*i] * dl[*j][k]);
            }
        }
        let mut jac = nalgebra::Matrix3::<f64>::zeros();
        for a in 0..10 {
            for r in 0..3 {
                for k in 0..3 {
                    jac[(r, k)] += x[a][r] * grads[a][k];
                }
            }
        }
        let det = jac.determinant();
        min_det = min_det.min(det);
        vol += w * det;
    }
    (vol, min_det)
}

#[test]
fn vtu3_reads_back_with_quadratic_tetrahedra_in_vtk_order() {
    let mf = mesh_file(Lattice::FourPillars);
    let s = snapshot(&mf, 1.0, 5_000.0);
    let d = scratch("vtu");
    let p = d.join("cell.vtu");
    write_vtu(&p, &mf, &s).expect("write vtu");
    let g = read_vtu_grid(&p).expect("read vtu");
    let v = &g.summary;
    assert_eq!(v.points, mf.nodes.len());
    assert_eq!(v.cells, mf.elements.len());
    assert!(v.cell_types.iter().all(|&t| t == QUADRATIC_TETRA));
    // The 2-D file's names, so ParaView states carry over.
    assert_eq!(v.point_arrays, ["displacement", "velocity", "mu_as"]);
    assert_eq!(v.cell_arrays, ["domain", "mean_E_norm", "det_F"]);
    let disp = v.displacement.as_ref().expect("displacement array");
    for (i, u) in s.u.iter().enumerate() {
        assert_eq!([disp[3 * i], disp[3 * i + 1], disp[3 * i + 2]], *u);
    }
    assert_eq!(g.points, mf.nodes);
    // Every cell: VTK's node order of the element, a positive VTK volume equal to the
    // element's own (gmsh order, fem::tet10), each mid-node nearest to the midpoint of
    // VTK's edge of its index.
    let rule = TetRule::degree(4);
    let (mut total_vtk, mut total) = (0.0, 0.0);
    for (cell, el) in g.cells.iter().zip(&mf.elements) {
        assert_eq!(cell.len(), 10);
        let expected: Vec<usize> = GMSH_OF_VTK.iter().map(|&a| el[a]).collect();
        assert_eq!(*cell, expected);
        let x: Vec<[f64; 3]> = cell.iter().map(|&i| g.points[i]).collect();
        let (vol, min_det) = vtk_volume(&x);
        assert!(min_det > 0.0, "cell {cell:?}: VTK det J {min_det:e}");
        let xe = el.map(|i| mf.nodes[i]);
        let own: f64 = rule
            .points
            .iter()
            .zip(&rule.weights)
            .map(|(xi, w)| w * Tet10::map(&xe, *xi).2)
            .sum();
        assert!(
            (vol - own).abs() < 1e-12 * own,
            "VTK volume {vol} against {own}"
        );
        total_vtk += vol;
        total += own;
        for (k, [i, j]) in VTK_EDGES.iter().enumerate() {
            let dist = |e: &[usize; 2]| {
                let m = [0, 1, 2].map(|c| 0.5 * (x[e[0]][c] + x[e[1]][c]));
                (0..3).map(|c| (x[4 + k][c] - m[c]).powi(2)).sum::<f64>()
            };
            let own = dist(&[*i, *j]);
            assert!(
                VTK_EDGES.iter().all(|e| dist(e) >= own),
                "mid-node {k} is not on VTK's edge ({i}, {j})"
            );
        }
    }
    let ball = 4.0 / 3.0 * PI * 1000.0 / 4.0;
    assert!(
        (total_vtk - ball).abs() < 2e-3 * ball,
        "quarter volume {total_vtk} ({total}) against {ball}"
    );

    // A snapshot that does not fit the mesh is refused, naming the file.
    let mut bad = s.clone();
    bad.element_strain.pop();
    let e = write_vtu(&d.join("bad.vtu"), &mf, &bad).expect_err("short snapshot");
    assert!(e.to_string().contains("bad.vtu"), "{e}");
}

#[test]
fn vtu3_series_writes_a_collection() {
    let mf = mesh_file(Lattice::Gap);
    let d = scratch("pvd");
    let mut series = QuarterVtuSeries::new(&d, "cell3", &mf).expect("series");
    for k in 0..3 {
        series
            .write(&snapshot(&mf, k as f64 / 2.0, 1000.0 * k as f64))
            .expect("write");
    }
    let pvd = std::fs::read_to_string(series.pvd_path()).expect("pvd");
    assert_eq!(pvd.matches("<DataSet ").count(), 3);
    for k in 0..3 {
        let f = format!("vtu/cell3_{k:05}.vtu");
        assert!(pvd.contains(&f), "{pvd}");
        assert!(d.join(&f).exists());
    }
    assert!(pvd.contains("timestep=\"2e3\""), "{pvd}");
}

/// The reference radii of the default cell.
const RADII: [f64; 3] = [5.0, 9.75, 10.0];

/// The section of the undeformed cell by `plane`, mirrored, has the areas of the full disks
/// of the three balls (the plane passes through the centre), to `tol` relative.
fn section_areas_are_the_disks(plane: Section, tol: [f64; 3]) {
    let mf = mesh_file(Lattice::FourPillars);
    let zero = vec![[0.0; 3]; mf.nodes.len()];
    let half = SectionShape::new(&mf, &zero, plane);
    let full = half.mirrored();
    let [r_n, r_cp, r_c] = RADII;
    let exact = [
        PI * r_n * r_n,
        PI * (r_cp * r_cp - r_n * r_n),
        PI * (r_c * r_c - r_cp * r_cp),
    ];
    for (k, d) in Domain::ALL.into_iter().enumerate() {
        let a = full.area(d);
        assert!(
            (full.area(d) - 2.0 * half.area(d)).abs() < 1e-9 * a,
            "the mirror doubles the area"
        );
        let rel = (a - exact[k]) / exact[k];
        eprintln!(
            "section {}: {d} area {a:.5} µm² against {:.5} ({rel:+.2e})",
            plane.name(),
            exact[k]
        );
        assert!(
            rel.abs() < tol[k],
            "{d}: {a} against {} ({rel:e})",
            exact[k]
        );
    }
    // Nothing outside the ball r_c, and the ball's extent is reached.
    let b = full.bounds();
    let c = mf.center;
    assert!(b.x_max <= r_c + 1e-9 && b.x_min >= -r_c - 1e-9, "{b:?}");
    assert!(
        (b.x_max - r_c).abs() < 5e-3 && (b.y_min - (c[1] - r_c)).abs() < 5e-3,
        "{b:?}"
    );
    // The active outlines: PAC between the nucleus and the outer ellipse (semi-axes 7.5
    // and 7 µm), above θ = −18°; the bottom region's below θ = −35° (both ±ε_a).
    let at = |p: &[f64; 2]| (p[0], p[1] - c[1]);
    assert!(!full.cell.pac.is_empty() && !full.cell.bottom.is_empty());
    for p in full.cell.pac.iter().flatten() {
        let (h, y) = at(p);
        let r = (h * h + y * y).sqrt();
        assert!(r > r_n - 0.05, "PAC point {p:?} inside the nucleus");
        assert!(
            (h / 7.5).powi(2) + (y / 7.0).powi(2) < 1.08,
            "PAC point {p:?}"
        );
        assert!(y > -r * (18f64 + 3.0).to_radians().sin(), "PAC point {p:?}");
    }
    for p in full.cell.bottom.iter().flatten() {
        let (h, y) = at(p);
        let r = (h * h + y * y).sqrt();
        assert!(r > r_n - 0.05 && r < r_c + 0.05, "bottom point {p:?}");
        assert!(
            y < -r * (35f64 - 3.0).to_radians().sin(),
            "bottom point {p:?}"
        );
    }
    // The markers p_t, c, p_b on the axis.
    assert_eq!(full.cell.markers.len(), 3);
    for (m, y) in full.cell.markers.iter().zip([c[1] + r_n, c[1], c[1] - r_n]) {
        assert!(m[0].abs() < 1e-9 && (m[1] - y).abs() < 1e-9, "{m:?}");
    }
}

#[test]
fn section_z0_of_the_reference_cell_has_the_disks_areas() {
    section_areas_are_the_disks(Section::Z0, [2e-4, 5e-5, 1e-4]);
}

#[test]
fn diagonal_section_of_the_reference_cell_has_the_disks_areas() {
    section_areas_are_the_disks(Section::Diagonal, [2e-4, 5e-5, 1e-4]);
}

#[test]
fn sections_follow_the_deformation() {
    // A rigid translation moves the section with it: down by 1 µm in both planes; along
    // (1, 0, 1) by a µm, the diagonal section by √2 a sideways (the half section; z = 0
    // sees a). Areas unchanged.
    let mf = mesh_file(Lattice::Gap);
    let n = mf.nodes.len();
    for plane in Section::ALL {
        let zero = SectionShape::new(&mf, &vec![[0.0; 3]; n], plane);
        let down = SectionShape::new(&mf, &vec![[0.0, -1.0, 0.0]; n], plane);
        let side = SectionShape::new(&mf, &vec![[0.3, 0.0, 0.3]; n], plane);
        let (b0, b1, b2) = (zero.bounds(), down.bounds(), side.bounds());
        let shift = match plane {
            Section::Z0 => 0.3,
            Section::Diagonal => 0.3 * 2f64.sqrt(),
        };
        assert!((b1.y_min - (b0.y_min - 1.0)).abs() < 1e-9, "{b0:?} {b1:?}");
        assert!((b1.y_max - (b0.y_max - 1.0)).abs() < 1e-9, "{b0:?} {b1:?}");
        assert!(
            (b2.x_max - (b0.x_max + shift)).abs() < 1e-9,
            "{b0:?} {b2:?}"
        );
        for d in Domain::ALL {
            assert!((down.area(d) - zero.area(d)).abs() < 1e-9 * zero.area(d));
        }
    }
}

/// Checks a PNG's size and that it is not blank (more than `min_frac` of its pixels not
/// white); returns its pixels.
fn check_png(path: &Path, size: (u32, u32), min_frac: f64) -> Vec<[u8; 3]> {
    let meta = std::fs::metadata(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    assert!(
        meta.len() > 10_000,
        "{}: {} bytes",
        path.display(),
        meta.len()
    );
    let img = image::open(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .to_rgb8();
    assert_eq!(img.dimensions(), size, "{}", path.display());
    let px: Vec<[u8; 3]> = img.pixels().map(|p| p.0).collect();
    let inked = px.iter().filter(|p| **p != [255, 255, 255]).count();
    assert!(
        inked as f64 > min_frac * px.len() as f64,
        "{}: almost blank ({inked} non-white pixels)",
        path.display()
    );
    px
}

fn count(px: &[[u8; 3]], c: RGBColor) -> usize {
    px.iter().filter(|p| **p == [c.0, c.1, c.2]).count()
}

#[test]
fn section_figures_draw_the_cell_and_the_substrate() {
    use cellsim::render::figures::{CYTOPLASM, MEMBRANE, NUCLEUS, SUBSTRATE};
    let d = scratch("sections");
    for lattice in [Lattice::FourPillars, Lattice::Gap] {
        let mf = mesh_file(lattice);
        let s = snapshot(&mf, 1.0, 10_000.0);
        for plane in Section::ALL {
            let p = d.join(format!("{lattice:?}-{}.png", plane.tag()));
            section_figure(&p, &mf, &s, plane, "a section").expect("section figure");
            let px = check_png(&p, FIGURE_SIZE, 0.3);
            // Each domain filled (the nucleus most), the substrate below.
            let (n, c, m) = (
                count(&px, NUCLEUS),
                count(&px, CYTOPLASM),
                count(&px, MEMBRANE),
            );
            assert!(
                n > 20_000 && c > n && m > 1_000,
                "{}: {n} {c} {m}",
                p.display()
            );
            assert!(count(&px, SUBSTRATE) > 20_000, "{}", p.display());
        }
    }
    // Equal scales: 1 µm has the same length on both axes.
    let mf = mesh_file(Lattice::FourPillars);
    let s = snapshot(&mf, 1.0, 10_000.0);
    let (w, h) = (900u32, 700u32);
    let mut buf = vec![0u8; 3 * (w * h) as usize];
    let area = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
    let view = cell3d_views::section_view(&mf, &[&s], Section::Diagonal);
    let opts = ShapeStyleOptions {
        title: "scale".into(),
        legend: false,
        font: 20,
        mesh_lines: false,
        gravity: None,
    };
    let scale =
        cell3d_views::draw_section(&area, &mf, &s.u, Section::Diagonal, view, &opts, &mut None)
            .expect("draw");
    assert!(
        (scale.px_per_um_x - scale.px_per_um_y).abs() < 0.11,
        "{scale:?}"
    );
}

#[test]
fn surface_figures_show_the_shaded_cell_on_its_pillars() {
    let d = scratch("surface");
    for lattice in [Lattice::FourPillars, Lattice::Gap] {
        let mf = mesh_file(lattice);
        let s = snapshot(&mf, 1.0, 10_000.0);
        for coloring in [Coloring::Domain, Coloring::Strain] {
            let p = d.join(format!("{lattice:?}-{coloring:?}.png"));
            surface_figure(&p, &mf, &s, coloring, "the cell").expect("surface figure");
            let px = check_png(&p, FIGURE_SIZE, 0.15);
            // Grey substrate (r = g = b) and the cell: shaded membrane green, or the strain
            // colours (the low end of viridis is violet), not both. Thresholds: half of
            // what the figures show (the strain figure's view from above is half as wide).
            let grey = px
                .iter()
                .filter(|p| p[0] == p[1] && p[1] == p[2] && p[0] < 250 && p[0] > 40)
                .count();
            let green = px
                .iter()
                .filter(|p| p[1] as i32 > p[0] as i32 + 30 && p[1] as i32 > p[2] as i32 + 30)
                .count();
            let violet = px
                .iter()
                .filter(|p| p[2] as i32 > p[1] as i32 + 20 && p[0] as i32 > p[1] as i32)
                .count();
            let what = format!(
                "{}: {grey} grey, {green} green, {violet} violet",
                p.display()
            );
            match coloring {
                Coloring::Domain => {
                    assert!(grey > 100_000 && green > 80_000 && violet == 0, "{what}")
                }
                Coloring::Strain => assert!(grey > 30_000 && violet > 25_000, "{what}"),
            }
        }
    }
}

#[test]
fn movie3_has_one_frame_per_offered_state() {
    let mf = mesh_file(Lattice::FourPillars);
    let d = scratch("movie");
    for (view, name) in [
        (MovieView::Section(Section::Z0), "section"),
        (MovieView::Section(Section::Diagonal), "diagonal"),
        (MovieView::Surface(Coloring::Domain), "surface"),
    ] {
        let p = d.join(format!("{name}.gif"));
        let n = 4;
        let mut m = QuarterMovie::with_view(&p, "cell", &mf, n, view).expect("movie");
        for k in 0..n {
            let w = k as f64 / (n - 1) as f64;
            m.frame(&snapshot(&mf, w, 10_000.0 * w)).expect("frame");
        }
        assert_eq!(m.frames(), n);
        m.finish().expect("finish");
        let dec = gif::DecodeOptions::new()
            .read_info(std::fs::File::open(&p).expect("open"))
            .expect("gif header");
        assert_eq!(
            (dec.width(), dec.height()),
            (FRAME_SIZE.0 as u16, FRAME_SIZE.1 as u16)
        );
        assert_eq!(gif_frames(&p), n, "{name}");
    }
    // The default movie (the section z = 0) with more outputs announced than MAX_FRAMES:
    // every third state, and the last one offered although skipped.
    let p = d.join("default.gif");
    let mut m = QuarterMovie::new(&p, "cell", &mf, 3 * MAX_FRAMES).expect("movie");
    for k in 0..5 {
        m.frame(&snapshot(&mf, k as f64 / 4.0, 1000.0 * k as f64))
            .expect("frame");
    }
    assert_eq!(m.frames(), 2);
    m.finish().expect("finish");
    assert_eq!(gif_frames(&p), 3);
}

fn gif_frames(p: &Path) -> usize {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::Indexed);
    let mut dec = opts
        .read_info(std::fs::File::open(p).expect("open"))
        .expect("gif header");
    let mut frames = 0;
    while dec.read_next_frame().expect("frame").is_some() {
        frames += 1;
    }
    frames
}
