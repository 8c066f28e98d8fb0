//! The cell model's derivatives, patch test and closed forms.

use cellsim::case::{self, Case};
use cellsim::dae::Dae;
use cellsim::dae::State;
use cellsim::fem::{Mesh, MeshParams};
use cellsim::model::{CellModel, ModelParams};
use cellsim::physics::Substrate;
use cellsim::scene;
use cellsim::scene::terms;

/// The reference case's mesh at refine 0.5.
pub fn coarse_mesh() -> Mesh {
    Mesh::generate(&MeshParams {
        refine: 0.5,
        ..terms::mesh_params(&Case::reference())
    })
    .unwrap()
}

pub use crate::fd::deformed_state;

/// Smallest finite-difference step on a μ_as exposure in the half-plane tests
/// ([`crate::fd::jacobian_fd_error`] also tries 10× and 100× it).
const MU_STEP: f64 = 1e-2;

/// [`crate::fd::jacobian_fd_error`] of a half-plane model with its μ_as step, at cj = 0
/// and cj = 37: the worst relative column error of each.
pub fn jacobian_fd_error(
    m: &mut CellModel,
    t: f64,
    y: &[f64],
    yp: &[f64],
    cols: &[usize],
) -> [(f64, f64); 2] {
    let off = m.dofs.mu_offset();
    let cjs = [0.0, 37.0];
    let errs = crate::fd::jacobian_fd_error(m, off, MU_STEP, t, y, yp, &cjs, cols);
    [0, 1].map(|k| (cjs[k], errs[k].0))
}

/// Pillars, adhesion (μ_as unknowns) and both active regions: every block of J present.
pub fn active_pillars_params(inertia: bool) -> ModelParams {
    let mut c = Case::reference_active();
    c.substrate = case::Substrate::pillars();
    let mut p = scene::model_params(&c, "pillars", inertia).expect("a valid case");
    p.drag = if inertia { 0.0 } else { 1e-3 };
    p
}

/// Checks J against finite differences in a deformed state with contact, adhesion and
/// active strain, at cj = 0 and cj = 37, on 150 random columns plus every column of the
/// lowest nodes (in contact) and their μ_as.
pub fn check_jacobian(params: ModelParams, sink: f64, label: &str) {
    let inertia = params.inertia;
    let mut m = CellModel::new(params, coarse_mesh()).unwrap();
    let (y, yp) = deformed_state(&m, sink, 7);
    // t in the active phase: gravity, adhesion and active strain all switched on.
    let t = 45_000.0;
    // Make sure contact and adhesion are really active in this state.
    let f = m.contact_force_total(&y);
    assert!(
        f.y > 1e-3,
        "{label}: no contact in the test state (force {f:?})"
    );
    // 150 random columns, every unknown of the lowest nodes (in contact) and their μ_as.
    let cols = crate::fd::contact_columns(&m, 150, None);
    for (cj, err) in jacobian_fd_error(&mut m, t, &y, &yp, &cols) {
        assert!(
            err < 1e-6,
            "{label}, inertia {inertia}, cj {cj}: relative column error {err:.2e}"
        );
    }
}

#[test]
fn global_jacobian_matches_finite_differences() {
    for (params, sink) in [
        (scene::reference_params(), 0.5),
        (active_pillars_params(true), 0.5),
        (active_pillars_params(false), 0.5),
    ] {
        check_jacobian(params, sink, "defaults");
    }
}

/// The outline's self-contact is in the model only where the outline can fold: on pillars
/// once adhesion acts. Its pairs widen the Jacobian's pattern; on a flat substrate and
/// while the μ_as unknowns are deferred (the fall) the pattern is that of the model
/// without it.
#[test]
fn self_contact_is_in_the_pattern_only_on_pillars_once_adhesion_acts() {
    let nnz = |m: &CellModel| m.pattern().compute_nnz();
    let without = |mut p: ModelParams| {
        p.contact.self_contact = false;
        p
    };
    let pillars = active_pillars_params(false);
    let with_mu = nnz(&CellModel::new(pillars.clone(), coarse_mesh()).unwrap());
    let with_mu_off = nnz(&CellModel::new(without(pillars.clone()), coarse_mesh()).unwrap());
    assert!(
        with_mu > with_mu_off,
        "pillars with μ_as: {with_mu} entries, {with_mu_off} without self-contact"
    );
    let deferred = nnz(&CellModel::deferring_adhesion(pillars.clone(), coarse_mesh()).unwrap());
    let deferred_off =
        nnz(&CellModel::deferring_adhesion(without(pillars), coarse_mesh()).unwrap());
    assert_eq!(deferred, deferred_off, "pillars, μ_as deferred");
    let flat = scene::reference_params();
    assert!(matches!(flat.substrate, Substrate::Flat { .. }));
    let flat_nnz = nnz(&CellModel::new(flat.clone(), coarse_mesh()).unwrap());
    let flat_off = nnz(&CellModel::new(without(flat), coarse_mesh()).unwrap());
    assert_eq!(flat_nnz, flat_off, "flat substrate");
}

