//! The linear solvers on the cell model's own iteration matrices: the condensed solve of
//! the (u, v) system against the full-size LUs, and IDA with either on an inertial fall.

use cellsim::case::Case;
use cellsim::dae::State;
use cellsim::dae::bdf2::{Bdf2, Bdf2Options};
use cellsim::dae::linsolve::LinearSolverError;
use cellsim::dae::{Atol, Dae, Integrator, IntegratorError, Pattern};
use cellsim::fem::Mesh;
use cellsim::solver::LinearSolver;

use cellsim::model::CellModel;
use cellsim::scene;
use cellsim::sundials::{Ida, IdaOptions};

fn pillars_model(inertia: bool) -> CellModel {
    CellModel::new(
        crate::model::active_pillars_params(inertia),
        crate::model::coarse_mesh(),
    )
    .unwrap()
}

/// The cell sunk 0.5 µm into the pillars (contact and adhesion bands active), with a
/// smooth random deformation, random velocities and μ_as.
fn deformed_state(m: &CellModel, seed: u64) -> (Vec<f64>, Vec<f64>) {
    crate::model::deformed_state(m, 0.5, seed)
}

fn matvec(p: &Pattern, v: &[f64], x: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; x.len()];
    for j in 0..x.len() {
        for k in p.col_ptr()[j]..p.col_ptr()[j + 1] {
            y[p.row_idx()[k]] += v[k] * x[j];
        }
    }
    y
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|a| a * a).sum::<f64>().sqrt()
}

fn solve(kind: LinearSolver, m: &CellModel, values: &[f64], b: &[f64]) -> Vec<f64> {
    let mut s = kind.build_for(m).unwrap();
    s.analyse(m.pattern()).unwrap();
    s.factorize(values).unwrap();
    let mut x = b.to_vec();
    s.solve_in_place(&mut x).unwrap();
    x
}

#[test]
fn condensed_solve_matches_the_full_lu_on_the_cell_jacobian() {
    let mut m = pillars_model(true);
    let (y, yp) = deformed_state(&m, 11);
    // In the active phase (gravity, adhesion, active strain on) and really in contact.
    let t = 45_000.0;
    assert!(
        m.contact_force_total(&y).y > 1e-3,
        "no contact in the test state"
    );
    let n = m.size();
    let pattern = m.pattern().clone();
    let mut values = vec![0.0; pattern.compute_nnz()];
    let mut rng = oorandom::Rand64::new(5);
    // cj from IDA's range on the scenes: 1/h for h from 1e-6 s (the fall) to 100 s.
    let cjs: Vec<f64> = [1e-2, 0.3, 10.0, 3e2, 1e4, 3e5]
        .iter()
        .map(|c| c * (1.0 + 2.0 * rng.rand_float()))
        .collect();
    for &cj in &cjs {
        m.jacobian(State::new(t, &y, &yp), cj, &mut values).unwrap();
        // A right-hand side with every block populated, at the scales of a Newton
        // residual (velocity rows large where cj is).
        let b: Vec<f64> = (0..n).map(|_| rng.rand_float() - 0.5).collect();
        let full = solve(LinearSolver::Faer, &m, &values, &b);
        let klu = solve(LinearSolver::Klu, &m, &values, &b);
        let cond = solve(LinearSolver::FaerCondensed, &m, &values, &b);
        // The same condensation factorized by UMFPACK without refinement.
        let cond_u = solve(LinearSolver::UmfpackCondensed, &m, &values, &b);
        let du: Vec<f64> = full.iter().zip(&cond_u).map(|(a, c)| a - c).collect();
        let rel_u = norm(&du) / norm(&full);
        assert!(
            rel_u < 1e-7,
            "cj = {cj:.3e}: condensed UMFPACK differs by {rel_u:.2e}"
        );
        let diff: Vec<f64> = full.iter().zip(&cond).map(|(a, c)| a - c).collect();
        let rel = norm(&diff) / norm(&full);
        // Residual of the condensed solution in J's own scale.
        let r: Vec<f64> = matvec(&pattern, &values, &cond)
            .iter()
            .zip(&b)
            .map(|(a, c)| a - c)
            .collect();
        let jmax = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let xmax = cond.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let res = r.iter().fold(0.0f64, |a, v| a.max(v.abs())) / (jmax * xmax);
        // The two full LUs differ by round-off amplified by J's condition (measured
        // 3e-12 to 3e-9 over these cj); the condensed solution is as close to faer's
        // (measured 1e-12 to 1.5e-8, largest at cj ~ 2e4), and its backward error is at
        // round-off (measured ≤ 8e-17).
        let kd: Vec<f64> = full.iter().zip(&klu).map(|(a, c)| a - c).collect();
        let rel_klu = norm(&kd) / norm(&full);
        eprintln!(
            "cj = {cj:.3e}: |x_full - x_cond|/|x_full| = {rel:.2e} (faer vs klu {rel_klu:.2e}), \
             scaled residual {res:.2e}"
        );
        assert!(rel < 1e-7, "cj = {cj:.3e}: condensed differs by {rel:.2e}");
        assert!(
            rel_klu < 1e-7,
            "cj = {cj:.3e}: KLU differs by {rel_klu:.2e}"
        );
        assert!(res < 1e-14, "cj = {cj:.3e}: scaled residual {res:.2e}");
    }
}

