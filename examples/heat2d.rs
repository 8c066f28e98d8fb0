//! SUNDIALS' idaHeat2D example (10 × 10 grid, algebraic boundary rows, IDACalcIC,
//! constraints u ≥ 0) through cellsim's IDA driver, printed in the layout of SUNDIALS'
//! `idaHeat2D_klu.out`.
//!
//! `cargo run --release --example heat2d [-- --klu] [--atol A] [--boundary B] [--grid M]`

use cellsim::dae::problems::Heat2D;
use cellsim::dae::{Atol, Integrator};
use cellsim::solver::LinearSolver;
use cellsim::sundials::{CalcIc, Ida, IdaOptions};

fn arg(name: &str, default: f64) -> f64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let klu = std::env::args().any(|a| a == "--klu");
    let (atol, bval, m) = (
        arg("--atol", 1e-8),
        arg("--boundary", 0.0),
        arg("--grid", 10.0) as usize,
    );
    let dae = Heat2D::new(m, bval);
    let opts = IdaOptions {
        rtol: 0.0,
        atol: Atol::Scalar(atol),
        linear_solver: if klu {
            LinearSolver::Klu.into()
        } else {
            LinearSolver::Faer.into()
        },
        calc_ic: Some(CalcIc::AlgebraicAndDerivatives { tout1: 0.01 }),
        constraints: Some(dae.constraints()),
        ..Default::default()
    };
    let mut ida = Ida::new(dae, opts).unwrap_or_else(|e| {
        eprintln!("heat2d: {e}");
        std::process::exit(1)
    });
    println!(
        "\nidaHeat2D: Heat equation, {m} x {m} grid, rtol = 0, atol = {atol}, boundary guesses = {bval}"
    );
    println!(
        "Linear solver: {}\n",
        if klu {
            "KLU (SUNDIALS)"
        } else {
            "faer sparse LU"
        }
    );
    println!("  time       umax     k  nst  nni  nje   nre     h       ");
    let s = ida.stats();
    let umax = ida.y().iter().fold(0.0f64, |a, v| a.max(v.abs()));
    println!(
        " {:5.2} {umax:13.5e}  {}  {:3}  {:3}  {:3}  {:4}  {:9.2e} ",
        0.0, s.last_order, s.steps, s.newton_iters, s.jacobian_evals, s.residual_evals, s.last_step
    );
    let mut tout = 0.01;
    for _ in 0..11 {
        if let Err(e) = ida.advance_to(tout, &mut |_, _| true) {
            eprintln!("heat2d: {e}");
            std::process::exit(1);
        }
        let s = ida.stats();
        let umax = ida.y().iter().fold(0.0f64, |a, v| a.max(v.abs()));
        println!(
            " {tout:5.2} {umax:13.5e}  {}  {:3}  {:3}  {:3}  {:4}  {:9.2e} ",
            s.last_order, s.steps, s.newton_iters, s.jacobian_evals, s.residual_evals, s.last_step
        );
        tout *= 2.0;
    }
    let s = ida.stats();
    println!(
        "\n netf = {},   ncfn = {} ",
        s.error_test_failures, s.newton_failures
    );
}
