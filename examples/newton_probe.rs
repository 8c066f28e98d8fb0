//! Newton's method from a run's written state, one backward-Euler step at a time: whether
//! the residual lets Newton converge there, and how (the update's and the residual's
//! norms at each iteration), with a fresh Jacobian at every iteration and with the first
//! one kept (IDA's modified Newton).
//!
//! `cargo run --release --example newton_probe -- CASE STATE [--set FIELD=VALUE ...]`
//! with `STATE` a state file of a half-plane run without inertia (`state_stopped.json`,
//! `state_spreading.json`, …; its run's `mesh.json` beside it) and the case and overrides
//! it ran with. From y₀ (the state's
//! u and μ_as) it solves F(t + h, y, (y − y₀)/h) = 0 for h = 10, 1, 0.1, 1e-2, 1e-3, 1e-4 s,
//! starting at y = y₀, and prints per iteration the weighted RMS norm of the update
//! (IDA's weights at rtol 1e-3, atol 1e-6: converged below 0.33 in IDA's test) and the
//! largest residual entry. With `PROBE_SPLIT=1` in the environment each iteration also
//! names the node of the largest displacement update (its current position) and gives
//! the u and μ_as blocks' own norms.

use std::path::Path;

use cellsim::case::{Case, Override};
use cellsim::dae::linsolve::{FaerFactory, LinearSolverFactory};
use cellsim::dae::{Atol, Dae, State, error_weights, wrms_norm};
use cellsim::fem::Mesh;
use cellsim::model::CellModel;
use cellsim::model::dofs::NONE;
use cellsim::run_files::read::{read_mesh, read_state};
use cellsim::scene;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (case_file, state_file) = match (args.first(), args.get(1)) {
        (Some(c), Some(s)) => (c.clone(), s.clone()),
        _ => return Err("usage: newton_probe CASE STATE [--set FIELD=VALUE ...]".into()),
    };
    let overrides: Vec<Override> = args[2..]
        .chunks(2)
        .filter(|c| c[0] == "--set")
        .map(|c| Override::parse(&c[1]).map_err(|e| e.to_string()))
        .collect::<Result<_, _>>()?;
    let case = Case::load_with_overrides(&case_file, &overrides).map_err(|e| e.to_string())?;
    let mesh = Mesh::generate(&scene::mesh_params(&case)).map_err(|e| e.to_string())?;
    let params = scene::model_params(&case, &case_file, false).map_err(|e| e.to_string())?;
    let mut m = CellModel::new(params, mesh).map_err(|e| e.to_string())?;
    let state_path = Path::new(&state_file);
    let mesh_file =
        read_mesh(&state_path.with_file_name("mesh.json")).map_err(|e| e.to_string())?;
    let s = read_state(state_path, &mesh_file).map_err(|e| e.to_string())?;
    let n = m.size();
    let mut y0 = vec![0.0; n];
    for (i, u) in s.u.iter().enumerate() {
        for (k, &uk) in u.iter().enumerate() {
            let d = m.dofs.u[i][k];
            if d != NONE {
                y0[d] = uk;
            }
        }
        let d = m.dofs.mu[i];
        if d != NONE {
            y0[d] = s.mu_as[i].unwrap_or(0.0);
        }
    }
    let mut w = vec![0.0; n];
    error_weights(&y0, 1e-3, &Atol::Scalar(1e-6), &mut w);
    let pattern = m.pattern().clone();
    let nnz = pattern.compute_nnz();
    let factory = FaerFactory;
    for keep in [false, true] {
        println!(
            "t = {} s, {} Jacobian{}",
            s.t,
            if keep { "the first" } else { "a fresh" },
            if keep { " kept" } else { " at every iteration" }
        );
        for h in [10.0, 1.0, 0.1, 1e-2, 1e-3, 1e-4] {
            let mut solver = factory.build_for(&m).map_err(|e| e.to_string())?;
            solver.analyse(&pattern).map_err(|e| e.to_string())?;
            let mut y = y0.clone();
            let mut jac = vec![0.0; nnz];
            let mut r = vec![0.0; n];
            let mut line = format!("  h = {h:e}:");
            for it in 1..=12 {
                let yp: Vec<f64> = y.iter().zip(&y0).map(|(a, b)| (a - b) / h).collect();
                let at = State::new(s.t + h, &y, &yp);
                if let Err(e) = m.residual(at, &mut r) {
                    line += &format!(" [{it}: {e}]");
                    break;
                }
                let rmax = r.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                if it == 1 || !keep {
                    m.jacobian(at, 1.0 / h, &mut jac)
                        .map_err(|e| e.to_string())?;
                    solver.factorize(&jac).map_err(|e| e.to_string())?;
                }
                r.iter_mut().for_each(|v| *v = -*v);
                solver.solve_in_place(&mut r).map_err(|e| e.to_string())?;
                y.iter_mut().zip(&r).for_each(|(a, d)| *a += d);
                let dn = wrms_norm(&r, &w);
                if std::env::var("PROBE_SPLIT").is_ok() {
                    let off = m.dofs.mu_offset();
                    let (ru, rm) = r.split_at(off);
                    let (wu, wm) = w.split_at(off);
                    let mx = |d: &[f64]| d.iter().fold(0.0f64, |a, b| a.max(b.abs()));
                    let (imax, _) = ru.iter().enumerate().fold((0, 0.0f64), |a, (i, v)| {
                        if v.abs() > a.1 { (i, v.abs()) } else { a }
                    });
                    let node = (0..m.dofs.u.len()).find(|&i| m.dofs.u[i].contains(&imax));
                    if let Some(i) = node {
                        let x = m.mesh.nodes[i];
                        let u = &s.u[i];
                        line += &format!(" @node {i} ({:.2},{:.2})", x[0] + u[0], x[1] + u[1]);
                    }
                    line += &format!(
                        " (u {:.1e} max {:.1e}; mu {:.1e} max {:.1e})",
                        wrms_norm(ru, wu),
                        mx(ru),
                        wrms_norm(rm, wm),
                        mx(rm)
                    );
                }
                line += &format!(" {dn:.1e}|{rmax:.0e}");
                if dn < 1e-6 {
                    break;
                }
            }
            println!("{line}");
        }
    }
    Ok(())
}
