//! Whole runs (`cellsim::run::run`, outputs written to a temporary directory):
//!
//! - `scene`: `cases/fast/flat-gravity.ron` to t = 30 s (the fall with inertia, landing
//!   and bounce, inertia switched off at 9.65 s, then settling) at mesh refinements 0.5
//!   (the case's own) and 1, with the default linear solver (faer). Parameter: unknowns
//!   at the start (with velocities).
//! - `inertial-fall`: the same case with inertia on throughout, to t = 12 s (fall,
//!   landing, first bounce), with the full-size LU (`faer`) and the condensed one
//!   (`faer-condensed`) at refinement 0.5 and 1: the whole-run gain of the condensed solve.
//!
//! `cargo bench --features bench --bench scene`

use std::path::Path;
use std::time::Duration;

use cellsim::case::{Case, InertiaMode};
use cellsim::run::{self, RunOptions};
use cellsim::solver::LinearSolver;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};

fn case(refine: f64, t_end: f64, inertia_on: bool) -> (Case, String) {
    let file = format!("{}/cases/fast/flat-gravity.ron", env!("CARGO_MANIFEST_DIR"));
    let mut case = Case::load(&file).unwrap();
    case.mesh.refine = refine;
    case.phases.t_end = t_end;
    if inertia_on {
        case.inertia.mode = InertiaMode::On;
    }
    (case, file)
}

/// Unknowns of the case's system at the start.
fn unknowns(case: &Case, file: &str) -> usize {
    let mesh = cellsim::fem::Mesh::generate(&cellsim::scene::mesh_params(case)).unwrap();
    let inertia = cellsim::scene::starts_with_inertia(case);
    let p = cellsim::scene::model_params(case, file, inertia).unwrap();
    cellsim::model::CellModel::new(p, mesh).unwrap().dofs.n
}

fn run_once(case: &Case, file: &str, kind: LinearSolver, out: &Path) -> u64 {
    let mut settings = case.solver.clone();
    settings.linear_solver = kind;
    let opts = RunOptions::new(out.to_path_buf(), settings);
    let s = run::run(case, file, &opts).unwrap();
    assert!(s.finished);
    s.stats.steps
}

fn scenes(c: &mut Criterion) {
    let out = std::env::temp_dir().join(format!("cellsim-bench-{}", std::process::id()));
    let mut g = c.benchmark_group("scene");
    for refine in [0.5, 1.0] {
        let (case, file) = case(refine, 30.0, false);
        let n = unknowns(&case, &file);
        let steps = run_once(&case, &file, LinearSolver::Faer, &out);
        eprintln!("scene refine {refine}: n = {n}, {steps} steps");
        g.bench_with_input(BenchmarkId::new("flat-gravity-30s", n), &n, |b, _| {
            b.iter(|| run_once(&case, &file, LinearSolver::Faer, &out))
        });
    }
    g.finish();
    let mut g = c.benchmark_group("inertial-fall");
    for refine in [0.5, 1.0] {
        let (case, file) = case(refine, 12.0, true);
        let n = unknowns(&case, &file);
        for kind in [LinearSolver::Faer, LinearSolver::FaerCondensed] {
            let steps = run_once(&case, &file, kind, &out);
            let name = kind.build().name();
            eprintln!("inertial fall refine {refine} {name}: n = {n}, {steps} steps");
            g.bench_with_input(
                BenchmarkId::new(format!("flat-gravity-12s-{name}"), n),
                &n,
                |b, _| b.iter(|| run_once(&case, &file, kind, &out)),
            );
        }
    }
    g.finish();
    let _ = std::fs::remove_dir_all(&out);
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(100))
        .measurement_time(Duration::from_secs(5));
    targets = scenes
}
criterion_main!(benches);
