//! SUNDIALS' idaRoberts example through cellsim's IDA driver (faer sparse LU, or KLU with
//! `--klu`), printed in the layout of SUNDIALS' `idaRoberts_dns.out`. With `--roots`, the
//! example's root functions y₁ − 1e-4 and y₃ − 0.01 as well: a row at each root and its
//! `rootsfound[]` line, as the published output prints them.
//!
//! `cargo run --release --example robertson [-- --klu] [--roots]`

use cellsim::dae::problems::{Robertson, WithRoots};
use cellsim::dae::{Atol, Dae, Integrator};
use cellsim::solver::LinearSolver;
use cellsim::sundials::{Ida, IdaOptions};

fn main() {
    let klu = std::env::args().any(|a| a == "--klu");
    let roots = std::env::args().any(|a| a == "--roots");
    let (rtol, atol) = (1.0e-4, [1.0e-8, 1.0e-6, 1.0e-6]);
    let opts = IdaOptions {
        rtol,
        atol: Atol::Vector(atol.to_vec()),
        linear_solver: if klu {
            LinearSolver::Klu.into()
        } else {
            LinearSolver::Faer.into()
        },
        ..Default::default()
    };
    let dae: Box<dyn Dae> = if roots {
        Box::new(WithRoots::robertson())
    } else {
        Box::new(Robertson::new())
    };
    let mut ida = match Ida::new(dae, opts) {
        Ok(ida) => ida,
        Err(e) => {
            eprintln!("robertson: {e}");
            std::process::exit(1);
        }
    };
    println!("\nidaRoberts: Robertson kinetics DAE serial example problem for IDA");
    println!("         Three equation chemical kinetics problem.\n");
    println!(
        "Linear solver: {}, with user-supplied Jacobian.",
        if klu {
            "KLU (SUNDIALS)"
        } else {
            "faer sparse LU"
        }
    );
    println!(
        "Tolerance parameters:  rtol = {rtol}   atol = {} {} {} ",
        atol[0], atol[1], atol[2]
    );
    println!("Initial conditions y0 = (1 0 0)");
    println!("Constraints and id not used.\n");
    let rule = "-----------------------------------------------------------------------";
    println!("{rule}\n  t             y1           y2           y3      | nst  k      h\n{rule}");
    let mut tout = 0.4;
    let mut printed = 0;
    while printed < 12 {
        if let Err(e) = ida.advance_to(tout, &mut |_, _| true) {
            eprintln!("robertson: {e}");
            std::process::exit(1);
        }
        let (y, s) = (ida.y(), ida.stats());
        println!(
            "{} {} {} {} | {:3}  {} {}",
            sci(ida.t(), 10),
            sci(y[0], 12),
            sci(y[1], 12),
            sci(y[2], 12),
            s.steps,
            s.last_order,
            sci(s.last_step, 12)
        );
        match ida.root() {
            Some(r) => {
                let found: Vec<String> = r.crossings.iter().map(|c| format!("{c:3}")).collect();
                println!("    rootsfound[] = {}", found.join(" "));
            }
            None => {
                tout *= 10.0;
                printed += 1;
            }
        }
    }
    let s = ida.stats();
    println!("\nFinal Run Statistics: \n");
    println!("Number of steps                    = {}", s.steps);
    println!("Number of residual evaluations     = {}", s.residual_evals);
    println!("Number of Jacobian evaluations     = {}", s.jacobian_evals);
    println!(
        "Number of LU factorizations        = {}",
        s.lu_factorizations
    );
    println!("Number of nonlinear iterations     = {}", s.newton_iters);
    println!(
        "Number of error test failures      = {}",
        s.error_test_failures
    );
    println!("Number of nonlinear conv. failures = {}", s.newton_failures);
}

/// C's `%W.4e`: four decimals, at least two exponent digits, right-aligned in `width`.
fn sci(v: f64, width: usize) -> String {
    let s = format!("{v:.4e}");
    let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
    let e: i32 = e.parse().unwrap_or(0);
    let t = format!("{m}e{}{:02}", if e < 0 { '-' } else { '+' }, e.abs());
    format!("{t:>width$}")
}
