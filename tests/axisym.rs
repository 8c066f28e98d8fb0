//! The axisymmetric model (MODEL.md §10): its derivatives, a patch test with the weight r,
//! closed forms of the r-weighting, free fall, Hertz's sphere, the refusal of pillars and
//! the scene end to end.

use cellsim::dae::State;
use std::f64::consts::PI;
use std::process::Command;

use cellsim::case::{self, Case, KinematicModel};
use cellsim::dae::{Atol, Dae, Integrator};
use cellsim::fem::tri6::{edge_map, edge_shape};
use cellsim::fem::{Domain, EdgeRule, Mesh};
use cellsim::model::{CellModel, ModelParams};
use cellsim::physics::{BlockDiag, Substrate, Viscosity, Yeoh, piola_total_hoop};
use cellsim::scene;
use cellsim::sundials::{Ida, IdaOptions};
use nalgebra::{Matrix2, Vector2};

use crate::model::{check_jacobian, coarse_mesh};

/// The model parameters of `case` in the axisymmetric model.
fn axisym_params(mut case: Case, inertia: bool) -> ModelParams {
    case.geometry.model = KinematicModel::Axisymmetric;
    case.validate().expect("a valid case");
    let p = scene::model_params(&case, "axisym", inertia).expect("a valid case");
    assert_eq!(p.kinematics, KinematicModel::Axisymmetric);
    p
}

#[test]
fn axisymmetric_global_jacobian_matches_finite_differences() {
    // The flat scene's terms (gravity, contact, adhesion with its exposure unknowns), with
    // and without inertia, and with both active regions added: relative column error
    // < 1e-6 at cj = 0 and 37, as the plane-strain check (measured ≤ 5e-9).
    let mut drag = axisym_params(Case::reference(), false);
    drag.drag = 1e-3;
    let mut active = axisym_params(Case::reference_active(), false);
    active.drag = 1e-3;
    let mut fibred = Case::reference_active();
    crate::model::with_fibres(&mut fibred, 1000.0);
    let mut fibred = axisym_params(fibred, false);
    fibred.drag = 1e-3;
    for (params, label) in [
        (
            axisym_params(Case::reference(), true),
            "axisymmetric flat, inertia",
        ),
        (drag, "axisymmetric flat, drag"),
        (active, "axisymmetric flat, active strain, drag"),
        (
            fibred,
            "axisymmetric flat, active strain and fibres (k1 = 1000 Pa), drag",
        ),
    ] {
        check_jacobian(params, 0.5, label);
    }
}

/// Parameters with every load switched off (no gravity, substrate far away, no adhesion,
/// no viscosity), axisymmetric, with the given solids.
fn unloaded(solids: [Yeoh; 3]) -> ModelParams {
    let mut p = axisym_params(Case::reference(), false);
    p.gravity = 0.0;
    p.substrate = Substrate::Flat { y_s: -100.0 };
    p.adhesion = None;
    p.viscosity = Viscosity {
        lambda_f: 0.0,
        mu_f: 0.0,
    };
    p.drag = 1e-3;
    p.solids = solids;
    p
}

/// Exact nodal internal forces of a piecewise-constant stress (one block-diagonal `P` per
/// domain) whose `P_rr = P_θθ` and `P_ry = P_yr = 0`: integrating the weak form
/// `∫ (P_iJ ∂Nₐ/∂X_J + δ_ir P_θθ Nₐ/r) r dA` by parts, the area terms
/// `−∫ Nₐ P_ir dA + δ_ir P_θθ ∫ Nₐ dA` cancel, and `f_a = Σ_d ∮_{∂Ω_d} Nₐ (P_d n) r ds`
/// over the outer circle and both sides of the interfaces; the axis contributes nothing
/// (r = 0 there). A 1-D Gauss rule on the P2 edge geometry, exact for these polynomial
/// integrands; independent of the element assembly.
fn boundary_forces_r(m: &CellModel, stress: &dyn Fn(Domain) -> Matrix2<f64>) -> Vec<[f64; 2]> {
    let mesh = &m.mesh;
    let mut f = vec![[0.0; 2]; mesh.nodes.len()];
    let rule = EdgeRule::degree(8);
    let mut add = |edge: &[usize; 3], p: Matrix2<f64>| {
        let x = edge.map(|i| mesh.nodes[i]);
        for (s, w) in rule.points.iter().zip(&rule.weights) {
            let (pos, dx) = edge_map(&x, *s);
            // Outward normal times ds for a counter-clockwise traversal, times r.
            let nds = Vector2::new(dx[1], -dx[0]) * pos[0];
            let t = p * nds;
            let n = edge_shape(*s);
            for k in 0..3 {
                f[edge[k]][0] += w * n[k] * t.x;
                f[edge[k]][1] += w * n[k] * t.y;
            }
        }
    };
    for e in &mesh.outer_edges {
        add(e, stress(Domain::Membrane));
    }
    for e in &mesh.nucleus_edges {
        add(e, stress(Domain::Nucleus) - stress(Domain::Cytoplasm));
    }
    for e in &mesh.membrane_inner_edges {
        add(e, stress(Domain::Cytoplasm) - stress(Domain::Membrane));
    }
    f
}

