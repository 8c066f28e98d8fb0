//! faer's sequential supernodal LU against SUNDIALS' KLU (AMD ordering) on the iteration
//! matrix J = ∂F/∂y + cj ∂F/∂ẏ of the idaHeat2D DAE (5-point Laplacian, algebraic
//! boundary rows), at one or more grid sizes: symbolic analysis and first
//! factorization once, then numeric factorization repeated (median of the repetitions), and the solutions compared.
//!
//! `cargo run --release --example lu_compare [-- M1 M2 ...]` (default grids 100 and 300:
//! 10 000 and 90 000 unknowns). The two backends are timed in the same run, alternately,
//! so their ratio is meaningful on a shared machine.

use cellsim::dae::State;
use std::time::Instant;

use cellsim::dae::Dae;
use cellsim::dae::problems::Heat2D;
use cellsim::solver::LinearSolver;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let grids: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let grids = if grids.is_empty() {
        vec![100, 300]
    } else {
        grids
    };
    const REPS: usize = 15;
    println!(
        "grid  unknowns       nnz   backend  analyse+1st[ms]  factorize[ms]  solve[ms]  max|x-x_faer|"
    );
    for m in grids {
        let mut dae = Heat2D::new(m, 0.0);
        let n = dae.size();
        let (t0, y, yp) = dae.initial();
        let pattern = dae.pattern().clone();
        let mut values = vec![0.0; pattern.compute_nnz()];
        // cj of a typical mid-run step (h ≈ 1e-2 at order 2).
        let cj = 150.0;
        dae.jacobian(State::new(t0, &y, &yp), cj, &mut values)
            .expect("heat2d jacobian");
        let b: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 1000) as f64 / 1000.0 - 0.5)
            .collect();
        let kinds = [LinearSolver::Faer, LinearSolver::Klu];
        let mut solvers: Vec<_> = kinds.iter().map(|k| k.build()).collect();
        let mut analyse = [0.0; 2];
        for (k, s) in solvers.iter_mut().enumerate() {
            let t0 = Instant::now();
            s.analyse(&pattern).expect("analyse");
            analyse[k] = t0.elapsed().as_secs_f64() * 1e3;
        }
        let mut fact = [Vec::new(), Vec::new()];
        let mut solve = [Vec::new(), Vec::new()];
        let mut x = [b.clone(), b.clone()];
        // SUNDIALS' KLU runs its symbolic analysis inside the first factorization:
        // the first one is counted with the analysis, the median is over the others.
        for rep in 0..=REPS {
            for (k, s) in solvers.iter_mut().enumerate() {
                let t0 = Instant::now();
                s.factorize(&values).expect("factorize");
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                if rep == 0 {
                    analyse[k] += ms;
                    continue;
                }
                fact[k].push(ms);
                x[k].copy_from_slice(&b);
                let t0 = Instant::now();
                s.solve_in_place(&mut x[k]).expect("solve");
                solve[k].push(t0.elapsed().as_secs_f64() * 1e3);
            }
        }
        let diff = x[0]
            .iter()
            .zip(&x[1])
            .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
        for (k, s) in solvers.iter().enumerate() {
            println!(
                "{m:4}  {n:8}  {:8}  {:>7}  {:15.2}  {:13.2}  {:9.3}  {:.1e}",
                values.len(),
                s.name(),
                analyse[k],
                median(fact[k].clone()),
                median(solve[k].clone()),
                if k == 0 { 0.0 } else { diff }
            );
        }
        println!(
            "      KLU / faer numeric factorization time: {:.2}",
            median(fact[1].clone()) / median(fact[0].clone())
        );
    }
}
