//! The 3-D quarter cell (MODEL.md §10): its Jacobian against finite differences of its
//! residual, the patch test on curved ten-node tetrahedra across the material interfaces,
//! the weight and the contact force at rest, and the slab check against plane strain.

use cellsim::case::{self, Case};
use cellsim::dae::State;
use cellsim::dae::{Atol, Dae, Integrator};
use cellsim::fem::tet10::{TET_FACES, face_map};
use cellsim::fem::{
    Domain, Lagrange, Mesh, MeshParams, TetMesh, TetMeshParams, TriangleRule, Wedge,
};
use cellsim::model::{CellModel, ModelParams};
use cellsim::model::{Constraints, QuarterCell};
use cellsim::physics::{KinematicModel, Lattice, Substrate, Viscosity, Yeoh, piola_total_full};
use cellsim::scene;
use cellsim::solver::LinearSolver;
use cellsim::sundials::{Ida, IdaOptions};
use nalgebra::{Matrix3, Vector3};

/// The quarter cell's mesh at the given sizes (µm) for the reference cell.
pub fn quarter_mesh(h_bottom: f64, h_nucleus: f64) -> TetMesh {
    wedge_mesh(h_bottom, h_nucleus, Wedge::Quarter)
}

/// The mesh of `wedge` at the given sizes (µm) for the reference cell.
pub fn wedge_mesh(h_bottom: f64, h_nucleus: f64, wedge: Wedge) -> TetMesh {
    let g = Case::reference().geometry;
    let c = g.centre();
    TetMesh::generate(&TetMeshParams {
        center: [c[0], c[1], 0.0],
        wedge,
        r_n: g.r_n,
        r_cp: g.r_cp,
        r_c: g.r_c,
        h_bottom,
        h_nucleus,
        refine: 1.0,
        h_surface: None,
    })
    .expect("the cell meshes")
}

/// A coarse quarter cell (fast tests).
pub fn coarse_quarter() -> TetMesh {
    quarter_mesh(0.6, 1.5)
}

/// A coarse eighth cell (fast tests).
pub fn coarse_eighth() -> TetMesh {
    wedge_mesh(0.6, 1.5, Wedge::Eighth)
}

/// The parameters of a half-plane case made the 3-D cell's (over four pillars).
fn quarter_params(plane: ModelParams) -> ModelParams {
    ModelParams {
        kinematics: KinematicModel::ThreeD,
        lattice: Lattice::FourPillars,
        ..plane
    }
}

use crate::fd::deformed_state;

/// Smallest finite-difference step on an exposure A (~1e3); [`crate::fd::jacobian_fd_error`]
/// also tries 10× and 100× it.
const MU_STEP: f64 = 1e-1;

#[test]
fn jacobian_of_the_quarter_cell_without_inertia_matches_finite_differences() {
    check_quarter_jacobian(false, Lattice::Gap, &coarse_quarter());
}

#[test]
fn jacobian_of_the_quarter_cell_with_fibres_matches_finite_differences() {
    // The cytoplasm's fibres (MODEL.md §11) at k₁ = 1000 Pa, written once for every
    // kinematics: in 3-D along the meridian tangent T and the radial N.
    check_quarter_jacobian_of(false, Lattice::FourPillars, &coarse_quarter(), 1000.0);
}

#[test]
fn jacobian_of_the_quarter_cell_with_inertia_matches_finite_differences() {
    check_quarter_jacobian(true, Lattice::FourPillars, &coarse_quarter());
}

#[test]
fn jacobian_of_the_eighth_cell_matches_finite_differences() {
    // What the eighth adds to the quarter's kernels is the tie on the diagonal plane: all of
    // its columns, and fewer of the others (the quarter's tests cover those).
    check_quarter_jacobian(true, Lattice::FourPillars, &coarse_eighth());
}

/// Pillars (the cell above the centre of four, or above the gap between two), contact,
/// adhesion with its exposure unknowns and both active regions, with inertia or without
/// (medium drag): every block of J. t in the active phase, the cell sunk 0.5 µm into the
/// bands. On the eighth cell, whose nodes on the diagonal plane carry one unknown for
/// u_x = u_z, the u and v unknowns of every such node in the lower half are columns.
fn check_quarter_jacobian(inertia: bool, lattice: Lattice, mesh: &TetMesh) {
    check_quarter_jacobian_of(inertia, lattice, mesh, 0.0)
}

