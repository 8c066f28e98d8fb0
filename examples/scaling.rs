//! How the cost grows with the mesh: the flat gravity phase (`cases/flat.ron` ended at
//! t = 10 000 s) at mesh refinements 0.5, 1, 2 and 4, each run as `cellsim run` would run
//! it; the wall time of the whole run and per step, and the fill nnz(L) + nnz(U) of the
//! default LU (faer, COLAMD) on the system after the fall (u, μ_as; the default scene's
//! Jacobian at the contact state of `benches/kernels.rs`), against the unknowns of that
//! system, with the fitted exponents.
//!
//! `cargo run --release --example scaling [-- REFINE ...]` writes `plots/scaling.tsv` and
//! `plots/scaling.png` (the README's scaling figure) and prints the exponents. Run it on a
//! quiet machine: the wall times are single runs.

use cellsim::dae::State;
use std::fmt::Write as _;
use std::path::PathBuf;

use cellsim::case::Case;
use cellsim::commands::step_study::fit_loglog;
use cellsim::commands::step_study::plots::{LogLogPanel, LogLogSeries, loglog_figure};
use cellsim::dae::linsolve::FaerLu;
use cellsim::dae::{Dae, LinearSolver};
use cellsim::run::{self, RunOptions};

#[path = "../benches/support/mod.rs"]
mod support;

struct Row {
    refine: f64,
    /// Unknowns after the fall (u, μ_as) and at the start (u, v; μ_as deferred).
    n: usize,
    n_start: usize,
    steps: u64,
    jacobians: u64,
    wall: f64,
    fill: usize,
    nnz: usize,
}

fn main() {
    let refines: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a refinement factor"))
        .collect();
    let refines = if refines.is_empty() {
        vec![0.5, 1.0, 2.0, 4.0]
    } else {
        refines
    };
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let file = root.join("cases/flat.ron");
    let base = Case::load(&file).unwrap_or_else(|e| panic!("{e}"));
    let mut rows = Vec::new();
    for &refine in &refines {
        let mut case = base.clone();
        case.name = format!("flat-gravity-refine{refine}");
        case.phases.t_end = case.phases.t_g0;
        case.mesh.refine = refine;
        let opts = RunOptions::new(
            root.join("target/scaling").join(&case.name),
            case.solver.clone(),
        );
        let s =
            run::run(&case, &file.display().to_string(), &opts).unwrap_or_else(|e| panic!("{e}"));
        // The fill of the system after the fall, on the same mesh.
        let m = support::model(refine, false);
        let (y, yp) = support::state(&m);
        let mut values = vec![0.0; m.pattern().compute_nnz()];
        let mut mm = m;
        mm.jacobian(State::new(45_000.0, &y, &yp), 0.1, &mut values)
            .unwrap();
        let mut lu = FaerLu::new();
        lu.analyse(mm.pattern()).unwrap();
        let fill = support::fill(mm.pattern(), &values, lu.column_permutation().unwrap());
        let row = Row {
            refine,
            n: mm.size(),
            n_start: s.unknowns.total,
            steps: s.stats.steps,
            jacobians: s.stats.jacobian_evals,
            wall: s.wall_seconds,
            fill,
            nnz: values.len(),
        };
        eprintln!(
            "refine {refine}: {} unknowns ({} at the start), {} steps, {} Jacobians, {:.2} s wall, fill {}",
            row.n, row.n_start, row.steps, row.jacobians, row.wall, row.fill
        );
        rows.push(row);
    }
    let mut tsv = String::from(
        "refine\tunknowns\tunknowns_at_start\tsteps\tjacobians\twall_s\twall_per_step_ms\tnnz_A\tfill_LU\n",
    );
    for r in &rows {
        let _ = writeln!(
            tsv,
            "{}\t{}\t{}\t{}\t{}\t{:.3}\t{:.3}\t{}\t{}",
            r.refine,
            r.n,
            r.n_start,
            r.steps,
            r.jacobians,
            r.wall,
            1e3 * r.wall / r.steps as f64,
            r.nnz,
            r.fill
        );
    }
    let plots = root.join("plots");
    std::fs::create_dir_all(&plots).unwrap();
    std::fs::write(plots.join("scaling.tsv"), &tsv).unwrap();
    let pts = |f: &dyn Fn(&Row) -> f64| -> Vec<(f64, f64)> {
        rows.iter().map(|r| (r.n as f64, f(r))).collect()
    };
    let series = |label: &str, f: &dyn Fn(&Row) -> f64| LogLogSeries {
        label: label.into(),
        points: pts(f),
        fit: true,
    };
    let panels = [
        LogLogPanel {
            title: "Flat gravity phase, 0–10 000 s".into(),
            x_desc: "unknowns after the fall (u, μ_as)".into(),
            y_desc: "wall time (whole run: s; per step: ms)".into(),
            series: vec![
                series("whole run (s)", &|r| r.wall),
                series("per step (ms)", &|r| 1e3 * r.wall / r.steps as f64),
            ],
        },
        LogLogPanel {
            title: "Sparse LU of the Jacobian (faer, COLAMD)".into(),
            x_desc: "unknowns (u, μ_as)".into(),
            y_desc: "entries".into(),
            series: vec![
                series("fill nnz(L) + nnz(U)", &|r| r.fill as f64),
                series("nnz(J)", &|r| r.nnz as f64),
            ],
        },
    ];
    let png = plots.join("scaling.png");
    loglog_figure(
        &png,
        "How the cost grows with the mesh (refine 0.5, 1, 2, 4)",
        &panels,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for (name, f) in [
        ("whole run", &(|r: &Row| r.wall) as &dyn Fn(&Row) -> f64),
        ("per step", &|r: &Row| r.wall / r.steps as f64),
        ("fill", &|r: &Row| r.fill as f64),
    ] {
        let all = fit_loglog(&pts(f)).map(|f| f.slope);
        let from1: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.refine >= 1.0)
            .map(|r| (r.n as f64, f(r)))
            .collect();
        let upper = fit_loglog(&from1).map(|f| f.slope);
        println!(
            "{name}: n^{:.2} over all refinements, n^{:.2} from refine 1",
            all.unwrap_or(f64::NAN),
            upper.unwrap_or(f64::NAN)
        );
    }
    println!(
        "wrote {} and {}",
        plots.join("scaling.tsv").display(),
        png.display()
    );
}