/// The push-pull case on pillars without inertia (drag 1e-3), with `change` applied.
fn pillars_reading(change: impl Fn(&mut Case)) -> ModelParams {
    let mut c = Case::reference_active();
    c.substrate = case::Substrate::pillars();
    change(&mut c);
    c.validate().expect("a valid case");
    let mut p = scene::model_params(&c, "pillars", false).expect("a valid case");
    p.drag = 1e-3;
    p
}

/// The residual in [`check_jacobian`]'s test state (the cell sunk by `sink`, t = 45 000 s).
fn test_state_residual(params: ModelParams, sink: f64) -> Vec<f64> {
    let mut m = CellModel::new(params, coarse_mesh()).unwrap();
    let (y, yp) = deformed_state(&m, sink, 7);
    let mut r = vec![0.0; m.size()];
    m.residual(State::new(45_000.0, &y, &yp), &mut r).unwrap();
    r
}

#[test]
fn global_jacobian_is_exact_for_every_reading_of_the_paper() {
    let adhesion =
        |f: fn(&mut case::Adhesion)| move |c: &mut Case| f(c.adhesion.as_mut().expect("adhesion"));
    let readings: Vec<(&str, ModelParams)> = vec![
        (
            "adhesion.direction = Unit",
            pillars_reading(adhesion(|a| a.direction = case::AdhesionDirection::Unit)),
        ),
        (
            "adhesion.jacobian_factor",
            pillars_reading(adhesion(|a| a.jacobian_factor = true)),
        ),
        (
            "adhesion.layer_excludes_substrate",
            pillars_reading(adhesion(|a| a.layer_excludes_substrate = true)),
        ),
        (
            "active.pac semi-axes clipped to the cell",
            pillars_reading(|c| {
                let pac = c.active.pac.as_mut().expect("pac");
                pac.inner_semi_axes = (10.0, 9.0);
                pac.outer_semi_axes = (15.0, 14.0);
                pac.clip_to_cell = true;
            }),
        ),
    ];
    // Each reading changes the residual of the default case in the test state (the
    // option reaches the model), and its Jacobian is exact.
    for (label, params) in readings {
        let change = residual_change(params.clone(), 0.5);
        assert!(change > 1e-6, "{label}: the residual did not change");
        check_jacobian(params, 0.5, label);
    }
}

/// How much `params` change the residual of the default pillars case in the test state
/// (the cell sunk by `sink`): the largest entry's change over the largest entry.
fn residual_change(params: ModelParams, sink: f64) -> f64 {
    let r0 = test_state_residual(pillars_reading(|_| {}), sink);
    let r = test_state_residual(params, sink);
    let change = r
        .iter()
        .zip(&r0)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    change / r0.iter().map(|v| v.abs()).fold(0.0, f64::max)
}

#[test]
fn global_jacobian_is_exact_with_a_contact_that_stiffens_beyond_its_band() {
    // Not a reading of the paper but an option beside it, acting only deeper than ε_ct:
    // the cell sunk 0.7 µm (its lowest point 0.2 µm into the pillar tops). (At 0.8 µm an
    // exposure column at the adhesion layer's edge, x ≈ 2.1 µm, meets the difference
    // quotients' limit described in `fd::jacobian_fd_error`, with or without the option.)
    let sink = 0.7;
    let stiffened = pillars_reading(|c| c.contact.stiffening = 2.0);
    let (r0, r) = (
        test_state_residual(pillars_reading(|_| {}), sink),
        test_state_residual(stiffened.clone(), sink),
    );
    assert!(
        r0.iter().zip(&r).any(|(a, b)| a != b),
        "the residual did not change"
    );
    check_jacobian(stiffened, sink, "contact.stiffening = 2");
}

/// The cytoplasm's fibres (MODEL.md §11) at stiffness `k1_pa`, the other fields at their
/// defaults.
pub fn with_fibres(c: &mut Case, k1_pa: f64) {
    c.materials.fibres = Some(case::Fibres {
        k1_pa,
        ..Default::default()
    });
}