/// [`check_quarter_jacobian`] with the cytoplasm's fibres at `k1_pa` (none at 0).
fn check_quarter_jacobian_of(inertia: bool, lattice: Lattice, mesh: &TetMesh, k1_pa: f64) {
    let wedge = mesh.params.wedge;
    let eighth = wedge == Wedge::Eighth;
    let mut c = Case::reference_active();
    c.substrate = case::Substrate::pillars();
    if k1_pa > 0.0 {
        crate::model::with_fibres(&mut c, k1_pa);
    }
    let mut p = scene::model_params(&c, "pillars-3d", inertia).expect("a valid case");
    p.drag = if inertia { 0.0 } else { 1e-3 };
    // The pillar tops 0.5 µm below the cell's lowest point over them, in 3-D.
    if let Substrate::Pillars(pl) = &mut p.substrate {
        let c3 = [p.center[0], p.center[1], 0.0];
        pl.y_top = pl
            .y_top_for_gap_on_lattice(0.5, lattice, c3, 10.0)
            .expect("placed");
    }
    let mut m = QuarterCell::new(
        ModelParams {
            lattice,
            ..quarter_params(p)
        },
        mesh.clone(),
    )
    .unwrap();
    let (y, yp) = deformed_state(&m, 0.5, 7);
    let t = 45_000.0;
    let f = m.contact_force_total(&y);
    assert!(f.y > 1e-3, "no contact in the test state (force {f:?})");
    // 60 random columns and every unknown of 40 of the lowest nodes (in contact), exposures
    // included; with inertia, whose velocity columns add a block each node's u columns
    // already exercise the contact of, 20 of the lowest nodes (the quarter without inertia
    // takes the 40); on the eighth 20 and 10, and the u and v of the 40 lowest nodes of the
    // diagonal plane (the tie is in u and v; μ_as is one unknown per node either way).
    let (random, lowest) = match (eighth, inertia) {
        (true, _) => (20, 10),
        (false, true) => (60, 20),
        (false, false) => (60, 40),
    };
    let mut cols = crate::fd::contact_columns(&m, random, Some(lowest));
    let mut diagonal = m.mesh.symmetry_diagonal.clone();
    diagonal.sort_by(|&a, &b| m.mesh.nodes[a][1].total_cmp(&m.mesh.nodes[b][1]));
    for &i in diagonal.iter().take(40) {
        assert_eq!(m.dofs.u[i][0], m.dofs.u[i][2], "u_z is u_x on the diagonal");
        cols.extend(m.dofs.u[i].iter().chain(&m.dofs.v[i]));
    }
    cols.retain(|&c| c != usize::MAX);
    assert_eq!(m.mesh.symmetry_diagonal.is_empty(), wedge == Wedge::Quarter);
    let (off, cjs) = (m.dofs.mu_offset(), [0.0, 37.0]);
    let errs = crate::fd::jacobian_fd_error(&mut m, off, MU_STEP, t, &y, &yp, &cjs, &cols);
    for (cj, (err, j)) in cjs.into_iter().zip(errs) {
        let node = (0..m.mesh.nodes.len())
            .find(|&i| m.dofs.u[i].contains(&j) || m.dofs.v[i].contains(&j) || m.dofs.mu[i] == j);
        assert!(
            err < 1e-6,
            "{wedge:?}, {lattice:?}, inertia {inertia}, cj {cj}: relative column error {err:.2e} \
             (column {j}, node {node:?} at {:?})",
            node.map(|i| m.mesh.nodes[i])
        );
    }
}

/// Parameters with every load switched off: the residual at rest is the internal force.
fn unloaded(solids: [Yeoh; 3]) -> ModelParams {
    let mut p = scene::reference_params();
    p.gravity = 0.0;
    p.substrate = Substrate::Flat { y_s: -100.0 };
    p.adhesion = None;
    p.viscosity = Viscosity {
        lambda_f: 0.0,
        mu_f: 0.0,
    };
    p.inertia = false;
    p.solids = solids;
    p
}