#[test]
fn every_backend_and_ordering_solves_the_cell_jacobian() {
    // Without inertia (u, μ_as) and with it (u, v, μ_as: the full-size LUs), at a state
    // in contact, for a small and a large cj.
    for inertia in [false, true] {
        let mut m = pillars_model(inertia);
        let (y, yp) = deformed_state(&m, 3);
        let pattern = m.pattern().clone();
        let mut values = vec![0.0; pattern.compute_nnz()];
        let mut rng = oorandom::Rand64::new(17);
        for cj in [0.1, 1e4] {
            m.jacobian(State::new(45_000.0, &y, &yp), cj, &mut values)
                .unwrap();
            let b: Vec<f64> = (0..m.size()).map(|_| rng.rand_float() - 0.5).collect();
            let reference = solve(LinearSolver::Faer, &m, &values, &b);
            for kind in [
                LinearSolver::Klu,
                LinearSolver::KluMetis,
                LinearSolver::Umfpack,
                LinearSolver::UmfpackNd,
            ] {
                let x = solve(kind, &m, &values, &b);
                let d: Vec<f64> = x.iter().zip(&reference).map(|(a, c)| a - c).collect();
                let rel = norm(&d) / norm(&reference);
                // Scaled residual |Jx − b| / (|J| |x|): round-off.
                let r: Vec<f64> = matvec(&pattern, &values, &x)
                    .iter()
                    .zip(&b)
                    .map(|(a, c)| a - c)
                    .collect();
                let jmax = values.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let xmax = x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let res = r.iter().fold(0.0f64, |a, v| a.max(v.abs())) / (jmax * xmax);
                eprintln!(
                    "inertia {inertia}, cj {cj:.0e}, {kind:?}: |x - x_faer|/|x_faer| = \
                     {rel:.1e}, scaled residual {res:.1e}"
                );
                assert!(rel < 1e-7, "{kind:?}: differs from faer by {rel:.2e}");
                // Every backend at round-off, UMFPACK on METIS's ordering without
                // iterative refinement too (measured ≤ 5.5e-17; with AMD and the
                // unsymmetric strategy it left 2.4e-14).
                assert!(res < 1e-14, "{kind:?}: scaled residual {res:.2e}");
            }
        }
    }
}

#[test]
fn condensed_solver_refuses_a_system_without_velocities() {
    let m = pillars_model(false);
    assert!(m.first_order_blocks().is_none());
    assert!(matches!(
        LinearSolver::FaerCondensed.build_for(&m),
        Err(LinearSolverError::Unsupported(_))
    ));
    // Through IDA: a clear error naming the solver, not a crash.
    let opts = IdaOptions {
        linear_solver: LinearSolver::FaerCondensed.into(),
        ..Default::default()
    };
    match Ida::new(m, opts) {
        Err(IntegratorError::Linear {
            source: LinearSolverError::Unsupported(msg),
            ..
        }) => {
            assert!(msg.contains("faer-condensed"), "{msg}")
        }
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("IDA accepted the condensed solver without velocities"),
    }
    assert_eq!(
        LinearSolver::FaerCondensed.uncondensed(),
        LinearSolver::Faer
    );
}

/// The model of `cases/fast/flat-gravity.ron` with inertia (u, v unknowns) throughout.
fn flat_gravity_with_inertia() -> (Case, CellModel) {
    let file = format!("{}/cases/fast/flat-gravity.ron", env!("CARGO_MANIFEST_DIR"));
    let case = Case::load(&file).unwrap();
    let mesh = Mesh::generate(&scene::mesh_params(&case)).unwrap();
    let model = CellModel::new(scene::model_params(&case, &file, true).unwrap(), mesh).unwrap();
    (case, model)
}

/// One output of the inertial fall: time, steps and LU factorizations so far, y.
struct Output {
    t: f64,
    steps: u64,
    lus: u64,
    y: Vec<f64>,
}