#[test]
fn global_jacobian_is_exact_with_fibres_in_the_cytoplasm() {
    // The fibre term (MODEL.md §11) at k₁ = 1000 Pa, ten times the cytoplasm's modulus, so
    // that its columns are not lost beside the solid's: it changes the residual of the test
    // state (the random deformation stretches fibres in both regions), and J stays exact.
    let fibred = pillars_reading(|c| with_fibres(c, 1000.0));
    let change = residual_change(fibred.clone(), 0.5);
    assert!(
        change > 1e-3,
        "the fibres did not change the residual ({change:.2e})"
    );
    check_jacobian(fibred, 0.5, "materials.fibres, k1 = 1000 Pa");
}

use cellsim::dae::{Atol, Integrator, Pattern};
use cellsim::fem::tri6::{edge_map, edge_shape};
use cellsim::fem::{Domain, EdgeRule};
use cellsim::physics::{Viscosity, Yeoh, piola_total};
use cellsim::sundials::{Ida, IdaOptions};
use nalgebra::{Matrix2, Vector2};

/// Parameters with every load switched off (no gravity, substrate far away, no adhesion,
/// no viscosity): the residual at rest velocities is the internal force vector alone.
fn unloaded(inertia: bool, solids: [Yeoh; 3]) -> ModelParams {
    let mut p = scene::reference_params();
    p.gravity = 0.0;
    p.substrate = Substrate::Flat { y_s: -100.0 };
    p.adhesion = None;
    p.viscosity = Viscosity {
        lambda_f: 0.0,
        mu_f: 0.0,
    };
    p.inertia = inertia;
    p.solids = solids;
    p
}

/// Exact nodal internal forces of a piecewise-constant stress field P_d (one per domain):
/// f_a = Σ_d ∮_{∂Ω_d} N_a P_d N dS, summed over the outer circle, the symmetry line and both
/// sides of the two interfaces, by a 1-D Gauss rule on the P2 edge geometry (exact for
/// these polynomial integrands). Independent of the element assembly.
fn boundary_forces(m: &CellModel, stress: &dyn Fn(Domain) -> Matrix2<f64>) -> Vec<[f64; 2]> {
    let mesh = &m.mesh;
    let mut f = vec![[0.0; 2]; mesh.nodes.len()];
    let rule = EdgeRule::degree(8);
    // Integrates N_a (P n) along an edge; `n` is the unit normal from the edge tangent,
    // rotated clockwise (outward for edges traversed with the domain on the left).
    let mut add = |edge: &[usize; 3], p: Matrix2<f64>, sign: f64| {
        let x = edge.map(|i| mesh.nodes[i]);
        for (s, w) in rule.points.iter().zip(&rule.weights) {
            let (_, dx) = edge_map(&x, *s);
            // Outward normal times ds: (dy, −dx) ds for a counter-clockwise traversal.
            let nds = Vector2::new(dx[1], -dx[0]) * sign;
            let t = p * nds;
            let n = edge_shape(*s);
            for k in 0..3 {
                f[edge[k]][0] += w * n[k] * t.x;
                f[edge[k]][1] += w * n[k] * t.y;
            }
        }
    };
    // Outer circle: bottom to top, counter-clockwise through x > 0: domain on the left.
    for e in &mesh.outer_edges {
        add(e, stress(Domain::Membrane), 1.0);
    }
    // Interfaces (bottom to top, counter-clockwise): the inner domain on the left.
    for e in &mesh.nucleus_edges {
        add(e, stress(Domain::Nucleus) - stress(Domain::Cytoplasm), 1.0);
    }
    for e in &mesh.membrane_inner_edges {
        add(e, stress(Domain::Cytoplasm) - stress(Domain::Membrane), 1.0);
    }
    // Symmetry line x = 0, sorted by y: traversed upwards the domain is on the right, so
    // the outward normal is −e_x = the clockwise rotation reversed.
    let sym = &mesh.symmetry_nodes;
    for k in (0..sym.len() - 2).step_by(2) {
        let edge = [sym[k], sym[k + 1], sym[k + 2]];
        let y_mid = mesh.nodes[edge[1]][1] - m.params.center[1];
        let r = y_mid.abs();
        let d = if r < 5.0 {
            Domain::Nucleus
        } else if r < 9.75 {
            Domain::Cytoplasm
        } else {
            Domain::Membrane
        };
        add(&edge, stress(d), -1.0);
    }
    f
}