#[test]
fn patch_test_homogeneous_deformation_gives_exact_internal_forces() {
    // u = (F₀ − I)(X − c) with an F₀ that keeps u_x = 0 on x = 0 and u_z = 0 on z = 0,
    // three different solids: the internal force of every node equals the surface
    // integral Σ over the faces of its elements of ∮ Nₐ P n dS (P constant per domain),
    // evaluated on the faces' own P2 geometry by a degree-8 triangle rule: interior faces
    // cancel, the boundary and the two interfaces remain. Independent of the volume
    // quadrature and of the gradients of the element assembly.
    let solids = [
        Yeoh::from_engineering(500.0, 0.485, 0.1, 0.2).unwrap(),
        Yeoh::from_engineering(100.0, 0.3, 0.1, 0.2).unwrap(),
        Yeoh::from_engineering(250.0, 0.45, 0.5, 0.1).unwrap(),
    ];
    let params = unloaded(solids);
    let visc = params.viscosity;
    let mut m = QuarterCell::new(quarter_params(params), coarse_quarter()).unwrap();
    let f0 = Matrix3::new(1.08, 0.0, 0.0, -0.06, 0.93, 0.04, 0.0, 0.0, 1.05);
    let c = Vector3::new(m.params.center[0], m.params.center[1], 0.0);
    let mut y = vec![0.0; m.size()];
    for (i, x) in m.mesh.nodes.iter().enumerate() {
        let d = (f0 - Matrix3::identity()) * (Vector3::from(*x) - c);
        for k in 0..3 {
            if m.dofs.u[i][k] != usize::MAX {
                y[m.dofs.u[i][k]] = d[k];
            }
        }
    }
    let yp = vec![0.0; m.size()];
    let mut r = vec![0.0; m.size()];
    m.residual(State::new(1.0, &y, &yp), &mut r).unwrap();
    let zero = Matrix3::zeros();
    let stress = |d: Domain| {
        let k = match d {
            Domain::Nucleus => 0,
            Domain::Cytoplasm => 1,
            Domain::Membrane => 2,
        };
        piola_total_full(&solids[k], &visc, &f0, &zero, &Matrix3::identity())
    };
    let rule = TriangleRule::degree(8);
    let mesh = &m.mesh;
    let mut exact = vec![[0.0; 3]; mesh.nodes.len()];
    for (el, &dom) in mesh.elements.iter().zip(&mesh.domains) {
        let p = stress(dom);
        let centroid: Vector3<f64> = (0..4)
            .map(|a| Vector3::from(mesh.nodes[el[a]]))
            .sum::<Vector3<f64>>()
            / 4.0;
        for face in TET_FACES {
            let nodes = face.map(|a| el[a]);
            let x = nodes.map(|i| mesh.nodes[i]);
            // Outward: the normal points away from the element's centroid.
            let (p0, n0) = face_map(&x, [1.0 / 3.0, 1.0 / 3.0]);
            let sign = if Vector3::from(n0).dot(&(Vector3::from(p0) - centroid)) > 0.0 {
                1.0
            } else {
                -1.0
            };
            for (xi, w) in rule.points.iter().zip(&rule.weights) {
                let (_, nda) = face_map(&x, *xi);
                let t = p * Vector3::from(nda) * sign;
                let nv = cellsim::fem::Tri6::shape(*xi);
                for a in 0..6 {
                    for k in 0..3 {
                        exact[nodes[a]][k] += w * nv[a] * t[k];
                    }
                }
            }
        }
    }
    let (mut err, mut scale): (f64, f64) = (0.0, 0.0);
    for (i, fe) in exact.iter().enumerate() {
        for k in 0..3 {
            let d = m.dofs.momentum_rows(i)[k];
            if d != usize::MAX {
                err = err.max((r[d] - fe[k]).abs());
                scale = scale.max(fe[k].abs());
            }
        }
    }
    assert!(scale > 0.0);
    assert!(
        err < 1e-10 * scale,
        "relative nodal force error {:.2e}",
        err / scale
    );
}

#[test]
fn weight_and_volumes_of_the_quarter_and_the_eighth_cell() {
    // The quarter (the eighth) of the ball's volume and weight, from the elements' mass,
    // to the P2 geometry's error.
    for (mesh, share) in [(coarse_quarter(), 0.25), (coarse_eighth(), 0.125)] {
        weight_and_volumes(mesh, share);
    }
}

fn weight_and_volumes(mesh: TetMesh, share: f64) {
    let m = QuarterCell::new(quarter_params(scene::reference_params()), mesh).unwrap();
    let g = Case::reference().geometry;
    let ball = |r: f64| share * 4.0 * std::f64::consts::PI * r.powi(3) / 3.0;
    let v = m.volume(None);
    assert!(
        (v / ball(g.r_c) - 1.0).abs() < 1e-3,
        "volume {v} against {}",
        ball(g.r_c)
    );
    let vn = m.volume(Some(Domain::Nucleus));
    assert!((vn / ball(g.r_n) - 1.0).abs() < 1e-3, "nucleus {vn}");
    let rho = m.params.densities;
    let domains = [Domain::Nucleus, Domain::Cytoplasm, Domain::Membrane];
    let weight = m.weight();
    let expected = m.params.gravity
        * domains
            .iter()
            .zip(rho)
            .map(|(&d, r)| r * m.volume(Some(d)))
            .sum::<f64>();
    assert!(
        (weight / expected - 1.0).abs() < 1e-12,
        "weight {weight} against {expected}"
    );
}