#[test]
fn axisymmetric_patch_test_homogeneous_deformation_gives_exact_internal_forces() {
    // u_r = ε r, u_y = δ (y − c_y): F = diag(1 + ε, 1 + δ) ⊕ (1 + ε), exactly representable
    // by the isoparametric P2 elements (u linear in X); isotropy gives P_rr = P_θθ. Three
    // different solids, so the interface terms matter.
    let solids = [
        Yeoh::from_engineering(500.0, 0.485, 0.1, 0.2).unwrap(),
        Yeoh::from_engineering(100.0, 0.3, 0.1, 0.2).unwrap(),
        Yeoh::from_engineering(250.0, 0.45, 0.5, 0.1).unwrap(),
    ];
    let params = unloaded(solids);
    let visc = params.viscosity;
    let cy = params.center[1];
    let mut m = CellModel::new(params, coarse_mesh()).unwrap();
    for (eps, delta) in [(0.08, -0.07), (-0.05, 0.12), (0.0, -0.1)] {
        let mut y = vec![0.0; m.size()];
        for (i, x) in m.mesh.nodes.iter().enumerate() {
            let d = [eps * x[0], delta * (x[1] - cy)];
            for k in 0..2 {
                if m.dofs.u[i][k] != usize::MAX {
                    y[m.dofs.u[i][k]] = d[k];
                }
            }
        }
        let yp = vec![0.0; m.size()];
        let mut r = vec![0.0; m.size()];
        m.residual(State::new(1.0, &y, &yp), &mut r).unwrap();
        let f0 = BlockDiag::new(Matrix2::new(1.0 + eps, 0.0, 0.0, 1.0 + delta), 1.0 + eps);
        let zero = BlockDiag::new(Matrix2::zeros(), 0.0);
        let p = |d: Domain| {
            let k = match d {
                Domain::Nucleus => 0,
                Domain::Cytoplasm => 1,
                Domain::Membrane => 2,
            };
            let p = piola_total_hoop(&solids[k], &visc, &f0, &zero, &Matrix2::identity());
            assert!((p.hoop - p.plane[(0, 0)]).abs() < 1e-12 * p.plane.norm());
            p.plane
        };
        let exact = boundary_forces_r(&m, &p);
        let (mut err, mut scale): (f64, f64) = (0.0, 0.0);
        for (i, fe) in exact.iter().enumerate() {
            for k in 0..2 {
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
            "ε {eps}, δ {delta}: relative nodal force error {:.2e}",
            err / scale
        );
    }
}

/// ∫ r dA over the half ring a < |X − c| < b of the meridian half-plane r ≥ 0 with c on
/// the axis: (2/3)(b³ − a³), the volume of the ring's shell per radian.
fn volume_per_radian(a: f64, b: f64) -> f64 {
    2.0 / 3.0 * (b.powi(3) - a.powi(3))
}

#[test]
fn axisymmetric_weight_volumes_and_gravity_rows_are_weighted_by_r() {
    let params = axisym_params(Case::reference(), true);
    let (g, rho) = (params.gravity, params.densities);
    let t_g0 = params.phases.t_g0;
    let mut m = CellModel::new(params, coarse_mesh()).unwrap();
    let (rn, rcp, rc) = (5.0, 9.75, 10.0);
    let vols = [
        volume_per_radian(0.0, rn),
        volume_per_radian(rn, rcp),
        volume_per_radian(rcp, rc),
    ];
    // The volumes per radian of the domains, from the observables' weights.
    let y = vec![0.0; m.size()];
    let s = m.mean_strain_norms(&y);
    for k in 0..3 {
        let err = s.area[k] / vols[k] - 1.0;
        assert!(
            err.abs() < 2e-4,
            "domain {k}: {} against {}",
            s.area[k],
            vols[k]
        );
    }
    // The weight: ρ g times those volumes, summed (the ball's is 2π times it).
    let exact: f64 = (0..3).map(|k| rho[k] * g * vols[k]).sum();
    let w = m.weight();
    assert!((w / exact - 1.0).abs() < 2e-4, "weight {w} against {exact}");
    assert!(
        (2.0 * PI * exact
            - 4.0 / 3.0 * PI * g * (rho[1] * rc.powi(3) + (rho[0] - rho[1]) * rn.powi(3)))
        .abs()
            < 1e-12 * exact
    );
    // The gravity rows of the residual at rest at full gravity add up to the weight.
    let yp = vec![0.0; m.size()];
    let mut r = vec![0.0; m.size()];
    m.residual(State::new(t_g0, &y, &yp), &mut r).unwrap();
    let sum_y: f64 = (0..m.mesh.nodes.len())
        .map(|i| m.dofs.momentum_rows(i)[1])
        .filter(|&d| d != usize::MAX)
        .map(|d| r[d])
        .sum();
    assert!(
        (sum_y / w - 1.0).abs() < 1e-12,
        "gravity rows {sum_y} against {w}"
    );
}

#[test]
fn axisymmetric_strain_means_are_volume_means_with_the_hoop_strain() {
    // A homogeneous radial stretch u_r = (λ − 1) r: E = ½(λ² − 1) along r and θ, 0 along y,
    // so ‖E‖ = √2 (λ² − 1)/2 in every domain.
    let m = CellModel::new(axisym_params(Case::reference(), true), coarse_mesh()).unwrap();
    let lambda = 1.2f64;
    let mut y = vec![0.0; m.size()];
    for (i, x) in m.mesh.nodes.iter().enumerate() {
        if m.dofs.u[i][0] != usize::MAX {
            y[m.dofs.u[i][0]] = (lambda - 1.0) * x[0];
        }
    }
    let o = m.observe(1.0, &y);
    let e = 2f64.sqrt() * (lambda * lambda - 1.0) / 2.0;
    for (name, v) in [
        ("nucleus", o.strain_nucleus),
        ("cytoplasm", o.strain_cytoplasm),
        ("membrane", o.strain_membrane),
    ] {
        assert!((v - e).abs() < 1e-12, "{name}: {v} against {e}");
    }
    // det F = λ² (1 along y) per element.
    for (k, (_, j)) in m.element_strain_and_jacobian(&y).iter().enumerate() {
        assert!(
            (j - lambda * lambda).abs() < 1e-12,
            "element {k}: det F {j}"
        );
    }
}

#[test]
fn axisymmetric_contact_rows_carry_the_contact_force_with_the_hoop_jacobian() {
    // A cell sunk into the substrate and stretched radially, u = ((λ − 1) r, −s), without
    // gravity (t = 0), adhesion or viscosity: the y-rows of the residual add up to minus
    // the contact force (the internal forces add to zero in y), which the observables
    // integrate on their own with J = λ_θ det F₂ = λ². The residual's contact force grows
    // as λ² with the stretch (J), the per-radian volume of the band being unchanged.
    let mut p = axisym_params(Case::reference(), false);
    p.adhesion = None;
    p.viscosity = Viscosity {
        lambda_f: 0.0,
        mu_f: 0.0,
    };
    p.drag = 1e-3;
    let mut m = CellModel::new(p, coarse_mesh()).unwrap();
    let sum_y = |m: &mut CellModel, y: &[f64]| {
        let yp = vec![0.0; m.size()];
        let mut r = vec![0.0; m.size()];
        m.residual(State::new(0.0, y, &yp), &mut r).unwrap();
        (0..m.mesh.nodes.len())
            .map(|i| m.dofs.momentum_rows(i)[1])
            .filter(|&d| d != usize::MAX)
            .map(|d| r[d])
            .sum::<f64>()
    };
    let state = |m: &CellModel, lambda: f64| {
        let mut y = vec![0.0; m.size()];
        for (i, x) in m.mesh.nodes.iter().enumerate() {
            let d = [(lambda - 1.0) * x[0], -0.6];
            for k in 0..2 {
                if m.dofs.u[i][k] != usize::MAX {
                    y[m.dofs.u[i][k]] = d[k];
                }
            }
        }
        y
    };
    let mut forces = Vec::new();
    for lambda in [1.0, 1.1] {
        let y = state(&m, lambda);
        let f = m.contact_force_total(&y).y;
        assert!(f > 1.0, "in contact: {f}");
        let s = sum_y(&mut m, &y);
        assert!(
            (s + f).abs() < 1e-9 * f,
            "λ {lambda}: rows {s} against force {f}"
        );
        forces.push(f);
    }
    // The band material (y < y_s + ε) is the same in both states; only J changes.
    let ratio = forces[1] / forces[0];
    assert!((ratio - 1.21).abs() < 1e-9, "force ratio {ratio}");
}

#[test]
fn axisymmetric_free_fall_under_the_ramped_gravity_matches_the_closed_form() {
    // As the plane-strain test: before contact the cell falls as a rigid body,
    // u(t) = −g T² (ξ⁷/7 − ξ⁶/2 + ξ⁵/2), ξ = t/T, whatever the weight of the integrals.
    let mut p = axisym_params(Case::reference(), true);
    p.substrate = Substrate::Flat { y_s: -100.0 };
    let (g, t_ramp) = (p.gravity, p.phases.t_g0);
    let m = CellModel::new(p, coarse_mesh()).unwrap();
    let pts = m.mesh.points;
    let opts = IdaOptions {
        rtol: 1e-8,
        atol: Atol::Scalar(1e-12),
        ..Default::default()
    };
    let mut ida = Ida::new(m, opts).unwrap();
    for t in [2.0, 5.0, 9.0] {
        ida.advance_to(t, &mut |_, _| true).unwrap();
        let xi = t / t_ramp;
        let exact = -g * t_ramp * t_ramp * (xi.powi(7) / 7.0 - xi.powi(6) / 2.0 + xi.powi(5) / 2.0);
        for i in [pts.nucleus_top, pts.centre, pts.cell_bottom] {
            let uy = ida.dae().dofs.node_u(ida.y(), i)[1];
            assert!(
                (uy - exact).abs() <= 1e-5 * exact.abs(),
                "t = {t}: u_y = {uy:.10e}, exact {exact:.10e}"
            );
        }
    }
}

#[test]
fn hertz_contact_radius_of_a_sphere_pressed_by_its_weight() {
    // A homogeneous elastic ball (E = 100 Pa, ν = 0.485, ρ = 1000 kg/m³, R = 10 µm)
    // pressed on the flat substrate by its own weight P = ρ g (4/3)π R³, quasi-static (no
    // inertia, medium drag only while it sinks). Hertz: a = (3PR/(4E*))^{1/3},
    // E* = E/(1 − ν²). The penalty contact and mesh of the cylinder's Hertz test
    // (tests/model.rs): ε_ct 0.002 µm, μ_ct 2e15 N/m³, 0.05 µm elements at the bottom,
    // a degree-10 contact rule on 16 sub-triangles. Measured a/a_Hertz = 0.983 (a 1.308 µm,
    // Hertz 1.331 µm), contact force = weight to 1e-12.
    let text = r#"(
        name: "hertz-sphere",
        geometry: (model: Axisymmetric),
        mesh: (h_bottom: 0.05, h_nucleus: 1.0, contact_quadrature_degree: 10, contact_subdivisions: 2),
        materials: (
            nucleus: (e: 100.0, nu: 0.485, rho_kg_m3: 1000.0),
            cytoplasm: (e: 100.0, nu: 0.485, rho_kg_m3: 1000.0),
            membrane: (e: 100.0, nu: 0.485, rho_kg_m3: 1000.0),
        ),
        substrate: Flat(y_s: -1.51),
        contact: (mu_ct_n_m3: 2e15, eps_ct: 0.002),
        adhesion: None,
        phases: (t_g0: 100.0, t_as0: 200.0, t_a0: 300.0, t_end: 150.0),
        inertia: (mode: Off, drag: 1e-8),
    )"#;
    let case = Case::from_str(text, "hertz-sphere.ron").unwrap();
    let mesh = Mesh::generate(&scene::mesh_params(&case)).unwrap();
    let params = scene::model_params(&case, "hertz-sphere.ron", false).unwrap();
    let m = CellModel::new(params, mesh).unwrap();
    let atol = Atol::Vector(m.atol_vector(1e-6));
    let mut ida = Ida::new(
        m,
        IdaOptions {
            rtol: 1e-5,
            atol,
            ..Default::default()
        },
    )
    .unwrap();
    ida.advance_to(150.0, &mut |_, _| true).unwrap();
    let (m, y) = (ida.dae(), ida.y());
    // Whole ball: 2π times the per-radian integrals.
    let weight = 2.0 * PI * m.weight();
    let force = 2.0 * PI * m.contact_force_total(y).y;
    assert!(
        (force - weight).abs() < 1e-4 * weight,
        "contact force {force} against weight {weight}"
    );
    let (e, nu, r) = (100.0, 0.485, 10.0f64);
    let g = 9.81e6;
    assert!((weight / (1e-9 * g * 4.0 / 3.0 * PI * r.powi(3)) - 1.0).abs() < 2e-4);
    let a_hertz = (3.0 * weight * r / (4.0 * e / (1.0 - nu * nu))).cbrt();
    let a = m.contact_lengths(y).0;
    assert!(
        (a / a_hertz - 1.0).abs() < 0.05,
        "contact radius {a:.4} µm, Hertz {a_hertz:.4} µm"
    );
}