/// Imposes u = (F₀ − I)(X − c) on every node.
fn homogeneous_state(m: &CellModel, f0: &Matrix2<f64>) -> Vec<f64> {
    let mut y = vec![0.0; m.size()];
    let c = m.params.center;
    for (i, x) in m.mesh.nodes.iter().enumerate() {
        let d = (f0 - Matrix2::identity()) * Vector2::new(x[0] - c[0], x[1] - c[1]);
        for k in 0..2 {
            if m.dofs.u[i][k] != usize::MAX {
                y[m.dofs.u[i][k]] = d[k];
            }
        }
    }
    y
}

fn compare_internal_forces(
    m: &mut CellModel,
    f0: &Matrix2<f64>,
    exact_p: &dyn Fn(Domain) -> Matrix2<f64>,
) -> f64 {
    let y = homogeneous_state(m, f0);
    let yp = vec![0.0; m.size()];
    let mut r = vec![0.0; m.size()];
    m.residual(State::new(1.0, &y, &yp), &mut r).unwrap();
    let exact = boundary_forces(m, exact_p);
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
    err / scale
}

#[test]
fn patch_test_homogeneous_deformation_gives_exact_internal_forces() {
    // Three different solids, so the interface terms matter. F₀ keeps u_x = 0 on x = 0.
    let solids = [
        Yeoh::from_engineering(500.0, 0.485, 0.1, 0.2).unwrap(),
        Yeoh::from_engineering(100.0, 0.3, 0.1, 0.2).unwrap(),
        Yeoh::from_engineering(250.0, 0.45, 0.5, 0.1).unwrap(),
    ];
    let params = unloaded(false, solids);
    let visc = params.viscosity;
    let mut m = CellModel::new(params, coarse_mesh()).unwrap();
    let f0 = Matrix2::new(1.08, 0.0, -0.06, 0.93);
    let zero = Matrix2::zeros();
    let p = |d: Domain| {
        let k = match d {
            Domain::Nucleus => 0,
            Domain::Cytoplasm => 1,
            Domain::Membrane => 2,
        };
        piola_total(&solids[k], &visc, &f0, &zero, &Matrix2::identity())
    };
    let err = compare_internal_forces(&mut m, &f0, &p);
    assert!(err < 1e-10, "relative nodal force error {err:.2e}");
}

/// Plane-strain uniaxial stretch F = diag(λ, 1) of the compressible Yeoh solid, by hand
/// from MODEL.md §3: C = diag(λ², 1, 1), I₁ = λ² + 2, I₃ = λ², J = λ, X = I₁ − 3λ^{2/3},
/// S₁₁ = 2W'(X)(1 − λ^{2/3}/λ²) + 2β(I₁ − λ² − 2λ^{4/3}/λ²) + λ_Y ln λ / λ²,
/// W'(X) = α₁ + 2α₂X + 3α₃X², and P₁₁ = λ S₁₁; S₂₂ = 2W'(X)(1 − λ^{2/3})
/// + 2β(I₁ − 1 − 2λ^{4/3}) + λ_Y ln λ, P₂₂ = S₂₂.
fn uniaxial_p(y: &Yeoh, l: f64) -> (f64, f64) {
    let i1 = l * l + 2.0;
    let x = i1 - 3.0 * l.powf(2.0 / 3.0);
    let wx = y.alpha1 + 2.0 * y.alpha2 * x + 3.0 * y.alpha3 * x * x;
    let s11 = 2.0 * wx * (1.0 - l.powf(2.0 / 3.0) / (l * l))
        + 2.0 * y.beta * (i1 - l * l - 2.0 * l.powf(4.0 / 3.0) / (l * l))
        + y.lambda_y * l.ln() / (l * l);
    let s22 = 2.0 * wx * (1.0 - l.powf(2.0 / 3.0))
        + 2.0 * y.beta * (i1 - 1.0 - 2.0 * l.powf(4.0 / 3.0))
        + y.lambda_y * l.ln();
    (l * s11, s22)
}

#[test]
fn uniaxial_stretch_of_the_yeoh_solid_matches_the_analytic_stress() {
    let yeoh = Yeoh::from_engineering(100.0, 0.485, 0.1, 0.2).unwrap();
    let mut m = CellModel::new(unloaded(false, [yeoh; 3]), coarse_mesh()).unwrap();
    for l in [0.7, 1.0 + 1e-3, 1.3, 1.8] {
        let (p11, p22) = uniaxial_p(&yeoh, l);
        let f0 = Matrix2::new(l, 0.0, 0.0, 1.0);
        let err = compare_internal_forces(&mut m, &f0, &|_| Matrix2::new(p11, 0.0, 0.0, p22));
        assert!(
            err < 1e-10,
            "stretch {l}: relative nodal force error {err:.2e}"
        );
    }
}