/// The flat scene's gravity phase quasi-statically (no inertia, medium drag while the
/// cell sinks onto the contact), ended at `t_end`.
fn quasi_static_flat(t_end: f64) -> ModelParams {
    let mut c = Case::reference();
    c.phases.t_g0 = 100.0;
    c.phases.t_as0 = 200.0;
    c.phases.t_a0 = 300.0;
    c.phases.t_end = t_end;
    c.adhesion = None;
    c.inertia.mode = case::InertiaMode::Off;
    c.inertia.drag = 1e-6;
    c.validate().expect("a valid case");
    scene::model_params(&c, "quasi-static", false).expect("a valid case")
}

/// IDA on `m` to `t` at rtol 1e-5 with the sparse LU `lu`.
fn ida_to<D: Dae>(m: D, atol: Vec<f64>, t: f64, lu: LinearSolver) -> Ida<D> {
    let mut ida = Ida::new(
        m,
        IdaOptions {
            rtol: 1e-5,
            atol: Atol::Vector(atol),
            linear_solver: std::sync::Arc::new(lu),
            ..Default::default()
        },
    )
    .unwrap();
    ida.advance_to(t, &mut |_, _| true).unwrap();
    ida
}

#[test]
fn flat_gravity_phase_of_the_quarter_cell_agrees_with_the_axisymmetric_model() {
    flat_gravity_phase_against_the_axisymmetric_model(coarse_quarter());
}

#[test]
fn flat_gravity_phase_of_the_eighth_cell_agrees_with_the_axisymmetric_model() {
    flat_gravity_phase_against_the_axisymmetric_model(coarse_eighth());
}

fn flat_gravity_phase_against_the_axisymmetric_model(mesh: TetMesh) {
    // MODEL.md §10 check (2): the ball settled under its weight on the flat substrate, in
    // the 3-D quarter cell and in the axisymmetric model, quasi-statically (gravity ramped
    // over 100 s, medium drag, no inertia). At rest the integrated contact force balances
    // the quarter cell's weight (the discrete equilibrium, whatever the band rule), and
    // u_y(p_t) and the contact radius agree with the axisymmetric model's to 1 %.
    // Measured on this coarse 3-D mesh (3 320 tets) against the default 2-D mesh:
    // u_y(p_t) −0.61832 against −0.61932 µm, contact radius 1.8827 against 1.8854 µm.
    // The eighth cell (0 ≤ z ≤ x, 1 804 tets) within the same 1 %.
    let t_end = 150.0;
    let p = quasi_static_flat(t_end);
    let mut pa = p.clone();
    pa.kinematics = cellsim::physics::KinematicModel::Axisymmetric;
    let mesh2 = Mesh::generate(&cellsim::scene::terms::mesh_params(&Case::reference())).unwrap();
    let ma = CellModel::new(pa, mesh2).unwrap();
    let atola = ma.atol_vector(1e-7);
    let idaa = ida_to(ma, atola, t_end, LinearSolver::Faer);
    let oa = idaa.dae().observe(t_end, idaa.y());
    let wedge = mesh.params.wedge;
    let m3 = QuarterCell::new(quarter_params(p.clone()), mesh).unwrap();
    let atol3 = m3.atol_vector(1e-7);
    let ida3 = ida_to(m3, atol3, t_end, LinearSolver::UmfpackNd);
    let (m3, y3) = (ida3.dae(), ida3.y());
    let (w, f) = (m3.weight(), m3.contact_force_total(y3));
    assert!(
        (f.y - w).abs() < 1e-3 * w,
        "{wedge:?}: contact force {f:?} against weight {w}"
    );
    assert!(f.x.abs() < 1e-6 * w && f.z.abs() < 1e-6 * w, "{f:?}");
    let o3 = m3.observe(t_end, y3);
    eprintln!(
        "3-D {wedge:?}: uy_top {:.5}, contact radius {:.4} (ref {:.4}); axisymmetric: \
         {:.5}, {:.4} ({:.4})",
        o3.uy_top,
        o3.contact_radius,
        o3.contact_radius_ref,
        oa.uy_top,
        oa.contact_radius,
        oa.contact_radius_ref
    );
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(
        rel(o3.uy_top, oa.uy_top) < 0.01,
        "{wedge:?}: uy_top {} against {}",
        o3.uy_top,
        oa.uy_top
    );
    assert!(
        rel(o3.contact_radius, oa.contact_radius) < 0.01,
        "{wedge:?}: contact radius {} against {}",
        o3.contact_radius,
        oa.contact_radius
    );
}