#[test]
fn a_pillar_substrate_is_refused_by_the_axisymmetric_model() {
    // The error names the file, the field and why; the same case in plane strain is
    // accepted.
    let text = |model: &str| {
        format!(
            "(name: \"p\", geometry: (model: {model}), substrate: Pillars(), \
             phases: (t_end: 100.0))"
        )
    };
    let err = Case::from_str(&text("Axisymmetric"), "p.ron").unwrap_err();
    assert_eq!(err.field(), Some("geometry.model"));
    let msg = err.to_string();
    assert!(msg.starts_with("p.ron:1:"), "{msg}");
    assert!(msg.contains("needs a Flat substrate"), "{msg}");
    assert!(Case::from_str(&text("PlaneStrain"), "p.ron").is_ok());
    // A pillar case turned axisymmetric from the command line is refused at the --set.
    let path = format!("{}/cases/pillars-push.ron", env!("CARGO_MANIFEST_DIR"));
    let set = [case::Override::parse("geometry.model=Axisymmetric").unwrap()];
    let err = Case::load_with_overrides(&path, &set).unwrap_err();
    assert_eq!(err.field(), Some("geometry.model"));
    assert!(
        err.to_string()
            .starts_with("--set geometry.model=Axisymmetric: "),
        "{err}"
    );
}