#[test]
fn free_fall_under_the_ramped_gravity_matches_the_closed_form() {
    // Before contact the cell falls as a rigid body: ü = −g S(t; 0, T) with the C² step
    // S = 10ξ³ − 15ξ⁴ + 6ξ⁵, ξ = t/T, so u(t) = −g T² (ξ⁷/7 − ξ⁶/2 + ξ⁵/2). (The issue's
    // g t³/(6T) is the same fall under a linear ramp; MODEL.md's ramp is this C² step.)
    let mut p = scene::reference_params();
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
            // IDA's global error at rtol 1e-8 (measured ≈ 7e-7 relative at t = 2 s).
            assert!(
                (uy - exact).abs() <= 1e-5 * exact.abs(),
                "t = {t}: u_y = {uy:.10e}, exact {exact:.10e}"
            );
        }
    }
}

/// One homogeneous material point under a constant nominal stress σ₀ (a block whose
/// deformation stays uniform): F = diag(1 + ε, 1), unknown the strain ε(t) (not the stretch,
/// whose error control relative to 1 would lose the small strain's digits), residual
/// P₁₁(F, Ḟ) − σ₀.
struct Creep {
    yeoh: Yeoh,
    visc: Viscosity,
    sigma0: f64,
    pattern: Pattern,
}

impl Dae for Creep {
    fn size(&self) -> usize {
        1
    }
    fn residual(
        &mut self,
        State { y, yp, .. }: State,
        r: &mut [f64],
    ) -> Result<(), cellsim::dae::DaeError> {
        let f = Matrix2::new(1.0 + y[0], 0.0, 0.0, 1.0);
        let fd = Matrix2::new(yp[0], 0.0, 0.0, 0.0);
        r[0] = piola_total(&self.yeoh, &self.visc, &f, &fd, &Matrix2::identity())[(0, 0)]
            - self.sigma0;
        Ok(())
    }
    fn pattern(&self) -> &Pattern {
        &self.pattern
    }
    fn jacobian(
        &mut self,
        State { y, yp, .. }: State,
        cj: f64,
        v: &mut [f64],
    ) -> Result<(), cellsim::dae::DaeError> {
        let f = Matrix2::new(1.0 + y[0], 0.0, 0.0, 1.0);
        let fd = Matrix2::new(yp[0], 0.0, 0.0, 0.0);
        let mp =
            cellsim::physics::material_point(&self.yeoh, &self.visc, &f, &fd, &Matrix2::identity());
        v[0] = mp.dP_dF[(0, 0)] + cj * mp.dP_dFdot[(0, 0)];
        Ok(())
    }
    fn differential(&self) -> Vec<bool> {
        vec![true]
    }
    fn initial(&self) -> (f64, Vec<f64>, Vec<f64>) {
        // Consistent start: no strain yet, the viscous stress carries σ₀ alone.
        let eta = self.visc.lambda_f + 2.0 * self.visc.mu_f;
        (0.0, vec![0.0], vec![self.sigma0 / eta])
    }
}

#[test]
fn kelvin_voigt_creep_follows_its_exponential() {
    // Small strain: P₁₁ ≈ M ε + η ε̇ with the plane-strain P-wave modulus M = λ_e + 2μ_e and
    // η = λ_f + 2μ_f, so ε(t) = (σ₀/M)(1 − e^{−t/τ}), τ = η/M.
    let (e, nu) = (100.0, 0.485);
    let yeoh = Yeoh::from_engineering(e, nu, 0.1, 0.2).unwrap();
    let visc = scene::reference_params().viscosity;
    let (mu, lam) = (
        e / (2.0 * (1.0 + nu)),
        e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
    );
    let modulus = lam + 2.0 * mu;
    let eta = visc.lambda_f + 2.0 * visc.mu_f;
    let tau = eta / modulus;
    let sigma0 = 1e-5 * modulus;
    let pattern = cellsim::fem::assembly::pattern_from_entries(1, &[(0, 0)]);
    let mut ida = Ida::new(
        Creep {
            yeoh,
            visc,
            sigma0,
            pattern,
        },
        IdaOptions {
            rtol: 1e-8,
            atol: Atol::Scalar(1e-14),
            ..Default::default()
        },
    )
    .unwrap();
    for k in 1..=10 {
        let t = 0.5 * tau * k as f64;
        ida.advance_to(t, &mut |_, _| true).unwrap();
        let eps = ida.y()[0];
        let exact = sigma0 / modulus * (1.0 - (-t / tau).exp());
        // Nonlinearity enters at O(ε) = 1e-5 relative.
        assert!(
            (eps - exact).abs() <= 1e-4 * exact,
            "t = {t}: ε = {eps:.6e}, exponential {exact:.6e}"
        );
    }
}

