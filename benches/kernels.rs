//! The kernels of one IDA step on the default scene's model (`cases/pillars-push-pull.ron`:
//! pillars, adhesion μ_as unknowns, both active regions) at three mesh refinements
//! (`mesh.refine` 0.5, 1 = the default, 2, 4): residual, Jacobian assembly, symbolic and
//! numeric LU and the solve with faer, KLU and KLU on the nested-dissection ordering, and, on the same model with inertia
//! (unknowns u, v, μ_as), the full-size LU against the condensed one (velocities
//! eliminated, `faer-condensed`).
//!
//! Each benchmark's parameter is the number of unknowns n of its system, so that
//! `scripts/bench_table.py` can fit cost ∝ n^α per kernel. The state is the cell at rest
//! translated 0.5 µm down into the pillars' contact band, with a smooth deformation, at
//! t = 45 000 s (gravity, adhesion and active strain all on), and cj = 1/(10 s) (no
//! inertia) or 1/(10 ms) (inertia, as during the fall).
//!
//! `cargo bench --features bench --bench kernels`

use cellsim::dae::State;
use std::hint::black_box;
use std::time::Duration;

use cellsim::dae::{Dae, LinearSolver};
use cellsim::solver;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

const REFINES: [f64; 4] = [0.5, 1.0, 2.0, 4.0];
const T: f64 = 45_000.0;

#[path = "support/mod.rs"]
mod support;
use support::{model, state};

/// Benchmarks `{prefix}lu-numeric-{name}` (factorize `vals`) and `{prefix}lu-solve-{name}`
/// (solve with `rhs`) of an analysed solver, parameter n = `rhs.len()`.
fn bench_numeric_and_solve(
    c: &mut Criterion,
    prefix: &str,
    s: &mut Box<dyn LinearSolver>,
    vals: &[f64],
    rhs: &[f64],
) {
    let (name, n) = (s.name(), rhs.len());
    let id = format!("{prefix}lu-numeric-{name}");
    let mut g = c.benchmark_group(&id);
    g.bench_with_input(BenchmarkId::new(&id, n), &n, |b, _| {
        b.iter(|| s.factorize(black_box(vals)).unwrap())
    });
    g.finish();
    s.factorize(vals).unwrap();
    let mut x = rhs.to_vec();
    let id = format!("{prefix}lu-solve-{name}");
    let mut g = c.benchmark_group(&id);
    g.bench_with_input(BenchmarkId::new(&id, n), &n, |b, _| {
        b.iter(|| {
            x.copy_from_slice(rhs);
            s.solve_in_place(black_box(&mut x)).unwrap()
        })
    });
    g.finish();
}

fn kernels(c: &mut Criterion) {
    for &refine in &REFINES {
        let mut m = model(refine, false);
        let n = m.size();
        let (y, yp) = state(&m);
        let mut r = vec![0.0; n];
        let nnz = m.pattern().compute_nnz();
        let mut vals = vec![0.0; nnz];
        eprintln!("refine {refine}: n = {n}, nnz(J) = {nnz}");
        let mut g = c.benchmark_group("residual");
        g.bench_with_input(BenchmarkId::new("residual", n), &n, |b, _| {
            b.iter(|| {
                m.residual(State::new(T, black_box(&y), black_box(&yp)), &mut r)
                    .unwrap()
            })
        });
        g.finish();
        let mut g = c.benchmark_group("jacobian");
        g.bench_with_input(BenchmarkId::new("jacobian", n), &n, |b, _| {
            b.iter(|| {
                m.jacobian(State::new(T, black_box(&y), black_box(&yp)), 0.1, &mut vals)
                    .unwrap()
            })
        });
        g.finish();
        m.jacobian(State::new(T, &y, &yp), 0.1, &mut vals).unwrap();
        let rhs: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
        for kind in [
            solver::LinearSolver::Faer,
            solver::LinearSolver::Klu,
            solver::LinearSolver::KluMetis,
        ] {
            let name = kind.build().name();
            let mut g = c.benchmark_group(format!("lu-symbolic-{name}"));
            g.bench_with_input(
                BenchmarkId::new(format!("lu-symbolic-{name}"), n),
                &n,
                |b, _| {
                    b.iter(|| {
                        let mut s = kind.build();
                        s.analyse(black_box(m.pattern())).unwrap();
                        s
                    })
                },
            );
            g.finish();
            let mut s = kind.build();
            s.analyse(m.pattern()).unwrap();
            bench_numeric_and_solve(c, "", &mut s, &vals, &rhs);
        }

        // With inertia: full-size LU against the condensed one, on the same J.
        let mut mi = model(refine, true);
        let ni = mi.size();
        let (y, yp) = state(&mi);
        let mut vals = vec![0.0; mi.pattern().compute_nnz()];
        mi.jacobian(State::new(T, &y, &yp), 100.0, &mut vals)
            .unwrap();
        let rhs: Vec<f64> = (0..ni).map(|i| (0.37 * i as f64).sin()).collect();
        eprintln!("refine {refine} with inertia: n = {ni}");
        for kind in [
            solver::LinearSolver::Faer,
            solver::LinearSolver::FaerCondensed,
            solver::LinearSolver::Klu,
            solver::LinearSolver::KluMetis,
        ] {
            let mut s = kind.build_for(&mi).unwrap();
            s.analyse(mi.pattern()).unwrap();
            bench_numeric_and_solve(c, "inertia-", &mut s, &vals, &rhs);
        }
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1));
    targets = kernels
}
criterion_main!(benches);
