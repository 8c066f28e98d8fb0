//! SUNDIALS' idaAnalytic_mels problem (Ascher & Petzold 10.2, x₁ = eᵗ, x₂ = eᵗ/(t − 2))
//! through cellsim's IDA driver, with the error at t = 1 and the statistics.
//!
//! `cargo run --release --example analytic [-- RTOL ATOL [suppress]]`

use cellsim::dae::problems::Analytic;
use cellsim::dae::{Atol, Integrator};
use cellsim::sundials::{Ida, IdaOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let rtol: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(1e-4);
    let atol: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1e-9);
    let suppress = args.iter().any(|a| a == "suppress");
    let opts = IdaOptions {
        rtol,
        atol: Atol::Scalar(atol),
        suppress_alg: suppress,
        ..Default::default()
    };
    let mut ida = Ida::new(Analytic::new(10.0), opts).unwrap_or_else(|e| {
        eprintln!("analytic: {e}");
        std::process::exit(1)
    });
    println!("        t          x1         x2");
    for k in 1..=10 {
        let t = 0.1 * k as f64;
        if let Err(e) = ida.advance_to(t, &mut |_, _| true) {
            eprintln!("analytic: {e}");
            std::process::exit(1);
        }
        println!("  {t:10.6}  {:10.6}  {:10.6}", ida.y()[0], ida.y()[1]);
    }
    let (exact, _) = Analytic::exact(1.0);
    println!(
        "error at t = 1: x1 {:.3e}, x2 {:.3e}",
        ida.y()[0] - exact[0],
        ida.y()[1] - exact[1]
    );
    println!("{:?}", ida.stats());
}