#[test]
fn hertz_contact_half_width_of_a_cylinder_pressed_by_its_weight() {
    // A homogeneous elastic cylinder (E = 100 Pa, ν = 0.485, ρ = 1000 kg/m³, R = 10 µm)
    // pressed on the flat substrate by its own weight, quasi-static (no inertia, medium
    // drag only while it sinks). 2-D Hertz: b = √(4PR/(πE*)), E* = E/(1 − ν²), P the weight
    // of the full cylinder per unit length. The penalty contact approaches Hertz as the
    // band narrows and the penalty stiffens; what it took to come within 5 %: ε_ct 0.002 µm
    // (paper 0.1), μ_ct 2e15 N/m³ (paper 2e9), 0.05 µm elements at the bottom, contact
    // rule of degree 10 on 16 sub-triangles. Measured sequence of b/b_Hertz: 1.13 (ε 0.005,
    // μ 2e11), 1.07 (2e13), 1.033 (2e15), 1.019 (ε 0.002), 1.008 (ε 0.002, μ 2e16, 0.03 µm).
    let text = r#"(
        name: "hertz",
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
    let case = cellsim::case::Case::from_str(text, "hertz.ron").unwrap();
    let mesh = Mesh::generate(&cellsim::scene::mesh_params(&case)).unwrap();
    let params = cellsim::scene::model_params(&case, "hertz.ron", false).unwrap();
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
    let weight = 2.0 * m.weight(); // full cylinder
    let force = 2.0 * m.contact_force_total(y).y;
    assert!(
        (force - weight).abs() < 1e-4 * weight,
        "contact force {force} against weight {weight}"
    );
    let (e, nu, r) = (100.0, 0.485, 10.0);
    let b_hertz = (4.0 * weight * r / (std::f64::consts::PI * e / (1.0 - nu * nu))).sqrt();
    let b = m.contact_lengths(y).0;
    assert!(
        (b / b_hertz - 1.0).abs() < 0.05,
        "contact half-width {b:.4} µm, Hertz {b_hertz:.4} µm"
    );
}

// ---------------------------------------------------------------------------------------
// Observables: the paper's measures against hand-computed cases

/// The state with displacement `u(X)` at every node (velocities and μ_as zero).
fn prescribed_state(m: &CellModel, u: impl Fn(Vector2<f64>) -> [f64; 2]) -> Vec<f64> {
    let mut y = vec![0.0; m.size()];
    for (i, x) in m.mesh.nodes.iter().enumerate() {
        let d = u(Vector2::new(x[0], x[1]));
        for k in 0..2 {
            if m.dofs.u[i][k] != usize::MAX {
                y[m.dofs.u[i][k]] = d[k];
            }
        }
    }
    y
}

#[test]
fn contact_length_of_a_rigidly_sunk_cell_is_the_arc_below_the_band_in_both_frames() {
    // The flat reference scene (y_s = −2, ε_ct = 0.1, c = (0, 8.5), r_c = 10), every node
    // moved down by s: the boundary in contact is the arc with c_y − r_c cos φ − s < y_s +
    // ε_ct, of length r_c acos((c_y − s − y_s − ε_ct)/r_c) on the half cell, the same
    // along the deformed and the reference contour.
    let m = CellModel::new(scene::reference_params(), coarse_mesh()).unwrap();
    let (cy, rc, ys, eps) = (8.5, 10.0, -2.0, 0.1);
    assert_eq!(m.params.substrate, Substrate::Flat { y_s: ys });
    assert_eq!(m.params.contact.eps, eps);
    for s in [0.6, 1.0, 2.0] {
        let y = prescribed_state(&m, |_| [0.0, -s]);
        let o = m.observe(1.0, &y);
        let arc = rc * ((cy - s - ys - eps) / rc).acos();
        assert!(
            (o.contact_radius - arc).abs() < 1e-3 * arc,
            "sink {s}: deformed {} against {arc}",
            o.contact_radius
        );
        assert!(
            (o.contact_radius_ref - o.contact_radius).abs() < 1e-12 * arc,
            "sink {s}: reference {} against deformed {}",
            o.contact_radius_ref,
            o.contact_radius
        );
    }
}