#[test]
fn a_slab_with_u_z_fixed_reproduces_plane_strain() {
    // MODEL.md §10 check (1): the 2-D half cell extruded one layer thick, u_z = 0 on
    // every node, settles under gravity as the plane-strain model does, to the
    // discretisation error between P2 triangles and P2 tetrahedra on the same section.
    // Measured: u_y(p_t) −0.49212 against −0.49187 µm (5e-4), contact radius 1.2217
    // against 1.2197 µm (1.7e-3).
    let mesh2 = Mesh::generate(&MeshParams {
        refine: 0.5,
        ..cellsim::scene::terms::mesh_params(&Case::reference())
    })
    .unwrap();
    let t_end = 150.0;
    let p = quasi_static_flat(t_end);
    let m2 = CellModel::new(p.clone(), mesh2.clone()).unwrap();
    let atol2 = m2.atol_vector(1e-7);
    let ida2 = ida_to(m2, atol2, t_end, LinearSolver::Faer);
    let o2 = ida2.dae().observe(t_end, ida2.y());
    let slab = TetMesh::extruded(&mesh2, 1.0);
    let m3 = QuarterCell::with_constraints(quarter_params(p), slab, Constraints::Slab).unwrap();
    let atol3 = m3.atol_vector(1e-7);
    let ida3 = ida_to(m3, atol3, t_end, LinearSolver::UmfpackNd);
    let o3 = ida3.dae().observe(t_end, ida3.y());
    eprintln!(
        "slab: uy_top {:.6}, contact radius {:.5}; plane strain: {:.6}, {:.5}",
        o3.uy_top, o3.contact_radius, o2.uy_top, o2.contact_radius
    );
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(
        rel(o3.uy_top, o2.uy_top) < 1e-3,
        "uy_top 3-D {} 2-D {}",
        o3.uy_top,
        o2.uy_top
    );
    assert!(
        rel(o3.contact_radius, o2.contact_radius) < 5e-3,
        "contact radius 3-D {} 2-D {}",
        o3.contact_radius,
        o2.contact_radius
    );
}

/// A 3-D case's text (the quarter cell on `substrate`).
fn case3_text(substrate: &str) -> String {
    format!(
        r#"(
    name: "cell-3d",
    geometry: (model: ThreeD),
    substrate: {substrate},
    phases: (t_g0: 10000.0, t_as0: 40000.0, t_a0: 50000.0, t_end: 40000.0),
)"#
    )
}

#[test]
fn pillar_tops_are_placed_over_the_lattice_in_3d() {
    // The same smallest initial gap, 0.5 µm, as in 2-D, but measured under the ball: over
    // the gap lattice the section z = 0 is the 2-D one (y_top −0.30 µm); the cell above
    // the centre of four pillars nests between them, the tops above its lowest point.
    let y_top = |text: &str| match scene::substrate(&Case::from_str(text, "c.ron").unwrap()) {
        Substrate::Pillars(p) => p.y_top,
        Substrate::Flat { .. } => unreachable!("a pillar case"),
    };
    let two_d = y_top(&case3_text("Pillars()").replace("geometry: (model: ThreeD),", ""));
    let gap = y_top(&case3_text("Pillars(lattice: Gap)"));
    let four = y_top(&case3_text("Pillars()"));
    assert!((gap - two_d).abs() < 1e-6, "gap lattice {gap}, 2-D {two_d}");
    assert!((two_d + 0.30).abs() < 0.01, "2-D y_top {two_d}");
    assert!(
        four > -1.5 && (four - 1.80).abs() < 0.01,
        "four pillars: y_top {four}"
    );
}