#[test]
fn the_axisymmetric_scene_runs_end_to_end_with_every_output() {
    // `cellsim run` on the fast axisymmetric case, with VTU files: CSV, summary, phase
    // states, VTU; the cell lands and the contact carries it.
    let out = format!("{}/axisym-fast", env!("CARGO_TARGET_TMPDIR"));
    let _ = std::fs::remove_dir_all(&out);
    let run = Command::new(env!("CARGO_BIN_EXE_cellsim"))
        .args([
            "run",
            "cases/fast/flat-axisym-gravity.ron",
            "--quiet",
            "--vtu",
            "--out",
            &out,
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("run cellsim");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let dir = std::path::Path::new(&out);
    for f in [
        "timeseries.csv",
        "summary.json",
        "mesh.json",
        "state_end.json",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let vtu = std::fs::read_dir(dir.join("vtu")).unwrap().count();
    assert!(vtu > 2, "{vtu} VTU files");
    let rows = crate::scenes::read_csv(&dir.join("timeseries.csv"));
    let last = rows.last().unwrap();
    assert_eq!(last[0], 200.0);
    // Fallen by 0.5 µm onto the substrate and resting on it (contact radius > 0).
    assert!(last[2] < -0.4 && last[2] > -0.6, "uy_top {}", last[2]);
    assert!(last[1] > 0.1, "contact radius {}", last[1]);
    let summary = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    assert!(summary.contains("\"finished\": true"), "{summary}");
}