#[test]
fn contact_length_under_a_horizontal_stretch_is_longer_in_the_deformed_frame() {
    // Sunk by 1 µm and stretched horizontally by λ about the symmetry line: the material
    // in the band is the arc near the bottom, almost horizontal, so the deformed length is
    // close to (and below) λ times the reference length; a compression λ < 1 the reverse.
    let m = CellModel::new(scene::reference_params(), coarse_mesh()).unwrap();
    for lambda in [1.5, 0.8] {
        let y = prescribed_state(&m, |p| [(lambda - 1.0) * p.x, -1.0]);
        let o = m.observe(1.0, &y);
        let ratio = o.contact_radius / o.contact_radius_ref;
        assert!(
            (ratio / lambda - 1.0).abs() < 0.02,
            "λ {lambda}: deformed/reference = {ratio}"
        );
        // The reference length is the rigid sink's: the same material is in the band
        // (the band criterion depends on the height, which the stretch does not change).
        let arc = 10.0 * ((8.5 - 1.0 + 2.0 - 0.1) / 10.0f64).acos();
        assert!((o.contact_radius_ref - arc).abs() < 1e-3 * arc);
    }
}

#[test]
fn strain_of_the_cytoplasm_includes_the_membrane_weighted_by_area() {
    let m = CellModel::new(scene::reference_params(), coarse_mesh()).unwrap();
    let c = Vector2::new(m.params.center[0], m.params.center[1]);
    let (rn, rcp, rc) = (5.0, 9.75, 10.0);
    // A homogeneous stretch λ along x: ‖E‖ = (λ² − 1)/2 in every domain.
    let lambda = 1.2f64;
    let e = (lambda * lambda - 1.0) / 2.0;
    let y = prescribed_state(&m, |p| [(lambda - 1.0) * (p.x - c.x), 0.0]);
    let o = m.observe(1.0, &y);
    for (name, v) in [
        ("nucleus", o.strain_nucleus),
        ("cytoplasm", o.strain_cytoplasm),
        ("membrane", o.strain_membrane),
    ] {
        assert!((v - e).abs() < 1e-12, "{name}: {v} against {e}");
    }
    // A homogeneous strain: its largest value is the mean, in every domain.
    for d in [Domain::Nucleus, Domain::Cytoplasm, Domain::Membrane] {
        let largest = m.largest_strain_norm(&y, d);
        assert!(
            (largest - e).abs() < 1e-12,
            "{d:?}: largest {largest} against {e}"
        );
    }
    // The same stretch on the membrane's nodes only (nodes of the cytoplasm and nucleus
    // elements do not move): the nucleus and the cytoplasm proper are unstrained, so the
    // paper's cytoplasm mean is the membrane's times its share of the area,
    // (r_c² − r_cp²)/(r_c² − r_n²) = 4.9375/75.
    let y = prescribed_state(&m, |p| {
        if (p - c).norm() > rcp + 1e-9 {
            [(lambda - 1.0) * (p.x - c.x), 0.0]
        } else {
            [0.0, 0.0]
        }
    });
    let o = m.observe(1.0, &y);
    assert_eq!(o.strain_nucleus, 0.0);
    assert_eq!(m.largest_strain_norm(&y, Domain::Nucleus), 0.0);
    // In the membrane the strain varies (its inner nodes are held): the largest value is
    // above the mean.
    let largest = m.largest_strain_norm(&y, Domain::Membrane);
    assert!(
        largest > o.strain_membrane,
        "{largest} against mean {}",
        o.strain_membrane
    );
    assert!(
        o.strain_membrane > 0.1 * e,
        "membrane {}",
        o.strain_membrane
    );
    let share = (rc * rc - rcp * rcp) / (rc * rc - rn * rn);
    let ratio = o.strain_cytoplasm / o.strain_membrane;
    assert!(
        (ratio / share - 1.0).abs() < 5e-4,
        "cytoplasm/membrane = {ratio}, area share {share}"
    );
    // The areas of the P2 mesh (curved edges on the circles) against the half rings'.
    let s = m.mean_strain_norms(&y);
    let half_ring = |a: f64, b: f64| std::f64::consts::FRAC_PI_2 * (b * b - a * a);
    for (k, (a, b)) in [(0.0, rn), (rn, rcp), (rcp, rc)].into_iter().enumerate() {
        let exact = half_ring(a, b);
        let err = s.area[k] / exact - 1.0;
        assert!(err.abs() < 5e-4, "area {k}: {} against {exact}", s.area[k]);
    }
}