/// Runs the `cellsim` binary from the crate's directory.
fn cellsim(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

/// The last row of a run's `timeseries.csv` text, by column name.
fn last_row(csv: &str) -> std::collections::HashMap<&str, f64> {
    let header = csv.lines().next().unwrap().split(',');
    let values = csv.lines().last().unwrap().split(',');
    header.zip(values.map(|v| v.parse().unwrap())).collect()
}

#[test]
fn the_cli_meshes_checks_and_runs_a_3d_case() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli-3d");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("cell-3d.ron");
    std::fs::write(&file, case3_text("Pillars(lattice: Gap)")).unwrap();
    let f = file.to_str().unwrap();
    let mesh = cellsim(&["mesh", f]);
    let text = String::from_utf8_lossy(&mesh.stdout);
    assert!(mesh.status.success(), "{text}");
    assert!(text.starts_with("tetrahedra 9660"), "{text}");
    let check = cellsim(&["check", f]);
    let text = String::from_utf8_lossy(&check.stdout);
    assert!(
        text.contains("model: ThreeD") && text.contains("lattice: Gap"),
        "{text}"
    );
    // The default lattice is not written: a 2-D pillar case prints as before.
    std::fs::write(&file, case3_text("Pillars()")).unwrap();
    let text = String::from_utf8_lossy(&cellsim(&["check", f]).stdout).to_string();
    assert!(!text.contains("lattice"), "{text}");

    // The fast 3-D flat scene to 110 s: gravity, then the first 10 s of adhesion.
    let out = dir.join("flat-3d");
    let _ = std::fs::remove_dir_all(&out);
    let o = out.to_str().unwrap();
    let run = cellsim(&[
        "run",
        "cases/fast/flat-3d-coarse.ron",
        "--set",
        "phases.t_end=110.0",
        "--out",
        o,
        "--vtu",
        "--gif",
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(out.join("timeseries.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    // The 2-D columns first, then the 3-D ones.
    let two_d: Vec<&str> = cellsim::run_files::Observables::CSV_HEADER
        .split(',')
        .collect();
    assert_eq!(&header[..two_d.len()], &two_d[..]);
    assert_eq!(
        &header[two_d.len()..],
        &[
            "contact_area",
            "contact_area_ref",
            "contact_radius_equiv",
            "penetration_depth"
        ]
    );
    let last = last_row(&csv);
    assert_eq!(last["t"], 110.0);
    let col = |name: &str| last[name];
    // On the flat substrate the contact patch is a disc: its radius along the meridian
    // and the radius of a disc of its area agree (measured 1.891 and 1.895 µm).
    let (r, r_eq) = (col("contact_radius"), col("contact_radius_equiv"));
    assert!(
        r > 1.0 && (r / r_eq - 1.0).abs() < 0.02,
        "contact radius {r}, equivalent {r_eq}"
    );
    assert_eq!(col("penetration_depth"), 0.0);
    for f in [
        "mesh3.json",
        "state_gravity.json",
        "state_end.json",
        "summary.json",
    ] {
        assert!(out.join(f).exists(), "{f}");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["finished"], true, "{s}");
    assert_eq!(s["mesh_elements"], 3320);
    let state: cellsim::run_files::QuarterStateFile =
        serde_json::from_str(&std::fs::read_to_string(out.join("state_gravity.json")).unwrap())
            .unwrap();
    assert_eq!(state.state.t, 100.0);
    assert_eq!(
        state.state.u.len(),
        s["mesh_nodes"].as_u64().unwrap() as usize
    );
    // ParaView output: one file of quadratic tetrahedra (VTK type 24) per CSV row, all
    // in the collection; the GIF of the section z = 0.
    let rows = csv.lines().count() - 1;
    let vtus: Vec<_> = std::fs::read_dir(out.join("vtu"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    assert_eq!(vtus.len(), rows);
    let pvd = std::fs::read_to_string(out.join("flat-3d-coarse.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet").count(), rows);
    let grid = cellsim::render::vtu::read_vtu(
        &out.join("vtu")
            .join(format!("flat-3d-coarse_{:05}.vtu", rows - 1)),
    )
    .unwrap();
    assert_eq!(grid.cells, 3320);
    assert!(grid.cell_types.iter().all(|&t| t == 24));
    let gif = std::fs::metadata(out.join("flat-3d-coarse.gif"))
        .unwrap()
        .len();
    assert!(gif > 10_000, "GIF of {gif} bytes");
    // `plot` reads the 3-D run back and draws its figures, and beside it the same case
    // in plane strain.
    let out2 = dir.join("flat-2d");
    let o2 = out2.to_str().unwrap();
    let run2 = cellsim(&[
        "run",
        "cases/fast/flat-3d-coarse.ron",
        "--set",
        "phases.t_end=110.0",
        "--set",
        "geometry.model=PlaneStrain",
        "--set",
        "solver.linear_solver=Faer",
        "--out",
        o2,
        "--quiet",
    ]);
    assert!(
        run2.status.success(),
        "{}",
        String::from_utf8_lossy(&run2.stderr)
    );
    let plots = out.join("plots");
    let plot = cellsim(&["plot", o, "--with", o2, "--out", plots.to_str().unwrap()]);
    assert!(
        plot.status.success(),
        "{}",
        String::from_utf8_lossy(&plot.stderr)
    );
    let listed = String::from_utf8_lossy(&plot.stdout).to_string();
    for f in [
        "contact-radius.png",
        "contact-3d.png",
        "shape-gravity-z0.png",
        "shape-gravity-diagonal.png",
        "surface-gravity.png",
        "surface-gravity-strain.png",
        "compare-contact-radius.png",
        "compare-displacement.png",
    ] {
        assert!(
            plots.join(f).exists() && listed.contains(f),
            "{f}: {listed}"
        );
    }
    assert!(
        !plots.join("penetration.png").exists(),
        "no pillars, no penetration plot"
    );
    let _ = std::fs::remove_dir_all(&out2);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn deferred_exposures_leave_the_same_cell_and_join_consistently() {
    // Before T_g0 the 3-D system without its exposure unknowns is the same cell (the same
    // residual rows, bit for bit); joining them at T_g0 keeps every row consistent.
    let mut c = Case::reference_active();
    c.substrate = case::Substrate::pillars();
    let mut p = scene::model_params(&c, "pillars-3d", false).expect("a valid case");
    p.drag = 1e-3;
    if let Substrate::Pillars(pl) = &mut p.substrate {
        pl.y_top = pl
            .y_top_for_gap_on_lattice(0.5, Lattice::Gap, [p.center[0], p.center[1], 0.0], 10.0)
            .expect("placed");
    }
    let params = ModelParams {
        lattice: Lattice::Gap,
        ..quarter_params(p)
    };
    let mesh = coarse_quarter();
    let mut full = QuarterCell::new(params.clone(), mesh.clone()).unwrap();
    let mut small = QuarterCell::deferring_adhesion(params, mesh).unwrap();
    assert!(small.adhesion_deferred() && !full.adhesion_deferred());
    let n_mu = full.dofs.n_mu();
    assert!(n_mu > 0 && small.size() + n_mu == full.size());
    let (y, yp) = deformed_state(&full, 0.5, 11);
    let m = small.size();
    let t = 5.0; // in the gravity phase of the reference case (t_g0 = 10 000 s)
    let (mut r_full, mut r_small) = (vec![0.0; full.size()], vec![0.0; m]);
    full.residual(State::new(t, &y, &yp), &mut r_full).unwrap();
    small
        .residual(State::new(t, &y[..m], &yp[..m]), &mut r_small)
        .unwrap();
    assert_eq!(&r_full[..m], &r_small[..]);

    let t0 = small.params.phases.t_g0;
    small.accepted_step(t0, &y[..m], &yp[..m]);
    let mut big = small.with_adhesion_unknowns(t0, &y[..m], &yp[..m]).unwrap();
    let (t, y2, yp2) = big.initial();
    assert_eq!(t, t0);
    let mut r = vec![0.0; big.size()];
    big.residual(State::new(t, &y2, &yp2), &mut r).unwrap();
    let mut r_small = vec![0.0; m];
    small
        .residual(State::new(t, &y[..m], &yp[..m]), &mut r_small)
        .unwrap();
    assert_eq!(&r[..m], &r_small[..]);
    assert!(r[m..].iter().all(|v| v.abs() < 1e-9));
    // The nodes that sank into the layer got an exposure from the history.
    let a = &y2[m..];
    assert!(a.iter().any(|&v| v > 0.0) && a.iter().all(|&v| v >= 0.0));
    assert!(big.with_adhesion_unknowns(t, &y2, &yp2).is_err());
}

/// The 3-D Hertz run: a homogeneous ball (E, ν = 0.485, ρ = 1000 kg/m³) settled on the
/// flat substrate by its weight, quasi-statically. Returns (contact radius along the
/// meridian, √(A/π) of the contact area, Hertz's radius, contact force / weight).
fn hertz_ball(e: f64, h_bottom: f64, eps_ct: f64, mu_ct: f64, degree: u32, sub: u32) -> [f64; 4] {
    let text = format!(
        r#"(
        name: "hertz-3d",
        geometry: (model: ThreeD),
        mesh: (h_bottom: {h_bottom}, h_nucleus: 1.5, contact_quadrature_degree: {degree}, contact_subdivisions: {sub}),
        materials: (
            nucleus: (e: {e}, nu: 0.485, rho_kg_m3: 1000.0),
            cytoplasm: (e: {e}, nu: 0.485, rho_kg_m3: 1000.0),
            membrane: (e: {e}, nu: 0.485, rho_kg_m3: 1000.0),
        ),
        substrate: Flat(y_s: -1.51),
        contact: (mu_ct_n_m3: {mu_ct:e}, eps_ct: {eps_ct}),
        adhesion: None,
        phases: (t_g0: 100.0, t_as0: 200.0, t_a0: 300.0, t_end: 150.0),
        inertia: (mode: Off, drag: 1e-8),
    )"#
    );
    let case = Case::from_str(&text, "hertz-3d.ron").unwrap();
    let p = scene::model_params(&case, "hertz-3d.ron", false).unwrap();
    let m = QuarterCell::new(quarter_params(p), quarter_mesh(h_bottom, 1.5)).unwrap();
    let atol = m.atol_vector(1e-6);
    let ida = ida_to(m, atol, 150.0, LinearSolver::Faer);
    let (m, y) = (ida.dae(), ida.y());
    // Whole ball: four quarters.
    let weight = 4.0 * m.weight();
    let force = 4.0 * m.contact_force_total(y).y;
    let r = case.geometry.r_c;
    let a_hertz = (3.0 * weight * r / (4.0 * e / (1.0 - 0.485f64.powi(2)))).cbrt();
    [
        m.observe(150.0, y).contact_radius,
        m.observe_quarter(y).contact_radius_equiv,
        a_hertz,
        force / weight,
    ]
}

#[test]
#[ignore = "about 8 minutes: cargo test --release --test integration -- --ignored hertz"]
fn hertz_contact_radius_of_a_ball_in_3d() {
    // Hertz: a = (3PR/(4E*))^{1/3}, E* = E/(1 − ν²), P the ball's weight (E = 100 Pa,
    // R = 10 µm). What it took: the penalty of the axisymmetric Hertz test (ε_ct 0.002
    // µm, μ_ct 2e15 N/m³) on the 3-D mesh with 0.3 µm at the bottom and 1.5 µm inside
    // (4 291 tetrahedra, 19 974 displacement unknowns), the band rule of degree 10 on 8
    // sub-tetrahedra. Measured
    // (2026-12-02): a = 1.3313 µm along the meridian against Hertz's 1.3308 µm (1.0003);
    // √(A/π) of the contact area 1.2877 µm (0.968: the area is sampled at the points of
    // a rule on each face's sub-triangles, a coarser measure of the patch's edge than the
    // meridian's); contact force = weight to 1e-14.
    let [a, a_eq, a_hertz, f] = hertz_ball(100.0, 0.3, 0.002, 2e15, 10, 1);
    eprintln!(
        "3-D Hertz: contact radius {a:.4} µm (√(A/π) {a_eq:.4}), Hertz {a_hertz:.4} µm; \
         force / weight {f}"
    );
    assert!((f - 1.0).abs() < 1e-3, "contact force / weight {f}");
    assert!(
        (a / a_hertz - 1.0).abs() < 0.05,
        "contact radius {a:.4} µm, Hertz {a_hertz:.4} µm"
    );
    assert!(
        (a_eq / a_hertz - 1.0).abs() < 0.05,
        "√(A/π) {a_eq:.4} µm, Hertz {a_hertz:.4} µm"
    );
}

#[test]
fn a_fast_3d_pillar_case_lands_on_the_four_pillar_tops() {
    // cases/fast/push-pull-3d-coarse.ron through its gravity phase: the cell's centre is
    // above the middle of a square of four pillars, whose tops (y_top = +1.80 µm) stand
    // above its lowest point, so it lands on the four tops. The section z = 0 runs along
    // the gap between two rows of pillars: nothing is in contact there while the contact
    // area on the tops carries the weight.
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("pillars-3d");
    let _ = std::fs::remove_dir_all(&dir);
    let run = cellsim(&[
        "run",
        "cases/fast/push-pull-3d-coarse.ron",
        "--set",
        "phases.t_end=100.0",
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let csv = std::fs::read_to_string(dir.join("timeseries.csv")).unwrap();
    let last = last_row(&csv);
    let col = |name: &str| last[name];
    assert_eq!(col("t"), 100.0);
    assert_eq!(col("contact_radius"), 0.0, "contact in the gap at z = 0");
    let (area, down) = (col("contact_area"), col("uy_centre"));
    assert!(area > 1.0, "contact area on the pillar tops {area} µm²");
    assert!(down < -0.1, "the cell did not come down: u_y(c) = {down}");
    let _ = std::fs::remove_dir_all(&dir);
}