/// IDA on [`flat_gravity_with_inertia`] with the case's tolerances, outputs every second.
fn inertial_fall(kind: LinearSolver, t_end: f64) -> Vec<Output> {
    let (case, model) = flat_gravity_with_inertia();
    let opts = IdaOptions {
        rtol: case.solver.rtol,
        atol: Atol::Vector(model.atol_vector(case.solver.atol)),
        linear_solver: kind.into(),
        ..Default::default()
    };
    let mut ida = Ida::new(model, opts).unwrap();
    let mut out = Vec::new();
    let mut t = 0.0;
    while t < t_end {
        t += 1.0;
        ida.advance_to(t, &mut |_, _| true).unwrap();
        let s = ida.stats();
        out.push(Output {
            t,
            steps: s.steps,
            lus: s.lu_factorizations,
            y: ida.y().to_vec(),
        });
    }
    out
}

#[test]
fn ida_with_the_condensed_solver_follows_the_full_lu_through_a_fall_and_landing() {
    // The fall reaches the contact band at ≈ 9.6 s; to 12 s covers the landing and the
    // first bounce, with inertia on throughout.
    let (_, model) = flat_gravity_with_inertia();
    let n_u = model.dofs.n_u;
    let full = inertial_fall(LinearSolver::Faer, 12.0);
    let cond = inertial_fall(LinearSolver::FaerCondensed, 12.0);
    for (f, c) in full.iter().zip(&cond) {
        let du = f.y[..n_u]
            .iter()
            .zip(&c.y[..n_u])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0f64, f64::max);
        let umax = f.y[..n_u].iter().fold(0.0f64, |a, v| a.max(v.abs()));
        if f.t <= 9.0 {
            // The free fall: the same steps, the same factorizations, the same state up
            // to round-off (measured |Δu| ≤ 6e-9 µm; atol is 1e-6 µm).
            assert_eq!(
                (f.steps, f.lus),
                (c.steps, c.lus),
                "t = {}: (steps, LUs) differ",
                f.t
            );
            assert!(du < 1e-7, "t = {}: |Δu| = {du:.2e} µm", f.t);
        } else {
            // Contact: round-off now moves IDA's step choices by a step or two (as does
            // swapping faer's LU for KLU's: measured 114 against 112 steps, 41 against 47
            // LUs at 12 s), so the paths differ at the level of the integration error:
            // |Δu| within 10 rtol of the displacement (measured ≤ 1e-4 µm, 0.4 ‰).
            assert!(
                du < 1e-3 * umax,
                "t = {}: |Δu| = {du:.2e} µm for |u| up to {umax:.3} µm",
                f.t
            );
        }
    }
    let (f, c) = (full.last().unwrap(), cond.last().unwrap());
    let close = |a: u64, b: u64, frac: f64| (a as f64 - b as f64).abs() <= frac * a.max(b) as f64;
    assert!(
        close(f.steps, c.steps, 0.05) && close(f.lus, c.lus, 0.1),
        "at 12 s: steps {} vs {}, LUs {} vs {}",
        f.steps,
        c.steps,
        f.lus,
        c.lus
    );
    // And the cell did land: the lowest displacement, −0.34 µm at 10 s, is back up to
    // −0.22 µm at 11 s, which only the contact can do against gravity (the cell bounces,
    // in the air at each of these output times).
    let lowest = |o: &Output| o.y[..n_u].iter().fold(0.0f64, |a, v| a.min(*v));
    let (at10, at11) = (lowest(&cond[9]), lowest(&cond[10]));
    assert!(
        at10 < -0.3 && at11 > at10 + 0.05,
        "no bounce: lowest u {at10:.3} µm at 10 s, {at11:.3} µm at 11 s"
    );
}

#[test]
fn bdf2_takes_the_same_steps_with_either_solver() {
    // Fixed steps: the two runs differ only by the linear solves' round-off.
    let run = |kind: LinearSolver| {
        let (case, model) = flat_gravity_with_inertia();
        let opts = Bdf2Options {
            dt: 0.25,
            rtol: case.solver.rtol,
            atol: Atol::Vector(model.atol_vector(case.solver.atol)),
            linear_solver: kind.into(),
            ..Default::default()
        };
        let mut b = Bdf2::new(model, opts).unwrap();
        b.advance_to(4.0, &mut |_, _| true).unwrap();
        (b.stats(), b.y().to_vec())
    };
    let (sf, yf) = run(LinearSolver::Faer);
    let (sc, yc) = run(LinearSolver::FaerCondensed);
    assert_eq!(
        (sf.steps, sf.newton_iters, sf.lu_factorizations),
        (sc.steps, sc.newton_iters, sc.lu_factorizations)
    );
    let d: Vec<f64> = yf.iter().zip(&yc).map(|(a, b)| a - b).collect();
    let rel = norm(&d) / norm(&yf);
    assert!(rel < 1e-9, "BDF2 states differ by {rel:.2e}");
    // The cell has fallen (a few nm by 4 s under the ramped gravity).
    assert!(yf.iter().any(|v| *v < -1e-3));
}