#[test]
fn lowest_nucleus_displacement_is_taken_over_every_nucleus_node() {
    let m = CellModel::new(scene::reference_params(), coarse_mesh()).unwrap();
    let c = Vector2::new(m.params.center[0], m.params.center[1]);
    let rn = 5.0;
    // A dip of depth a centred on an interior nucleus node X0 off the symmetry line (not
    // p_t, c or p_b), and a larger downward displacement 5a outside the nucleus: the
    // answer is −a, at X0.
    let target = Vector2::new(2.0, 7.0);
    let x0 = m
        .mesh
        .nodes
        .iter()
        .map(|x| Vector2::new(x[0], x[1]))
        .filter(|x| (x - c).norm() < rn - 0.5)
        .min_by(|a, b| (a - target).norm().total_cmp(&(b - target).norm()))
        .unwrap();
    assert!(x0.x > 0.5, "X0 = {x0}");
    let a = 0.7;
    let y = prescribed_state(&m, |p| {
        if (p - c).norm() <= rn + 1e-9 {
            [0.0, -a * (-(p - x0).norm_squared() / 4.0).exp()]
        } else {
            [0.0, -5.0 * a]
        }
    });
    let o = m.observe(1.0, &y);
    assert_eq!(o.uy_nucleus_max, -a);
    assert!(o.uy_top > -a && o.uy_bottom > -a && o.uy_centre > -a);
    // Rigid translation: every point has the same displacement.
    let y = prescribed_state(&m, |_| [0.0, -1.25]);
    assert_eq!(m.observe(1.0, &y).uy_nucleus_max, -1.25);
}

#[test]
fn element_loops_give_the_same_bits_in_parallel() {
    // Residual and Jacobian with the element loops on rayon's pool and without.
    let mut m = CellModel::new(active_pillars_params(true), coarse_mesh()).unwrap();
    let (y, yp) = deformed_state(&m, 0.5, 11);
    let t = 45_000.0;
    let n = m.size();
    let nnz = m.pattern().compute_nnz();
    let mut out = Vec::new();
    for parallel in [false, true] {
        m.set_parallel(parallel);
        let (mut r, mut j) = (vec![0.0; n], vec![0.0; nnz]);
        m.residual(State::new(t, &y, &yp), &mut r).unwrap();
        m.jacobian(State::new(t, &y, &yp), 37.0, &mut j).unwrap();
        out.push((r, j));
    }
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&out[0].0), bits(&out[1].0));
    assert_eq!(bits(&out[0].1), bits(&out[1].1));
}

/// The model remembers the element its last evaluation found inverted (what a run that
/// gives up reports as its place), and forgets it after an evaluation that succeeds.
#[test]
fn the_last_inverted_element_is_remembered_with_its_place() {
    let yeoh = Yeoh::from_engineering(500.0, 0.485, 0.1, 0.2).unwrap();
    let mut m = CellModel::new(unloaded(false, [yeoh; 3]), coarse_mesh()).unwrap();
    let n = m.size();
    let (rest, yp) = (vec![0.0; n], vec![0.0; n]);
    let mut r = vec![0.0; n];
    m.residual(State::new(1.0, &rest, &yp), &mut r).unwrap();
    assert!(m.last_inadmissible().is_none());
    // Every element mirrored: element 0 is the first the loop meets.
    let f0 = Matrix2::new(-1.0, 0.0, 0.0, 1.0);
    let y = homogeneous_state(&m, &f0);
    let err = m.residual(State::new(2.0, &y, &yp), &mut r).unwrap_err();
    assert!(err.to_string().contains("det F"), "{err}");
    let (why, domain, x) = m.last_inadmissible().expect("an inverted element").clone();
    let cellsim::dae::Inadmissible::Element {
        t, element, value, ..
    } = why
    else {
        panic!("not an element: {why}");
    };
    assert_eq!((t, element), (2.0, 0));
    assert!(value <= 0.0);
    assert_eq!(domain, m.mesh.domains[0]);
    // The centroid of its six nodes, mirrored about the vertical through the centre.
    let c = m.params.center;
    let nodes = m.mesh.elements[0];
    let mean = |k: usize| nodes.iter().map(|&i| m.mesh.nodes[i][k]).sum::<f64>() / 6.0;
    assert!((x[0] - (2.0 * c[0] - mean(0))).abs() < 1e-12, "{x:?}");
    assert!((x[1] - mean(1)).abs() < 1e-12, "{x:?}");
    m.residual(State::new(3.0, &rest, &yp), &mut r).unwrap();
    assert!(m.last_inadmissible().is_none());
}
